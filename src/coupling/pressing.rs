//! How a polyhedral tool's sharp features press a surface between its vertices in one surface
//! substep: the geometry layer finds the tool's vertices inside surface triangles and its edges
//! across surface edges ([`crate::geometry::tool_surface_contacts`]); each contact point is
//! pushed onto the tool and held there along the contact normal
//! ([`MassSpringSurface::press_point`]), loading the vertices around it by their weights inside
//! the filter's constraint solve. The tool gets the impulses those holds gave: the press's own
//! velocity change and the next surface step's constraint impulse.

use super::tool_shape::contact_margin;
use crate::geometry::{tool_surface_contacts, SurfaceContact, SurfaceSnapshot, TouchMesh};
use crate::math::{Pose, Real, Vector};
use crate::surface::{MassSpringSurface, PointPress};
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
}

/// Reads the impulses the holds of `pressed` gave up to the end of the surface step just taken
/// (before the surface releases them).
pub(super) fn record_impulses(surface: &MassSpringSurface, pressed: &mut [Pressed]) {
    for p in pressed {
        p.impulse = surface.point_impulse(p.id).unwrap_or(0.0);
    }
}

/// Force (on the tool, surface frame), `Σ p × f` and count of the points `tool` pressed during
/// the surface step just taken (`h` its time step). A hold that pulled (negative impulse)
/// gives no force.
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
        if p.impulse > 0.0 {
            let f = -p.normal * (p.impulse / h);
            force += f;
            moment += p.point.cross(f);
            count += 1;
        }
    }
    (force, moment, count)
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
/// scratch) and appends them to `contacts`, with the tool's velocity along each contact's
/// normal in `velocities`.
#[allow(clippy::too_many_arguments)]
pub(super) fn find_contacts(
    triangles: &[[u32; 3]],
    (candidates, kept): (&[u32], &mut Vec<u32>),
    mesh: &TouchMesh,
    start: &Pose,
    end: &Pose,
    h: Real,
    before: &[Vector],
    now: &[Vector],
    contacts: &mut Vec<SurfaceContact>,
    velocities: &mut Vec<Real>,
) {
    let (query, margin) = part_sweep(mesh, start, end);
    let snapshot = SurfaceSnapshot {
        before,
        now,
        triangles,
    };
    // Keep the triangles whose own bounds over the substep meet the tool's (`part_query`).
    kept.clear();
    kept.extend(candidates.iter().copied().filter(|&t| {
        snapshot
            .swept_bounds(t)
            .is_some_and(|b| b.intersects(&query))
    }));
    let candidates = &kept[..];
    if candidates.is_empty() {
        return;
    }
    let first = contacts.len();
    tool_surface_contacts(&snapshot, candidates, mesh, start, end, margin, contacts);
    for c in &contacts[first..] {
        // The tool's material point under the contact: its velocity along the normal.
        let material = end.inverse_transform_point(c.point);
        velocities.push(if h > 0.0 {
            (c.point - start.transform_point(material)).dot(c.normal) / h
        } else {
            0.0
        });
    }
}

/// Presses every contact (all tools together, so presses sharing a vertex do not undo each
/// other) and records them in `pressed` (`owners[i]`: the tool of `contacts[i]`).
pub(super) fn press_all(
    surface: &mut MassSpringSurface,
    contacts: &[SurfaceContact],
    velocities: &[Real],
    owners: &[ColliderHandle],
    pressed: &mut Vec<Pressed>,
) {
    let presses: Vec<PointPress<'_>> = contacts
        .iter()
        .zip(velocities)
        .map(|(c, &v)| PointPress {
            vertices: c.weights(),
            normal: c.normal,
            depth: c.depth,
            normal_velocity: v,
        })
        .collect();
    // The geometry layer's contacts are finite, with weights on existing vertices: an error
    // here would mean a bug, and then nothing is pressed in this substep.
    let Ok(ids) = surface.press_points(&presses) else {
        return;
    };
    for ((c, id), tool) in contacts.iter().zip(ids).zip(owners) {
        if let Some(id) = id {
            pressed.push(Pressed {
                tool: *tool,
                id,
                normal: c.normal,
                point: c.point,
                impulse: 0.0,
            });
        }
    }
}
