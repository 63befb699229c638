//! Dynamic tools, coupled implicitly: a dynamic body pressing a surface is a rigid holder of
//! the surface's constraint solve ([`crate::surface::RigidHolder`]), so its mass meets the
//! surface's in the same substep instead of a force handed to it a rigid step later.
//!
//! Over a rigid step, rapier moves the body first (gravity, the user's forces, its other
//! contacts, and the surfaces' support of the last step as a force: [`Fed`]). Each surface
//! then replays the step in its substeps from the body's pose and velocities at the start,
//! what rapier's step changed of them (less the support) added a substep at a time
//! ([`DynamicTool::new`]): before each substep the body is the surface's holder at
//! its current velocity, the step's solve gives it the surface's impulses, and it moves on with
//! the velocity they leave. The points it will meet in the next substep are pressed at its
//! pose then: surface vertices it holds or will reach (speculative contacts: such a point may
//! close its gap, not pass the body) and its own vertices and edges crossing the surface; where
//! the body already overlaps the surface past its slop by more than its approach over the
//! substep made, the body is moved out of that part, not the surface
//! ([`push_out::push_out_bodies`]: pressing the surface out stores energy the body never
//! paid for). At
//! the end of the rigid step the body takes the pose and velocity the surfaces left it
//! (several surfaces add what each changed). A body no surface touched keeps rapier's pose.

use super::friction::Friction;
use super::holding::{friction_on, ToolMotion};
use super::pressing::{press_all, reaction_of, PressOwner};
use super::surface_set::{AttachedSurface, ToolReaction};
use super::tool_shape::contact_margin;
use crate::geometry::solid_contacts::{triangle_contacts, vertex_contacts};
use crate::geometry::SurfaceContact;
use crate::math::{Matrix, Pose, Real, Rotation, Vector};
use crate::surface::{MassSpringSurface, RigidHolder};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::shape::Shape;
use rapier3d::dynamics::RigidBodyHandle;
use rapier3d::geometry::ColliderHandle;
use rapier3d::pipeline::PhysicsWorld;

mod fed;
mod push_out;
pub(crate) use fed::Fed;
pub(super) use push_out::push_out_bodies;

/// A dynamic tool's rigid state while the surfaces step (world frame).
#[derive(Copy, Clone, Debug)]
pub(super) struct DynamicTool {
    pub collider: ColliderHandle,
    pub body: RigidBodyHandle,
    /// The collider's pose in the body's frame.
    local: Pose,
    /// The body's pose.
    pub pose: Pose,
    /// The centre of mass in the body's frame.
    local_com: Vector,
    /// Velocity of the centre of mass, and angular velocity.
    pub linvel: Vector,
    pub angvel: Vector,
    /// Inverse mass per world axis (zero on locked axes) and world inverse inertia.
    inverse_mass: Vector,
    inverse_inertia: Matrix,
    /// What rapier's step did to its velocities besides the surfaces' support ([`Fed`]), per
    /// second (gravity, the user's forces, its other contacts and joints; gravity alone for a
    /// body asleep): the substeps add it a substep at a time ([`Self::fall`]).
    acceleration: Vector,
    angular_acceleration: Vector,
    /// Whether a surface gave it an impulse in this rigid step.
    pub touched: bool,
    /// How far it may overlap the surface without being pushed out ([`SLOP`] of its size).
    pub slop: Real,
    /// The impulses it took ([`Self::take`]) and their moments about the centre of mass.
    pub impulse: Vector,
    pub angular_impulse: Vector,
    /// Whether rapier's step had the surfaces' support on its body ([`Fed`]).
    pub supported: bool,
}

/// A dynamic tool's allowed overlap with a surface, as a fraction of its size: within it a
/// contact is held where it is, not pushed out (rapier's `allowed_linear_error` does the same
/// for rigid contacts, 1 mm by default).
pub(super) const SLOP: Real = 1e-3;

