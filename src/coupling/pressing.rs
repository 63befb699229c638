//! How a polyhedral tool's sharp features press a surface between its vertices in one surface
//! substep: the geometry layer finds the tool's vertices inside surface triangles and its edges
//! across surface edges ([`crate::geometry::tool_surface_contacts`]); each contact point is
//! pushed onto the tool and held there along the contact normal
//! ([`MassSpringSurface::press_point`]), loading the vertices around it by their weights inside
//! the filter's constraint solve. The tool gets the impulses those holds gave: the press's own
//! velocity change and the next surface step's constraint impulse.
//!
//! With friction each point also sticks or slides: Coulomb's law on the step's own impulses,
//! solved by the surface with its other constraints ([`Tangential::Coulomb`]); a grasping tool
//! holds its points in every direction ([`Tangential::Grasped`]).

use super::friction::Friction;
use super::tool_shape::contact_margin;
use crate::geometry::{
    tool_surface_contacts_with_rings, Feature, SurfaceContact, SurfaceSnapshot, TouchMesh,
    TrianglesRound,
};
use crate::math::{Pose, Real, Vector};
use crate::surface::{MassSpringSurface, PointPress, Tangential};
use glamx::DVec3;
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::geometry::ColliderHandle;

/// A point a tool pressed in the last substep (surface frame).
#[derive(Copy, Clone, Debug)]
pub(super) struct Pressed {
    pub tool: ColliderHandle,
    /// The hold's index in the surface ([`MassSpringSurface::point_impulse`]).
    pub id: usize,
    /// Unit direction from the tool into the surface.
    pub normal: Vector,
    pub point: Vector,
    /// The impulse the hold gave from the press through the surface step after it (N·s, along
    /// `normal`), filled in by [`record_impulses`].
    pub impulse: Real,
    /// The impulse the tool gave the point along its tangent plane through that step (N·s,
    /// friction), filled in by [`record_impulses`].
    pub tangent_impulse: Vector,
    /// What the step gave, through the point, vertices the tools hold on a sliding hold,
    /// across that hold's normal (N·s, [`MassSpringSurface::point_held_across`]), filled in by
    /// [`record_impulses`].
    pub held_across: Vector,
    /// The momentum the hold gave the surface's vertices by its press (the velocity change,
    /// booked in the substep it happened in). Its books are kept in double precision, as the
    /// surface keeps them: a tool twisting a plate presses with momenta tens of times the
    /// plate's net change, and their single-precision sums drifted off it.
    pub pressed_momentum: DVec3,
    /// The momentum it gave by the press and the step after it
    /// ([`MassSpringSurface::point_momentum`]), filled in by [`record_impulses`].
    pub momentum: DVec3,
}

/// The tool a contact belongs to, as [`press_all`] needs it.
#[derive(Copy, Clone, Debug)]
pub(super) struct PressOwner {
    pub tool: ColliderHandle,
    pub friction: Friction,
    /// Whether the tool grasps (its points are held in every direction).
    pub grasp: bool,
    /// A dynamic tool's index among the surface's rigid holders ([`super::dynamic_tools`]).
    pub holder: Option<usize>,
}

/// Reads the impulses the holds of `pressed` gave up to the end of the surface step just taken
/// (before the surface releases them).
pub(super) fn record_impulses(surface: &MassSpringSurface, pressed: &mut [Pressed]) {
    for p in pressed {
        p.impulse = surface.point_impulse(p.id).unwrap_or(0.0);
        p.tangent_impulse = surface.point_tangent_impulse(p.id).unwrap_or(Vector::ZERO);
        p.held_across = surface.point_held_across(p.id).unwrap_or(Vector::ZERO);
        p.momentum = surface.point_momentum_f64(p.id).unwrap_or(DVec3::ZERO);
    }
}

