//! The world's side of haptic links ([`crate::haptics`]): each linked tool is moved to its
//! servo loop's proxy before the rigid step, and after the surfaces' step the set publishes the
//! tool's local contact model.

use super::holding::attached_with_pose;
use super::surface_set::AttachedSurface;
use super::surface_set::{CouplingError, SurfaceSet};
use crate::geometry::tool_boundary::outward_normal_toward;
use crate::haptics::{
    is_smooth, normal_at, outer, positive_part, HeldVertex, PatchVertex, ServoModel, WorldLink,
    MAX_PATCH,
};
use crate::math::{Matrix, Pose, Real, Vector};
use parry3d::bounding_volume::Aabb;
use rapier3d::dynamics::RigidBodySet;
use rapier3d::geometry::{ColliderHandle, ColliderSet, SharedShape};
use rapier3d::pipeline::PhysicsWorld;

/// A first touch is rendered with this share of the touched vertex's spring stiffness (the sum
/// over its edges, what it resists with while its neighbours have not moved yet): the static
/// stiffness of one vertex of a membrane with free neighbours is a fraction of it. The next
/// world update replaces the estimate with the full solution and its secant.
const FIRST_TOUCH_SHARE: Real = 0.5;

/// One linked tool on the world's side.
#[derive(Debug)]
pub(super) struct LinkState {
    link: WorldLink,
    /// The vertices and points the tool held at the last update.
    held: usize,
    /// The last model published (its force and pose for the secant, its patch for a first
    /// touch).
    last: ServoModel,
}

impl SurfaceSet {
    /// Links `tool` to a servo loop (the servo end of `link` drives it, see
    /// [`crate::haptics`]): before each [`SurfaceSet::step`] the tool moves to the servo
    /// loop's latest proxy (`set_next_kinematic_position` for a kinematic body, the collider's
    /// pose for a collider with no body), and after it the set publishes the tool's
    /// [`ServoModel`]. The tool is registered ([`SurfaceSet::add_tool`]) if it was not. A tool
    /// linked again drops its old link (whose servo loop then renders nothing).
    ///
    /// The model's stiffness is the secant of the full solution between world updates (a
    /// symmetric Broyden update along the tool's motion, negative curvature dropped, split into
    /// normal and tangent parts, the normal one at least half the last: see
    /// `normal_and_tangent`): what the next update will report, within the surface's own
    /// relaxation between updates. The model's force is the full solution less what the held
    /// vertices' dampers put on the tool's last move (`damper_share`). The
    /// filter's columns at the contact vertices, which the constraint solve uses, give the
    /// surface's response within one substep, dominated by the vertices' inertia (ten times
    /// stiffer than the next world update on the crate's scenes) and are not used for it.
    ///
    /// # Errors
    /// [`CouplingError::NoSuchCollider`], [`CouplingError::ZeroSizeTool`] as
    /// [`SurfaceSet::add_tool`]; [`CouplingError::DynamicHapticTool`] for a tool on a dynamic
    /// body (its motion is rapier's, not the device's). Nothing changes then.
    pub fn connect_haptic(
        &mut self,
        tool: ColliderHandle,
        link: WorldLink,
        world: &mut PhysicsWorld,
    ) -> Result<(), CouplingError> {
        let c = world
            .colliders
            .get(tool)
            .ok_or(CouplingError::NoSuchCollider)?;
        if c.parent()
            .and_then(|b| world.bodies.get(b))
            .is_some_and(|b| b.is_dynamic())
        {
            return Err(CouplingError::DynamicHapticTool);
        }
        self.add_tool(tool, world)?;
        self.links.insert(
            tool,
            LinkState {
                link,
                held: 0,
                last: ServoModel::default(),
            },
        );
        Ok(())
    }

    /// Unlinks `tool` and gives its world end back (the tool stays a tool, where its last
    /// proxy put it).
    pub fn disconnect_haptic(&mut self, tool: ColliderHandle) -> Option<WorldLink> {
        self.links.remove(&tool).map(|s| s.link)
    }

    /// The model last published for `tool` (`None` for a tool not linked).
    pub fn haptic_model(&self, tool: ColliderHandle) -> Option<&ServoModel> {
        self.links.get(&tool).map(|s| &s.last)
    }

    /// Whether `tool` is linked to a servo loop.
    pub fn is_haptic(&self, tool: ColliderHandle) -> bool {
        self.links.contains_key(&tool)
    }

