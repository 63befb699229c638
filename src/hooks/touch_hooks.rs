//! [`TouchHooks`]: rapier `PhysicsHooks` that replace the solver's view of a penetrating pair by
//! the reconstructed first-touch configuration.

use super::pose_history::PoseHistory;
use super::step_motion::{relative_motion, relative_travel};
use crate::geometry::{ContactConfiguration, ReconstructionOptions, Reconstructor, TouchMesh};
use crate::math::{Pose, Vector};
use rapier3d::dynamics::RigidBodySet;
use rapier3d::geometry::{ColliderHandle, ColliderSet, SolverFlags};
use rapier3d::pipeline::{ContactModificationContext, PairFilterContext, PhysicsHooks};
// parry's hash map (hashbrown with foldhash), as rapier uses: SipHash was 4.5 % of a pile's step.
use parry3d::utils::hashmap::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// This step's reconstructions, by (collider 1, collider 2).
type PairCache = HashMap<(ColliderHandle, ColliderHandle), Option<Arc<ContactConfiguration>>>;

/// A collider's cached [`TouchMesh`], with the address of the shape it was built from (a new
/// shape gets a new mesh).
#[derive(Clone)]
pub(crate) struct CachedMesh {
    pub shape_ptr: usize,
    pub mesh: Arc<TouchMesh>,
    /// The mesh is the shape itself (a polyhedral shape), not a tessellation of a curved one.
    pub exact: bool,
    /// What the shape is, for the primitives ([`shape_key`]): equal primitives share a mesh.
    pub key: Option<ShapeKey>,
    /// [`shape_reach`] of the shape, computed once (a convex hull's bounding sphere is a pass
    /// over its points: asked for every moving hull every step, it was a twentieth of the
    /// guard on rapier's convex-hull stress scene).
    pub reach: crate::math::Real,
}

/// A primitive shape by kind and dimensions (the bits of its parameters).
pub(crate) type ShapeKey = (u8, Vec<u32>);

/// The [`ShapeKey`] of a primitive shape (a ball, a cuboid, a capsule, a cylinder, a cone and
/// their rounded forms), `None` for the others. Colliders built one by one with
/// `ColliderBuilder::ball(r)` hold equal shapes in separate `Arc`s; meshing a rounded cylinder
/// (the hull of thousands of points) once per collider was most of rapier's CCD stress scene's
/// extra cost.
pub(crate) fn shape_key(shape: &dyn parry3d::shape::Shape) -> Option<ShapeKey> {
    use parry3d::shape::TypedShape;
    let bits = |v: &[crate::math::Real]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
    let v3 = |v: Vector| [v.x, v.y, v.z];
    Some(match shape.as_typed_shape() {
        TypedShape::Ball(b) => (0, bits(&[b.radius])),
        TypedShape::Cuboid(c) => (1, bits(&v3(c.half_extents))),
        TypedShape::Capsule(c) => {
            let (a, b) = (v3(c.segment.a), v3(c.segment.b));
            (2, bits(&[a[0], a[1], a[2], b[0], b[1], b[2], c.radius]))
        }
        TypedShape::Cylinder(c) => (3, bits(&[c.half_height, c.radius])),
        TypedShape::Cone(c) => (4, bits(&[c.half_height, c.radius])),
        TypedShape::RoundCuboid(c) => {
            let h = v3(c.inner_shape.half_extents);
            (5, bits(&[h[0], h[1], h[2], c.border_radius]))
        }
        TypedShape::RoundCylinder(c) => (
            6,
            bits(&[
                c.inner_shape.half_height,
                c.inner_shape.radius,
                c.border_radius,
            ]),
        ),
        TypedShape::RoundCone(c) => (
            7,
            bits(&[
                c.inner_shape.half_height,
                c.inner_shape.radius,
                c.border_radius,
            ]),
        ),
        _ => return None,
    })
}

/// Shapes whose touch mesh is the shape itself: their surface is made of flat triangles.
pub(crate) fn meshed_exactly(shape: &dyn parry3d::shape::Shape) -> bool {
    use parry3d::shape::TypedShape;
    match shape.as_typed_shape() {
        TypedShape::TriMesh(_)
        | TypedShape::Triangle(_)
        | TypedShape::HeightField(_)
        | TypedShape::Voxels(_)
        | TypedShape::Cuboid(_)
        | TypedShape::ConvexPolyhedron(_) => true,
        TypedShape::Compound(c) => c.shapes().iter().all(|(_, s)| meshed_exactly(&**s)),
        _ => false,
    }
}

