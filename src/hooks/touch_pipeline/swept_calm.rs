//! A fast body's pair with a still partner that stayed within the slop along one axis over
//! the whole step ([`swept_within`]): no first touch to walk back to, no passage through, and
//! left to rapier before its path is reconstructed.
//!
//! On rapier's CCD stress scene (balls, capsules, cones, cylinders and cubes shot at a 200 m
//! floor at 1000 m/s, then bouncing and rolling on it) about two in three of the guard's
//! reconstructions were of bodies faster than the floor's safe step rolling, sliding or
//! bouncing on it, nearly all found touching, apart, or overlapping since the step began (at
//! most one in twenty corrected); this check let 5,100 of its 18,300 go (README, stop 55).

use super::pair_view::{overlap_along, parry_overlap_within};
use super::relative_motion;
use crate::geometry::tool_boundary::rounded;
use crate::geometry::{RigidMotion, TouchMesh};
use crate::hooks::pose_history::PoseHistory;
use crate::math::{Pose, Real, Vector};
use parry3d::shape::Shape;
use rapier3d::geometry::Collider;
use rapier3d::pipeline::PhysicsWorld;

/// Whether the mover `co` (its collider pose `pose_now`, its touch mesh `mesh`) stayed within
/// `slop` of its partner, a collider held still or moved kinematically (at `partner_pose`
/// now), over the whole step: [`swept_within`] along rapier's contact normal `rapier_normal`
/// (out of the partner) when rapier has the pair, along parry's at the pose now otherwise
/// (asked within the pair's relative `travel` over the step and the slop; a pair farther
/// apart is left to the reconstruction, which finds it apart). The mover's path is the one
/// the reconstruction would walk (`relative_motion`).
pub(super) fn stayed_within_slop(
    (world, prev_poses): (&PhysicsWorld, &PoseHistory),
    (partner, partner_pose): (&Collider, &Pose),
    (co, pose_now, mesh): (&Collider, &Pose, &TouchMesh),
    rapier_normal: Option<Vector>,
    (travel, slop): (Real, Real),
) -> bool {
    // (Two support maps: a TriMesh floor is not asked for a normal it has no use for.)
    if partner.shape().as_support_map().is_none() || co.shape().as_support_map().is_none() {
        return false;
    }
    let n = rapier_normal.or_else(|| {
        parry_overlap_within((partner, partner_pose), (co, pose_now), travel + slop)
            .and_then(|(_, n)| n)
    });
    let Some(n) = n else {
        return false;
    };
    let motion = relative_motion(
        prev_poses,
        &world.bodies,
        partner,
        *partner_pose,
        co,
        *pose_now,
        mesh,
    );
    swept_within((partner, partner_pose), co, &motion, n, slop)
}

/// The most samples of the path [`swept_within`] takes; a path that needs more (a body
/// turning fast, far from its centre of mass) is reconstructed.
const MAX_SAMPLES: usize = 16;

/// Whether `mover`, moving relative to `partner` (held at `partner_pose`) along `motion`,
/// overlaps it by no more than `limit` along the unit direction `n` (out of `partner`) at
/// every moment of the step. Then it never got deeper than `limit` into the partner and never
/// passed through it (the overlap along any direction bounds the depth from above).
///
/// The overlap along `n` (the highest point of the partner less the lowest of the mover,
/// [`overlap_along`]) is sampled at evenly spaced moments. Between two samples no point of the
/// mover leaves the straight line between its two places by more than `θ² r s / (8 k²)` along
/// `n`, for `k` intervals, `θ` the angle turned over the step about the axis `a`, `s` the sine
/// of the angle between `a` and `n`, and `r` the farthest the mover's core lies from the
/// centre it turns about ([`core_reach`]): the centre of mass moves on a straight line
/// ([`RigidMotion`]), and a point's offset from it turns about `a` at a constant rate, its
/// part at right angles to `a` (at most `r` long) on a circle in the plane at right angles to
/// `a`; the component along `n` of that circular motion (`n`'s part in that plane is `s`
/// long) has a second derivative of at most `θ² r s`. So the overlap between two samples is at
/// most the larger of theirs plus that. (A box turning flat on a floor about the floor's
/// normal has no bend at all.) `false` when either shape has no
/// support map (a TriMesh, a compound), when the path needs more than [`MAX_SAMPLES`], or when
/// an answer is not finite.
fn swept_within(
    (partner, partner_pose): (&Collider, &Pose),
    mover: &Collider,
    motion: &RigidMotion,
    n: Vector,
    limit: Real,
) -> bool {
    if !(limit > 0.0 && n.is_finite() && motion.is_finite()) {
        return false;
    }
    let theta = motion.angle();
    // Only the part of the offset at right angles to the axis turns, and only the part of `n`
    // at right angles to it sees the turn.
    let (axis, _) = (motion.start.rotation.inverse() * motion.end.rotation).to_axis_angle();
    let across = (motion.start.rotation * axis).cross(n).length().min(1.0);
    let bend = theta * theta * across * core_reach(mover.shape(), motion.local_center) / 8.0;
    // Half the limit for the bend, half for the samples' own overlap.
    let k = if bend <= 0.5 * limit {
        1
    } else {
        (bend / (0.5 * limit)).sqrt().ceil() as usize
    };
    if !(1..=MAX_SAMPLES).contains(&k) {
        return false;
    }
    let margin = limit - bend / (k * k) as Real;
    (0..=k).all(|i| {
        let pose = motion.pose_at(i as Real / k as Real);
        overlap_along((partner, partner_pose), (mover, &pose), n).is_some_and(|o| o <= margin)
    })
}

