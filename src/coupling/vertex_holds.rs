//! How a rigid tool holds the surface vertices it contains in one surface substep: every vertex
//! inside the tool is walked back along its inverse trajectory relative to the tool to the
//! tool's boundary (eq. 1-2 for one vertex) and held there, a moving pin inside the filter;
//! the tool gets the reaction of the vertices it holds.

use super::friction::{settle, Contact, Friction, Settled, Sticks};
use super::tool_shape::contact_margin;
use crate::geometry::tool_boundary::{
    distance_outside, exit_along, nearest_on_boundary, outward_normal_toward,
};
use crate::math::{Pose, Real, Vector};
use crate::surface::MassSpringSurface;
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::geometry::ColliderHandle;

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
    /// The momentum the tool gave the vertices it took hold of, kept or let go (their velocity
    /// changes times their masses; surface frame).
    pub given: glamx::DVec3,
}

/// Moves every surface vertex the tool contains out of it and holds it there (see [`Holds`]).
///
/// A vertex that just entered is walked back along its inverse trajectory relative to the tool
/// (eq. 1-2 for one vertex): from where it is, back along its own motion over the substep minus
/// the tool's, to the tool's boundary, and slides on from there along the face it entered by
/// for the rest of the substep ([`slid_on`]). A vertex already in contact slides: it is
/// snapped to the nearest boundary point, keeps its own tangential velocity and takes the
/// tool's normal velocity. With friction ([`super::friction`]) a vertex that sticks is carried
/// by the tool's material point it stuck to, with that point's whole velocity, until its
/// tangential force passes the static limit; a slipping vertex is pulled back by kinetic
/// friction. A grasping tool keeps every vertex it touches stuck, pulled or pushed, until it
/// lets go.
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
    // (vertex, normal, contact point in the tool's frame, stuck in the last substep, the way
    // from the tool to a vertex found outside it, its velocity before the hold)
    let mut held: Vec<(u32, Vector, Vector, bool, Option<Vector>, Vector)> = Vec::new();
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
                        .map_or(nearest, |q| slid_on(shape, pose, *p, q, rel, margin))
                } else {
                    nearest
                };
                (out, pose.inverse_transform_point(out))
            }
        };
        if !out.is_finite() {
            continue;
        }
        // A sliding vertex held in the last substep that is now outside the tool, carried
        // there by its own motion along the face it was held on (more than 60° from that
        // face's normal): it slid off the face, past an edge or a corner, and is let go where
        // it is. (A vertex left outside by the tool's motion, or lifted off a curved tool by
        // its curvature, is still in contact: put back below unless its springs pull it
        // away.) A tilted U's leg held a plate vertex on its bottom edge while the leg's
        // corner pressed the triangle beside it with 0.78 of the point's weight on the
        // vertex: the press's push slid the vertex along the leg's bottom, off the edge, in
        // every substep, the hold put it back by position alone, and the press pushed its two
        // free neighbours down after it: the tool's force read 6.14 N for the pins' 6.38 N.
        // Let go, the vertex rests outside the leg and the corner's press holds the triangle.
        if stuck.is_none() && !entering && gap > margin {
            let was = surface.last_held_normal(iu);
            let slid_off = (*p - out).try_normalize().is_some_and(|away| {
                was != Vector::ZERO && own.dot(away) > 0.5 * gap && away.dot(was).abs() < 0.5
            });
            if slid_off {
                continue;
            }
        }
        // The tool's outward normal at the contact point (at an edge or a corner, the face
        // the vertex's springs push it against), and the vertex's way back onto it.
        let push = pose.rotation.inverse() * -surface.internal_force(iu);
        let n = pose.rotation * outward_normal_toward(shape, local, margin, push);
        let moved = out - *p;
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
        let before = surface.velocity(iu);
        if surface.set_state(iu, out, v).is_ok() {
            let _ = if stuck.is_some() {
                surface.hold(iu)
            } else {
                surface.hold_sliding(iu, n)
            };
            // A vertex the tool left behind (outside it) is away from it along the way back
            // from the tool's nearest point, which under an edge or a corner is not the
            // face's normal `n`.
            let away = (gap > margin).then(|| (-moved).try_normalize()).flatten();
            held.push((iu, n, local, stuck.is_some(), away, before));
        }
    }
    // Contact only pushes: a held vertex whose springs pull it away from the tool (it would
    // stick to a receding tool) is let go; away is along the normal, and for a vertex found
    // outside the tool also along the way from the tool to it (under an edge). The others
    // stick or slip (friction), and the tool receives their spring and damper forces: the
    // normal part, and the tangential part of those that stick, or kinetic friction for those
    // that slip.
    let mut out = Holds {
        force: Vector::ZERO,
        moment: Vector::ZERO,
        count: 0,
        sticking: 0,
        vertices: Vec::new(),
        contacts: Vec::new(),
        given: glamx::DVec3::ZERO,
    };
    // A vertex moving over the tool slower than this (a millionth of the tool's size per
    // substep) is at rest on it.
    let slip_eps = if h > 0.0 {
        1e-6 * aabb.extents().max_element() / h
    } else {
        Real::MAX
    };
    for &(i, n, local, was_stuck, away, before) in &held {
        let f = surface.internal_force(i);
        let (on_tool, next) = if grasp {
            // Grasped: stuck whatever its springs do, pulled or pushed; the tool feels it all.
            (f, Settled::Stick)
        } else if f.dot(n) >= 0.0 || away.is_some_and(|d| f.dot(d) >= 0.0) {
            surface.release(i);
            if let Some(&(_, p, v)) = followed.iter().find(|f| f.0 == i) {
                // A vertex that only followed the tool separates where its own motion took it.
                let _ = surface.set_state(i, p, v);
            } else if (surface.velocity(i) - before).dot(n) < 0.0 {
                // Nor does a vertex let go keep a pull: one the hold gave the tool's normal
                // velocity toward it (a vertex found a hair inside a receding wall) leaves
                // with its own. Kept, that pull sped a plate vertex beside a cylinder's side up
                // toward it at every substep, each time let go: at a 4 kHz surface step a
                // slow cylinder put 7 mJ into a heavy plate in 2 s, its reaction reading no
                // work (the vertices' springs along the wall's normal).
                let _ = surface.set_state(i, surface.position(i), before);
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
    out.given = held
        .iter()
        .map(|&(i, .., before)| ((surface.velocity(i) - before) * surface.mass(i)).as_dvec3())
        .sum();
    // This tool's contacts end where it let the vertex go.
    sticks.retain(|v, s| s.0 != tool || surface.is_held(*v) && held.iter().any(|h| h.0 == *v));
    out
}

/// Where a vertex that entered the tool at `q` over the substep (found at `p`, inside, its
/// motion relative to the tool `-rel`) ends it: after `q` it slides along the face it entered
/// by, its normal motion stopped there and its tangential motion kept (as its velocity is):
/// `p` put on that face's plane, then on the tool's boundary (a curved face's).
///
/// The paper leaves the vertex at `q`, where it entered. That is right for a vertex coming in
/// along the normal, and wrong for one grazing in: its tangential velocity is kept, its
/// tangential motion was not, and the springs sped it up where it could not move. A plate
/// vertex lying on a cube's face that circled over it entered by a micrometre at every
/// substep, was put back where it had been, and reached 4 m/s in place, the plate's energy
/// rising from 1.4 mJ to 65 mJ in 2.4 s under a tool that did 0.1 µJ of work a step.
fn slid_on(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    p: Vector,
    q: Vector,
    rel: Vector,
    margin: Real,
) -> Vector {
    let out_of = pose.rotation.inverse() * rel.normalize_or_zero();
    let n = pose.rotation
        * outward_normal_toward(shape, pose.inverse_transform_point(q), margin, out_of);
    let on_plane = p - n * (p - q).dot(n);
    let out = nearest_on_boundary(shape, pose, on_plane);
    if out.is_finite() && (out - q).length() <= (p - q).length() + margin {
        out
    } else {
        q
    }
}
