//! [`TouchPipeline`]: one call that steps a rapier `PhysicsWorld` with the touch hooks, the
//! step guard, the tools' proxies and the contact report.

use super::pair_filter::{rapier_solves_pair, user_removes_contact};
use super::report::{PairReport, ToolFeedback};
use super::touch_hooks::{
    body_motion, meshed_exactly, pair_configuration, previous_collider_pose, CachedMesh, TouchHooks,
};
use crate::geometry::{
    ReconstructionOptions, Reconstructor, TouchMesh, TouchMeshError, TouchState,
};
use crate::math::{Pose, Real, Vector};
use parry3d::bounding_volume::BoundingVolume;
use rapier3d::dynamics::{IntegrationParameters, RigidBodyHandle};
use rapier3d::geometry::{ColliderHandle, ColliderSet};
use rapier3d::pipeline::{ActiveHooks, EventHandler, PhysicsHooks, PhysicsWorld, QueryFilter};
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

/// Tuning of [`TouchPipeline`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TouchOptions {
    /// Penetration (along the trajectory) the step guard tolerates before it moves a body back
    /// to first touch. Default `2e-4` m: below rapier's own resting overlap noise, well below the
    /// 1 mm a user sees. Range `0 ..= 0.01`; smaller values correct more often.
    pub penetration_slop: Real,
    /// Correct poses between steps (the step guard). Default `true`. With `false` the crate only
    /// rewrites manifolds (hooks) and reports.
    pub correct_poses: bool,
    /// Penetration tolerated for a body that already overlapped a fixed or kinematic collider
    /// when the step began (a resting contact rapier is resolving with its own soft push-out;
    /// rapier's own contact points say whether it did). Deeper than this after a step, the
    /// guard pushes the body back along rapier's contact normal to the deeper of this depth and
    /// the depth the pair had when the step began, so a tumbling or pressed body never digs
    /// further into the floor, while rapier's steady overlap under a tall pile is left alone.
    /// Resting pairs of two dynamic bodies (a stack, whose soft contacts rapier lets overlap by
    /// about a millimetre) are left to rapier. Default `9e-4` m: above rapier's usual resting
    /// overlap, below the 1 mm a user sees. Range `slop ..= 0.01`.
    pub resting_slop: Real,
    /// Guard passes per step (a correction can push a body into a third one). Default 3.
    pub max_passes: usize,
    /// Manage the `ActiveHooks::MODIFY_SOLVER_CONTACTS` flag of the colliders opted in with
    /// it: the pipeline remembers them, clears the flag, and raises it after a step only on
    /// the colliders whose body moved more than rapier's prediction distance during it (a
    /// slower body meets nothing rapier's speculative contacts did not see coming, and the
    /// guard corrects poses anyway). rapier never recycles the contacts
    /// of a pair with a hook flag (its narrow phase recomputes them every step), so a resting
    /// pile with the flag everywhere costs rapier itself about 1.7×. `false` in
    /// [`TouchPipeline::new`] (your hooks may need the flag on every manifold: a one-way
    /// platform), `true` in `TouchPipeline::default()` (no hooks of yours). With it on,
    /// [`TouchPipeline::untrack_collider`] also lets go of a flagged collider.
    pub hook_flags_on_demand: bool,
    /// Reconstruct and report touching pairs too. Default `false`: the guard then skips pairs
    /// that can neither have tunneled (relative step shorter than the safe step length) nor
    /// penetrate deeper than the slop (parry's contact query), and reports only the pairs it
    /// reconstructs. `true` reconstructs every pair whose swept boxes meet (slower).
    pub report_touching: bool,
    /// Options of the reconstructions.
    pub reconstruction: ReconstructionOptions,
}

impl Default for TouchOptions {
    fn default() -> Self {
        Self {
            penetration_slop: 2.0e-4,
            resting_slop: 9.0e-4,
            correct_poses: true,
            max_passes: 3,
            hook_flags_on_demand: false,
            report_touching: false,
            reconstruction: ReconstructionOptions::default(),
        }
    }
}

/// A user-driven tool (god-object / proxy): where the device puts it, and where the crate lets
/// it be.
#[derive(Copy, Clone, Debug)]
struct Tool {
    device: Pose,
    proxy: Pose,
}