impl DynamicTool {
    /// The tool on collider `collider` if its body is dynamic: at `start` (the collider's pose
    /// before the rigid step) with its velocities then (`fed`, recorded before rapier's step),
    /// and what rapier's step changed of them, less the support `fed` to its body, as an
    /// acceleration the substeps add a substep at a time ([`Self::fall`]). Added at once,
    /// gravity knocked a body resting on a surface down at the start of every rigid step, to be
    /// pushed back up through the substeps (a millimetre's bounce at 60 Hz); and the contact of
    /// a box stacked on it struck it down by the upper box's weight times the step, the surface
    /// threw it back up, and rapier's next step carried that velocity to the box above: the
    /// pair kept a velocity of 1.4 cm/s upward at rest, and the upper box drifted off sideways.
    /// A body asleep starts from the velocity rapier left it, gravity added in the substeps
    /// (the surfaces still carry it); one with no record otherwise starts from rapier's new
    /// velocity less gravity and the support.
    pub fn new(
        world: &PhysicsWorld,
        collider: ColliderHandle,
        start: Pose,
        fed: &[Fed],
    ) -> Option<Self> {
        let c = world.colliders.get(collider)?;
        let body = c.parent()?;
        let b = world.bodies.get(body)?;
        if !b.is_dynamic() {
            return None;
        }
        let local = *c.position_wrt_parent()?;
        let m = b.mass_properties();
        let w = &m.effective_world_inv_inertia;
        let inverse_inertia = Matrix::from_cols(
            Vector::new(w.m11, w.m12, w.m13),
            Vector::new(w.m12, w.m22, w.m23),
            Vector::new(w.m13, w.m23, w.m33),
        );
        let gravity = world.gravity * b.gravity_scale();
        let dt = world.integration_parameters.dt;
        let (force, torque) = fed
            .iter()
            .filter(|f| f.body == body)
            .fold((Vector::ZERO, Vector::ZERO), |(f, t), fed| {
                (f + fed.force, t + fed.torque)
            });
        let support = (m.effective_inv_mass * force, inverse_inertia * torque);
        let before = fed.iter().find(|f| f.body == body);
        let (linvel, angvel, acceleration, angular_acceleration) = match before {
            Some(f) if dt > 0.0 && !b.is_sleeping() => {
                let (v0, w0) = f.start_velocities(&world.integration_parameters, b.angvel());
                (
                    v0,
                    w0,
                    (b.linvel() - v0) / dt - support.0,
                    (b.angvel() - w0) / dt - support.1,
                )
            }
            // Asleep, rapier left it where it was; the surfaces still carry its weight (with
            // none, a ball asleep on a plate let the plate rise, and it carried 97 % of it).
            _ if b.is_sleeping() => (b.linvel(), b.angvel(), gravity, Vector::ZERO),
            _ => (
                b.linvel() - (gravity + support.0) * dt,
                b.angvel() - support.1 * dt,
                gravity,
                Vector::ZERO,
            ),
        };
        let tool = DynamicTool {
            collider,
            body,
            local,
            pose: start * local.inverse(),
            local_com: m.local_mprops.local_com,
            linvel,
            angvel,
            inverse_mass: m.effective_inv_mass,
            inverse_inertia,
            acceleration,
            angular_acceleration,
            touched: false,
            slop: SLOP * c.compute_aabb().extents().max_element(),
            impulse: Vector::ZERO,
            angular_impulse: Vector::ZERO,
            supported: force != Vector::ZERO || torque != Vector::ZERO,
        };
        let finite = [tool.linvel, tool.angvel, acceleration, angular_acceleration]
            .iter()
            .all(|v| v.is_finite());
        (tool.pose.is_finite() && finite).then_some(tool)
    }

    /// The velocities rapier's step adds over `h` seconds of it ([`Self::new`]).
    pub fn fall(&mut self, h: Real) {
        self.linvel += self.acceleration * h;
        self.angvel += self.angular_acceleration * h;
    }

    /// Free motion over `n` substeps of `h`: falling and moving on.
    pub fn free(&self, h: Real, n: u32) -> Self {
        let mut t = *self;
        for _ in 0..n {
            t.fall(h);
            t.advance(h);
        }
        t
    }

    /// The collider's pose.
    pub fn collider_pose(&self) -> Pose {
        self.pose * self.local
    }

    /// The collider's pose after `h` seconds of free motion (falling).
    pub fn predicted(&self, h: Real) -> Pose {
        self.free(h, 1).collider_pose()
    }

    /// Moves the body on by `h` seconds at its velocity (about its centre of mass).
    pub fn advance(&mut self, h: Real) {
        self.displace(self.linvel * h, self.angvel * h);
    }

    /// Moves the centre of mass by `shift` and turns the body about it by `turn` (a scaled
    /// axis); `false`, with the pose unchanged, where the new pose is not finite.
    pub fn displace(&mut self, shift: Vector, turn: Vector) -> bool {
        let com = self.pose.transform_point(self.local_com);
        let turn = Rotation::from_scaled_axis(turn);
        let rotation = (turn * self.pose.rotation).normalize();
        let next = Pose::from_parts(com + shift - rotation * self.local_com, rotation);
        if next.is_finite() {
            self.pose = next;
        }
        next.is_finite()
    }

