//! A dynamic tool found overlapping the surface past its slop is moved out of the part of the
//! overlap that the surface's point should not take: all but what the tool's fall over the
//! substep made and its plastic impact's share of what its own approach made, and where moving
//! the tool out costs more energy than pressing the surface in, none.

use super::DynamicTool;
use crate::coupling::pressing::PressOwner;
use crate::geometry::SurfaceContact;
use crate::math::{Pose, Real, Rotation, Vector};
use crate::surface::MassSpringSurface;

/// Sweeps of the projected Gauss-Seidel solve below (its rows are one body's contacts, of rank
/// six at most). Over the dynamic tests' 16,000 push-outs (CI's seed) half its answers left at
/// most 4 % of the deepest overlap, nine in ten at most 32 %: where the rows disagree
/// (contacts pushing the body opposite ways) what is left is pressed into the surface as
/// before. At 200 sweeps half left 6e-7 and nine in ten still 37 %.
const SWEEPS: usize = 30;

/// Moves each dynamic tool (`dynamic`, by the contacts' `owners`' holder index) out of the
/// part of its overlap with `surface` that the surface's point should not take (`contacts`,
/// surface frame, the surface's body at `body_pose`; depths already less the tool's slop; a
/// contact's approach is its tool point's velocity (`velocities`) less the surface point's,
/// along its normal, and `h` times it is what the last substep could have driven in). Of the
/// overlap the approach made, the point takes what the tool's fall over the substep made
/// (`fed_approach`) and, of the rest, the tool's share of a plastic impact at the touch
/// (`tool_share`); the tool is moved out of everything else (where that costs less energy than
/// pressing the surface by it, contact by contact, `cheaper_pressed`, and for the shift as a
/// whole): the least mass-weighted shift
/// of its pose (translation and turn about its centre of mass) that takes that part off (as
/// far as [`SWEEPS`] sweeps get). The contacts' points move with it and their depths lose what
/// the shift took off; what is left is pressed into the surface as before. Its velocities are
/// unchanged. Returns whether any tool moved.
///
/// Pressing the surface out (the press's position change, which stays for kinematic tools,
/// whose motion nothing changes) stored energy in the surface's springs that the body never
/// paid for, where the overlap came from the tool's turning or from a feature that came into
/// contact rather than from its approach: a 2.5 g cylinder whose standing edge came to cross a
/// 12 g plate's edge by 2 mm, moving away, pushed two vertices 2 mm along the plate, 8 mJ in a
/// scene of 0.9 mJ; a cube spinning on a light plate, 0.39 mJ at once. Moving the body changes
/// no velocity. Not for the overlap its fall made, nor, for a tool far heavier than the point,
/// the overlap its approach made: moved out of that too, a 7.4 kg dumbbell resting on an 882
/// N/m plate at one substep sank 0.93 mm a substep at 5.6 cm/s and was lifted back each time,
/// never at rest (and its weight's energy made each time). But a light tool's approach is
/// mostly its own: pressed as far as it came, an edge of a 2.3 g cube spinning onto a free
/// 1 kg plate (6 g vertices, 127 N/m) moved two vertices by 13 and 66 um at its first touch,
/// and the springs stored 2.2 uJ, 17 % of the scene's energy, a step before the body paid for
/// it (a rigid holder's press changes no velocity). Nor out of a
/// contact on a triangle with a pinned vertex (which the surface holds in its
/// step's solve without moving anything:
/// [`crate::surface::MassSpringSurface::press_points`]), which only keeps the shift from taking
/// the tool deeper into it: pushed out of a plate's pinned rim too, a box tipping over it was
/// lifted a little every substep and gained up to 0.55 J in a 0.18 J scene.
pub(crate) fn push_out_bodies(
    contacts: &mut [SurfaceContact],
    velocities: &[Vector],
    owners: &[PressOwner],
    dynamic: &mut [DynamicTool],
    surface: &MassSpringSurface,
    body_pose: &Pose,
    h: Real,
) -> bool {
    // The depth contact `c` (`i`) asks the shift to take off; `fed`: how far the tool's fall
    // over the substep drove its point in (`fed_approach`); `tool_inverse`: the tool's inverse
    // effective mass along the contact's normal at its point (its row's diagonal, below).
    let asked =
        |i: usize, c: &SurfaceContact, fed: Real, (tool_inverse, fed_along): (Real, Real)| {
            let weights = c.weights();
            if weights
                .iter()
                .any(|&(v, w)| w > 0.0 && surface.is_pinned(v))
            {
                return c.depth.min(0.0);
            }
            let point: Vector = weights.iter().map(|&(v, w)| surface.velocity(v) * w).sum();
            let tool = velocities.get(i).copied().unwrap_or(Vector::ZERO);
            let approach = h * (tool - point).dot(c.normal).max(0.0);
            if c.depth <= 0.0 {
                return c.depth - approach;
            }
            // Of the overlap its approach made, the surface point keeps what the tool's fall over
            // the substep made (gravity and the other forces rapier's step fed it did that work:
            // a body resting on the surface presses it with its weight), and of the rest only
            // what a plastic impact at the touch would have carried it along since: the tool's
            // share of the two effective masses (`tool_share`).
            let made = c.depth.min(approach);
            let fed = made.min(fed);
            let rest = c.depth - fed - tool_share(c, surface, tool_inverse) * (made - fed);
            // Where shifting the tool out of the rest costs more energy than pressing the surface
            // in by it, the surface takes it (`cheaper_pressed`).
            if rest > 0.0 && cheaper_pressed(c, surface, rest, (fed_along, tool_inverse)) {
                return 0.0;
            }
            rest
        };
    let mut moved = false;
    for (j, d) in dynamic.iter_mut().enumerate() {
        let centre = d.centre();
        // Each of its contacts' row (world): the tool's point must move by at least `depth`
        // against the normal: -(δt · n + δθ · (r × n)) ≥ depth; its diagonal, the tool's
        // inverse effective mass along the normal at the point.
        let rows: Vec<(usize, Vector, Vector, Real, Real)> = (0..contacts.len().min(owners.len()))
            .filter(|&i| owners[i].holder == Some(j))
            .map(|i| {
                let c = &contacts[i];
                let n = body_pose.rotation * c.normal;
                let r = body_pose.transform_point(c.point) - centre;
                let (lin, ang) = (-n, -r.cross(n));
                let diag = lin.dot(d.inverse_mass * lin) + ang.dot(d.inverse_inertia * ang);
                // The acceleration rapier's step fed the tool's point along the normal.
                let fed_along = (d.acceleration + d.angular_acceleration.cross(r)).dot(n);
                let depth = asked(i, c, fed_approach(fed_along, h), (diag, fed_along));
                (i, lin, ang, depth, diag)
            })
            .collect();
        if !rows.iter().any(|&(_, _, _, depth, _)| depth > 0.0) {
            continue;
        }
        let (mut shift, mut turn) = (Vector::ZERO, Vector::ZERO);
        let mut lambda = vec![0.0; rows.len()];
        for _ in 0..SWEEPS {
            for (l, &(_, lin, ang, depth, diag)) in lambda.iter_mut().zip(&rows) {
                if !diag.is_finite() || diag <= 0.0 {
                    continue;
                }
                let gap = depth - (lin.dot(shift) + ang.dot(turn));
                let next = (*l + gap / diag).max(0.0);
                let dl = next - *l;
                *l = next;
                shift += d.inverse_mass * lin * dl;
                turn += d.inverse_inertia * (ang * dl);
            }
        }
        // The shift as a whole: where moving the tool against the acceleration rapier feeds it
        // costs more than pressing the surface by what the shift would take off, the surface
        // takes it (each contact alone may be cheaper moved, while together they lift the
        // body: the U in a funnel, its walls' contacts pushing sideways, was lifted up to 3.8
        // cm and turned 0.42 rad in a substep).
        let lifting: Real = (0..3)
            .filter(|&k| d.inverse_mass[k] > 0.0)
            .map(|k| -d.acceleration[k] * shift[k] / d.inverse_mass[k])
            .sum();
        let pressing: Option<Real> = rows
            .iter()
            .filter(|r| r.3 > 0.0)
            .map(|&(i, _, _, depth, _)| press_energy(&contacts[i], surface, depth))
            .sum();
        if pressing.is_some_and(|p| p < lifting) {
            continue;
        }
        if !(shift.is_finite() && turn.is_finite())
            || (shift == Vector::ZERO && turn == Vector::ZERO)
            || !d.displace(shift, turn)
        {
            continue;
        }
        let rotation = Rotation::from_scaled_axis(turn);
        let new_centre = centre + shift;
        d.touched = true;
        moved = true;
        let to_surface = body_pose.inverse();
        for &(i, lin, ang, _, _) in &rows {
            let c = &mut contacts[i];
            let p = body_pose.transform_point(c.point);
            let p = new_centre + rotation * (p - centre);
            c.point = to_surface.transform_point(p);
            c.depth -= lin.dot(shift) + ang.dot(turn);
        }
    }
    moved
}