/// Steps a rapier [`PhysicsWorld`] with exact touch contacts.
///
/// Colliders take part when they have `ActiveHooks::MODIFY_SOLVER_CONTACTS` (hooks, guard and
/// reports) or were given to [`TouchPipeline::track_collider`] (guard and reports, no rapier
/// hooks), and have a shape with a triangle-mesh form ([`TouchMesh::from_shape`]). Each [`TouchPipeline::step`]:
/// 1. records every body's pose (the history the reconstruction walks back along);
/// 2. runs rapier's step with [`TouchHooks`] (which forward to your hooks);
/// 3. **step guard:** for every moving dynamic body, reconstructs it against each opted-in
///    collider its swept box touches; a body that penetrates deeper than the slop, or that went
///    through a thin object (perforation), is moved back along its own trajectory to first touch
///    and loses its velocity into the surface. This *clamps the motion to first touch*, so fast
///    objects do not tunnel even with rapier's CCD off, and moving TriMesh bodies (which
///    rapier's CCD never sweeps) are guarded too. Only pairs rapier itself would solve are
///    corrected: a body passes sensors, colliders its collision or solver groups exclude,
///    disabled colliders, pairs its `ActiveCollisionTypes` leave out, bodies joined by a joint
///    with contacts disabled, pairs your `filter_contact_pair` refuses and contacts your
///    `modify_solver_contacts` removes (a one-way platform: the guard asks it on the first-touch
///    contact before correcting), exactly as in vanilla rapier (tools ignore the collision
///    types only). The colliders of moved bodies and their broad-phase boxes are synced at
///    once, so collider poses and the query pipeline see the corrected poses after the step;
/// 4. **tools:** a kinematic body registered with [`TouchPipeline::set_tool_target`] is put at
///    the last pose that does not penetrate (its proxy), and
///    [`TouchPipeline::tool_feedback`] gives the device-to-proxy offset for a feedback force;
/// 5. fills the [`PairReport`]s of the step ([`TouchPipeline::reports`]).
///
/// # Example
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// let mut world = PhysicsWorld::default();
/// world.integration_parameters.contact_clustering = false;
/// world.insert_collider(
///     ColliderBuilder::cuboid(5.0, 0.05, 5.0).active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS),
///     None,
/// );
/// let body = world.insert_body(
///     RigidBodyBuilder::dynamic()
///         .translation(Vector::new(0.0, 2.0, 0.0))
///         .linvel(Vector::new(0.0, -100.0, 0.0)),
/// );
/// world.insert_collider(
///     ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS),
///     Some(body),
/// );
/// let mut touch = TouchPipeline::default();
/// for _ in 0..60 {
///     touch.step(&mut world);
/// }
/// // A 100 m/s box does not go through a 10 cm slab (rapier's CCD is on by default, but the
/// // guard does not need it).
/// assert!(world.bodies[body].translation().y > 0.0);
/// ```
pub struct TouchPipeline<H: PhysicsHooks = ()> {
    /// The hooks handed to rapier's step (they forward to your hooks).
    pub hooks: TouchHooks<H>,
    /// Tuning.
    pub options: TouchOptions,
    reconstructor: Reconstructor,
    reports: Vec<PairReport>,
    tools: HashMap<RigidBodyHandle, Tool>,
    corrections: usize,
    odometers: HashMap<RigidBodyHandle, Real>,
    tracked: HashSet<ColliderHandle>,
    /// Colliders opted in with the hook flag while the pipeline manages it
    /// ([`TouchOptions::hook_flags_on_demand`]).
    hooked: HashSet<ColliderHandle>,
    pair_states: HashMap<(ColliderHandle, ColliderHandle), PairState>,
    /// Opted-in colliders whose shape has no touch mesh: the shape's address and why.
    refused: HashMap<ColliderHandle, (usize, TouchMeshError)>,
}

impl Default for TouchPipeline<()> {
    /// A pipeline with no hooks of yours, managing the hook flags
    /// ([`TouchOptions::hook_flags_on_demand`]).
    fn default() -> Self {
        let mut pipeline = Self::new(());
        pipeline.options.hook_flags_on_demand = true;
        pipeline
    }
}

impl TouchPipeline<()> {
    /// Sets the integration parameters this crate expects: no contact clustering (mesh
    /// manifolds keep their triangles).
    pub fn configure(params: &mut IntegrationParameters) {
        params.contact_clustering = false;
    }
}

impl<H: PhysicsHooks> TouchPipeline<H> {
    /// A pipeline whose hooks forward to `inner`.
    pub fn new(inner: H) -> Self {
        Self {
            hooks: TouchHooks::new(inner),
            options: TouchOptions::default(),
            reconstructor: Reconstructor::default(),
            reports: Vec::new(),
            tools: HashMap::new(),
            corrections: 0,
            odometers: HashMap::new(),
            tracked: HashSet::new(),
            hooked: HashSet::new(),
            pair_states: HashMap::new(),
            refused: HashMap::new(),
        }
    }

    /// The reports of the last step: one per reconstructed pair that touched, penetrated or
    /// perforated.
    pub fn reports(&self) -> &[PairReport] {
        &self.reports
    }

    /// Opted-in colliders the crate cannot guard, with the reason: their shape has no finite
    /// triangle surface ([`TouchMesh::from_shape`]: a half-space, a segment, a polyline). rapier
    /// handles their contacts alone. Filled by each step (a changed shape is tried again).
    ///
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    /// let mut world = PhysicsWorld::default();
    /// // A segment is a curve: it has no surface to touch.
    /// let ground = world.insert_collider(ColliderBuilder::segment(Vector::ZERO, Vector::X), None);
    /// let mut touch = TouchPipeline::default();
    /// touch.track_collider(ground);
    /// touch.step(&mut world);
    /// let (h, why) = touch.refused_colliders().next().unwrap();
    /// assert_eq!(h, ground);
    /// assert!(matches!(why, TouchMeshError::UnsupportedShape { .. }));
    /// ```
    pub fn refused_colliders(&self) -> impl Iterator<Item = (ColliderHandle, &TouchMeshError)> {
        self.refused.iter().map(|(h, (_, e))| (*h, e))
    }

    /// How many body poses the step guard corrected during the last step.
    pub fn corrections(&self) -> usize {
        self.corrections
    }

    /// Guards and reports `collider` without rapier hooks. Colliders with
    /// `ActiveHooks::MODIFY_SOLVER_CONTACTS` are guarded anyway and also get their manifolds
    /// rewritten; rapier never recycles the contacts of a pair with active hooks (1.4-1.7x its
    /// step time with 100 boxes on a TriMesh floor, see the README), which
    /// [`TouchOptions::hook_flags_on_demand`] avoids by raising the flag only on fast bodies.
    /// Tracking needs no flag at all.
    pub fn track_collider(&mut self, collider: ColliderHandle) {
        self.tracked.insert(collider);
    }

