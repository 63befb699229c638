//! How rigid tools hold the vertices of a surface in one surface substep: the surface steps,
//! then every vertex inside a tool is walked back along its inverse trajectory relative to the
//! tool to the tool's boundary and held there (a moving pin inside the filter), and each tool
//! gets the reaction of the vertices it holds.

use super::dynamic_tools::{
    depths_now, move_on, press_dynamic, set_holders, within_slop, DynamicTool,
};
use super::friction::{settle, Contact, Friction, Settled, Sticks};
use super::pressing::{
    add_grasped, find_contacts, part_query, press_all, reaction_of, record_grasped,
    record_impulses, Grasper, PressOwner,
};
use super::surface_set::{AttachedSurface, SurfaceHandle, ToolReaction};
use super::tool_shape::{contact_margin, ToolShape};
use crate::geometry::tool_boundary::{
    distance_outside, exit_along, nearest_on_boundary, outward_normal,
};
use crate::geometry::SurfaceContact;
use crate::math::{Pose, Real, Vector};
use crate::surface::MassSpringSurface;
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::geometry::ColliderHandle;
use rapier3d::pipeline::PhysicsWorld;
use std::sync::Arc;

/// The attached surfaces whose body is still in the world, with that body's pose.
pub(super) fn attached_with_pose<'a>(
    entries: &'a mut [(u32, Option<AttachedSurface>)],
    world: &'a PhysicsWorld,
) -> impl Iterator<Item = (SurfaceHandle, &'a mut AttachedSurface, Pose)> + 'a {
    entries
        .iter_mut()
        .enumerate()
        .filter_map(move |(i, (generation, e))| {
            let s = e.as_mut()?;
            let pose = *world.bodies.get(s.body)?.position();
            let handle = SurfaceHandle {
                index: i as u32,
                generation: *generation,
            };
            Some((handle, s, pose))
        })
}

/// A tool over one substep: its collider, its poses (world) at the start and the end, and its
/// shape as the coupling uses it (its polyhedral parts' vertices and edges press the surface
/// between the surface's vertices, [`super::pressing`]).
#[derive(Clone, Debug)]
pub(super) struct ToolMotion {
    pub handle: ColliderHandle,
    pub start: Pose,
    pub end: Pose,
    pub shape: Arc<ToolShape>,
    /// The tool's friction on this surface.
    pub friction: Friction,
    /// Whether the tool grasps what it touches (bilateral contacts).
    pub grasp: bool,
    /// Whether to hand back the vertices it holds with their forces (for a haptic link).
    pub record: bool,
    /// A dynamic tool's index in the substep's dynamic tools: it presses as the surface's
    /// rigid holder of that index ([`super::dynamic_tools`]), and `start`/`end` are its pose now
    /// and after a substep of free motion.
    pub holder: Option<usize>,
}

impl ToolMotion {
    /// Where its sharp features may press over its motion (surface frame, `inv`: world to
    /// surface), or `None` for a tool with no polyhedral part.
    pub(super) fn parts_reach(&self, inv: &Pose) -> Option<Aabb> {
        self.shape
            .parts
            .iter()
            .map(|(local, mesh)| {
                part_query(
                    mesh,
                    &(*inv * self.start * *local),
                    &(*inv * self.end * *local),
                )
            })
            .reduce(|a, b| a.merged(&b))
    }

    /// Who presses its contacts, with `friction`.
    pub(super) fn owner(&self, friction: Friction) -> PressOwner {
        PressOwner {
            tool: self.handle,
            friction,
            grasp: self.grasp,
            holder: self.holder,
        }
    }

    /// Its vertices and edges against the surface (`triangles`; this substep's `candidates` of
    /// the tool, `kept` scratch; positions `before` and `now`), appended to `contacts` with the
    /// tool's material velocities there. A dynamic tool's motion is the next substep's,
    /// predicted: the surface stands still in it (`now` both times), and each contact is
    /// pressed at its depth now ([`super::dynamic_tools::depths_now`]: negative, a speculative
    /// contact).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn feature_contacts(
        &self,
        inv: &Pose,
        h: Real,
        (triangles, candidates, kept): (&[[u32; 3]], &[u32], &mut Vec<u32>),
        (before, now): (&[Vector], &[Vector]),
        contacts: &mut Vec<SurfaceContact>,
        velocities: &mut Vec<Vector>,
    ) {
        let before = if self.holder.is_some() { now } else { before };
        for (local, mesh) in &self.shape.parts {
            let first = contacts.len();
            find_contacts(
                triangles,
                (candidates, kept),
                mesh,
                &(*inv * self.start * *local),
                &(*inv * self.end * *local),
                h,
                before,
                now,
                contacts,
                velocities,
            );
            if self.holder.is_some() {
                depths_now(&mut contacts[first..], &velocities[first..], h);
            }
        }
    }
}