/// The momentum `tool`'s points gave the surface in the step just taken (surface frame): the
/// step's impulses on them (their presses' velocity changes were booked when they were
/// pressed, [`press_all`]).
pub(super) fn momentum_of(pressed: &[Pressed], tool: ColliderHandle) -> DVec3 {
    pressed
        .iter()
        .filter(|p| p.tool == tool)
        .map(|p| p.momentum - p.pressed_momentum)
        .sum()
}

/// Force (on the tool, surface frame), `Σ p × f` and count of the points `tool` pressed during
/// the surface step just taken (`h` its time step): normal and friction, or a grasp's pull.
pub(super) fn reaction_of(
    pressed: &[Pressed],
    tool: ColliderHandle,
    h: Real,
) -> (Vector, Vector, usize) {
    let (mut force, mut moment, mut count) = (Vector::ZERO, Vector::ZERO, 0);
    if h <= 0.0 {
        return (force, moment, count);
    }
    for p in pressed.iter().filter(|p| p.tool == tool) {
        // (A point all on held vertices reports no impulse of its own, but may have moved
        // them across their holds.)
        if p.impulse != 0.0 || p.held_across != Vector::ZERO {
            let f = p.force_on_tool(h);
            force += f;
            moment += p.point.cross(f);
            count += 1;
        }
    }
    (force, moment, count)
}

impl Pressed {
    /// The force the point put on the tool through the step (`h` long).
    fn force_on_tool(&self, h: Real) -> Vector {
        -(self.normal * self.impulse + self.tangent_impulse + self.held_across) / h
    }
}

/// Where the surface may meet `mesh` moving from `start` to `end` (surface frame): its swept
/// bounds and a margin.
pub(super) fn part_query(mesh: &TouchMesh, start: &Pose, end: &Pose) -> Aabb {
    part_sweep(mesh, start, end).0
}

/// [`part_query`]'s box (the bounds of `mesh` over its motion from `start` to `end`,
/// loosened by twice its contact margin), and that margin.
fn part_sweep(mesh: &TouchMesh, start: &Pose, end: &Pose) -> (Aabb, Real) {
    let local = mesh.local_aabb();
    let swept: Aabb = local.transform_by(start).merged(&local.transform_by(end));
    let margin = contact_margin(&swept, 1e-4);
    (swept.loosened(2.0 * margin), margin)
}