    /// Stops tracking `collider` (see [`TouchPipeline::track_collider`]).
    pub fn untrack_collider(&mut self, collider: ColliderHandle) {
        self.tracked.remove(&collider);
        self.hooked.remove(&collider);
    }

    /// Drives kinematic body `body` as a tool toward `device` (a mouse or haptic device pose).
    /// At each step the body moves toward the device pose but stops at first touch; see
    /// [`TouchPipeline::tool_feedback`].
    pub fn set_tool_target(&mut self, body: RigidBodyHandle, device: Pose) {
        let e = self.tools.entry(body).or_insert(Tool {
            device,
            proxy: device,
        });
        e.device = device;
    }

    /// Stops treating `body` as a tool.
    pub fn remove_tool(&mut self, body: RigidBodyHandle) {
        self.tools.remove(&body);
    }

    /// The device pose, the proxy pose and their offset for tool `body`, after the last step.
    pub fn tool_feedback(&self, body: RigidBodyHandle) -> Option<ToolFeedback> {
        self.tools.get(&body).map(|t| ToolFeedback {
            device: t.device,
            proxy: t.proxy,
            offset: t.proxy.translation - t.device.translation,
        })
    }

    /// Steps `world` once: see the type's documentation.
    pub fn step(&mut self, world: &mut PhysicsWorld) {
        self.step_with_events(world, &());
    }

    /// Like [`TouchPipeline::step`], with rapier's event handler.
    pub fn step_with_events(&mut self, world: &mut PhysicsWorld, events: &dyn EventHandler) {
        self.refresh_meshes(&world.colliders);
        self.hooks.options = self.options.reconstruction;
        self.hooks.slop = self.options.penetration_slop;
        self.reconstructor.options = self.options.reconstruction;

        // Tools: aim the kinematic bodies at their device pose.
        self.tools.retain(|h, _| world.bodies.contains(*h));
        for (h, tool) in &self.tools {
            if let Some(b) = world.bodies.get_mut(*h) {
                if b.is_kinematic() {
                    b.set_next_kinematic_position(tool.device);
                }
            }
        }

        // Pose history: where every body starts this step.
        let prev: HashMap<RigidBodyHandle, Pose> = world
            .bodies
            .iter()
            .map(|(h, b)| (h, *b.position()))
            .collect();
        self.hooks.begin_step();
        world.step_with_events(&self.hooks, events);
        self.hooks.prev_poses = prev;

        self.reports.clear();
        self.corrections = 0;
        self.guard(world);
        let proxies: Vec<(RigidBodyHandle, Pose)> = self
            .tools
            .keys()
            .filter_map(|h| Some((*h, *world.bodies.get(*h)?.position())))
            .collect();
        for (h, p) in proxies {
            if let Some(t) = self.tools.get_mut(&h) {
                t.proxy = p;
            }
        }
    }

    /// Builds (or drops) the touch meshes of opted-in colliders.
    fn refresh_meshes(&mut self, colliders: &ColliderSet) {
        self.tracked.retain(|h| colliders.contains(*h));
        self.hooked.retain(|h| colliders.contains(*h));
        if self.options.hook_flags_on_demand {
            for (h, co) in colliders.iter() {
                if co
                    .active_hooks()
                    .contains(ActiveHooks::MODIFY_SOLVER_CONTACTS)
                {
                    self.hooked.insert(h);
                }
            }
        }
        let (tracked, hooked) = (&self.tracked, &self.hooked);
        let opted_in = |h: &ColliderHandle, co: &rapier3d::geometry::Collider| {
            co.active_hooks()
                .contains(ActiveHooks::MODIFY_SOLVER_CONTACTS)
                || tracked.contains(h)
                || hooked.contains(h)
        };
        self.refused
            .retain(|h, _| colliders.get(*h).is_some_and(|co| opted_in(h, co)));
        let meshes = &mut self.hooks.meshes;
        meshes.retain(|h, _| colliders.contains(*h));
        // Colliders sharing one shape (rapier's `SharedShape` is an `Arc`) share one mesh.
        let mut by_shape: HashMap<usize, Arc<TouchMesh>> = meshes
            .values()
            .map(|m| (m.shape_ptr, m.mesh.clone()))
            .collect();
        for (h, co) in colliders.iter() {
            if !opted_in(&h, co) {
                meshes.remove(&h);
                continue;
            }
            let ptr = Arc::as_ptr(&co.shared_shape().0) as *const u8 as usize;
            if meshes.get(&h).is_some_and(|m| m.shape_ptr == ptr)
                || self.refused.get(&h).is_some_and(|r| r.0 == ptr)
            {
                continue;
            }
            let built = match by_shape.get(&ptr) {
                Some(mesh) => Ok(mesh.clone()),
                None => TouchMesh::from_shape(co.shape()).map(Arc::new),
            };
            match built {
                Ok(mesh) => {
                    self.refused.remove(&h);
                    by_shape.insert(ptr, mesh.clone());
                    meshes.insert(
                        h,
                        CachedMesh {
                            shape_ptr: ptr,
                            mesh,
                            exact: meshed_exactly(co.shape()),
                        },
                    );
                }
                Err(e) => {
                    meshes.remove(&h);
                    self.refused.insert(h, (ptr, e));
                }
            }
        }
    }