/// Counters of what the hooks did during the last step (they never panic; what they skip is
/// counted here).
///
/// # Example
/// A box that ends its step about 2 mm deep in a slab (deeper than the slop) has its manifold
/// rewritten at the start of the next step:
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// let mut world = PhysicsWorld::default();
/// TouchPipeline::configure(&mut world.integration_parameters);
/// world.integration_parameters.max_ccd_substeps = 0;
/// let hooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;
/// let slab = ColliderBuilder::cuboid(2.0, 0.5, 2.0).translation(Vector::new(0.0, -0.5, 0.0));
/// world.insert_collider(slab.active_hooks(hooks), None);
/// let body = world.insert_body(
///     RigidBodyBuilder::dynamic()
///         .translation(Vector::new(0.0, 0.45, 0.0))
///         .linvel(Vector::new(0.0, -12.0, 0.0)),
/// );
/// let cube = ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(hooks);
/// world.insert_collider(cube, Some(body));
/// // Hooks only (no step guard): the box ends its first step in the slab...
/// let mut touch = TouchPipeline::new(());
/// touch.options.correct_poses = false;
/// touch.step(&mut world);
/// assert_eq!(touch.hooks.counters(), HookCounters::default());
/// let bottom = world.bodies[body].translation().y - 0.25;
/// assert!(bottom < -TouchOptions::default().penetration_slop);
/// // ... and at the start of the next one the hooks rewrite its manifold with the first touch.
/// touch.step(&mut world);
/// let counters = touch.hooks.counters();
/// assert_eq!(counters, HookCounters { rewritten: 1, dropped: 0, skipped: 0 });
/// assert!(world.bodies[body].linvel().y > 0.0); // pushed back out
/// ```
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct HookCounters {
    /// Manifolds whose solver contacts were moved onto the reconstructed first touch.
    pub rewritten: usize,
    /// Manifolds whose penetrating solver contacts were removed because the reconstruction
    /// found the pair apart. Only pairs of polyhedral shapes (cuboids, convex polyhedra,
    /// triangle meshes, height fields, voxels, compounds of these): a curved shape's mesh is a
    /// tessellation, and rapier's contacts on the true shape are kept.
    pub dropped: usize,
    /// Deep manifolds left to rapier: a collider without a touch mesh, a shape that has no
    /// triangle-mesh form, or a failed reconstruction.
    pub skipped: usize,
}

