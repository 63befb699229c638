//! One surface substep with its tools: the surface steps, then every vertex inside a tool is
//! walked back to the tool's boundary and held there (a moving pin inside the filter,
//! [`super::vertex_holds`]), the tools' sharp features press between the vertices
//! ([`super::pressing`]), and each tool gets the reaction of what it holds and presses.

use super::dynamic_tools::{
    depths_now, move_on, press_dynamic, push_out_bodies, set_holders, within_slop, DynamicTool,
};
use super::friction::Friction;
use super::pressing::{
    add_grasped, find_contacts, momentum_of, part_query, press_all, reaction_of, record_grasped,
    record_impulses, Grasper, PressOwner,
};
use super::surface_set::{AttachedSurface, SurfaceHandle, ToolReaction};
use super::tool_shape::{contact_margin, ToolShape};
use super::vertex_holds::hold_vertices;
use crate::geometry::tool_boundary::distance_outside;
use crate::geometry::{SurfaceContact, TrianglesRound};
use crate::math::{Pose, Real, Vector};
use crate::surface::MassSpringSurface;
use glamx::DVec3;
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
        (triangles, candidates, kept, rings): (
            &[[u32; 3]],
            &[u32],
            &mut Vec<u32>,
            TrianglesRound<'_>,
        ),
        (before, now): (&[Vector], &[Vector]),
        contacts: &mut Vec<SurfaceContact>,
        velocities: &mut Vec<Vector>,
    ) {
        let before = if self.holder.is_some() { now } else { before };
        for (part, (local, mesh)) in self.shape.parts.iter().enumerate() {
            let first = contacts.len();
            let end = *inv * self.end * *local;
            find_contacts(
                triangles,
                (candidates, kept, rings),
                mesh,
                &(*inv * self.start * *local),
                &end,
                h,
                before,
                now,
                contacts,
                velocities,
            );
            // A compound's part's features inside its other parts make no contact.
            if self.shape.is_compound() {
                let margin = contact_margin(&mesh.local_aabb(), 1e-3);
                let mut k = first;
                for i in first..contacts.len() {
                    let point =
                        local.transform_point(end.inverse_transform_point(contacts[i].point));
                    if !self.shape.covered(part, point, margin) {
                        contacts.swap(k, i);
                        velocities.swap(k, i);
                        k += 1;
                    }
                }
                contacts.truncate(k);
                velocities.truncate(k);
            }
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
    // What each kinematic tool gives the surface through its vertex holds over the substep
    // (surface frame): the velocities it sets before the step, then the holds' impulses
    // through it.
    let mut given = retarget_holds(&mut s.surface, &s.held_list, world, tools, &inv, h);
    s.surface.positions_into(&mut s.before);
    s.surface.step();
    record_impulses(&s.surface, &mut s.pressed);
    given.extend(
        s.held_by
            .iter()
            .map(|&(v, tool)| (tool, s.surface.hold_impulse_f64(v))),
    );
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
    // Each kinematic tool's books over the substep (the momentum it gave the surface, in
    // double precision: see `Pressed::pressed_momentum`), its reaction's `mean_force` once
    // its presses are in; `None` for a dynamic tool, whose reaction has its own.
    let mut books: Vec<Option<DVec3>> = Vec::with_capacity(tools.len());
    let mut now_held = Vec::new();
    s.held_by.clear();
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
            books.push(None);
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
        s.held_by
            .extend(holds.vertices.iter().map(|&v| (v, t.handle)));
        let (pf, pm, pn) = reaction_of(&s.last_pressed, t.handle, h);
        let (force, arm_sum) = (holds.force + pf, holds.moment + pm);
        let world_force = body_pose.rotation * force;
        // Over the substep the tool took back what it gave the surface through its holds (the
        // velocities it set and the holds' impulses through the step, and the velocity changes
        // of the vertices it took hold of or let go at its end) and through its points (their
        // presses and the step's impulses on them): its momentum books balance with the
        // surface's.
        let held_given = given
            .iter()
            .filter(|g| g.0 == t.handle)
            .map(|g| g.1)
            .sum::<DVec3>()
            + holds.given;
        books.push((h > 0.0).then(|| held_given + momentum_of(&s.last_pressed, t.handle)));
        // (Set from the books at the end of the substep, `mean_force_of`.)
        let mean_force = world_force;
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
                mean_force,
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
                    &|v, out| s.search.triangles_round(v, out),
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
        // A dynamic tool overlapping the surface past what its approach made is moved out.
        if push_out_bodies(
            &mut s.contacts,
            &velocities,
            &owners,
            dynamic,
            &s.surface,
            body_pose,
            h,
        ) {
            set_holders(&mut s.surface, dynamic, &inv, h);
        }
        let ids = press_all(
            &mut s.surface,
            &s.contacts,
            &velocities,
            &owners,
            &mut s.pressed,
        );
        // The presses' velocity changes are the tools' impulses in this substep.
        for ((handle, _, _), book) in out.iter().zip(books.iter_mut()) {
            if let Some(book) = book {
                *book += s
                    .pressed
                    .iter()
                    .filter(|p| p.tool == *handle)
                    .map(|p| p.pressed_momentum)
                    .sum::<DVec3>();
            }
        }
        let new = ..first_grasped.min(ids.len());
        record_grasped(
            &mut s.grasped,
            &graspers,
            &s.contacts[new],
            &owners[new],
            &ids[new],
        );
    }
    for ((_, reaction, _), book) in out.iter_mut().zip(&books) {
        if let Some(book) = book {
            reaction.mean_force = mean_force_of(*book, body_pose, h);
        }
    }
    out
}

/// A kinematic tool's mean force over a substep (`h` long, world frame) from its books: the
/// reverse of the momentum it gave the surface (surface frame, on the body at `body_pose`).
fn mean_force_of(given: DVec3, body_pose: &Pose, h: Real) -> Vector {
    body_pose.rotation * -(given / f64::from(h)).as_vec3()
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
) -> Vec<(ColliderHandle, DVec3)> {
    let mut given = Vec::new();
    if h <= 0.0 {
        return given;
    }
    type Holder<'a> = (
        &'a dyn parry3d::shape::Shape,
        Pose,
        Pose,
        Aabb,
        Real,
        ColliderHandle,
    );
    let poses: Vec<Holder> = tools
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
            Some((shape, start, end, aabb.loosened(margin), margin, t.handle))
        })
        .collect();
    if poses.is_empty() {
        return given;
    }
    for &i in held {
        if !surface.is_held(i) {
            continue;
        }
        let p = surface.position(i);
        let holder = poses.iter().find(|(shape, start, _, aabb, margin, _)| {
            aabb.contains_local_point(p) && distance_outside(*shape, start, p) <= *margin
        });
        let Some((_, start, end, _, _, tool)) = holder else {
            continue;
        };
        let local = start.inverse_transform_point(p);
        let tool_velocity = (end.transform_point(local) - p) / h;
        let n = surface.held_normal(i);
        let own = surface.velocity(i);
        let v = if n == Vector::ZERO {
            tool_velocity
        } else {
            own - n * own.dot(n) + n * tool_velocity.dot(n)
        };
        if surface.set_state(i, p, v).is_ok() {
            given.push((*tool, ((v - own) * surface.mass(i)).as_dvec3()));
        }
    }
    given
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