    /// The step guard: moves bodies that penetrate (or went through something) back to first
    /// touch, and records the reports.
    ///
    /// A calm pile costs little: rapier's own contact points (computed at the step's start,
    /// local to the colliders) are re-read at the poses now, as rapier's solver does, and say
    /// whether a pair already overlapped when the step began and how deep it is now. They are
    /// trusted while the pair moved less than rapier's prediction distance (they hold every
    /// feature pair within it), and for curved shapes (rapier's contacts are exact there; the
    /// touch mesh is a tessellation). A body that moved less than half the slop is skipped
    /// against fixed and dynamic partners (a dynamic partner that moved checks the pair).
    ///
    /// Work is bounded three ways. A body slower than its safe step length cannot have tunneled,
    /// so only the partners rapier's narrow phase already pairs it with are looked at (a swept
    /// box query otherwise). A pair whose last measured overlap plus the distance both bodies
    /// travelled since (their odometers) stays under the slop is skipped. Other pairs get
    /// parry's contact query, and a reconstruction only when it finds them deeper than the slop
    /// (or when parry has no query for the shapes, such as TriMesh against TriMesh).
    fn guard(&mut self, world: &mut PhysicsWorld) {
        let passes = if self.options.correct_poses {
            self.options.max_passes.max(1)
        } else {
            1
        };
        let slop = self.options.penetration_slop;
        let prediction = world.integration_parameters.prediction_distance();
        // Odometers: distance every point of each moving body may have travelled.
        for (h, b) in world.bodies.iter() {
            let Some(prev) = self.hooks.prev_poses.get(&h) else {
                continue;
            };
            let pose = b.position();
            let radius = b
                .colliders()
                .iter()
                .filter_map(|c| world.colliders.get(*c))
                .map(collider_reach)
                .fold(0.0, Real::max);
            let step = (pose.translation - prev.translation).length()
                + prev.rotation.angle_between(pose.rotation) * radius;
            if step > 0.0 && step.is_finite() {
                *self.odometers.entry(h).or_insert(0.0) += step;
            }
        }
        self.odometers.retain(|h, _| world.bodies.contains(*h));
        self.pair_states
            .retain(|(a, b), _| world.colliders.contains(*a) && world.colliders.contains(*b));

        let mut reported: HashSet<(ColliderHandle, ColliderHandle)> = HashSet::new();
        let mut moved_bodies: Vec<RigidBodyHandle> = Vec::new();
        let mut moved_before = 0;
        for pass in 0..passes {
            let mut moved = false;
            // Later passes look again only at the bodies the previous pass moved (a correction
            // can push a body into a third one).
            let movers: Vec<RigidBodyHandle> = if pass == 0 {
                world
                    .bodies
                    .iter()
                    .filter(|(h, b)| {
                        (b.is_dynamic() || self.tools.contains_key(h))
                            && !b.is_sleeping()
                            && b.colliders()
                                .iter()
                                .any(|c| self.hooks.meshes.contains_key(c))
                    })
                    .map(|(h, _)| h)
                    .collect()
            } else {
                let mut m = moved_bodies[moved_before..].to_vec();
                m.sort_unstable_by_key(|h| h.into_raw_parts());
                m.dedup();
                m
            };
            moved_before = moved_bodies.len();
            for bh in movers {
                let Some(body) = world.bodies.get(bh) else {
                    continue;
                };
                let body_pose = *body.position();
                let d = body_motion(&self.hooks.prev_poses, &world.bodies, Some(bh));
                let is_tool = self.tools.contains_key(&bh);
                let own: Vec<ColliderHandle> = body.colliders().to_vec();
                for ch in own {
                    let mesh_exact = self.hooks.meshes.get(&ch).is_some_and(|m| m.exact);
                    let Some(mesh) = self.hooks.meshes.get(&ch).map(|m| m.mesh.clone()) else {
                        continue;
                    };
                    let Some(co) = world.colliders.get(ch) else {
                        continue;
                    };
                    let co_rel = co.position_wrt_parent().copied();
                    let pose_now = co_rel.map_or(*co.position(), |rel| body_pose * rel);
                    let prev_pose = previous_collider_pose(&self.hooks.prev_poses, co, pose_now);
                    // How far a point of the collider may have travelled: translation plus the
                    // arc of its rotation.
                    let turn =
                        prev_pose.rotation.angle_between(pose_now.rotation) * collider_reach(co);
                    let fast = d.length() + turn >= mesh.min_extent().min(prediction);
                    // Tools (kinematic) may have no narrow-phase pairs with fixed colliders
                    // (rapier's default collision types): always query them.
                    let partners: Vec<ColliderHandle> = if fast || pass > 0 || is_tool {
                        let swept = co
                            .shape()
                            .compute_aabb(&pose_now)
                            .merged(&co.shape().compute_aabb(&prev_pose))
                            .loosened(turn);
                        world
                            .intersect_aabb_conservative(swept, QueryFilter::default())
                            .map(|(h, _)| h)
                            .collect()
                    } else {
                        // A slow body: only rapier's pairs, and among them only those its own
                        // contact points (re-read at the poses now) do not show calm.
                        // A body that moved less than half the slop changes a pair's depth by
                        // less than the slop unless its partner moved too: a fixed partner did
                        // not, and a dynamic one that did checks the pair from its side.
                        let still =
                            !self.options.report_touching && d.length() + turn <= 0.5 * slop;
                        let mut calm_skipped = Vec::new();
                        for p in world.narrow_phase.contact_pairs_with(ch) {
                            let ph = if p.collider1 == ch {
                                p.collider2
                            } else {
                                p.collider1
                            };
                            let Some(partner) = world.colliders.get(ph) else {
                                continue;
                            };
                            if still
                                && partner
                                    .parent()
                                    .and_then(|pb| world.bodies.get(pb))
                                    .is_none_or(|b| !b.is_kinematic())
                            {
                                continue;
                            }
                            let partner_pose = collider_pose_now(&world.bodies, partner);
                            let partner_prev = previous_collider_pose(
                                &self.hooks.prev_poses,
                                partner,
                                partner_pose,
                            );
                            let travel = (d - body_motion(
                                &self.hooks.prev_poses,
                                &world.bodies,
                                partner.parent(),
                            ))
                            .length()
                                + turn
                                + partner_prev.rotation.angle_between(partner_pose.rotation)
                                    * collider_reach(partner);
                            // rapier's points hold every feature pair within its prediction
                            // distance at the step's start: they still tell the depth when
                            // the pair moved less than that.
                            let rc = rapier_contact_of(
                                p,
                                ph,
                                (&partner_pose, &partner_prev),
                                (&pose_now, &prev_pose),
                            );
                            let trusted = travel <= prediction
                                || !(mesh_exact
                                    && self.hooks.meshes.get(&ph).is_some_and(|m| m.exact));
                            let partner_dynamic = partner
                                .parent()
                                .and_then(|pb| world.bodies.get(pb))
                                .is_some_and(|b| b.is_dynamic());
                            let calm = match &rc {
                                Some(r) if r.overlapped_at_start => {
                                    partner_dynamic
                                        || (trusted && r.depth <= self.options.resting_slop)
                                }
                                Some(r) => {
                                    !self.options.report_touching && trusted && r.depth <= slop
                                }
                                None => !self.options.report_touching && travel <= slop,
                            };
                            if !calm {
                                calm_skipped.push(ph);
                            }
                        }
                        calm_skipped
                    };
                    for ph in partners {
                        let Some(partner) = world.colliders.get(ph) else {
                            continue;
                        };
                        if ph == ch || partner.parent() == Some(bh) {
                            continue;
                        }
                        // Only pairs rapier itself would solve (sensors, groups, disabled
                        // colliders, collision types and the user's pair filter are rapier's
                        // say), asked in rapier's own pair order when it has the pair.
                        let (a, b) = world
                            .narrow_phase
                            .contact_pair(ph, ch)
                            .map_or((ph, ch), |p| (p.collider1, p.collider2));
                        if !rapier_solves_pair(
                            &world.bodies,
                            &world.colliders,
                            (&world.impulse_joints, &world.multibody_joints),
                            &self.hooks.inner,
                            a,
                            b,
                            is_tool,
                        ) {
                            continue;
                        }
                        let Some(partner_mesh) = self.hooks.meshes.get(&ph).map(|m| m.mesh.clone())
                        else {
                            continue;
                        };
                        let partner_pose = collider_pose_now(&world.bodies, partner);
                        let partner_body = partner.parent();
                        let partner_dynamic = partner_body
                            .and_then(|pb| world.bodies.get(pb))
                            .is_some_and(|b| b.is_dynamic());
                        // A pair rapier's manifold shows overlapping when the step began is a
                        // resting contact rapier is resolving: no first touch on this step's
                        // path. Pairs of two dynamic bodies (a stack) are rapier's; against a
                        // fixed or kinematic partner, only a pair now deeper than the resting
                        // slop is measured (along rapier's normal) and pushed back. Nothing is
                        // reconstructed for the resting pairs of a calm pile.
                        let partner_prev =
                            previous_collider_pose(&self.hooks.prev_poses, partner, partner_pose);
                        let dp = body_motion(&self.hooks.prev_poses, &world.bodies, partner_body);
                        let travel = (d - dp).length()
                            + turn
                            + partner_prev.rotation.angle_between(partner_pose.rotation)
                                * collider_reach(partner);
                        // rapier's contact points say whether the pair overlapped when the
                        // step began. Their depth now is trusted while the pair moved less
                        // than rapier's prediction distance (they hold every feature pair
                        // within it at the step's start; a spinning body brings new corners
                        // in).
                        let rapier = rapier_contact(
                            world,
                            ph,
                            (&partner_pose, &partner_prev),
                            ch,
                            (&pose_now, &prev_pose),
                        );
                        // A curved shape's contacts are rapier's exact ones (its touch mesh is
                        // a tessellation): they are trusted at any travel.
                        let trusted = travel <= prediction
                            || !(mesh_exact && self.hooks.meshes.get(&ph).is_some_and(|m| m.exact));
                        let overlapped = rapier.is_some_and(|r| r.overlapped_at_start);
                        if partner_dynamic && overlapped {
                            continue;
                        }
                        // (A pair that moved farther is measured on its own path below.)
                        let resting = rapier.filter(|_| overlapped && trusted);
                        if let Some(r) = &resting {
                            // Within the resting slop: rapier's.
                            if r.depth <= self.options.resting_slop {
                                continue;
                            }
                        }
                        let odo = |h: Option<RigidBodyHandle>| {
                            h.and_then(|h| self.odometers.get(&h).copied())
                                .unwrap_or(0.0)
                        };
                        let (odo_self, odo_partner) = (odo(Some(bh)), odo(partner_body));
                        let (config, along_normal) = if let Some(r) = &resting {
                            let mut rec = Reconstructor::new(ReconstructionOptions {
                                zero_motion_direction: Some(-r.normal),
                                ..self.options.reconstruction
                            });
                            let Ok(c) = rec.reconstruct(
                                &partner_mesh,
                                &partner_pose,
                                &mesh,
                                &pose_now,
                                &pose_now,
                            ) else {
                                continue;
                            };
                            (c.clone(), Some(c))
                        } else {
                            let safe = match (mesh.min_extent(), partner_mesh.min_extent()) {
                                (a, b) if b > 0.0 => a.min(b),
                                (a, _) => a,
                            };
                            let may_tunnel = (d - dp).length() >= safe;
                            if !self.options.report_touching && !may_tunnel {
                                // A slow pair: rapier's own contact points, re-read at the poses
                                // now, say how deep it is; with no points rapier found it apart
                                // (beyond its prediction distance) when the step began, so it can
                                // be no deeper than the pair's relative travel.
                                let bound = match rapier {
                                    Some(r) if trusted => r.depth,
                                    _ => travel,
                                };
                                if bound <= slop {
                                    continue;
                                }
                            }
                            // A pair rapier has contact points for, but that moved too far to
                            // read them, is reconstructed: parry's contact query is not asked
                            // (it answered wrongly for a 4 m plate lying on a 100 m floor).
                            if !self.options.report_touching && !may_tunnel && rapier.is_none() {
                                // Skip pairs whose overlap cannot have grown past the slop.
                                if let Some(st) = self.pair_states.get(&(ch, ph)) {
                                    let bound = st.overlap
                                        + (odo_self - st.odo_self)
                                        + (odo_partner - st.odo_partner);
                                    if bound <= slop {
                                        continue;
                                    }
                                }
                                // With a prediction of 0 parry answers `None` for separated
                                // shapes; a contact with a positive distance is one of its wrong
                                // answers (seen for a small tumbling cuboid on a large one: +1.1 mm
                                // where a corner was 1.1 mm deep). Such pairs are reconstructed.
                                let measured = parry3d::query::contact(
                                    &partner_pose,
                                    partner.shape(),
                                    &pose_now,
                                    co.shape(),
                                    0.0,
                                )
                                .ok()
                                .and_then(|c| match c {
                                    None => Some(0.0),
                                    Some(c) if c.dist <= 0.0 => Some(-c.dist),
                                    Some(_) => None,
                                });
                                if let Some(overlap) = measured {
                                    self.pair_states.insert(
                                        (ch, ph),
                                        PairState {
                                            overlap,
                                            odo_self,
                                            odo_partner,
                                        },
                                    );
                                    if overlap <= slop {
                                        continue;
                                    }
                                }
                            }
                            let Some(config) = pair_configuration(
                                &mut self.reconstructor,
                                &self.hooks.meshes,
                                &self.hooks.prev_poses,
                                &world.bodies,
                                &world.colliders,
                                ph,
                                Some(partner_pose),
                                ch,
                                Some(pose_now),
                            ) else {
                                continue;
                            };
                            // A pair that already overlapped when the step began has no first touch
                            // on this step's path: it is measured along rapier's own contact normal
                            // instead (its exit along -D can be far away).
                            let along_normal = if config.on_trajectory || !config.needs_correction()
                            {
                                None
                            } else {
                                rapier_normal(world, ph, ch).and_then(|n| {
                                    let mut rec = Reconstructor::new(ReconstructionOptions {
                                        zero_motion_direction: Some(-n),
                                        ..self.options.reconstruction
                                    });
                                    rec.reconstruct(
                                        &partner_mesh,
                                        &partner_pose,
                                        &mesh,
                                        &pose_now,
                                        &pose_now,
                                    )
                                    .ok()
                                })
                            };
                            (config, along_normal)
                        };
                        if pass == 0
                            && config.state != TouchState::Separated
                            && reported.insert((ph, ch))
                        {
                            self.reports.push(PairReport::new(
                                ph,
                                ch,
                                along_normal.as_ref().unwrap_or(&config),
                            ));
                        }
                        // A first touch on this step's own path is undone to first touch. A pair
                        // that already overlapped when the step began (a resting contact rapier
                        // is resolving) against a fixed or kinematic partner is only pushed
                        // back, along rapier's normal, to the resting slop when it got deeper;
                        // resting pairs of two dynamic bodies (a stack) are rapier's.
                        let on_path = config.on_trajectory && resting.is_none();
                        // A resting contact is pushed back to the depth it had when the step
                        // began (at least the resting slop): whatever got deeper than the
                        // resting slop never gets deeper still, and rapier's steady overlap is
                        // left alone.
                        let target = resting.map_or(self.options.resting_slop, |r| {
                            r.depth_at_start.max(self.options.resting_slop)
                        });
                        let config = match (&along_normal, on_path) {
                            (_, true) => config,
                            (Some(c), false)
                                if c.depth > target + 0.1 * slop && !partner_dynamic =>
                            {
                                let keep = target / c.depth;
                                let mut c = c.clone();
                                c.reversing_vector *= 1.0 - keep;
                                c.touch_pose.translation =
                                    pose_now.translation + c.reversing_vector;
                                c.depth -= target;
                                c
                            }
                            _ => continue,
                        };
                        // (A resting push is already net of its slop.)
                        if !self.options.correct_poses
                            || !config.needs_correction()
                            || (config.on_trajectory
                                && config.state == TouchState::Penetrating
                                && config.depth <= slop)
                        {
                            continue;
                        }
                        // Contacts the user's `modify_solver_contacts` removes (a one-way
                        // platform passed from below) are not solved by rapier either.
                        if let Some(patch) = config.patches.first() {
                            if user_removes_contact(
                                world,
                                &self.hooks.inner,
                                (a, b),
                                ph,
                                patch.normal,
                                patch.center(),
                                config.depth,
                            ) {
                                continue;
                            }
                        }
                        let r = config.reversing_vector;
                        // (A translation keeps the current orientation exactly.)
                        let turned = config.touch_pose.rotation != pose_now.rotation;
                        let n = config.patches.first().map(|p| p.normal);
                        // Split the correction by inverse mass when the partner is dynamic
                        // too, unless the partner rests on a fixed or kinematic collider: its
                        // share would push it into what supports it (seen: a thin dynamic plate
                        // pushed 2.25 mm into the floor under it). The moving body then takes
                        // it all, walked back along its own path as in the paper.
                        let partner_mass = partner_body
                            .and_then(|pb| world.bodies.get(pb))
                            .filter(|b| b.is_dynamic())
                            .filter(|_| !supported(world, ph))
                            .map(|b| b.mass());
                        let own_mass = world.bodies.get(bh).map_or(1.0, |b| b.mass());
                        let share = match partner_mass {
                            Some(mp) if mp > 0.0 && own_mass > 0.0 => {
                                (1.0 / own_mass) / (1.0 / own_mass + 1.0 / mp)
                            }
                            _ => 1.0,
                        };
                        if let Some(b) = world.bodies.get_mut(bh) {
                            if turned {
                                // A rotating path: the body goes to its pose at first touch
                                // (its share of the way when the partner moves too).
                                let rel = co_rel.unwrap_or(Pose::IDENTITY);
                                let target = config.touch_pose * rel.inverse();
                                let now = *b.position();
                                let p = Pose::from_parts(
                                    now.translation.lerp(target.translation, share),
                                    now.rotation.slerp(target.rotation, share),
                                );
                                if p.is_finite() {
                                    b.set_position(p, true);
                                }
                            } else {
                                let t = b.translation() + r * share;
                                if t.is_finite() {
                                    b.set_translation(t, true);
                                }
                            }
                            if let Some(n) = n {
                                // n points out of the partner toward this body: remove the
                                // velocity into the partner (inelastic).
                                let v = b.linvel();
                                let vn = v.dot(n);
                                if vn < 0.0 && b.is_dynamic() {
                                    b.set_linvel(v - vn * n, true);
                                }
                            }
                        }
                        moved_bodies.push(bh);
                        if let (Some(pb), true) = (partner_body, share < 1.0) {
                            moved_bodies.push(pb);
                            if let Some(b) = world.bodies.get_mut(pb) {
                                let t = b.translation() - r * (1.0 - share);
                                if t.is_finite() {
                                    b.set_translation(t, true);
                                }
                            }
                        }
                        self.pair_states.insert(
                            (ch, ph),
                            PairState {
                                overlap: 0.0,
                                odo_self,
                                odo_partner,
                            },
                        );
                        moved = true;
                        self.corrections += 1;
                        break;
                    }
                }
            }
            if !moved {
                break;
            }
        }
        sync_moved_colliders(world, &mut moved_bodies);
        self.sync_hook_flags(world);
    }

