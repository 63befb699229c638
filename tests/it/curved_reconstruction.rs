//! The reconstruction on curved shapes themselves (`Reconstructor::reconstruct_shapes`,
//! `push_out_shapes`), checked against parry's own queries at poses sampled along the path and
//! against an analytic first touch: every curved shape rapier has, turning and translating, at
//! scales from 1e-4 to 1e4.

use crate::common::round_parts;
use parry3d::query;
use parry3d::shape::{Ball, Cuboid, SharedShape};
use proptest::prelude::*;
use rapier_touch::prelude::*;

/// A curved shape of size about `s`, by kind.
fn curved(kind: u8, s: Real) -> SharedShape {
    match kind % 6 {
        0 => SharedShape::ball(0.4 * s),
        1 => SharedShape::capsule_y(0.3 * s, 0.2 * s),
        2 => SharedShape::round_cuboid(0.3 * s, 0.1 * s, 0.2 * s, 0.05 * s),
        3 => SharedShape::cylinder(0.2 * s, 0.3 * s),
        4 => SharedShape::cone(0.25 * s, 0.3 * s),
        _ => SharedShape::round_convex_hull(
            &[
                Vector::new(0.0, 0.0, 0.0) * s,
                Vector::new(0.5, 0.1, 0.0) * s,
                Vector::new(0.1, 0.45, 0.1) * s,
                Vector::new(0.0, 0.1, 0.4) * s,
                Vector::new(0.3, 0.3, 0.3) * s,
            ],
            0.05 * s,
        )
        .expect("five points in general position"),
    }
}

fn distance(
    a: &dyn parry3d::shape::Shape,
    pa: &Pose,
    b: &dyn parry3d::shape::Shape,
    pb: &Pose,
) -> Real {
    signed_distance(a, pa, b, pb).max(0.0)
}

/// The distance between `a` (not rounded) and `b`, negative by the penetration depth when they
/// overlap: parry's queries, except that a rounded `b` is measured as its inner shape less its
/// border radius. parry's GJK on a rounded shape's support map converges to distances
/// millimetres too large near contact (a rounded cuboid within 0.02 mm of a box read 5.0 mm, one
/// overlapping it by 1.4 mm read 3.3 mm apart); on the inner polyhedron it is exact.
fn signed_distance(
    a: &dyn parry3d::shape::Shape,
    pa: &Pose,
    b: &dyn parry3d::shape::Shape,
    pb: &Pose,
) -> Real {
    let (inner, border) = round_parts(b).unwrap_or((b, 0.0));
    let d = query::distance(pa, a, pb, inner).unwrap().distance;
    let d = if d > 0.0 {
        // parry's GJK distance can read a cone's rim a millimetre far where its contact query
        // finds the shapes touching (1.24 mm at a pose between readings of 0.43 mm and 0 along
        // a path, where the contact query read 0.007 mm): the contact query within that
        // distance is taken where it reads less.
        query::contact(pa, a, pb, inner, d)
            .unwrap()
            .map_or(d, |c| c.dist.min(d))
    } else {
        query::contact(pa, a, pb, inner, 0.0)
            .unwrap()
            .map_or(0.0, |c| c.dist.min(0.0))
    };
    d - border
}

#[test]
fn a_ball_falling_onto_a_slab_touches_where_its_radius_says() {
    for &s in &[1e-4, 1e-2, 1.0, 1e2, 1e4] {
        let slab = Cuboid::new(Vector::new(2.0, 0.5, 2.0) * s);
        let ball = Ball::new(0.25 * s);
        let slab_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0) * s);
        // From 0.95 down to -0.05 (times s), turning 1.5 rad about the ball's centre.
        let before = Pose::from_translation(Vector::new(0.1, 0.95, 0.0) * s);
        let now = Pose::from_parts(
            Vector::new(0.0, -0.05, 0.0) * s,
            Rotation::from_rotation_x(1.5),
        );
        let motion = RigidMotion::new(before, now, Vector::ZERO);
        let c = Reconstructor::default()
            .reconstruct_shapes(&slab, &slab_pose, &ball, &motion)
            .unwrap()
            .unwrap();
        assert_eq!(c.state, TouchState::Penetrating, "scale {s}");
        assert!(c.on_trajectory);
        // The centre reaches y = 0.25 s at t = 0.7.
        let t = c.time_of_impact.unwrap();
        assert!((t - 0.7).abs() < 1e-4, "scale {s}: t = {t}");
        assert!(
            (c.touch_pose.translation.y - 0.25 * s).abs() < 1e-4 * s,
            "scale {s}"
        );
        let n = c.patches[0].normal;
        assert!(n.dot(Vector::Y) > 0.999, "scale {s}: normal {n:?}");
    }
}