    /// Moves each linked tool to its servo loop's latest proxy (after the start poses are
    /// recorded, so the surfaces sweep the motion).
    pub(crate) fn drive_haptic_tools(
        &mut self,
        bodies: &mut RigidBodySet,
        colliders: &mut ColliderSet,
    ) {
        self.links.retain(|h, _| colliders.contains(*h));
        for (h, state) in self.links.iter_mut() {
            let sample = state.link.device();
            if sample.tick == 0 || !sample.proxy.is_finite() {
                continue;
            }
            let Some(c) = colliders.get_mut(*h) else {
                continue;
            };
            match c.parent() {
                Some(b) => {
                    if let Some(body) = bodies.get_mut(b) {
                        if body.is_kinematic() {
                            let to_body = c.position_wrt_parent().copied();
                            let pose = to_body.map_or(sample.proxy, |p| sample.proxy * p.inverse());
                            body.set_next_kinematic_position(pose);
                        }
                    }
                }
                None => c.set_position(sample.proxy),
            }
        }
    }

    /// Publishes each linked tool's model from the step just taken.
    pub(crate) fn publish_haptic_models(&mut self, world: &PhysicsWorld) {
        let handles: Vec<ColliderHandle> = self.links.keys().copied().collect();
        for h in handles {
            let Some(c) = world.colliders.get(h) else {
                continue;
            };
            let pose = *c.position();
            let shape = c.shared_shape().clone();
            let (force, grasping, held) =
                self.tools.get(&h).map_or((Vector::ZERO, false, 0), |t| {
                    let r = &t.reaction;
                    (r.force, t.grasp, r.held_vertices + r.pressed_points)
                });
            let force = if force.is_finite() {
                force
            } else {
                Vector::ZERO
            };
            let Some(state) = self.links.get(&h) else {
                continue;
            };
            let touched = if force != Vector::ZERO && !state.last.in_contact() {
                touched_stiffness(self, world, &shape, &pose)
            } else {
                0.0
            };
            let Some(state) = self.links.get(&h) else {
                continue;
            };
            // A change of the held set is a jump of the solution, not a stiffness: the last
            // stiffness carries over it.
            let stiffness =
                if held != state.held && state.last.in_contact() && force != Vector::ZERO {
                    state.last.stiffness
                } else {
                    secant(&state.last, &pose, force, &shape, touched)
                };
            let stiffness = normal_and_tangent(&state.last, force, stiffness);
            // The model's force: what the surfaces push with if the tool stays where it is,
            // the full solution less what its held vertices' dampers put on its last move.
            let resting = if force == Vector::ZERO {
                force
            } else {
                let f = force - damper_share(self, world, &shape, &pose);
                if f.is_finite() && f.dot(force) > 0.0 {
                    f
                } else {
                    // The dampers carry all of it: a contact that lets go if the tool stops.
                    force * DAMPED_OUT
                }
            };
            // A smooth tool's held vertices, each with its share of the normal stiffness.
            let held_vertices = match self.tools.get(&h) {
                Some(t)
                    if force != Vector::ZERO
                        && is_smooth(shape.as_ref())
                        && t.held.len() <= MAX_ANCHORED =>
                {
                    held_vertices(&t.held, shape.as_ref(), &pose, &stiffness)
                }
                _ => Vec::new(),
            };
            let patch = if force == Vector::ZERO {
                patch_near(self, world, &shape, &pose)
            } else if held_vertices.is_empty() {
                Vec::new()
            } else {
                capture_patch(
                    patch_near(self, world, &shape, &pose),
                    &held_vertices,
                    &shape,
                    &pose,
                )
            };
            let model = ServoModel {
                sequence: 0,
                tool_pose: pose,
                force: resting,
                stiffness,
                grasping,
                shape: Some(shape),
                patch,
                held: held_vertices,
                attached: true,
            };
            if let Some(state) = self.links.get_mut(&h) {
                state.held = held;
                state.link.publish(model.clone());
                state.last = model;
                state.last.sequence = state.link.sequence();
            }
        }
    }
}

/// The share of the full solution left in the model where the held vertices' dampers carry
/// all of it (the contact stays a contact, with next to no force if the tool stays).
const DAMPED_OUT: Real = 1e-3;