    /// With [`TouchOptions::hook_flags_on_demand`]: raises the hook flag on the managed
    /// colliders whose body moved more than rapier's prediction distance (and the slop) over
    /// this step (translation plus the arc of its rotation), clears it on the others.
    fn sync_hook_flags(&mut self, world: &mut PhysicsWorld) {
        if !self.options.hook_flags_on_demand {
            return;
        }
        // A body that moved less than rapier's prediction distance met nothing rapier had not
        // already seen coming (its speculative contacts); the guard corrects the others, so the
        // hooks only matter for the fast ones.
        let slop = self
            .options
            .penetration_slop
            .max(world.integration_parameters.prediction_distance());
        for h in &self.hooked {
            let Some(co) = world.colliders.get(*h) else {
                continue;
            };
            let moved = co.parent().is_some_and(|bh| {
                match (world.bodies.get(bh), self.hooks.prev_poses.get(&bh)) {
                    (Some(b), Some(prev)) => {
                        let now = b.position();
                        (now.translation - prev.translation).length()
                            + prev.rotation.angle_between(now.rotation) * collider_reach(co)
                            > slop
                    }
                    _ => false,
                }
            });
            let flags = co.active_hooks();
            let want = if moved {
                flags | ActiveHooks::MODIFY_SOLVER_CONTACTS
            } else {
                flags - ActiveHooks::MODIFY_SOLVER_CONTACTS
            };
            if want != flags {
                if let Some(co) = world.colliders.get_mut(*h) {
                    co.set_active_hooks(want);
                }
            }
        }
    }
}