#[test]
fn a_ball_pushed_out_of_a_slab_along_a_slanted_direction() {
    let slab = Cuboid::new(Vector::new(2.0, 0.5, 2.0));
    let ball = Ball::new(0.25);
    let slab_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
    // The ball's centre 0.1 below the height where it would touch the top face (y = 0).
    let now = Pose::from_translation(Vector::new(0.0, 0.15, 0.0));
    let out = Vector::new(1.0, 1.0, 0.0).normalize();
    let c = Reconstructor::default()
        .push_out_shapes(&slab, &slab_pose, &ball, &now, out)
        .unwrap()
        .unwrap();
    // Along 45°, the centre must rise by 0.1: a way out of 0.1·√2.
    assert_eq!(c.state, TouchState::Penetrating);
    assert!((c.depth - 0.1 * 2.0f32.sqrt()).abs() < 1e-4, "{}", c.depth);
    assert!(distance(&slab, &slab_pose, &ball, &c.touch_pose) < 1e-4);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Any curved shape moving (translating and turning about an off-centre point) toward a
    /// box: the answer agrees with parry's distance at 200 poses sampled along the path. A pair
    /// apart at the start and touching on the path is walked back to a pose within the touch
    /// tolerance of the box, and no sampled pose before it overlaps; a pair apart all along is
    /// never corrected; a pair in contact at the start is not on the path.
    #[test]
    fn first_touch_agrees_with_parry_along_the_path(
        kind in 0u8..6,
        log_scale in -4.0f32..4.0,
        half in (0.2f32..3.0, 0.1f32..1.0, 0.2f32..3.0),
        from in (-1.5f32..1.5, 0.0f32..2.0, -1.5f32..1.5),
        to in (-1.5f32..1.5, -0.5f32..0.6, -1.5f32..1.5),
        turn in (-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0),
        start_turn in (-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0),
        center in (-0.2f32..0.2, -0.2f32..0.2, -0.2f32..0.2),
    ) {
        agrees_with_parry_along_the_path(
            (kind, log_scale),
            half,
            (from, to),
            (turn, start_turn),
            center,
        )?;
    }
}

type Triple = (f32, f32, f32);