/// Vertices a tool holds: each one's position and the force it puts on the tool (world).
pub(super) type HeldContacts = Vec<(Vector, Vector)>;

/// One surface substep: the surface steps, then each tool holds the vertices it contains, then
/// each polyhedral tool presses its vertices and edges into the surface between the surface's
/// vertices. Returns each tool's reaction (world): the holds' spring forces at the end of the
/// substep plus the impulses the pressed points gave during it; and the vertices it holds,
/// each with its position and force on the tool (world). The dynamic tools (`dynamic`, the
/// tools' `holder` indices) are the step's rigid holders: they take the surface's impulses
/// and move on by the substep, and press what they will meet in the next one.
pub(super) fn surface_substep(
    s: &mut AttachedSurface,
    world: &PhysicsWorld,
    body_pose: &Pose,
    (tools, dynamic): (&[ToolMotion], &mut [DynamicTool]),
    h: Real,
) -> Vec<(ColliderHandle, ToolReaction, HeldContacts)> {
    let inv = body_pose.inverse();
    // The dynamic tools hold at their velocities now, with their masses (their holder
    // indices are their places in `dynamic`; none clears the last step's holders).
    set_holders(&mut s.surface, dynamic, &inv, 0.0);
    retarget_holds(&mut s.surface, &s.held_list, world, tools, &inv, h);
    s.surface.positions_into(&mut s.before);
    s.surface.step();
    record_impulses(&s.surface, &mut s.pressed);
    // (The tools' list is copied only to change the dynamic ones' motions.)
    let moved;
    let tools = if dynamic.is_empty() {
        tools
    } else {
        let mut copy = tools.to_vec();
        move_on(&mut s.surface, dynamic, &mut copy, body_pose, h);
        moved = copy;
        &moved[..]
    };
    std::mem::swap(&mut s.pressed, &mut s.last_pressed);
    s.pressed.clear();
    // Which vertices the tools held through this step: marked in `was_held` (all false but
    // those) while the tools look, cleared after.
    s.was_held.resize(s.surface.num_vertices(), false);
    s.held_list.retain(|&i| s.surface.is_held(i));
    for &i in &s.held_list {
        s.was_held[i as usize] = true;
    }
    s.surface.release_all();
    // A tool moves only the vertices it holds, which later tools skip: one read of the
    // positions serves every tool.
    s.surface.positions_into(&mut s.scratch);
    s.search.refresh(&mut s.surface, &s.scratch, &s.before);
    let mut out = Vec::with_capacity(tools.len());
    let mut now_held = Vec::new();
    // The dynamic tools' vertex contacts, pressed with the sharp features' below.
    let (mut vertex_presses, mut vertex_velocities, mut vertex_owners) =
        (Vec::new(), Vec::new(), Vec::new());
    s.search.clear_tools();
    s.search
        .retain_tools(|h| tools.iter().any(|t| t.handle == h));
    for (k, t) in tools.iter().enumerate() {
        // Where the tool's sharp features may press in this substep.
        let parts = t.parts_reach(&inv);
        let Some(tool) = world.colliders.get(t.handle) else {
            if let Some(parts) = parts {
                s.search.near(k, t.handle, &parts);
            }
            continue;
        };
        // Vertices follow a tool whose motion is prescribed (kinematic or no body); a dynamic
        // tool's own motion comes from the surface's force, so it is not chased.
        let follow = tool
            .parent()
            .and_then(|b| world.bodies.get(b))
            .is_none_or(|b| !b.is_dynamic());
        let friction = friction_on(s, t);
        let shape = t.shape.query.as_deref().unwrap_or(tool.shape());
        if let Some(j) = t.holder {
            let reaction = press_dynamic(
                s,
                (t, k, j),
                (shape, parts, friction),
                dynamic,
                body_pose,
                h,
                (
                    &mut vertex_presses,
                    &mut vertex_velocities,
                    &mut vertex_owners,
                ),
            );
            out.push((t.handle, reaction, Vec::new()));
            continue;
        }
        let pose = inv * t.end;
        // Candidates, from one walk of the BVH: the vertices near the tool, those held
        // through the step (which may chase it from farther), and the triangles its sharp
        // features may press.
        let aabb = shape.compute_aabb(&pose);
        let near = aabb.loosened(contact_margin(&aabb, 1e-4));
        s.search
            .near(k, t.handle, &parts.map_or(near, |p| p.merged(&near)));
        merge_sorted(&mut s.search.vertices, &s.held_list);
        let holds = hold_vertices(
            (t.handle, friction, t.grasp, t.record, &mut s.sticks),
            follow,
            &mut s.surface,
            shape,
            &pose,
            &(inv * t.start),
            h,
            &s.before,
            &s.was_held,
            (&s.scratch, &s.search.vertices),
        );
        now_held.extend_from_slice(&holds.vertices);
        let (pf, pm, pn) = reaction_of(&s.last_pressed, t.handle, h);
        let (force, arm_sum) = (holds.force + pf, holds.moment + pm);
        let world_force = body_pose.rotation * force;
        let centre = tool
            .parent()
            .and_then(|b| world.bodies.get(b))
            .map(|b| b.center_of_mass())
            .unwrap_or(t.end.translation);
        // Torque about the tool's centre of mass: Σ (p - c) × f, in world.
        let torque =
            body_pose.rotation * arm_sum - (centre - body_pose.translation).cross(world_force);
        let contacts = holds
            .contacts
            .iter()
            .map(|&(p, f)| (body_pose.transform_point(p), body_pose.rotation * f))
            .collect();
        out.push((
            t.handle,
            ToolReaction {
                force: world_force,
                torque,
                mean_force: world_force,
                held_vertices: holds.count,
                sticking_vertices: holds.sticking,
                pressed_points: pn,
            },
            contacts,
        ));
    }
    for &i in &s.held_list {
        s.was_held[i as usize] = false;
    }
    // Sharp features, against the surface as the vertex holds left it, pressed together.
    now_held.sort_unstable();
    now_held.dedup();
    s.held_list = now_held;
    if !vertex_presses.is_empty() || tools.iter().any(|t| !t.shape.parts.is_empty()) {
        s.surface.positions_into(&mut s.scratch);
        // The holds moved the vertices they hold: the triangles around those that went
        // past the BVH's slack join the candidates.
        s.search.refresh(&mut s.surface, &s.scratch, &s.before);
        s.search.add_moved_triangles();
        s.contacts.clear();
        s.contacts.append(&mut vertex_presses);
        let (mut velocities, mut owners, mut kept) = (vertex_velocities, vertex_owners, Vec::new());
        for (k, t) in tools.iter().enumerate() {
            t.feature_contacts(
                &inv,
                h,
                (
                    s.surface.triangles(),
                    s.search.triangles_of_tool(k),
                    &mut kept,
                ),
                (&s.before, &s.scratch),
                &mut s.contacts,
                &mut velocities,
            );
            owners.resize(s.contacts.len(), t.owner(friction_on(s, t)));
        }
        // Grasping tools hold the points they pressed (pressing::GraspedPoint).
        let graspers: Vec<Grasper> = tools
            .iter()
            .filter(|t| t.grasp)
            .map(|t| (t.handle, inv * t.start, inv * t.end, t.holder))
            .collect();
        let first_grasped = add_grasped(
            &mut s.grasped,
            &graspers,
            &s.scratch,
            h,
            &mut s.contacts,
            &mut velocities,
            &mut owners,
        );
        within_slop(&mut s.contacts, &owners, dynamic);
        let ids = press_all(
            &mut s.surface,
            &s.contacts,
            &velocities,
            &owners,
            &mut s.pressed,
        );
        let new = ..first_grasped.min(ids.len());
        record_grasped(
            &mut s.grasped,
            &graspers,
            &s.contacts[new],
            &owners[new],
            &ids[new],
        );
    }
    out
}

