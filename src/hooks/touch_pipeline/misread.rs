//! Where the step guard does not take rapier's contact points (or its own reading of a graze)
//! at their word: rapier's points are parry's `f32` queries on world coordinates, which go wrong
//! on a body far smaller than its still partner (a sub-millimetre body, or a plate hundreds of
//! times the body's size). These checks ask `geometry::contact_near` instead
//! ([`parry_overlap_within`]): on coordinates scaled to the smaller shape, of a huge box only
//! its part near the mover.

use super::pair_view::parry_overlap_within;
use crate::geometry::ContactConfiguration;
use crate::math::{Pose, Real, Vector};
use rapier3d::geometry::Collider;

/// Whether rapier's depth when the step began, `depth_at_start`, for the mover `co` (at
/// `prev_pose` then) against the still `partner` (at `partner_prev` then), is a misreading: it
/// claims more than `claim_from` (a quarter of the mover's thinnest extent, at least the resting
/// slop), and the scaled query reads less than half of it, or the pair apart. A 0.14 mm hull
/// skimming a 5 µm plate 300 times its size was held 134 µm deep, along a normal out of the
/// plate's bottom: the guard took it as a resting pair that deep, then pushed it down through
/// the plate. (Checked from the resting slop on, the CCD stress scene cost 12 % more.)
pub(super) fn depth_misread(
    depth_at_start: Real,
    claim_from: Real,
    (partner, partner_prev): (&Collider, &Pose),
    (co, prev_pose): (&Collider, &Pose),
) -> bool {
    depth_at_start > claim_from
        && parry_overlap_within((partner, partner_prev), (co, prev_pose), 0.0)
            .is_some_and(|(overlap, _)| overlap < 0.5 * depth_at_start)
}

/// Whether the mover `co` (at `prev_pose` when the step began) touched the still `partner` (at
/// `partner_prev` then) within `slop`, by the scaled query. rapier's manifold may miss such a
/// pair: it held no point for a 1 km hull lying 0.2 m into a 100 km plate (parry's query on the
/// whole plate read them 17 m apart a step before), and read a 1 mm hull on a plate 300 times
/// its size apart along a normal 45° off the plate's; walked back along their paths as first
/// touches, both stopped dead.
pub(super) fn touching_at_start(
    (partner, partner_prev): (&Collider, &Pose),
    (co, prev_pose): (&Collider, &Pose),
    slop: Real,
) -> bool {
    parry_overlap_within((partner, partner_prev), (co, prev_pose), slop)
        .is_some_and(|(overlap, _)| overlap > -slop)
}

/// The normal of `config`'s first patch, turned out of the convex `partner` (at
/// `partner_pose`): away from the partner's centre of mass, which lies inside it, at the
/// patch's contact point. Turned instead toward where the body came from along its path, as
/// for an open mesh's triangles, a path nearly parallel to the surface is a coin toss: a 697 m
/// capsule whose path rose by 0.5 % as it grazed a plate 50 times its size had its normal
/// turned into the plate, and its push out went 494 m down through the 28 m plate.
pub(super) fn normal_out_of_convex(
    config: &ContactConfiguration,
    (partner, partner_pose): (&Collider, &Pose),
) -> Option<Vector> {
    let p = config.patches.first()?;
    let middle = partner_pose.transform_point(partner.shape().mass_properties(1.0).local_com);
    Some(if p.normal.dot(p.center() - middle) < 0.0 {
        -p.normal
    } else {
        p.normal
    })
}

/// How deep the mover `co` overlapped the still convex `partner` when the step began (at
/// `prev_pose`, `partner_prev`), by the scaled query, where it is now deeper than that, and
/// than `keep`, by more than `tolerance` (at `pose_now`, `partner_pose`); `None` otherwise.
/// For a pair rapier holds points for that read it apart at the step's start and now, whose
/// path has no first touch (it overlapped already): a manifold rapier computed while the body
/// was tilted, with one corner's point and that tilt's normal, and recycled since. A 43 cm box
/// dropped at 23 m/s across three tiles' seams came to rest flat 0.9 and then 1.25 mm into
/// all three, while their manifolds read it apart along a normal 1.8° off the tiles' (rapier's
/// `swept_partners` property, seed 5117): neither a resting pair nor a first touch, the guard
/// left it.
pub(super) fn deeper_than_at_start(
    (partner, partner_prev, partner_pose): (&Collider, &Pose, &Pose),
    (co, prev_pose, pose_now): (&Collider, &Pose, &Pose),
    (keep, tolerance): (Real, Real),
) -> Option<Real> {
    if !partner.shape().is_convex() {
        return None;
    }
    let (now, _) = parry_overlap_within((partner, partner_pose), (co, pose_now), 0.0)?;
    if now <= keep + tolerance {
        return None;
    }
    let (start, _) = parry_overlap_within((partner, partner_prev), (co, prev_pose), 0.0)?;
    let start = start.max(0.0);
    (now > start.max(keep) + tolerance).then_some(start)
}