/// The property above for one path: a curved shape (`kind`, at scale `10^log_scale`) moving
/// from `from` to `to` (turning by `turn` from `start_turn`, about `center`) toward a box of
/// half-size `half`.
fn agrees_with_parry_along_the_path(
    (kind, log_scale): (u8, f32),
    half: Triple,
    (from, to): (Triple, Triple),
    (turn, start_turn): (Triple, Triple),
    center: Triple,
) -> Result<(), TestCaseError> {
    let s = 10f32.powf(log_scale);
    let shape = curved(kind, s);
    let boxed = Cuboid::new(Vector::new(half.0, half.1, half.2) * s);
    let box_pose = Pose::from_translation(Vector::new(0.1, -half.1, -0.2) * s);
    let q0 = Rotation::from_scaled_axis(Vector::new(start_turn.0, start_turn.1, start_turn.2));
    let q1 = Rotation::from_scaled_axis(Vector::new(turn.0, turn.1, turn.2)) * q0;
    let start = Pose::from_parts(Vector::new(from.0, from.1 + 0.6, from.2) * s, q0);
    let end = Pose::from_parts(Vector::new(to.0, to.1, to.2) * s, q1);
    let motion = RigidMotion::new(start, end, Vector::new(center.0, center.1, center.2) * s);
    let c = Reconstructor::default()
        .reconstruct_shapes(&boxed, &box_pose, shape.as_ref(), &motion)
        .unwrap();
    let Some(c) = c else {
        // (No answer: the mesh method takes over. Allowed, but must be rare.)
        return Ok(());
    };
    // The oracle: parry's distance on the same scene at unit scale (its GJK tolerances are
    // absolute), times the scale.
    let unit_shape = curved(kind, 1.0);
    let unit_box = Cuboid::new(Vector::new(half.0, half.1, half.2));
    let unit_pose = |p: Pose| Pose::from_parts(p.translation / s, p.rotation);
    let unit_motion = RigidMotion::new(
        unit_pose(start),
        unit_pose(end),
        Vector::new(center.0, center.1, center.2),
    );
    let unit_box_pose = unit_pose(box_pose);
    let d_at = |t: Real| {
        s * distance(
            &unit_box,
            &unit_box_pose,
            unit_shape.as_ref(),
            &unit_motion.pose_at(t),
        )
    };
    let depth_at = |t: Real| {
        let pose = unit_motion.pose_at(t);
        s * (-signed_distance(&unit_box, &unit_box_pose, unit_shape.as_ref(), &pose)).max(0.0)
    };
    // How close "touching" is: parry's GJK, which both the crate and this oracle run, is
    // precise to about 1e-3 of the shape near a cone's or a cylinder's rim, and the crate
    // stops short rather than past (a separating plane bounds each advance).
    let touch = 1e-3 * s;
    let start_d = d_at(0.0);
    // Poses along the path (parry's distance is 0 when overlapping).
    let samples: Vec<(Real, Real)> = (0..=200)
        .map(|k| {
            let t = k as Real / 200.0;
            (t, d_at(t))
        })
        .collect();
    if start_d > 2.0 * touch {
        match c.time_of_impact {
            Some(t) => {
                prop_assert!(c.on_trajectory);
                prop_assert!(c.needs_correction());
                // Touching there, within the touch tolerance (plus f32 noise).
                let d = d_at(t);
                prop_assert!(d <= touch, "distance {d} at t = {t}");
                // And not inside the box there.
                let depth = depth_at(t);
                prop_assert!(depth <= touch, "overlap {depth} at the touch t = {t}");
                // Nothing overlapped before (deeper than the touch tolerance).
                for (tk, dk) in &samples {
                    if *tk < t && *dk <= 0.0 {
                        let depth = depth_at(*tk);
                        prop_assert!(
                            depth <= touch,
                            "overlap {depth} at {tk} before the touch at {t}"
                        );
                    }
                }
                // The touch pose is on the path.
                let p = motion.pose_at(t);
                prop_assert!((c.touch_pose.translation - p.translation).length() <= 1e-5 * s);
            }
            None => {
                // Apart along the whole path, or touching only now.
                // (A graze may dip in by less than the touch tolerance.)
                prop_assert!(!c.needs_correction());
                for (t, d) in &samples {
                    if *d <= 0.0 {
                        let depth = depth_at(*t);
                        prop_assert!(
                            depth <= 2.0 * touch,
                            "overlap {depth} at {t} but no touch found"
                        );
                    }
                }
            }
        }
    } else if start_d <= 0.0 {
        prop_assert!(!c.on_trajectory);
    }
    Ok(())
}