/// A held vertex moves through the next step as a pin with the velocity its holder gave it in
/// the last substep. A tool that changed speed since (a hand stopping, a servo's proxy) would
/// drag it on by a substep of the old motion, off the tool and into the springs it just
/// loaded, and a contact that should rest bounces. So before the step each held vertex takes
/// its holder's velocity over this substep at the contact point: the normal part for a
/// sliding hold, all of it for a stuck one. The holder is the kinematic (or bodiless) tool
/// whose boundary at the start of the substep the vertex lies on.
fn retarget_holds(
    surface: &mut MassSpringSurface,
    held: &[u32],
    world: &PhysicsWorld,
    tools: &[ToolMotion],
    inv: &Pose,
    h: Real,
) {
    if h <= 0.0 {
        return;
    }
    let poses: Vec<(&dyn parry3d::shape::Shape, Pose, Pose, Aabb, Real)> = tools
        .iter()
        .filter_map(|t| {
            let collider = world.colliders.get(t.handle)?;
            // Only tools whose motion is prescribed: a dynamic tool's comes from the
            // surface's solve itself (its rigid holder), and is not chased (as in
            // `hold_vertices`).
            if collider
                .parent()
                .and_then(|b| world.bodies.get(b))
                .is_some_and(|b| b.is_dynamic())
            {
                return None;
            }
            let shape = t.shape.query.as_deref().unwrap_or(collider.shape());
            let (start, end) = (*inv * t.start, *inv * t.end);
            let aabb = shape.compute_aabb(&start);
            let margin = contact_margin(&aabb, 1e-3);
            Some((shape, start, end, aabb.loosened(margin), margin))
        })
        .collect();
    if poses.is_empty() {
        return;
    }
    for &i in held {
        if !surface.is_held(i) {
            continue;
        }
        let p = surface.position(i);
        let holder = poses.iter().find(|(shape, start, _, aabb, margin)| {
            aabb.contains_local_point(p) && distance_outside(*shape, start, p) <= *margin
        });
        let Some((_, start, end, _, _)) = holder else {
            continue;
        };
        let local = start.inverse_transform_point(p);
        let tool_velocity = (end.transform_point(local) - p) / h;
        let n = surface.held_normal(i);
        let v = if n == Vector::ZERO {
            tool_velocity
        } else {
            let own = surface.velocity(i);
            own - n * own.dot(n) + n * tool_velocity.dot(n)
        };
        let _ = surface.set_state(i, p, v);
    }
}