/// The part of the full solution's force on a tool at `pose` that its held vertices' dampers
/// put on it (world, N): `Σ c (v_j - v_i)` over the edges from the held vertices in its
/// bounding box (grown by a thousandth of its size) to vertices not held, with the last
/// step's velocities. A sharp tool's pressed points (a corner in a triangle) are left out.
///
/// It goes at the next update if the tool stops: a held vertex stops with the tool, and the
/// free ones round it, which the held ones dragged through their dampers, slow down with them.
/// A surface's implicit step meets a tool's move with its springs and, over the step, its
/// dampers; on the 100,000-node sphere of `examples/haptic_thread.rs` (edges of 100 N/m and
/// 1 N·s/m, one substep at 60 Hz) the dampers gave most of a moving press's force. The model
/// used to keep that force as if it stayed: the servo moved the proxy out, the world's next
/// update then read the force without it and the proxy went back in, and with the world
/// stepping every 60 ms the full solution swung by half its size from one update to the
/// next, the simulated hand with it (see the README's haptics section for the numbers).
fn damper_share(
    set: &mut SurfaceSet,
    world: &PhysicsWorld,
    shape: &SharedShape,
    pose: &Pose,
) -> Vector {
    let (lo, hi) = touch_box(shape, pose);
    let mut share = Vector::ZERO;
    for (_, s, body) in attached_with_pose(&mut set.entries, world) {
        let surface = &s.surface;
        for &i in surface.held_list() {
            let p = body * surface.position(i);
            if p.cmpge(lo).all() && p.cmple(hi).all() {
                share += body.rotation * surface.held_damper_force(i);
            }
        }
    }
    share
}

/// The corners (world) of the bounding box of `shape` at `pose` grown by a thousandth of its
/// size: where the vertices it touches lie.
fn touch_box(shape: &SharedShape, pose: &Pose) -> (Vector, Vector) {
    let aabb = shape.compute_aabb(pose);
    let size = shape.compute_local_aabb().half_extents().max_element();
    let margin = Vector::splat(1e-3 * size);
    (aabb.mins - margin, aabb.maxs + margin)
}

/// The model's stiffness from the secant's `stiffness`, split along the contact's force: the
/// normal stiffness (along the force) and the tangent block, with no coupling between the two,
/// and the normal stiffness at least half of the last model's.
///
/// Why: a secant fitted to updates that move the tool mostly along the normal picks up
/// couplings from noise (a held vertex captured, the surface's creep). On the 100,000-node
/// sphere such a coupling, 7,000 N/m against a normal stiffness of 16,600, sent the proxy
/// sideways as the hand lifted off and the model's force grew from 0.1 N to 9 N within 30
/// ticks. And one update whose force fell while the tool pressed on (a vertex let go) took
/// the normal stiffness to zero: the model then pushed the hand out with a constant force
/// until the passivity controller held the proxy, and the rendered force fell by a tenth of
/// its peak per tick. Halving at most per update, the stiffness still follows a contact that
/// softens over a few updates.
fn normal_and_tangent(last: &ServoModel, force: Vector, stiffness: Matrix) -> Matrix {
    if force == Vector::ZERO {
        return stiffness;
    }
    let n = force.normalize();
    let mut normal = n.dot(stiffness * n);
    if last.in_contact() {
        let m = last.force.normalize_or_zero();
        normal = normal.max(MOST_SOFTENING * m.dot(last.stiffness * m));
    }
    let across = Matrix::IDENTITY - outer(n, n);
    let split = outer(n, n) * normal.max(0.0) + across * stiffness * across;
    if split.is_finite() {
        split
    } else {
        stiffness
    }
}

/// The least share of the last model's normal stiffness a new model keeps
/// ([`normal_and_tangent`]).
const MOST_SOFTENING: Real = 0.5;