/// Whether collider `c` has a contact with a fixed or kinematic collider in rapier's narrow
/// phase (a body resting on the floor).
fn supported(world: &PhysicsWorld, c: ColliderHandle) -> bool {
    world.narrow_phase.contact_pairs_with(c).any(|p| {
        let other = if p.collider1 == c {
            p.collider2
        } else {
            p.collider1
        };
        p.has_any_active_contact()
            && world.colliders.get(other).is_some_and(|co| {
                co.parent()
                    .and_then(|b| world.bodies.get(b))
                    .is_none_or(|b| !b.is_dynamic())
            })
    })
}

/// Where collider `co` is now: its body's pose times its offset (the guard moves bodies; their
/// colliders follow only when it syncs them after its passes).
fn collider_pose_now(
    bodies: &rapier3d::dynamics::RigidBodySet,
    co: &rapier3d::geometry::Collider,
) -> Pose {
    match (
        co.parent().and_then(|pb| bodies.get(pb)),
        co.position_wrt_parent(),
    ) {
        (Some(b), Some(rel)) => *b.position() * *rel,
        _ => *co.position(),
    }
}

/// How far a point of collider `co` can be from its body's origin: the offset to its parent
/// plus its bounding radius (a turn by `θ` moves it by at most `θ` times this).
fn collider_reach(co: &rapier3d::geometry::Collider) -> Real {
    co.position_wrt_parent()
        .map_or(0.0, |p| p.translation.length())
        + co.shape().compute_local_bounding_sphere().radius
}