/// The friction of tool `t` on surface `s`: the pair's own, or else the tool's.
pub(super) fn friction_on(s: &AttachedSurface, t: &ToolMotion) -> Friction {
    s.pair_friction
        .get(&t.handle)
        .copied()
        .unwrap_or(t.friction)
}

/// Merges the sorted, duplicate-free `extra` into the sorted, duplicate-free `list`.
fn merge_sorted(list: &mut Vec<u32>, extra: &[u32]) {
    if extra.is_empty() {
        return;
    }
    list.extend_from_slice(extra);
    list.sort_unstable();
    list.dedup();
}

pub(super) fn lerp_pose(a: &Pose, b: &Pose, t: Real) -> Pose {
    Pose::from_parts(
        a.translation.lerp(b.translation, t),
        a.rotation.slerp(b.rotation, t),
    )
}

/// What one tool's holds give back: the force on the tool, `Σ p × f` (surface frame), how many
/// vertices it holds and how many of those stick to it.
pub(super) struct Holds {
    pub force: Vector,
    pub moment: Vector,
    pub count: usize,
    pub sticking: usize,
    /// The vertices held at the end.
    pub vertices: Vec<u32>,
    /// Each held vertex's position and the force it puts on the tool (surface frame), when
    /// asked to record them.
    pub contacts: Vec<(Vector, Vector)>,
}