/// The contact's stiffness for the new model: zero out of contact; at a first touch, the last
/// model's patch stiffness scaled to the force found (or, when the patch saw a much weaker or
/// no touch there, the touched vertices' first-touch stiffness along the force); in contact,
/// the last stiffness updated along the motion to agree with the change of force (symmetric,
/// negative curvature dropped).
fn secant(
    last: &ServoModel,
    pose: &Pose,
    force: Vector,
    shape: &SharedShape,
    touched: Real,
) -> Matrix {
    if force == Vector::ZERO {
        return Matrix::ZERO;
    }
    let x = pose.translation;
    if !last.in_contact() {
        let (predicted, k) = last.force_and_stiffness_at(x);
        let scale = force.length() / predicted.length();
        if scale.is_finite() && (0.2..=5.0).contains(&scale) {
            return k * scale;
        }
        let n = force.normalize();
        return outer(n, n) * touched;
    }
    let s = x - last.tool_pose.translation;
    let size = shape.compute_local_aabb().half_extents().max_element();
    if s.length() <= (1e-3 * size).max(1e-7) {
        return last.stiffness;
    }
    // K s should be the drop of force along s that the turning normals do not account for:
    // y = f_last + turning - f.
    let y = last.force + last.turning(x) - force;
    let k = last.stiffness;
    let r = y - k * s;
    let ss = s.dot(s);
    // The symmetric rank-two update closest to K with K s = y (Powell-symmetric Broyden).
    let updated = k + (outer(r, s) + outer(s, r)) / ss - outer(s, s) * (r.dot(s) / (ss * ss));
    let psd = positive_part(&updated);
    if updated.is_finite() {
        psd
    } else {
        k
    }
}

/// The most vertices a smooth tool may hold for the servo model to anchor them
/// ([`HeldVertex`]): a contact of a few vertices (a tool on a coarse mesh) is discrete, and
/// how its normals turn as the tool moves is most of how its force changes; a contact of many
/// is a patch whose force changes smoothly, and the linear secant alone follows it. Anchoring
/// every vertex of the 99,848-node sphere's contact (`examples/haptic_thread.rs`) made the
/// servo's force jump by 4.6-27.6 % of the peak between ticks in two of four runs (their
/// normals' turning pushes the ball on, which the contact's spread of loads holds back); with
/// this limit it jumped by 2.0-2.7 % in five (2.7 % before the anchors).
const MAX_ANCHORED: usize = 4;

/// The vertices a smooth tool at `pose` holds (`held`: each one's position and force on the
/// tool), as the servo model reads them: the tool's normal at each, its normal load, its
/// share of the contact's normal stiffness (by load, from `stiffness` along its normal) and
/// its anchor's depth. A vertex whose anchor would not come back to it at `pose` (deeper than
/// the tool is round there) keeps its load and only turns.
fn held_vertices(
    held: &[(Vector, Vector)],
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    stiffness: &Matrix,
) -> Vec<HeldVertex> {
    let mut out: Vec<HeldVertex> = held
        .iter()
        .filter_map(|&(position, f)| {
            // A held vertex lies on the tool's boundary: its normal is the shape's there (on
            // an edge or a corner, the face it pushes against, as the surface's holds take).
            let normal = normal_at(shape, pose, position).or_else(|| {
                let local = pose.inverse_transform_point(position);
                let push = pose.rotation.inverse() * -f;
                let n = pose.rotation * outward_normal_toward(shape, local, 0.0, push);
                n.is_finite().then_some(n)
            })?;
            let load = -f.dot(normal);
            (load > 0.0 && load.is_finite()).then_some(HeldVertex {
                position,
                load,
                normal,
                stiffness: 0.0,
                depth: 0.0,
            })
        })
        .collect();
    let total: Real = out.iter().map(|v| v.load).sum();
    let half = shape.compute_local_aabb().half_extents();
    let deepest = 0.25 * half.min_element();
    for v in &mut out {
        let s = v.load / total * v.normal.dot(*stiffness * v.normal);
        if !(s > 0.0 && s.is_finite()) {
            continue;
        }
        let depth = (v.load / s).min(deepest);
        let anchor = v.position - v.normal * depth;
        let back = shape.project_point(pose, anchor, false).point;
        if (back - v.position).length() <= 1e-3 * half.max_element() {
            v.stiffness = s;
            v.depth = depth;
        }
    }
    out
}