/// The farthest a point of `shape`'s core lies from `center` (the shape's frame): the shape
/// less its round border (a ball's centre, a capsule's segment, a rounded shape's inner
/// shape), bounded by the corners of its box. A border is the same whichever way the shape
/// turns, so its support along any direction only follows its core.
fn core_reach(shape: &dyn Shape, center: Vector) -> Real {
    let from = |p: Vector| (p - center).length();
    if shape.as_ball().is_some() {
        return center.length();
    }
    if let Some(c) = shape.as_capsule() {
        return from(c.segment.a).max(from(c.segment.b));
    }
    let core = rounded(shape).map_or(shape, |(inner, _)| inner);
    core.compute_local_aabb()
        .vertices()
        .into_iter()
        .map(from)
        .fold(0.0, Real::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rotation;
    use proptest::prelude::*;
    use rapier3d::geometry::{ColliderBuilder, SharedShape};

    /// The movers: every support-map shape a game builds, `k` across.
    fn mover_of(which: usize, k: Real) -> Collider {
        let shape = match which {
            0 => SharedShape::ball(0.5 * k),
            1 => SharedShape::capsule_y(0.5 * k, 0.3 * k),
            2 => SharedShape::cone(0.5 * k, 0.5 * k),
            3 => SharedShape::round_cylinder(0.4 * k, 0.4 * k, 0.05 * k),
            4 => SharedShape::cuboid(0.5 * k, 0.2 * k, 0.35 * k),
            _ => SharedShape::convex_hull(&[
                Vector::new(-0.5, -0.3, -0.2) * k,
                Vector::new(0.6, -0.2, -0.3) * k,
                Vector::new(0.1, 0.5, -0.1) * k,
                Vector::new(0.0, -0.1, 0.6) * k,
                Vector::new(-0.3, 0.4, 0.4) * k,
            ])
            .unwrap(),
        };
        ColliderBuilder::new(shape).build()
    }

    /// The pose that puts `mover`'s lowest point along `n` at `height` over the plane through
    /// `top` (normal `n`), turned by `rotation`, its centre of mass at `center` sideways.
    fn pose_at_height(
        mover: &Collider,
        rotation: Rotation,
        center: Vector,
        (top, n): (Vector, Vector),
        height: Real,
    ) -> Pose {
        let pose = Pose::from_parts(center, rotation);
        let sm = mover.shape().as_support_map().unwrap();
        let low = sm.support_point_toward(&pose, -n);
        Pose::from_parts(center + n * (height - (low - top).dot(n)), rotation)
    }

    proptest! {
        /// Wherever `swept_within` finds a path within the limit, the mover lifted by the limit
        /// along `n` is apart from the partner by parry's intersection test at every one of 400
        /// poses along the path: it never got deeper, and never passed through. Movers of every
        /// support-map shape at 1e-4 to 1e4 m, turning up to a radian about a centre of mass
        /// off their origin, sliding over or dipping into a slab or a thin plate (turned).
        #[test]
        fn a_path_found_within_stays_within_at_every_pose(
            which in 0usize..6,
            k in prop::sample::select(vec![1e-4f32, 1e-2, 1.0, 1e2, 1e4]),
            thin in any::<bool>(),
            h0 in -2.0f32..4.0, h1 in -2.0f32..4.0,
            (sx, sz) in (-3.0f32..3.0, -3.0f32..3.0),
            (ax, ay, az, angle) in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0, 0.0f32..1.0),
            start_turn in 0.0f32..6.0,
            off in 0.0f32..0.3,
            tilt in -0.5f32..0.5,
        ) {
            let partner = ColliderBuilder::cuboid(4.0 * k, if thin { 0.02 * k } else { k }, 4.0 * k)
                .build();
            let partner_pose = Pose::from_parts(
                Vector::new(0.3, -0.7, 0.2) * k,
                Rotation::from_axis_angle(Vector::X, tilt),
            );
            let n = partner_pose.rotation * Vector::Y;
            let top = partner_pose
                .transform_point(Vector::Y * partner.shape().as_cuboid().unwrap().half_extents.y);
            let mover = mover_of(which, k);
            let slop = 2.0e-4 * k;
            let axis = Vector::new(ax, ay, az).try_normalize().unwrap_or(Vector::Z);
            let r0 = Rotation::from_axis_angle(Vector::new(0.3, 1.0, -0.2).normalize(), start_turn);
            let r1 = Rotation::from_axis_angle(axis, angle) * r0;
            let c0 = top + partner_pose.rotation * Vector::new(sx, 0.0, sz) * 0.5 * k;
            let c1 = top + partner_pose.rotation * Vector::new(-sz, 0.0, sx) * 0.5 * k;
            let start = pose_at_height(&mover, r0, c0, (top, n), h0 * slop);
            let end = pose_at_height(&mover, r1, c1, (top, n), h1 * slop);
            let local_center = Vector::new(off, -off, 0.5 * off) * k;
            let motion = RigidMotion::new(start, end, local_center);
            if swept_within((&partner, &partner_pose), &mover, &motion, n, slop) {
                // Checked on the same scene at 1 m (parry's GJK tolerances are absolute), by
                // parry's contact query (its intersection test found a cone 0.8 mm over the
                // slab intersecting it).
                let unit = |p: Pose| Pose::from_parts(p.translation / k, p.rotation);
                let unit_partner = ColliderBuilder::cuboid(4.0, if thin { 0.02 } else { 1.0 }, 4.0)
                    .build();
                let unit_mover = mover_of(which, 1.0);
                for i in 0..=400 {
                    let t = i as Real / 400.0;
                    let depth = parry3d::query::contact(
                        &unit(partner_pose),
                        unit_partner.shape(),
                        &unit(motion.pose_at(t)),
                        unit_mover.shape(),
                        0.0,
                    )
                    .unwrap()
                    .map_or(0.0, |c| -c.dist);
                    prop_assert!(depth <= 2.0e-4 + 1e-5, "{depth} deep at t = {t}");
                }
            }
        }
    }

    /// Not vacuous: a ball rolling a turn over a floor within the slop, and a box sliding a
    /// quarter turn flat on it, are found within; the same box turning a quarter turn about
    /// its centre in place, flat on the floor at both ends, dips a corner into it half-way and
    /// is not (found only by the samples in between: with the bend left out, start and end
    /// alone pass).
    #[test]
    fn rolling_and_sliding_on_a_floor_are_within_and_a_corner_dipping_half_way_is_not() {
        let partner = ColliderBuilder::cuboid(100.0, 0.1, 100.0).build();
        let partner_pose = Pose::translation(0.0, -0.1, 0.0);
        let (top, n) = (Vector::ZERO, Vector::Y);
        let slop = 2.0e-4;
        let ball = mover_of(0, 1.0);
        let rolled = Rotation::from_axis_angle(Vector::Z, -1.0);
        let motion = RigidMotion::new(
            pose_at_height(
                &ball,
                Rotation::IDENTITY,
                Vector::ZERO,
                (top, n),
                0.5 * slop,
            ),
            pose_at_height(&ball, rolled, Vector::X * 0.5, (top, n), 0.1 * slop),
            Vector::ZERO,
        );
        assert!(swept_within(
            (&partner, &partner_pose),
            &ball,
            &motion,
            n,
            slop
        ));
        let cuboid = mover_of(4, 1.0);
        let quarter = Rotation::from_axis_angle(Vector::Y, std::f32::consts::FRAC_PI_2);
        let motion = RigidMotion::new(
            pose_at_height(&cuboid, Rotation::IDENTITY, Vector::ZERO, (top, n), 0.0),
            pose_at_height(&cuboid, quarter, Vector::X * 0.3, (top, n), 0.0),
            Vector::ZERO,
        );
        assert!(swept_within(
            (&partner, &partner_pose),
            &cuboid,
            &motion,
            n,
            slop
        ));
        let on_edge = Rotation::from_axis_angle(Vector::Z, std::f32::consts::FRAC_PI_2);
        let start = pose_at_height(&cuboid, Rotation::IDENTITY, Vector::ZERO, (top, n), 0.0);
        let end = Pose::from_parts(start.translation, on_edge);
        // At the end the box stands on its 0.5 half-extent side: lifted to touch again.
        let end = pose_at_height(&cuboid, end.rotation, end.translation, (top, n), 0.0);
        let motion = RigidMotion::new(start, end, Vector::ZERO);
        let half_way = motion.pose_at(0.5);
        let dip = parry3d::query::contact(
            &partner_pose,
            partner.shape(),
            &half_way,
            cuboid.shape(),
            0.0,
        )
        .unwrap()
        .map_or(0.0, |c| -c.dist);
        assert!(dip > 10.0 * slop, "the corner dips {dip} half-way");
        assert!(!swept_within(
            (&partner, &partner_pose),
            &cuboid,
            &motion,
            n,
            slop
        ));
    }
}