/// Puts the colliders of the bodies the guard moved where their bodies now are, and their
/// broad-phase boxes with them, so renderers, ray casts and the query pipeline see the
/// corrected poses right after the step (rapier would only sync them at the next step).
fn sync_moved_colliders(world: &mut PhysicsWorld, moved: &mut Vec<RigidBodyHandle>) {
    if moved.is_empty() {
        return;
    }
    world
        .bodies
        .propagate_modified_body_positions_to_colliders(&mut world.colliders);
    moved.sort_unstable_by_key(|h| h.into_raw_parts());
    moved.dedup();
    let params = world.integration_parameters;
    for h in moved.iter() {
        let Some(body) = world.bodies.get(*h) else {
            continue;
        };
        for ch in body.colliders() {
            if let Some(co) = world.colliders.get(*ch) {
                if co.is_enabled() {
                    let aabb = co.compute_broad_phase_aabb(&params, &world.bodies);
                    if aabb.mins.is_finite() && aabb.maxs.is_finite() {
                        world.broad_phase.set_aabb(&params, *ch, aabb);
                    }
                }
            }
        }
    }
}

/// The overlap of a pair when it was last measured, and both bodies' odometers then.
#[derive(Copy, Clone, Debug)]
struct PairState {
    overlap: Real,
    odo_self: Real,
    odo_partner: Real,
}