/// How far the accelerations rapier's step fed a tool over the substep `h` (gravity, the
/// user's forces: [`DynamicTool::fall`]) drove its point in, from their part along the
/// contact's normal at the point (`fed_along`, world).
fn fed_approach(fed_along: Real, h: Real) -> Real {
    (h * h * fed_along).max(0.0)
}

/// The inverse effective mass of contact `c`'s point of the surface along any direction,
/// `Σ wⱼ² / mⱼ` over its vertices.
fn point_inverse(c: &SurfaceContact, surface: &MassSpringSurface) -> Real {
    c.weights()
        .iter()
        .map(|&(v, w)| w * w / surface.mass(v))
        .sum()
}

/// Whether pressing the surface's point of contact `c` (surface frame) in by `rest` costs less
/// energy than shifting its tool out by as much: the tool's shift works against the
/// acceleration rapier's step feeds its point along the normal (`fed_along`; its effective
/// mass there the inverse of `tool_inverse`); the press, the least mass-weighted motion of the
/// point's vertices ([`MassSpringSurface::press_points`]'s), against their springs' forces now
/// and their stiffness. Neither body's motion made that part of the overlap, so whichever
/// takes it gains energy nobody paid for: the cheaper does. A 7.4 kg U resting in a soft
/// plate's funnel was lifted by up to 1.3 mm a substep (73 mJ a millimetre against its
/// weight, where the surface's points, holding a tenth of it each, would have stored a tenth
/// of that), and it gained 2.35 J and went through. The light bodies on stiff plates the push
/// out was written for still move out (`momentum_books`' thrown bodies, in no gravity: their
/// shift works against nothing, where pressing the plate stored up to 40 mJ in a 4.9 mJ
/// scene). The press's estimate takes each vertex's whole stiffness (the sum of its edges'),
/// more than a plate resists along its normal: where in doubt, the tool moves, as before.
fn cheaper_pressed(
    c: &SurfaceContact,
    surface: &MassSpringSurface,
    rest: Real,
    (fed_along, tool_inverse): (Real, Real),
) -> bool {
    if !(tool_inverse > 0.0 && tool_inverse.is_finite()) {
        return false;
    }
    let shifting = (fed_along / tool_inverse).max(0.0) * rest;
    press_energy(c, surface, rest).is_some_and(|pressing| pressing < shifting)
}