/// A case the property above found at four times its cases (`PROPTEST_RNG_SEED=5103`, stop
/// 65): a rounded box turning 2 rad as it slides down across a box dips 2.6 mm into it at
/// `t = 0.83` and comes out, then 2.3 mm at `t = 0.94`, and ends apart. Apart halfway between
/// its first and last touch, it was read as a graze and not corrected; now each of the two
/// stretches is checked, and it is walked back to its first touch.
#[test]
fn a_rounded_box_dipping_into_a_box_twice_is_walked_back_to_its_first_touch() {
    agrees_with_parry_along_the_path(
        (2, 0.0),
        (0.663_719_5, 0.1, 2.121_949_7),
        (
            (-0.363_723_5, 1.099_171_4, 0.0),
            (1.212_056_2, 0.100_603_6, 0.0),
        ),
        (
            (-0.733_723_3, 0.402_168_3, 1.794_831_4),
            (1.523_591_4, 1.592_487_3, -2.744_659_7),
        ),
        (0.0, 0.0, -0.176_290_21),
    )
    .unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// A curved shape (a ball, a capsule lying down, a rounded cylinder, a cylinder, a cone, a
    /// rounded box) sliding over a box 50 to 500 times its size, the straight path of its
    /// centre staying above the box's top by 0.1 % to 20 % of its size at both ends and all
    /// between (the top is a plane, the path a line, and the shape turns only about the
    /// vertical, a ball about any axis), at 1e-4 to 1e4 m: it never touches, so nothing is
    /// corrected and it is never taken through the box, by the shape method or, where that
    /// gives up, the mesh method (as `TouchPipeline` asks them). Checked against the plane's
    /// distance, written here. GJK on the two support maps answered such shapes (a 1 m ball
    /// 3-4 mm over a 200 m box, rapier's CCD stress scene) overlapping at some poses, and the
    /// reconstruction took them through the box, walking them back up to 1.1 of their size
    /// (1-9 % of the cases for the cylinders and capsules of this test).
    #[test]
    fn a_curved_shape_sliding_just_over_a_huge_box_is_never_taken_through_it(
        kind in 0u8..6,
        log_scale in -4.0f32..4.0,
        log_size in 1.7f32..2.7,
        gaps in (-3.0f32..-0.7, -3.0f32..-0.7),
        start_xz in (-0.5f32..0.5, -0.5f32..0.5),
        slide in (-1.0f32..1.0, -1.0f32..1.0),
        turn in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
    ) {
        slides_over_a_huge_box(kind, (log_scale, log_size), gaps, (start_xz, slide), turn)?;
    }
}

/// The property above for one case: shape `kind` of size `10^log_scale` over a box
/// `10^log_size` times it, its path's gaps over the top `10^gaps` of its size, starting at
/// `start_xz` of the box's half-size and sliding by `slide` of its size, turned by `turn`.
fn slides_over_a_huge_box(
    kind: u8,
    (log_scale, log_size): (f32, f32),
    gaps: (f32, f32),
    (start_xz, slide): ((f32, f32), (f32, f32)),
    turn: (f32, f32, f32),
) -> Result<(), TestCaseError> {
    let r = 10f32.powf(log_scale);
    let half = 10f32.powf(log_size) * r;
    let floor = Cuboid::new(Vector::new(half, 0.1 * r, half));
    let floor_pose = Pose::from_translation(Vector::new(0.0, -0.1 * r, 0.0));
    // The shape, and how far its lowest point lies below its centre.
    let (shape, low) = match kind {
        0 => (SharedShape::ball(r), r),
        1 => (SharedShape::capsule_x(r, 0.5 * r), 0.5 * r),
        2 => (SharedShape::round_cylinder(0.5 * r, r, 0.1 * r), 0.6 * r),
        3 => (SharedShape::cylinder(0.5 * r, r), 0.5 * r),
        4 => (SharedShape::cone(0.5 * r, r), 0.5 * r),
        _ => (SharedShape::round_cuboid(r, 0.5 * r, r, 0.1 * r), 0.6 * r),
    };
    let (g0, g1) = (r * 10f32.powf(gaps.0), r * 10f32.powf(gaps.1));
    let from = Vector::new(start_xz.0 * half, low + g0, start_xz.1 * half);
    let to = from + Vector::new(slide.0 * r, g1 - g0, slide.1 * r);
    let q1 = if kind == 0 {
        Rotation::from_scaled_axis(Vector::new(turn.0, turn.1, turn.2))
    } else {
        Rotation::from_rotation_y(turn.1)
    };
    let motion = RigidMotion::new(
        Pose::from_translation(from),
        Pose::from_parts(to, q1),
        Vector::ZERO,
    );
    let mut rec = Reconstructor::default();
    let c = match rec
        .reconstruct_shapes(&floor, &floor_pose, shape.as_ref(), &motion)
        .unwrap()
    {
        Some(c) => c,
        None => {
            let fm = TouchMesh::from_shape(&floor).unwrap();
            let mm = TouchMesh::from_shape(shape.as_ref()).unwrap();
            rec.reconstruct_motion(&fm, &floor_pose, &mm, &motion)
                .unwrap()
        }
    };
    prop_assert!(
        matches!(c.state, TouchState::Separated | TouchState::Touching),
        "{:?}, depth {} of the size",
        c.state,
        c.depth / r
    );
    prop_assert!(!c.needs_correction());
    Ok(())
}