    /// The body as the surface's holder, in the surface's frame (`to_surface`: world to
    /// surface).
    pub fn holder(&self, to_surface: &Pose) -> RigidHolder {
        let r = Matrix::from_quat(to_surface.rotation);
        RigidHolder {
            inverse_mass: r * Matrix::from_diagonal(self.inverse_mass) * r.transpose(),
            inverse_inertia: r * self.inverse_inertia * r.transpose(),
            centre: to_surface.transform_point(self.pose.transform_point(self.local_com)),
            velocity: to_surface.rotation * self.linvel,
            angular_velocity: to_surface.rotation * self.angvel,
        }
    }

    /// Takes an impulse and its moment about the centre of mass (world).
    pub fn take(&mut self, impulse: Vector, angular: Vector) {
        if !(impulse.is_finite() && angular.is_finite()) {
            return;
        }
        if impulse != Vector::ZERO || angular != Vector::ZERO {
            self.touched = true;
        }
        self.impulse += impulse;
        self.angular_impulse += angular;
        self.linvel += self.inverse_mass * impulse;
        self.angvel += self.inverse_inertia * angular;
    }

    /// The support to hand rapier's next step ([`Fed`]) after a surface's replay of `dt`
    /// seconds: the share of the impulses the body took that held it against what else moved
    /// it (gravity, the user's forces, its other contacts: [`Self::fall`]), not the share that
    /// changed its own motion. A body resting under a stack gets its whole impulse back as a
    /// force; one the surface stopped (a landing, a spin) none of what stopped it. Fed back
    /// whole, a box tumbling onto the plate had the impulse that stopped its spin handed to
    /// rapier again as a torque and spun the other way at 290 rad/s; a column of four 12 g
    /// boxes on a stiff plate went from 0.32 J to 63 J, and in one of four 16 g boxes those
    /// above the lowest never came to rest, where vanilla rapier's column on rigid ground does
    /// (`tests/it/dropped_columns.rs`). The share is the part of the impulse's change of
    /// velocity that the other loads took back, between none and all of it (linear and
    /// angular apart).
    pub fn support(&self, dt: Real) -> (Vector, Vector) {
        if dt <= 0.0 {
            return (Vector::ZERO, Vector::ZERO);
        }
        let share = |change: Vector, load: Vector| {
            let size = change.length_squared();
            if size > 0.0 {
                (-load.dot(change) * dt / size).clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        let linear = share(self.inverse_mass * self.impulse, self.acceleration);
        let angular = share(
            self.inverse_inertia * self.angular_impulse,
            self.angular_acceleration,
        );
        (
            self.impulse * (linear / dt),
            self.angular_impulse * (angular / dt),
        )
    }

    /// The centre of mass (world).
    pub fn centre(&self) -> Vector {
        self.pose.transform_point(self.local_com)
    }
}

/// What one or more surfaces changed of a dynamic tool's motion over a rigid step: against
/// the same substeps of free motion, its velocities, its centre's position and its rotation;
/// and that free motion's end, of the first surface that touched it.
#[derive(Copy, Clone, Debug, Default)]
pub(super) struct MotionChange {
    free: Option<DynamicTool>,
    linvel: Vector,
    angvel: Vector,
    translation: Vector,
    rotation: Rotation,
}

impl MotionChange {
    /// Adds what a surface left of `start` after `n` substeps of `h` (`end`).
    pub fn add(&mut self, start: &DynamicTool, end: &DynamicTool, h: Real, n: u32) {
        let free = start.free(h, n);
        self.free.get_or_insert(free);
        self.linvel += end.linvel - free.linvel;
        self.angvel += end.angvel - free.angvel;
        self.translation += end.centre() - free.centre();
        self.rotation = (end.pose.rotation * free.pose.rotation.inverse()) * self.rotation;
    }

    /// The body's pose, velocity and angular velocity with the changes, or `None` when no
    /// surface touched it. From its free motion at rapier's new velocity, not from rapier's
    /// pose: that moved by the velocities of rapier's solver substeps, which gravity changed
    /// (a body resting on a surface gained 3/8 g dt² a step against the free motion the
    /// surfaces replayed, 1 mm at 60 Hz).
    pub fn motion(&self) -> Option<(Pose, Vector, Vector)> {
        let free = self.free?;
        let com = free.centre() + self.translation;
        let rotation = (self.rotation * free.pose.rotation).normalize();
        Some((
            Pose::from_parts(com - rotation * free.local_com, rotation),
            free.linvel + self.linvel,
            free.angvel + self.angvel,
        ))
    }
}

/// Makes the dynamic tools the surface's rigid holders (index: place in `dynamic`), in the
/// surface's frame (`to_surface`), at their velocities after `fall` seconds of gravity.
pub(super) fn set_holders(
    surface: &mut MassSpringSurface,
    dynamic: &[DynamicTool],
    to_surface: &Pose,
    fall: Real,
) {
    let holders: Vec<RigidHolder> = dynamic
        .iter()
        .map(|d| {
            let mut next = *d;
            next.fall(fall);
            next.holder(to_surface)
        })
        .collect();
    // Checked on the way in: finite poses and velocities, rapier's mass properties.
    let _ = surface.set_holders(&holders);
}

/// After a surface step of `h`: each dynamic tool takes the surface's impulses (surface frame,
/// the surface's body at `body_pose`) and moves on by the substep with what they leave; its
/// motion in `tools` becomes the next substep's, free; and the surface's holders become the
/// tools over that substep, for the presses to come. Those are relative to the holders'
/// velocities then (having fallen for a substep: the contacts' velocities are those of the
/// same free motion; against the velocity now, a resting body floated a substep's fall above
/// its contacts).
pub(super) fn move_on(
    surface: &mut MassSpringSurface,
    dynamic: &mut [DynamicTool],
    tools: &mut [ToolMotion],
    body_pose: &Pose,
    h: Real,
) {
    for (j, d) in dynamic.iter_mut().enumerate() {
        if let Some((impulse, angular)) = surface.holder_impulse(j) {
            d.take(body_pose.rotation * impulse, body_pose.rotation * angular);
        }
        d.advance(h);
        for t in tools.iter_mut().filter(|t| t.holder == Some(j)) {
            t.start = d.collider_pose();
            t.end = d.predicted(h);
        }
    }
    if !dynamic.is_empty() {
        set_holders(surface, dynamic, &body_pose.inverse(), h);
    }
}

/// Dynamic tool `t` (the substep's tool `k`, holder `j`; its query `shape`, the box of its
/// sharp features' reach `parts` and its `friction`) against surface `s`: the surface
/// vertices and triangle points it holds or may reach over the next substep, at its pose now
/// ([`crate::geometry::solid_contacts`]), appended to `out` (contacts, the tool's velocities
/// there, owners). Returns its reaction from the points it pressed in the step just taken.
#[allow(clippy::too_many_arguments)]
pub(super) fn press_dynamic(
    s: &mut AttachedSurface,
    (t, k, j): (&ToolMotion, usize, usize),
    (shape, parts, friction): (&dyn Shape, Option<Aabb>, Friction),
    dynamic: &[DynamicTool],
    body_pose: &Pose,
    h: Real,
    (contacts, velocities, owners): (
        &mut Vec<SurfaceContact>,
        &mut Vec<Vector>,
        &mut Vec<PressOwner>,
    ),
) -> ToolReaction {
    let inv = body_pose.inverse();
    let (start, end) = (inv * t.start, inv * t.end);
    let aabb = shape.compute_aabb(&start).merged(&shape.compute_aabb(&end));
    let margin = contact_margin(&aabb, 1e-4);
    // The box over its motion holds what it may reach (a vertex fast enough to come from
    // farther is pressed out when it is in).
    let near = aabb.loosened(2.0 * margin);
    s.search
        .near(k, t.handle, &parts.map_or(near, |p| p.merged(&near)));
    let material = |q: Vector| {
        let local = start.inverse_transform_point(q);
        (end.transform_point(local) - q) / h
    };
    let surface = &s.surface;
    let first = contacts.len();
    vertex_contacts(
        shape,
        &start,
        material,
        h,
        (&s.search.vertices, &s.scratch, |i| surface.velocity(i)),
        margin,
        contacts,
        velocities,
    );
    let depths: Vec<(u32, Real)> = contacts[first..]
        .iter()
        .map(|c| (c.surface[0].0, c.depth))
        .collect();
    let vertex_depth = |v: u32| depths.iter().find(|d| d.0 == v).map(|d| d.1);
    triangle_contacts(
        shape,
        &start,
        material,
        h,
        (
            surface.triangles(),
            s.search.triangles_of_tool(k),
            &s.scratch,
            |i| surface.velocity(i),
        ),
        vertex_depth,
        (margin, dynamic.get(j).map_or(margin, |d| d.slop)),
        t.shape.unit.as_ref().map(|(k, u)| (*k, u.as_ref())),
        contacts,
        velocities,
    );
    owners.resize(contacts.len(), t.owner(friction));
    let (pf, pm, pn) = reaction_of(&s.last_pressed, t.handle, h);
    let force = body_pose.rotation * pf;
    let centre = dynamic.get(j).map_or(t.end.translation, |d| d.centre());
    ToolReaction {
        force,
        // About the centre of mass: Σ (p - c) × f, in world.
        torque: body_pose.rotation * pm - (centre - body_pose.translation).cross(force),
        mean_force: force,
        held_vertices: 0,
        sticking_vertices: 0,
        pressed_points: pn,
    }
}

/// Before a rigid step's first substep (`h` long): each dynamic tool presses what it may meet
/// over that substep at the velocity rapier gave it. The presses the last substep made were
/// chosen for the tool's motion then: a body that starts at rest, or that rapier sped up,
/// could cross a thin surface in the first substep with nothing pressed (a 0.08 mm ball
/// dropped 0.3 mm onto a 1 mm plate fell through at one substep per rigid step). Presses
/// that repeat those already there are left out by the solve.
pub(super) fn press_ahead(
    s: &mut AttachedSurface,
    world: &PhysicsWorld,
    body_pose: &Pose,
    (tools, dynamic): (&[ToolMotion], &[DynamicTool]),
    h: Real,
) {
    if dynamic.is_empty() {
        return;
    }
    let inv = body_pose.inverse();
    set_holders(&mut s.surface, dynamic, &inv, 0.0);
    s.surface.positions_into(&mut s.scratch);
    s.search.refresh(&mut s.surface, &s.scratch, &s.scratch);
    // Their motion over the substep at their velocities now (this substep's gravity is in
    // them already).
    let tools: Vec<ToolMotion> = tools
        .iter()
        .map(|t| match t.holder.and_then(|j| dynamic.get(j)) {
            Some(d) => {
                let mut next = *d;
                next.advance(h);
                ToolMotion {
                    start: d.collider_pose(),
                    end: next.collider_pose(),
                    shape: t.shape.clone(),
                    ..*t
                }
            }
            None => t.clone(),
        })
        .collect();
    let (mut contacts, mut velocities, mut owners, mut kept) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (k, t) in tools.iter().enumerate() {
        let (Some(j), Some(collider)) = (t.holder, world.colliders.get(t.handle)) else {
            continue;
        };
        let shape = t.shape.query.as_deref().unwrap_or(collider.shape());
        let friction = friction_on(s, t);
        let parts = t.parts_reach(&inv);
        press_dynamic(
            s,
            (t, k, j),
            (shape, parts, friction),
            dynamic,
            body_pose,
            h,
            (&mut contacts, &mut velocities, &mut owners),
        );
        t.feature_contacts(
            &inv,
            h,
            (
                s.surface.triangles(),
                s.search.triangles_of_tool(k),
                &mut kept,
                // No rings: a dynamic tool's smooth normals stay summed over its candidates
                // (summed over the rings, a heavy U at rest on a soft plate at one substep
                // was kicked about at 1.2 cm/s).
                &|_, _| {},
            ),
            (&s.scratch, &s.scratch),
            &mut contacts,
            &mut velocities,
        );
        owners.resize(contacts.len(), t.owner(friction));
    }
    if contacts.is_empty() {
        return;
    }
    within_slop(&mut contacts, &owners, dynamic);
    press_all(
        &mut s.surface,
        &contacts,
        &velocities,
        &owners,
        &mut s.pressed,
    );
}

/// A dynamic tool's contacts found at its pose after a substep of free motion (its material
/// points' velocities `velocities`), at their depths now: that motion taken off (negative, a
/// speculative contact).
pub(super) fn depths_now(contacts: &mut [SurfaceContact], velocities: &[Vector], h: Real) {
    for (c, v) in contacts.iter_mut().zip(velocities) {
        c.depth -= h * v.dot(c.normal);
    }
}

/// A dynamic tool's contacts that overlap by less than its slop are pressed as touching, the
/// rest by what passes the slop: moving a vertex that carries a load out by `d` does work
/// `F d` the body never paid for (a ball resting on the edges round a vertex overlapped them by
/// 20 µm at every substep, and the energy that added kept it sliding about the dent).
pub(super) fn within_slop(
    contacts: &mut [SurfaceContact],
    owners: &[PressOwner],
    dynamic: &[DynamicTool],
) {
    for (c, o) in contacts.iter_mut().zip(owners) {
        if let Some(d) = o.holder.and_then(|j| dynamic.get(j)) {
            if c.depth > 0.0 {
                c.depth = (c.depth - d.slop).max(0.0);
            }
        }
    }
}