/// The work pressing the surface's point of contact `c` in by `depth` does against the springs
/// of its vertices (the least mass-weighted motion of them, as
/// [`MassSpringSurface::press_points`] moves them: their forces now, and each vertex's whole
/// edge stiffness, more than a plate resists along its normal); `None` where the point's
/// masses are not finite and positive.
fn press_energy(c: &SurfaceContact, surface: &MassSpringSurface, depth: Real) -> Option<Real> {
    let point_inverse = point_inverse(c, surface);
    if !(point_inverse > 0.0 && point_inverse.is_finite()) {
        return None;
    }
    let mu = depth / point_inverse;
    let pressing: Real = c
        .weights()
        .iter()
        .map(|&(v, w)| {
            let moved = w / surface.mass(v) * mu;
            -surface.internal_force(v).dot(c.normal) * moved
                + 0.5 * surface.vertex_stiffness(v) * moved * moved
        })
        .sum();
    pressing.is_finite().then_some(pressing)
}

/// The share of a contact's depth made by its tool's approach that the surface's point keeps:
/// after a plastic impact at the touch, tool and point move on together at the tool's share of
/// their momentum, its effective mass along the contact's normal at its point (the inverse of
/// `tool_inverse`) over the sum of it and the point's (`1 / Σ wⱼ² / mⱼ`). A tool far heavier than the point presses it as far
/// as it came (a dumbbell resting on a plate); a light one carries it by little (a 2.3 g cube
/// spinning onto a plate of 6 g vertices) and is moved out of the rest. 1 where either mass is
/// not finite and positive.
fn tool_share(c: &SurfaceContact, surface: &MassSpringSurface, tool_inverse: Real) -> Real {
    let point_inverse = point_inverse(c, surface);
    let share = point_inverse / (point_inverse + tool_inverse);
    if share.is_finite() && tool_inverse >= 0.0 && point_inverse > 0.0 {
        share.clamp(0.0, 1.0)
    } else {
        1.0
    }
}