/// Finds the contacts of `mesh` (moving from `start` to `end`, surface frame) with the surface
/// (`before`: positions at the start of the substep, `now`: at its end; `candidates`: a
/// superset of the triangles whose bounds over the substep meet [`part_query`], sorted; `kept`:
/// scratch) and appends them to `contacts`, with the velocity of the tool's material point at
/// each in `velocities`.
#[allow(clippy::too_many_arguments)]
pub(super) fn find_contacts(
    triangles: &[[u32; 3]],
    (candidates, kept, rings): (&[u32], &mut Vec<u32>, TrianglesRound<'_>),
    mesh: &TouchMesh,
    start: &Pose,
    end: &Pose,
    h: Real,
    before: &[Vector],
    now: &[Vector],
    contacts: &mut Vec<SurfaceContact>,
    velocities: &mut Vec<Vector>,
) {
    let (query, margin) = part_sweep(mesh, start, end);
    let snapshot = SurfaceSnapshot {
        before,
        now,
        triangles,
    };
    // Keep the triangles whose own bounds over the substep meet the tool's (`part_query`).
    snapshot.triangles_meeting(candidates, &query, kept);
    let candidates = &kept[..];
    if candidates.is_empty() {
        return;
    }
    let first = contacts.len();
    tool_surface_contacts_with_rings(
        &snapshot, candidates, rings, mesh, start, end, margin, contacts,
    );
    for c in &contacts[first..] {
        // The tool's material point under the contact: its velocity.
        let material = end.inverse_transform_point(c.point);
        velocities.push(if h > 0.0 {
            (c.point - start.transform_point(material)) / h
        } else {
            Vector::ZERO
        });
    }
}

/// Presses every contact (all tools together, so presses sharing a vertex do not undo each
/// other) and records them in `pressed` (`owners[i]`: the tool of `contacts[i]`; `velocities`:
/// its material point's velocity there). Returns each contact's hold, if pressed.
pub(super) fn press_all(
    surface: &mut MassSpringSurface,
    contacts: &[SurfaceContact],
    velocities: &[Vector],
    owners: &[PressOwner],
    pressed: &mut Vec<Pressed>,
) -> Vec<Option<usize>> {
    let presses: Vec<PointPress<'_>> = contacts
        .iter()
        .zip(velocities)
        .zip(owners)
        .map(|((c, &v), owner)| {
            let (depth, normal_velocity) = past_rounding(surface, c, v, owner.holder.is_none());
            PointPress {
                vertices: c.weights(),
                normal: c.normal,
                depth,
                normal_velocity,
                tangential: friction_of(v, owner),
                holder: owner.holder.map(|k| (k, c.point)),
            }
        })
        .collect();
    // The geometry layer's contacts are finite, with unit normals and weights on existing
    // vertices. One that is not (a bug) fails `press_points` as a whole, which presses nothing
    // (a contact with a zero normal once took every press of a substep with it: a resting body
    // fell a step's worth into the surface). Then the invalid ones are left out, reported, and
    // the rest pressed; the usual call checks each press once.
    let ids = match surface.press_points(&presses) {
        Ok(ids) => ids,
        Err(_) => {
            let valid: Vec<bool> = presses.iter().map(|p| surface.press_is_valid(p)).collect();
            let bad = valid.iter().filter(|v| !**v).count();
            log::warn!("rapier_touch: {bad} invalid surface contact(s) left out of a substep");
            let kept: Vec<PointPress<'_>> = presses
                .iter()
                .zip(&valid)
                .filter(|(_, v)| **v)
                .map(|(p, _)| *p)
                .collect();
            let Ok(kept_ids) = surface.press_points(&kept) else {
                return Vec::new();
            };
            let mut kept_ids = kept_ids.into_iter();
            valid
                .iter()
                .map(|&v| if v { kept_ids.next().flatten() } else { None })
                .collect()
        }
    };
    for ((c, id), owner) in contacts.iter().zip(&ids).zip(owners) {
        let Some(id) = *id else {
            continue;
        };
        pressed.push(Pressed {
            tool: owner.tool,
            id,
            normal: c.normal,
            point: c.point,
            impulse: 0.0,
            tangent_impulse: Vector::ZERO,
            held_across: Vector::ZERO,
            pressed_momentum: surface.point_momentum_f64(id).unwrap_or(DVec3::ZERO),
            momentum: DVec3::ZERO,
        });
    }
    ids
}

/// A contact's depth and the normal velocity of the tool's material point there (`v`), each 0
/// within four `f32` steps of the coordinates of the contact's vertices (the velocity over the
/// surface's substep, only where the depth is 0 too, and only for a `kinematic` tool, whose
/// velocity is its poses' difference), where their signs are rounding. (A dynamic tool's
/// velocity is its body's, which the surface's solve meets with the body's mass.)
///
/// A flipping depth pressed the point in by that much, or left it a gap of that size for the
/// step to close, each with a velocity change to match: at rest the force swung from substep
/// to substep (a jaw 8.84-10.15 N for 9.55 N, cycling through four contact sets; a needle on a
/// plate of 1 kg vertices, its depth ±6e-8 m on 0.3 m coordinates, 0.42-0.58 N for 0.50 N, now
/// half that). A tool held still reads a normal velocity of a few `f32` steps per substep
/// (its pose's round trip through the tool's frame): pressed with it, the point crept away
/// from the tool, and once its gap passed the depth's cut one substep closed it (a cube corner
/// at rest, 0.466 N and then 0.535 N for 0.503 N). A vertex out of range (a bug upstream,
/// which [`press_all`] reports) counts for nothing here.
fn past_rounding(
    surface: &MassSpringSurface,
    c: &SurfaceContact,
    v: Vector,
    kinematic: bool,
) -> (Real, Real) {
    let reach = c
        .weights()
        .iter()
        .filter(|(v, _)| (*v as usize) < surface.num_vertices())
        .map(|(v, _)| surface.position(*v).abs().max_element())
        .fold(0.0, Real::max);
    let cut = 4.0 * Real::EPSILON * reach;
    let normal_velocity = v.dot(c.normal);
    if c.depth.abs() > cut {
        (c.depth, normal_velocity)
    } else if !kinematic || (normal_velocity * surface.dt()).abs() > cut {
        (0.0, normal_velocity)
    } else {
        (0.0, 0.0)
    }
}

/// What the tool does along a point's tangent plane: Coulomb friction with the tool's
/// material point there (moving with `v`), which the surface solves with the step's other
/// constraints; a grasping tool holds it in every direction.
fn friction_of(v: Vector, owner: &PressOwner) -> Tangential {
    if owner.grasp {
        Tangential::Grasped(v)
    } else if owner.friction.is_frictionless() {
        Tangential::Free
    } else {
        Tangential::Coulomb {
            velocity: v,
            static_coefficient: owner.friction.static_coefficient,
            dynamic_coefficient: owner.friction.dynamic_coefficient,
        }
    }
}

/// A surface point a grasping tool holds, from the substep it pressed it (in contact) until it
/// lets go: the point's vertices and weights, and the tool's material point and normal there
/// (the collider's frame). Each substep it is pressed onto that material point, bilateral
/// ([`Tangential::Grasped`]), however far the tool has moved: a grasper lifts a fold it holds
/// between the surface's vertices as well as one it holds by a vertex.
#[derive(Copy, Clone, Debug)]
pub(super) struct GraspedPoint {
    tool: ColliderHandle,
    feature: Feature,
    surface: [(u32, Real); 3],
    count: usize,
    local: Vector,
    local_normal: Vector,
}

impl GraspedPoint {
    /// Whether the point and the contact `c` load a vertex in common.
    fn shares_a_vertex(&self, c: &SurfaceContact) -> bool {
        let mine = &self.surface[..self.count.min(3)];
        c.weights()
            .iter()
            .any(|(v, _)| mine.iter().any(|(u, _)| u == v))
    }
}

/// A grasping tool over the substep (surface frame): its collider, its poses at the start and
/// the end, and its index among the surface's rigid holders if it is dynamic.
pub(super) type Grasper = (ColliderHandle, Pose, Pose, Option<usize>);

/// Appends the grasped points of the tools still grasping (`graspers`) to the contacts, each
/// pressed onto its material point with that point's velocity (plus what closes its
/// tangential gap over the substep, `h` long), and drops the grasping tools' new contacts that
/// load a grasped point's vertices (the grasped points hold them, and two bilateral points on
/// the same vertices with targets that differ a little fight: huge impulses); forgets the
/// points of tools that let go. `positions`: the surface's vertices now. Returns where the
/// grasped points start in `contacts`.
#[allow(clippy::too_many_arguments)]
pub(super) fn add_grasped(
    grasped: &mut Vec<GraspedPoint>,
    graspers: &[Grasper],
    positions: &[Vector],
    h: Real,
    contacts: &mut Vec<SurfaceContact>,
    velocities: &mut Vec<Vector>,
    owners: &mut Vec<PressOwner>,
) -> usize {
    grasped.retain(|g| graspers.iter().any(|t| t.0 == g.tool));
    if !grasped.is_empty() {
        let held = |c: &SurfaceContact, o: &PressOwner| {
            o.grasp && grasped.iter().any(|g| g.shares_a_vertex(c))
        };
        let mut k = 0;
        for i in 0..contacts.len() {
            if !held(&contacts[i], &owners[i]) {
                contacts.swap(k, i);
                velocities.swap(k, i);
                owners.swap(k, i);
                k += 1;
            }
        }
        contacts.truncate(k);
        velocities.truncate(k);
        owners.truncate(k);
    }
    let first = contacts.len();
    for g in grasped.iter() {
        let Some(&(_, start, end, holder)) = graspers.iter().find(|t| t.0 == g.tool) else {
            continue;
        };
        let material = end.transform_point(g.local);
        let normal = end.rotation * g.local_normal;
        let point: Vector = g.surface[..g.count]
            .iter()
            .filter_map(|&(v, w)| positions.get(v as usize).map(|p| *p * w))
            .sum();
        let gap = material - point;
        let depth = gap.dot(normal);
        let velocity = if h > 0.0 {
            (material - start.transform_point(g.local) + (gap - normal * depth)) / h
        } else {
            Vector::ZERO
        };
        if !(velocity.is_finite() && depth.is_finite() && normal.is_finite()) {
            continue;
        }
        contacts.push(SurfaceContact {
            tool_feature: g.feature,
            surface: g.surface,
            count: g.count,
            normal,
            depth,
            point: material,
        });
        velocities.push(velocity);
        owners.push(PressOwner {
            tool: g.tool,
            friction: Friction::NONE,
            grasp: true,
            holder,
        });
    }
    first
}

/// Records the new contacts (`contacts`, before the grasped points) that a grasping tool
/// pressed in contact (`ids`: their holds) as grasped points, each on vertices no other
/// grasped point loads.
pub(super) fn record_grasped(
    grasped: &mut Vec<GraspedPoint>,
    graspers: &[Grasper],
    contacts: &[SurfaceContact],
    owners: &[PressOwner],
    ids: &[Option<usize>],
) {
    for ((c, o), id) in contacts.iter().zip(owners).zip(ids) {
        if !o.grasp || id.is_none() || c.depth < 0.0 {
            continue;
        }
        if grasped.iter().any(|g| g.shares_a_vertex(c)) {
            continue;
        }
        let Some((_, _, end, _)) = graspers.iter().find(|t| t.0 == o.tool) else {
            continue;
        };
        grasped.push(GraspedPoint {
            tool: o.tool,
            feature: c.tool_feature,
            surface: c.surface,
            count: c.count,
            local: end.inverse_transform_point(c.point),
            local_normal: end.rotation.inverse() * c.normal,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::meshing::plate;
    use crate::surface::MassSpringSurfaceBuilder;

    /// A contact the geometry layer should never give (a zero normal) is left out on its own:
    /// the valid press beside it still moves its vertex by its depth along its normal.
    #[test]
    fn an_invalid_contact_costs_no_other_press() {
        let mut surface = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 4, 4))
            .build()
            .unwrap();
        let v = 12; // the plate's centre vertex
        let before = surface.position(v);
        let contact = |normal: Vector| SurfaceContact {
            tool_feature: Feature::Face(u32::MAX),
            surface: [(v, 1.0), (v, 0.0), (v, 0.0)],
            count: 1,
            normal,
            depth: 0.01,
            point: before,
        };
        let contacts = [contact(Vector::ZERO), contact(Vector::NEG_Y)];
        let owner = PressOwner {
            tool: ColliderHandle::invalid(),
            friction: Friction::default(),
            grasp: false,
            holder: None,
        };
        let mut pressed = Vec::new();
        let ids = press_all(
            &mut surface,
            &contacts,
            &[Vector::ZERO; 2],
            &[owner, owner],
            &mut pressed,
        );
        assert_eq!(ids.len(), 2);
        assert!(ids[0].is_none() && ids[1].is_some(), "{ids:?}");
        assert_eq!(pressed.len(), 1);
        let moved = surface.position(v) - before;
        assert!(
            (moved - Vector::new(0.0, -0.01, 0.0)).length() < 1e-6,
            "{moved:?}"
        );
    }
}