/// Moves every surface vertex the tool contains out of it and holds it there (see [`Holds`]).
///
/// A vertex that just entered is walked back along its inverse trajectory relative to the tool
/// (eq. 1-2 for one vertex): from where it is, back along its own motion over the substep minus
/// the tool's, to the tool's boundary. A vertex already in contact slides: it is snapped to the
/// nearest boundary point, keeps its own tangential velocity and takes the tool's normal
/// velocity. With friction ([`super::friction`]) a vertex that sticks is carried by the tool's
/// material point it stuck to, with that point's whole velocity, until its tangential force
/// passes the static limit; a slipping vertex is pulled back by kinetic friction. A grasping
/// tool keeps every vertex it touches stuck, pulled or pushed, until it lets go.
#[allow(clippy::too_many_arguments)]
pub(super) fn hold_vertices(
    (tool, friction, grasp, record, sticks): (ColliderHandle, Friction, bool, bool, &mut Sticks),
    follow: bool,
    surface: &mut MassSpringSurface,
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    before: &Pose,
    h: Real,
    prev_positions: &[Vector],
    was_held: &[bool],
    (positions, candidates): (&[Vector], &[u32]),
) -> Holds {
    let aabb: Aabb = shape.compute_aabb(pose);
    let margin = contact_margin(&aabb, 1e-4);
    let aabb = aabb.loosened(margin);
    let motion = pose.translation - before.translation;
    // The velocity of the tool's material point at `local` (tool frame) over the substep.
    let material_velocity = |local: Vector| {
        if h > 0.0 {
            (pose.transform_point(local) - before.transform_point(local)) / h
        } else {
            Vector::ZERO
        }
    };
    // A vertex held in the last substep moved on with the tool's old normal velocity; when the
    // tool slowed down or turned back, that leaves it outside by up to the relative motion over
    // the substep. It is still in contact (and snapped back) unless its springs pull it away
    // (the push-only test below).
    // (vertex, normal, contact point in the tool's frame, stuck in the last substep)
    let mut held: Vec<(u32, Vector, Vector, bool)> = Vec::new();
    // (vertex, its free position and velocity) for vertices that followed the tool.
    let mut followed: Vec<(u32, Vector, Vector)> = Vec::new();
    for &iu in candidates {
        let i = iu as usize;
        let Some(p) = positions.get(i) else {
            continue;
        };
        let entering = !was_held.get(i).copied().unwrap_or(false);
        let chase = follow && !entering;
        let own = prev_positions.get(i).map_or(Vector::ZERO, |q| *p - *q);
        let slack = if chase {
            own.length() + 2.0 * motion.length() + margin
        } else {
            0.0
        };
        let near = p.cmpge(aabb.mins - Vector::splat(slack)).all()
            && p.cmple(aabb.maxs + Vector::splat(slack)).all();
        if !near || surface.is_pinned(iu) || surface.is_held(iu) {
            continue;
        }
        let rel = motion - own;
        // In contact: inside the tool, or on its boundary (where the last substep left a held
        // vertex) within a hair, or held before and left behind by the relative motion.
        let gap = distance_outside(shape, pose, *p);
        if gap > margin {
            if !chase || gap > rel.length() + motion.length() + margin {
                continue;
            }
            followed.push((iu, *p, surface.velocity(iu)));
        }
        // A vertex stuck to this tool stays on the material point it stuck to.
        let stuck = match sticks.get(&iu) {
            Some(&(t, Contact::Stuck(anchor))) if t == tool && !entering => Some(anchor),
            _ => None,
        };
        let (out, local) = match stuck {
            Some(anchor) => (pose.transform_point(anchor), anchor),
            None => {
                let nearest = nearest_on_boundary(shape, pose, *p);
                // Walked back along its relative motion over the substep, a vertex that came
                // in leaves where it entered: no farther than that motion (twice, for the arc
                // a turning tool's point follows). An exit farther away is the far side of a
                // tool the vertex did not cross this substep: one lying on a face and grazed
                // along it (a cube dragged over a plate) is "inside" by a rounding error, and
                // was thrown across the whole cube (a 2 kN spike on a 440 N press).
                let walk = 2.0 * rel.length() + margin;
                let out = if entering && rel.length() > (nearest - *p).length() + margin {
                    exit_along(shape, pose, *p, rel.normalize())
                        .filter(|q| (*q - *p).length() <= walk)
                        .unwrap_or(nearest)
                } else {
                    nearest
                };
                (out, pose.inverse_transform_point(out))
            }
        };
        if !out.is_finite() {
            continue;
        }
        // The tool's outward normal at the contact point.
        let n = pose.rotation * outward_normal(shape, local, margin);
        let tool_velocity = material_velocity(local);
        let v = if stuck.is_some() {
            tool_velocity
        } else {
            // Sliding: the tool sets the normal velocity only.
            let v_own = surface.velocity(iu);
            let v = v_own - n * v_own.dot(n) + n * tool_velocity.dot(n);
            // A vertex held since the last substep and put back on the tool along another
            // direction than the normal (under an edge or a corner, back onto the face it
            // slid off) also loses what it has of motion into the tool along that move: kept,
            // that motion carried it back in at every substep, and back out by position
            // alone, for good (a U's leg held a vertex on its wall that slid down at
            // 0.25 m/s while a neighbour see-sawed up at the same speed, and neither moved:
            // their dampers took 1 N of a 10 N press from the tool's reaction). Inelastic: it
            // only takes energy out. (A vertex entering is left as it was: its way out is
            // walked back along its motion.)
            let moved = out - *p;
            match moved.try_normalize() {
                Some(d) if !entering && moved.length() > margin => {
                    let into = (v - tool_velocity).dot(d);
                    if into < 0.0 {
                        v - d * into
                    } else {
                        v
                    }
                }
                _ => v,
            }
        };
        if surface.set_state(iu, out, v).is_ok() {
            let _ = if stuck.is_some() {
                surface.hold(iu)
            } else {
                surface.hold_sliding(iu, n)
            };
            held.push((iu, n, local, stuck.is_some()));
        }
    }
    // Contact only pushes: a held vertex whose springs pull it away from the tool (it would
    // stick to a receding tool) is let go. The others stick or slip (friction), and the tool
    // receives their spring and damper forces: the normal part, and the tangential part of
    // those that stick, or kinetic friction for those that slip.
    let mut out = Holds {
        force: Vector::ZERO,
        moment: Vector::ZERO,
        count: 0,
        sticking: 0,
        vertices: Vec::new(),
        contacts: Vec::new(),
    };
    // A vertex moving over the tool slower than this (a millionth of the tool's size per
    // substep) is at rest on it.
    let slip_eps = if h > 0.0 {
        1e-6 * aabb.extents().max_element() / h
    } else {
        Real::MAX
    };
    for &(i, n, local, was_stuck) in &held {
        let f = surface.internal_force(i);
        let (on_tool, next) = if grasp {
            // Grasped: stuck whatever its springs do, pulled or pushed; the tool feels it all.
            (f, Settled::Stick)
        } else if f.dot(n) >= 0.0 {
            surface.release(i);
            // A vertex that only followed the tool separates where its own motion took it.
            if let Some(&(_, p, v)) = followed.iter().find(|f| f.0 == i) {
                let _ = surface.set_state(i, p, v);
            }
            continue;
        } else {
            let was = sticks
                .get(&i)
                .filter(|s| s.0 == tool && !friction.is_frictionless())
                .map(|s| s.1);
            let relative = surface.velocity(i) - material_velocity(local);
            let slip = relative - n * relative.dot(n);
            settle(friction, f, n, was, slip, slip_eps)
        };
        match next {
            Settled::Stick => {
                if !was_stuck {
                    // From now on carried by the material point it touches.
                    let _ = surface.set_state(i, surface.position(i), material_velocity(local));
                    let _ = surface.hold(i);
                }
                sticks.insert(i, (tool, Contact::Stuck(local)));
                out.sticking += 1;
            }
            Settled::Slip { on_vertex, dir } => {
                let _ = surface.hold_sliding_with_friction(i, n, on_vertex);
                if !friction.is_frictionless() {
                    sticks.insert(i, (tool, Contact::Slipping(dir)));
                }
            }
        }
        out.force += on_tool;
        out.moment += surface.position(i).cross(on_tool);
        out.count += 1;
        out.vertices.push(i);
        if record {
            out.contacts.push((surface.position(i), on_tool));
        }
    }
    // This tool's contacts end where it let the vertex go.
    sticks.retain(|v, s| s.0 != tool || surface.is_held(*v) && held.iter().any(|h| h.0 == *v));
    out
}