/// Found by the property above with `PROPTEST_RNG_SEED=5121` (also on stop 61's code). A
/// rounded cylinder of unit size sliding over a box 80 times its size, its path 5.3 % and then
/// 0.19 % of its size over the top, was read perforated, 0.62 % of its size deep: the advance
/// found its first touch at 0.9951 of the step, and the advance back from the end (which is in
/// the touch band by parry's contact, not by the advance's bound) its last touch at 0.9995,
/// farther apart than the band, so it went in and out. Now a perforation must overlap halfway
/// between the first and the last touch.
#[test]
fn a_rounded_cylinder_just_over_a_huge_box_is_not_read_through_it() {
    slides_over_a_huge_box(
        2,
        (0.0, 1.902_021),
        (-1.277_019, -2.724_091_5),
        ((0.120_312_06, -0.064_466_074), (-0.854_117_6, 0.946_348)),
        (0.0, -0.760_403_5, 0.0),
    )
    .unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// A curved shape (every kind of `curved`), turned any way, sunk 0.01 % to 3 % of its size
    /// into the top of a box 1 to 1000 times its size placed off the origin, at 1e-4 to 1e4 m,
    /// pushed out along the box's up: the way out is the depth of the shape's lowest point under
    /// the top (its support point, computed here), and the push leaves that point on the top,
    /// not lifted off. Within 1e-3 of the size (parry's GJK near a rim, as above; on a capsule
    /// in a box 7 times its size, not cut down, it read 1.7e-4 of the size off) and two `f32`
    /// steps of the box's coordinates (the inputs' own rounding). The advance that measures the way out stops within its touch band
    /// (ten such steps of the coordinates: 2.7 mm on rapier's 200 m CCD floor): the band was
    /// counted in the depth, and every push lifted the shape off the box by up to that much.
    #[test]
    fn a_push_out_of_a_huge_box_leaves_the_shape_touching_it(
        kind in 0u8..6,
        log_scale in -4.0f32..4.0,
        log_size in 0.3f32..3.0,
        log_depth in -4.0f32..-1.5,
        turn in (-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0),
        off in (-0.4f32..0.4, -0.4f32..0.4),
    ) {
        push_out_of_a_huge_box(kind, log_scale, log_size, log_depth, turn, off)?;
    }
}

/// [`a_push_out_of_a_huge_box_leaves_the_shape_touching_it`]'s case.
fn push_out_of_a_huge_box(
    kind: u8,
    log_scale: f32,
    log_size: f32,
    log_depth: f32,
    turn: (f32, f32, f32),
    off: (f32, f32),
) -> Result<(), TestCaseError> {
    let s = 10f32.powf(log_scale);
    let shape = curved(kind, s);
    let half = 10f32.powf(log_size) * s;
    let plate = Cuboid::new(Vector::new(half, 0.1 * half, half));
    let plate_pose = Pose::from_translation(Vector::new(0.3 * half, -0.1 * half, -0.2 * half));
    let rot = Rotation::from_scaled_axis(Vector::new(turn.0, turn.1, turn.2));
    let depth = 10f32.powf(log_depth) * s;
    let sm = shape.as_support_map().expect("a support map");
    let low = sm
        .support_point_toward(&Pose::from_rotation(rot), -Vector::Y)
        .y;
    let at = Vector::new(
        0.3 * half + off.0 * half,
        -low - depth,
        -0.2 * half + off.1 * half,
    );
    let now = Pose::from_parts(at, rot);
    let c = Reconstructor::default()
        .push_out_shapes(&plate, &plate_pose, shape.as_ref(), &now, Vector::Y)
        .unwrap()
        .expect("a way out");
    // The inputs' rounding: the plate's coordinates, where the shape lies.
    let magnitude = (1.5 * half).max(at.abs().max_element());
    let allowed = 1e-3 * s + 2.0 * 8.0 * Real::EPSILON * magnitude;
    if c.needs_correction() {
        prop_assert!(
            (c.depth - depth).abs() <= allowed,
            "way out {} for a depth {depth} (allowed {allowed})",
            c.depth
        );
        prop_assert!((c.reversing_vector - Vector::Y * c.depth).length() <= 1e-6 * c.depth);
        // The lowest point where the push leaves the shape, against the plate's top (y = 0):
        // above the plate's footprint, that is the gap.
        prop_assert_eq!(c.touch_pose.rotation, rot);
        let gap = c.touch_pose.translation.y + low;
        prop_assert!(
            gap.abs() <= allowed,
            "left {gap} from the plate (allowed {allowed})"
        );
    } else {
        // Touching: within the touch band, ten tolerances of the plate's coordinates.
        let band = 10.0 * 8.0 * Real::EPSILON * 3.0 * half + 1e-3 * s;
        prop_assert!(
            depth <= band,
            "{:?} at a depth {depth} (band {band})",
            c.state
        );
    }
    Ok(())
}