/// rapier's contact manifold of a pair, read at the step's poses: the deepest of its contact
/// points at the poses now and rapier's normal there (out of `partner` toward `mover`), and
/// whether a point overlapped at the start of the step. The points are local to the colliders,
/// so they are re-read at any pose as rapier's solver does; a recycled manifold (rapier keeps
/// a pair's points while its relative pose drifts little) is read the same way.
#[derive(Copy, Clone, Debug)]
struct RapierContact {
    depth: Real,
    depth_at_start: Real,
    normal: Vector,
    overlapped_at_start: bool,
}

/// The [`RapierContact`] of a pair, `None` when rapier's manifolds hold no contact point for
/// it. `*_prev` are the colliders' poses at the start of the step.
fn rapier_contact(
    world: &PhysicsWorld,
    partner: ColliderHandle,
    partner_poses: (&Pose, &Pose),
    mover: ColliderHandle,
    mover_poses: (&Pose, &Pose),
) -> Option<RapierContact> {
    let pair = world.narrow_phase.contact_pair(partner, mover)?;
    rapier_contact_of(pair, partner, partner_poses, mover_poses)
}

/// [`rapier_contact`] of a pair at hand.
fn rapier_contact_of(
    pair: &rapier3d::geometry::ContactPair,
    partner: ColliderHandle,
    (partner_pose, partner_prev): (&Pose, &Pose),
    (mover_pose, mover_prev): (&Pose, &Pose),
) -> Option<RapierContact> {
    let partner_first = pair.collider1 == partner;
    let ((pos1, prev1), (pos2, prev2)) = if partner_first {
        ((partner_pose, partner_prev), (mover_pose, mover_prev))
    } else {
        ((mover_pose, mover_prev), (partner_pose, partner_prev))
    };
    let mut overlapped_at_start = false;
    let mut depth_at_start: Real = 0.0;
    let mut deepest: Option<(Real, Vector)> = None;
    for m in pair.manifolds() {
        if m.points.is_empty() {
            continue;
        }
        // The manifold's frames (a composite shape's part) at the poses now and at the start.
        let frames = |a: &Pose, b: &Pose| {
            let w1 = m.subshape_pos1().map_or(*a, |s| *a * *s);
            let w2 = m.subshape_pos2().map_or(*b, |s| *b * *s);
            (w1, w2, w1.rotation * m.local_n1)
        };
        let (w1, w2, n1) = frames(pos1, pos2);
        let (v1, v2, m1) = frames(prev1, prev2);
        for p in &m.points {
            // Signed distances along collider 1's normal.
            let before = (v2.transform_point(p.local_p2) - v1.transform_point(p.local_p1)).dot(m1);
            overlapped_at_start |= before < 0.0;
            depth_at_start = depth_at_start.max(-before);
            let now = (w2.transform_point(p.local_p2) - w1.transform_point(p.local_p1)).dot(n1);
            if deepest.is_none_or(|(best, _)| -now > best) {
                deepest = Some((-now, n1));
            }
        }
    }
    let (depth, n1) = deepest?;
    let normal = if partner_first { n1 } else { -n1 }.try_normalize()?;
    depth.is_finite().then_some(RapierContact {
        depth,
        depth_at_start,
        normal,
        overlapped_at_start,
    })
}

/// rapier's contact normal for the pair (from its deepest contact), oriented out of `fixed`
/// toward `moving`.
fn rapier_normal(
    world: &PhysicsWorld,
    fixed: ColliderHandle,
    moving: ColliderHandle,
) -> Option<Vector> {
    let pair = world.narrow_phase.contact_pair(fixed, moving)?;
    let (manifold, _) = pair.find_deepest_contact()?;
    let n = manifold.data.normal;
    let n = if pair.collider1 == fixed { n } else { -n };
    n.try_normalize()
}