/// rapier [`PhysicsHooks`] that rewrite the manifolds of penetrating pairs with the
/// reconstructed first-touch configuration, and forward everything to the user's hooks `H`.
///
/// # When it runs
/// rapier calls `modify_solver_contacts` at the start of `step`, on the poses the previous step
/// left (after [`super::TouchPipeline`]'s corrections), for colliders with
/// `ActiveHooks::MODIFY_SOLVER_CONTACTS`. For such a manifold, when rapier finds a solver
/// contact deeper than the slop but no deeper than the two bodies travelled over the previous
/// step (deeper, the pair already overlapped before it: a resting contact rapier is resolving),
/// and both colliders are single polyhedra (cuboids, convex polyhedra: a curved shape's touch
/// mesh is a tessellation and rapier's own contacts on it are exact; a triangle mesh, a height
/// field or a compound gets one manifold per part, which one first-touch patch cannot stand
/// for), it reconstructs the pair along its relative motion over the previous step
/// (from the pose history the pipeline records), then:
/// - **penetrating deeper than the slop or perforated, first touch on the last step's path:**
///   sets the manifold normal to the first-touch patch normal and, for each solver contact,
///   puts `anchor1` on the first-touch contact plane, `anchor2` the reversing vector behind it
///   and `dist = -(reversing vector · normal)`: the solver pushes out exactly what the
///   reconstruction found, along the right normal;
/// - **touching, or penetrating since before the last step** (a resting contact rapier is
///   already pushing apart): leaves the contacts as rapier made them;
/// - **separated:** removes solver contacts with `dist < 0` (rapier's estimate was wrong), keeps
///   speculative ones.
///
/// Then the user's hooks run on the result. Filtering hooks are forwarded unchanged.
///
/// # Caveats (rapier 0.36)
/// - A hook cannot add solver contacts: at most the (≤ 4) contacts rapier selected are moved.
/// - Softness is global: rapier removes a written `dist` over several substeps unless the
///   contact softness is stiff. [`super::TouchPipeline`] therefore also corrects poses between
///   steps; the hooks give the solver the right normal and points.
/// - Set `IntegrationParameters::contact_clustering = false`, or mesh manifolds arrive merged.
///
/// # Example
/// Your hooks run after the crate's, and the whole pipeline obeys them: a floor whose pairs
/// your `filter_contact_pair` refuses lets a box fall through, past the step guard too.
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// /// Your own hooks: refuse every contact pair.
/// struct Ghost;
/// impl PhysicsHooks for Ghost {
///     fn filter_contact_pair(&self, _: &PairFilterContext) -> Option<SolverFlags> {
///         None
///     }
/// }
///
/// /// Drops a box on a floor whose pairs go through your `filter_contact_pair`; its final height.
/// fn drop_box<H: PhysicsHooks>(touch: &mut TouchPipeline<H>) -> Real {
///     let mut world = PhysicsWorld::default();
///     TouchPipeline::configure(&mut world.integration_parameters);
///     let hooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;
///     let floor = ColliderBuilder::cuboid(2.0, 0.05, 2.0)
///         .active_hooks(hooks | ActiveHooks::FILTER_CONTACT_PAIRS);
///     world.insert_collider(floor, None);
///     let start = Vector::new(0.0, 1.0, 0.0);
///     let body = world.insert_body(RigidBodyBuilder::dynamic().translation(start));
///     let cube = ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(hooks);
///     world.insert_collider(cube, Some(body));
///     for _ in 0..60 {
///         touch.step(&mut world);
///     }
///     world.bodies[body].translation().y
/// }
///
/// // No hooks of yours (`()`): the box lands on the floor, its centre at 0.05 + 0.25.
/// assert!((drop_box(&mut TouchPipeline::new(())) - 0.3).abs() < 2e-3);
/// // Yours, forwarded by the `TouchHooks` and obeyed by the step guard: it falls through.
/// let mut touch = TouchPipeline::new(Ghost);
/// let _: &TouchHooks<Ghost> = &touch.hooks;
/// assert!(drop_box(&mut touch) < -1.0);
/// assert_eq!(touch.hooks.counters(), HookCounters::default()); // nothing to rewrite
/// ```
pub struct TouchHooks<H: PhysicsHooks = ()> {
    /// The user's hooks, called after this crate's.
    pub inner: H,
    pub(crate) meshes: HashMap<ColliderHandle, CachedMesh>,
    pub(crate) prev_poses: PoseHistory,
    pub(crate) options: ReconstructionOptions,
    pub(crate) slop: crate::math::Real,
    cache: Mutex<PairCache>,
    pool: Mutex<Vec<Reconstructor>>,
    rewritten: AtomicUsize,
    dropped: AtomicUsize,
    skipped: AtomicUsize,
    /// The counters of the steps before the last one, summed.
    earlier: HookCounters,
}

impl<H: PhysicsHooks> std::fmt::Debug for TouchHooks<H> {
    /// Your hooks by type name, the settings, the sizes of the caches and the last step's
    /// counters (not the cached meshes and reconstructions).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TouchHooks")
            .field("inner", &std::any::type_name::<H>())
            .field("meshes", &self.meshes.len())
            .field("prev_poses", &self.prev_poses.len())
            .field("options", &self.options)
            .field("slop", &self.slop)
            .field("counters", &self.counters())
            .field("total_counters", &self.total_counters())
            .finish_non_exhaustive()
    }
}

impl Default for TouchHooks<()> {
    fn default() -> Self {
        Self::new(())
    }
}

impl<H: PhysicsHooks> TouchHooks<H> {
    /// Hooks that forward to `inner` after their own work.
    pub fn new(inner: H) -> Self {
        Self {
            inner,
            meshes: HashMap::default(),
            prev_poses: PoseHistory::default(),
            options: ReconstructionOptions::default(),
            slop: 0.0,
            cache: Mutex::new(HashMap::default()),
            pool: Mutex::new(Vec::new()),
            rewritten: AtomicUsize::new(0),
            dropped: AtomicUsize::new(0),
            skipped: AtomicUsize::new(0),
            earlier: HookCounters::default(),
        }
    }

    /// What the hooks did during the last step ([`TouchHooks::total_counters`]: over the
    /// whole run).
    pub fn counters(&self) -> HookCounters {
        HookCounters {
            rewritten: self.rewritten.load(Ordering::Relaxed),
            dropped: self.dropped.load(Ordering::Relaxed),
            skipped: self.skipped.load(Ordering::Relaxed),
        }
    }

    /// What the hooks did since they were created, the last step included.
    pub fn total_counters(&self) -> HookCounters {
        let last = self.counters();
        HookCounters {
            rewritten: self.earlier.rewritten.saturating_add(last.rewritten),
            dropped: self.earlier.dropped.saturating_add(last.dropped),
            skipped: self.earlier.skipped.saturating_add(last.skipped),
        }
    }

