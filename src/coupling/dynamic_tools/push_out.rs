//! A dynamic tool found overlapping the surface past its slop is moved out, not the surface.

use super::DynamicTool;
use crate::coupling::pressing::PressOwner;
use crate::geometry::SurfaceContact;
use crate::math::{Pose, Real, Rotation, Vector};

/// Sweeps of the projected Gauss-Seidel solve below (its rows are one body's contacts, of rank
/// six at most), which leaves part of the overlap where the rows disagree: what is left is
/// pressed into the surface as before. Over the dynamic tests' 112,000 solves (CI's seed) half
/// its answers left none of the deepest overlap and nine in ten at most 13 %; solved out (200
/// sweeps: nine in ten within 2.6e-3), resting bodies were pushed about at every substep and
/// did not settle (a column's box still turning at 0.058 rad/s after 10 s, a U on a soft
/// plate bouncing at 1.6 cm/s, against 0.05 rad/s and 1 cm/s allowed).
const SWEEPS: usize = 30;

/// Moves each dynamic tool (`dynamic`, by the contacts' `owners`' holder index) out of the
/// contacts it overlaps by more than nothing (`contacts`, surface frame, the surface's body at
/// `body_pose`; depths already less the tool's slop): the least mass-weighted shift of its pose
/// (translation and turn about its centre of mass) that leaves none of its contacts below
/// the surface (as far as [`SWEEPS`] sweeps get), with the contacts' points carried along and their depths less what the shift
/// took off (zero for those it met, more negative for those it left). Its velocities are
/// unchanged. A contact `on_pins` (on a triangle with a pinned vertex, which the surface holds
/// in its step's solve without moving anything: [`crate::surface::MassSpringSurface::press_points`])
/// only keeps the shift from taking the tool deeper into it: pushed out of a plate's pinned rim
/// too, a box tipping over it was lifted a little every substep, and gained up to 0.55 J of
/// height in a 0.18 J scene. Returns whether any tool moved.
///
/// Pressing the surface out instead (the press's position change, which stays for kinematic
/// tools, whose motion nothing changes) stored energy in the surface's springs that the body
/// never paid for: a 2.5 g cylinder whose standing edge came to cross a 12 g plate's edge by
/// 2 mm pushed two vertices 2 mm along the plate, 8 mJ in a scene of 0.9 mJ. Moving the body
/// changes no velocity; at rest it costs what pressing the surface costs (its weight times the
/// shift, against the load the pressed vertices carry times theirs).
pub(crate) fn push_out_bodies(
    contacts: &mut [SurfaceContact],
    owners: &[PressOwner],
    dynamic: &mut [DynamicTool],
    body_pose: &Pose,
    on_pins: impl Fn(&SurfaceContact) -> bool,
) -> bool {
    let mut moved = false;
    for (j, d) in dynamic.iter_mut().enumerate() {
        let mine: Vec<(usize, bool)> = (0..contacts.len().min(owners.len()))
            .filter(|&i| owners[i].holder == Some(j))
            .map(|i| (i, on_pins(&contacts[i])))
            .collect();
        if !mine
            .iter()
            .any(|&(i, pinned)| !pinned && contacts[i].depth > 0.0)
        {
            continue;
        }
        let centre = d.centre();
        // Each contact's row (world): the tool's point must move by at least `depth` against
        // the normal: -(δt · n + δθ · (r × n)) ≥ depth.
        let rows: Vec<(Vector, Vector, Real, Real)> = mine
            .iter()
            .map(|&(i, pinned)| {
                let c = &contacts[i];
                let n = body_pose.rotation * c.normal;
                let r = body_pose.transform_point(c.point) - centre;
                let (lin, ang) = (-n, -r.cross(n));
                let diag = lin.dot(d.inverse_mass * lin) + ang.dot(d.inverse_inertia * ang);
                let depth = if pinned { c.depth.min(0.0) } else { c.depth };
                (lin, ang, depth, diag)
            })
            .collect();
        let (mut shift, mut turn) = (Vector::ZERO, Vector::ZERO);
        let mut lambda = vec![0.0; rows.len()];
        for _ in 0..SWEEPS {
            for (l, &(lin, ang, depth, diag)) in lambda.iter_mut().zip(&rows) {
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
        if !(shift.is_finite() && turn.is_finite())
            || (shift == Vector::ZERO && turn == Vector::ZERO)
        {
            continue;
        }
        let rotation = Rotation::from_scaled_axis(turn);
        let new_centre = centre + shift;
        d.pose = Pose::from_parts(
            new_centre - (rotation * d.pose.rotation).normalize() * d.local_com,
            (rotation * d.pose.rotation).normalize(),
        );
        d.touched = true;
        moved = true;
        let to_surface = body_pose.inverse();
        for (&(i, _), &(lin, ang, _, _)) in mine.iter().zip(&rows) {
            let c = &mut contacts[i];
            let p = body_pose.transform_point(c.point);
            let p = new_centre + rotation * (p - centre);
            c.point = to_surface.transform_point(p);
            c.depth -= lin.dot(shift) + ang.dot(turn);
        }
    }
    moved
}