/// Found by the property above on a random seed (stop 63; also on stop 62's code): a cylinder
/// 1.2 mm across, turned, 3.8 µm into the top of a box 23.6 mm wide, was answered `Separated`
/// by the push out, where the test allows a touch only 2.4 µm deep. Mended with the next case.
#[test]
fn a_cylinder_on_its_rim_just_in_a_box_is_pushed_out() {
    push_out_of_a_huge_box(
        3,
        -2.687_602_8,
        0.760_623_2,
        -2.727_72,
        (-1.111_356, -1.961_037_9, 0.340_299_43),
        (0.264_447_6, 0.0),
    )
    .unwrap();
}

/// Found by the property above at four times its cases (`PROPTEST_RNG_SEED=5124`; also on stop
/// 62's code): a cylinder 12.6 m across, turned, 0.67 m into the top of a box 776 m wide, was
/// answered `Separated` by the push out. Coming back down from 30 m out, parry's
/// GJK read the cylinder 6.08 m from the box where it was 0.065 m over it (along a direction
/// the two overlapped 37.5 m along), and the advance stepped past the whole box. The advance
/// now steps by no more than the support points' gap along GJK's direction or the last one
/// the shapes were found apart along (`PairQuery::advance`).
#[test]
fn a_large_cylinder_deep_in_a_box_is_pushed_out() {
    push_out_of_a_huge_box(
        3,
        1.323_542_7,
        1.265_042_4,
        -1.5,
        (-0.315_134_88, 1.290_839, 1.963_457_7),
        (-0.307_401_93, 0.267_967_85),
    )
    .unwrap();
}

/// Found by the property above on a random seed (stop 63's review; also on stop 62's code): a
/// cone of unit size, turned, 3.2 % of its size into the top of a box about twice its size, got
/// no way out (`None`). The advance back toward it stopped at a touch, and parry's contact at
/// that pose read the cone 1.29e-4 away, past twice the 5.6e-5 touch band, so it was refused.
/// The advance's touch is the measure; the contact there, however far, gives the gap left.
#[test]
fn a_cone_pushed_out_of_a_box_gets_a_way_out() {
    push_out_of_a_huge_box(
        4,
        0.0,
        0.313_600_96,
        -1.5,
        (1.768_787_9, 0.388_255_66, -2.292_393_2),
        (-0.082_617_804, 0.245_617_85),
    )
    .unwrap();
}

/// A case the property above found at four times its cases (`PROPTEST_RNG_SEED=5136`, stop
/// 65): a cone 2.5 m across turning as it comes down onto a box ends 0.1 mm into it, and the
/// advance reads the path apart all along. It was pushed out along the end's contact normal (a
/// correction off the path), which the property refuses: a path apart all along is left
/// alone, one that overlaps is walked back to a touch on it. The crossing is now found on the
/// path (bisection on parry's distance) and walked back to.
#[test]
fn a_cone_read_apart_but_ending_in_a_box_is_walked_back_along_its_path() {
    agrees_with_parry_along_the_path(
        (4, 0.396_402_93),
        (1.565_439_2, 0.232_874_7, 2.234_96),
        (
            (-1.367_710_5, 1.276_275_3, -0.558_323_5),
            (-1.144_859_9, 0.387_514_23, -0.579_217_8),
        ),
        (
            (1.805_790_2, -1.913_505_3, -1.157_792_6),
            (0.915_115, -2.396_602_4, 0.360_048_77),
        ),
        (0.051_056_71, 0.088_275_366, 0.027_063_36),
    )
    .unwrap();
}