    /// Clears the per-step cache and counters (called by the pipeline before each step); the
    /// counters are added to the run's totals first.
    pub(crate) fn begin_step(&mut self) {
        self.earlier = self.total_counters();
        self.cache.get_mut().map(|c| c.clear()).unwrap_or(());
        *self.rewritten.get_mut() = 0;
        *self.dropped.get_mut() = 0;
        *self.skipped.get_mut() = 0;
    }

    /// Whether the hooks can rewrite the pairs of collider `c`: its touch mesh is its shape
    /// (a polyhedron, not the tessellation of a curved shape: rapier's contacts on a ball, a
    /// capsule or a rounded shape are exact) and the shape is not composite (a triangle mesh,
    /// a height field or a compound gets one manifold per part from rapier, and one
    /// first-touch patch cannot stand for all of them: rewriting them put bodies through a
    /// bumpy TriMesh floor in rapier's `trimesh3` stress scene).
    pub(crate) fn rewritable(&self, colliders: &ColliderSet, c: ColliderHandle) -> bool {
        self.meshes.get(&c).is_some_and(|m| m.exact)
            && colliders
                .get(c)
                .is_some_and(|co| co.shape().as_composite_shape().is_none())
    }

    fn reconstruct_pair(
        &self,
        bodies: &RigidBodySet,
        colliders: &ColliderSet,
        c1: ColliderHandle,
        c2: ColliderHandle,
    ) -> Option<Arc<ContactConfiguration>> {
        if let Ok(cache) = self.cache.lock() {
            if let Some(hit) = cache.get(&(c1, c2)) {
                return hit.clone();
            }
        }
        let mut rec = self
            .pool
            .lock()
            .ok()
            .and_then(|mut p| p.pop())
            .unwrap_or_else(|| Reconstructor::new(self.options));
        let result = pair_configuration(
            &mut rec,
            &self.meshes,
            &self.prev_poses,
            bodies,
            colliders,
            c1,
            colliders.get(c1).map(|c| *c.position()),
            c2,
            colliders.get(c2).map(|c| *c.position()),
        )
        .map(Arc::new);
        if let Ok(mut p) = self.pool.lock() {
            p.push(rec);
        }
        if let Ok(mut cache) = self.cache.lock() {
            cache.insert((c1, c2), result.clone());
        }
        result
    }
}

/// Reconstructs collider 2 against collider 1 (at the given world poses) along their relative
/// motion over the last step ([`relative_motion`]: translation and rotation). `None` when a
/// mesh is missing or a pose is not finite.
#[allow(clippy::too_many_arguments)]
pub(crate) fn pair_configuration(
    rec: &mut Reconstructor,
    meshes: &HashMap<ColliderHandle, CachedMesh>,
    prev_poses: &PoseHistory,
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
    c1: ColliderHandle,
    pos1: Option<Pose>,
    c2: ColliderHandle,
    pos2: Option<Pose>,
) -> Option<ContactConfiguration> {
    let (m1, m2) = (meshes.get(&c1)?, meshes.get(&c2)?);
    let (co1, co2) = (colliders.get(c1)?, colliders.get(c2)?);
    let (pos1, pos2) = (pos1?, pos2?);
    let motion = relative_motion(prev_poses, bodies, co1, pos1, co2, pos2, &m2.mesh);
    // A curved shape's touch mesh is a tessellation: its pairs are walked back on the shapes
    // themselves (conservative advancement on parry's distance), polyhedra by the exact method
    // that names features.
    if !(m1.exact && m2.exact) {
        match rec.reconstruct_shapes(co1.shape(), &pos1, co2.shape(), &motion) {
            Ok(Some(c)) => return Some(c),
            Ok(None) => {}
            Err(_) => return None,
        }
    }
    rec.reconstruct_motion(&m1.mesh, &pos1, &m2.mesh, &motion)
        .ok()
}

impl<H: PhysicsHooks> PhysicsHooks for TouchHooks<H> {
    fn filter_contact_pair(&self, context: &PairFilterContext) -> Option<SolverFlags> {
        self.inner.filter_contact_pair(context)
    }

    fn filter_intersection_pair(&self, context: &PairFilterContext) -> bool {
        self.inner.filter_intersection_pair(context)
    }