/// The vertices a smooth tool that holds a few (`held`) may capture before the next world
/// update: `patch` less the held ones, each resisting with the mean of the held vertices'
/// stiffness shares (the contact's own secant, read where the tool already presses; the
/// first-touch estimate where no held vertex has one). Without them a capsule dragged over a
/// coarse stiff plate met the next vertex only at the world update: the force jumped by up to
/// 2.3 N of a 5 N press, the proxy was thrown back, let the vertex go and came on again.
fn capture_patch(
    mut patch: Vec<PatchVertex>,
    held: &[HeldVertex],
    shape: &SharedShape,
    pose: &Pose,
) -> Vec<PatchVertex> {
    let size = shape.compute_local_aabb().half_extents().max_element();
    patch.retain(|p| {
        held.iter()
            .all(|h| (h.position - p.position).length() > 1e-4 * size)
    });
    // The nearest few: the servo scans them at every evaluation of its proxy search (every
    // vertex within a tool size of a ball on the 100,000-node sphere, scanned there, took the
    // tick's p99 from 50 to 180 µs).
    keep_nearest(&mut patch, pose.translation, MAX_CAPTURE);
    let shares = held.iter().map(|h| h.stiffness).filter(|k| *k > 0.0);
    let (sum, count) = shares.fold((0.0, 0), |(s, n), k| (s + k, n + 1));
    if count > 0 {
        let mean = sum / count as Real;
        for p in &mut patch {
            p.stiffness = mean;
        }
    }
    patch
}

/// Most free vertices a smooth tool in contact carries in its model ([`capture_patch`]).
const MAX_CAPTURE: usize = 16;

/// The largest first-touch stiffness of the surface vertices on or in the tool at `pose` (those
/// it holds): one contact point, as in [`ServoModel`]'s first touch.
fn touched_stiffness(
    set: &mut SurfaceSet,
    world: &PhysicsWorld,
    shape: &SharedShape,
    pose: &Pose,
) -> Real {
    let size = shape.compute_local_aabb().half_extents().max_element();
    let (lo, hi) = touch_box(shape, pose);
    let mut k = 0.0;
    let mut near = Vec::new();
    for (_, s, body) in attached_with_pose(&mut set.entries, world) {
        candidates(s, &body, lo, hi, &mut near);
        let surface = &s.surface;
        for &i in &near {
            let p = body * surface.position(i);
            if p.cmpge(lo).all()
                && p.cmple(hi).all()
                && shape.distance_to_point(pose, p, true) <= 1e-3 * size
            {
                k = Real::max(k, FIRST_TOUCH_SHARE * surface.vertex_stiffness(i));
            }
        }
    }
    k
}

/// The surface vertices within one tool size of the tool's bounding box (world), each with its
/// first-touch stiffness, nearest first when there are too many.
fn patch_near(
    set: &mut SurfaceSet,
    world: &PhysicsWorld,
    shape: &SharedShape,
    pose: &Pose,
) -> Vec<PatchVertex> {
    let aabb = shape.compute_aabb(pose);
    let reach = shape.compute_local_aabb().half_extents().max_element();
    let (lo, hi) = (
        aabb.mins - Vector::splat(reach),
        aabb.maxs + Vector::splat(reach),
    );
    let mut patch = Vec::new();
    let mut near = Vec::new();
    for (_, s, body) in attached_with_pose(&mut set.entries, world) {
        candidates(s, &body, lo, hi, &mut near);
        let surface = &s.surface;
        for &i in &near {
            let p = body * surface.position(i);
            if p.cmpge(lo).all() && p.cmple(hi).all() && !surface.is_pinned(i) {
                patch.push(PatchVertex {
                    position: p,
                    stiffness: FIRST_TOUCH_SHARE * surface.vertex_stiffness(i),
                });
            }
        }
    }
    keep_nearest(&mut patch, pose.translation, MAX_PATCH);
    patch
}

/// Keeps the `n` vertices of `patch` nearest `c` (all of them when there are no more).
fn keep_nearest(patch: &mut Vec<PatchVertex>, c: Vector, n: usize) {
    if patch.len() > n {
        patch.select_nth_unstable_by(n, |a, b| {
            (a.position - c)
                .length_squared()
                .total_cmp(&(b.position - c).length_squared())
        });
        patch.truncate(n);
    }
}

/// The vertices of `s` that may lie in the world box `lo..hi` (its body at `body`): from the
/// surface's contact-search BVH (the box taken into the body's frame), so that publishing a
/// model costs the tool's neighbourhood, not the mesh; every vertex while the surface has no
/// BVH yet (no tool has searched it).
fn candidates(s: &mut AttachedSurface, body: &Pose, lo: Vector, hi: Vector, out: &mut Vec<u32>) {
    let local = Aabb::new(lo, hi).transform_by(&body.inverse());
    if !s.search.vertices_in(&local, out) {
        out.clear();
        out.extend(0..s.surface.num_vertices() as u32);
    }
}