    fn modify_solver_contacts(&self, context: &mut ContactModificationContext) {
        let (c1, c2) = (context.collider1, context.collider2);
        // Only manifolds rapier finds deeper than the slop are worth a reconstruction, and only
        // if the pair can have first touched on the last step's path: a pair deeper than the
        // two bodies travelled over that step already overlapped when it began (a resting
        // contact rapier is resolving), and is left as rapier made it.
        let depth = context.rigid().map_or(0.0, |m| {
            m.solver_contacts
                .iter()
                .map(|c| -c.dist)
                .fold(0.0, crate::math::Real::max)
        });
        // Two dynamic bodies that moved less than their safe step length relative to each
        // other cannot have passed through each other: their contact is rapier's soft contact,
        // as the step guard leaves it (one contact model for both).
        let dynamic = |c: ColliderHandle| {
            context
                .colliders
                .get(c)
                .and_then(|co| co.parent())
                .and_then(|b| context.bodies.get(b))
                .is_some_and(|b| b.is_dynamic())
        };
        let safe = |c: ColliderHandle| self.meshes.get(&c).map_or(0.0, |m| m.mesh.min_extent());
        // (The travel only for a manifold deeper than the slop: a TriMesh floor's pairs have a
        // manifold per triangle, and most are shallow.)
        let deep = depth > self.slop && {
            let travel = relative_travel(
                &self.meshes,
                &self.prev_poses,
                context.bodies,
                context.colliders,
                c1,
                c2,
            );
            depth <= self.slop + travel
                && !(dynamic(c1) && dynamic(c2) && travel < safe(c1).min(safe(c2)))
        };
        let exact = |c| self.meshes.get(&c).map(|m| m.exact);
        let config = if deep
            && self.rewritable(context.colliders, c1)
            && self.rewritable(context.colliders, c2)
        {
            self.reconstruct_pair(context.bodies, context.colliders, c1, c2)
        } else {
            None
        };
        match (config, context.rigid_mut()) {
            (Some(config), Some(m)) => {
                if config.needs_correction() && config.on_trajectory && config.depth > self.slop {
                    let Some(patch) = config.patches.first() else {
                        self.skipped.fetch_add(1, Ordering::Relaxed);
                        return self.inner.modify_solver_contacts(context);
                    };
                    let n = patch.normal;
                    let center = patch.center();
                    let r = config.reversing_vector;
                    *m.normal = n;
                    for sc in m.solver_contacts.iter_mut() {
                        // Keep the contact where rapier put it (its lever arms are frozen at the
                        // manifold point), on the first-touch contact plane; the moving surface's
                        // matching point is the reversing vector behind it.
                        let p = sc.anchor1 - n * (sc.anchor1 - center).dot(n);
                        sc.anchor1 = p;
                        sc.anchor2 = p - r;
                        sc.dist = -r.dot(n);
                    }
                    self.rewritten.fetch_add(1, Ordering::Relaxed);
                } else if config.state == crate::geometry::TouchState::Separated
                    && self.meshes.get(&c1).is_some_and(|m| m.exact)
                    && self.meshes.get(&c2).is_some_and(|m| m.exact)
                {
                    let before = m.solver_contacts.len();
                    m.solver_contacts.retain(|c| c.dist >= 0.0);
                    if m.solver_contacts.len() != before {
                        self.dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
            }
            _ if deep && (exact(c1).is_none() || exact(c2).is_none()) => {
                self.skipped.fetch_add(1, Ordering::Relaxed);
            }
            _ => {}
        }
        self.inner.modify_solver_contacts(context);
    }
}

#[cfg(test)]
mod tests {
    use super::shape_key;
    use parry3d::shape::SharedShape;

    #[test]
    fn equal_primitives_share_a_key_and_different_ones_do_not() {
        let key = |s: SharedShape| shape_key(s.as_ref());
        assert_eq!(
            key(SharedShape::round_cylinder(1.0, 0.5, 0.1)),
            key(SharedShape::round_cylinder(1.0, 0.5, 0.1))
        );
        assert!(key(SharedShape::ball(0.5)).is_some());
        assert_ne!(key(SharedShape::ball(0.5)), key(SharedShape::ball(0.5001)));
        assert_ne!(
            key(SharedShape::cylinder(1.0, 0.5)),
            key(SharedShape::cone(1.0, 0.5))
        );
        assert_ne!(
            key(SharedShape::capsule_y(1.0, 0.5)),
            key(SharedShape::capsule_x(1.0, 0.5))
        );
        // Meshes and hulls are shared by `Arc` only.
        let hull = SharedShape::convex_hull(&[
            parry3d::math::Vector::ZERO,
            parry3d::math::Vector::X,
            parry3d::math::Vector::Y,
            parry3d::math::Vector::Z,
        ])
        .unwrap();
        assert_eq!(key(hull), None);
    }
}
