//! Property tests of the reconstruction over random convex polyhedra, random non-convex closed
//! meshes, random poses and motions: after the reversing vector the objects touch without
//! penetrating, a further step along D penetrates, the reversing vector is parallel to -D, it
//! agrees with parry's linear shape cast for convex pairs, and swapping which object moves
//! gives the same contact.

use crate::common::strategies::{direction, rotation, vec3};
use crate::common::{shifted, surface_distance, surfaces_intersect};
use parry3d::query::{self, ShapeCastOptions};
use proptest::prelude::*;
use rapier_touch::geometry::generators::{icosphere, subdivided_box};
use rapier_touch::prelude::*;

/// A random convex polyhedron, as a parry support-map shape and as its touch mesh (the exact
/// hull of the shape's points: parry's own `f32` quickhull of the raw points can leave points
/// outside by ~1e-4, and `ConvexPolyhedron::to_trimesh` triangulates merged, slightly
/// non-planar faces).
fn convex() -> impl Strategy<Value = (ConvexPolyhedron, TouchMesh)> {
    prop::collection::vec(vec3(), 8..20).prop_filter_map("non-degenerate hull", |pts| {
        let c = ConvexPolyhedron::from_convex_hull(&pts)?;
        let e = parry3d::shape::Shape::compute_local_aabb(&c).extents();
        (e.min_element() > 0.3).then(|| (c.clone(), TouchMesh::from_shape(&c).unwrap()))
    })
}

/// A convex mesh of one of three kinds: the hull of random points, a box whose faces are split
/// into coplanar triangles (flat plateaus for hill climbing), or an icosphere.
fn convex_mesh() -> impl Strategy<Value = TouchMesh> {
    prop_oneof![
        convex().prop_map(|(_, m)| m),
        (vec3(), 1u32..4).prop_map(|(h, n)| {
            let (v, i) = subdivided_box(h.abs() * 0.5 + Vector::splat(0.1), n);
            TouchMesh::new(v, i).unwrap()
        }),
        (0.2f32..0.8, 1u32..3).prop_map(|(r, n)| {
            let (v, i) = icosphere(r, n);
            TouchMesh::new(v, i).unwrap()
        }),
    ]
}

/// A star-shaped closed mesh: an icosphere whose vertices are pushed in or out.
fn lumpy_sphere() -> impl Strategy<Value = TouchMesh> {
    prop::collection::vec(0.6f32..1.3, 42).prop_map(|radii| {
        let (v, i) = icosphere(1.0, 1);
        let v = v.iter().zip(&radii).map(|(p, r)| *p * *r).collect();
        TouchMesh::new(v, i).unwrap()
    })
}

/// Places `moving` (orientation `rot`) `pen` past its first touch with `fixed` along `u`,
/// starting 4 m away with a lateral offset. Returns (prev, now, exact first-touch pose), or
/// `None` when the path misses.
fn approach(
    fixed: &dyn parry3d::shape::Shape,
    pose_f: &Pose,
    moving: &dyn parry3d::shape::Shape,
    rot: Rotation,
    u: Vector,
    lateral: Vector,
    pen: f32,
) -> Option<(Pose, Pose, f32)> {
    let lateral = lateral.reject_from(u) * 0.5;
    let prev = Pose::from_parts(pose_f.translation - 4.0 * u + lateral, rot);
    let hit = query::cast_shapes(
        pose_f,
        Vector::ZERO,
        fixed,
        &prev,
        u,
        moving,
        ShapeCastOptions::with_max_time_of_impact(10.0),
    )
    .ok()??;
    let now = shifted(&prev, (hit.time_of_impact + pen) * u);
    Some((prev, now, hit.time_of_impact))
}

fn check_touching(
    fixed: &TouchMesh,
    pose_f: &Pose,
    moving: &TouchMesh,
    now: &Pose,
    c: &ContactConfiguration,
    u: Vector,
    shapes: Option<(&dyn parry3d::shape::Shape, &dyn parry3d::shape::Shape)>,
) -> Result<(), TestCaseError> {
    let scale = fixed.scale().max(moving.scale());
    let at = shifted(now, c.reversing_vector);
    // Parallel to -D.
    prop_assert!(c.reversing_vector.cross(u).length() <= 1e-5 * c.depth.max(1e-3));
    prop_assert!(c.reversing_vector.dot(u) <= 0.0);
    // Touching.
    let d = surface_distance(fixed, pose_f, moving, &at);
    prop_assert!(d <= 1e-5 * scale, "distance after reversal {d}");
    // Not penetrating: a hair behind, the surfaces are apart. Walking back by δ separates them
    // by δ |n·u| (n the contact normal), so δ is chosen for a 1e-4·scale gap, which parry's f32
    // GJK resolves; up to the start of the step the way back is free by definition.
    let nu = c
        .patches
        .iter()
        .map(|p| p.normal.dot(u).abs())
        .fold(1.0f32, f32::min)
        .max(1e-3);
    let behind = shifted(&at, -(1e-4 * scale / nu) * u);
    // Surfaces that still touch behind (distance 0) may only slide along each other: when the
    // original convex shapes are at hand, parry's contact query says how deep they are there.
    let grazing = shapes.is_some_and(|(a, b)| {
        query::contact(pose_f, a, &behind, b, 0.0)
            .ok()
            .flatten()
            .is_none_or(|k| k.dist >= -1e-5 * scale)
    });
    prop_assert!(
        grazing || !surfaces_intersect(fixed, pose_f, moving, &behind),
        "penetrates after reversal: distance behind {}, at {}, state {:?}, depth {}",
        surface_distance(fixed, pose_f, moving, &behind),
        d,
        c.state,
        c.depth
    );
    // A further epsilon along D penetrates.
    let ahead = shifted(&at, 1e-3 * scale * u);
    prop_assert!(
        surfaces_intersect(fixed, pose_f, moving, &ahead),
        "epsilon ahead does not touch"
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn convex_pairs_touch_after_reversal_and_agree_with_shape_cast(
        (a, fixed) in convex(), (b, moving) in convex(), rf in rotation(), rm in rotation(),
        u in direction(), lateral in vec3(), frac in 0.02f32..0.4,
    ) {
        let pose_f = Pose::from_parts(Vector::new(0.3, -0.2, 0.1), rf);
        let pen = frac * safe_step_length(&fixed, &moving);
        let Some((prev, now, toi)) = approach(&a, &pose_f, &b, rm, u, lateral, pen) else {
            return Err(TestCaseError::reject("path misses"));
        };
        let mut rec = Reconstructor::default();
        let c = rec.reconstruct(&fixed, &pose_f, &moving, &now, &prev).unwrap();
        // `pen` is below the smallest box edge, not the smallest width along `u`: a thin part
        // can be passed right through. parry's own contact query says which it is.
        let expected = match query::contact(&pose_f, &a, &now, &b, 0.0) {
            Ok(Some(k)) if k.dist < -1e-5 => TouchState::Penetrating,
            Ok(None) => TouchState::Perforated,
            _ => return Err(TestCaseError::reject("grazing: parry's depth is below tolerance")),
        };
        prop_assert_eq!(c.state, expected);
        prop_assert!(c.on_trajectory);
        // Agrees with parry's linear shape cast from the pre-step pose.
        let len = toi + pen;
        check_touching(&fixed, &pose_f, &moving, &now, &c, u, Some((&a, &b)))?;
        let cast_pose = shifted(&now, -pen * u);
        let ours = shifted(&now, c.reversing_vector);
        let contact_dist = |p: &Pose| {
            parry3d::query::contact(&pose_f, &a, p, &b, 0.01).ok().flatten().map(|c| c.dist)
        };
        // parry's cast stops on a distance tolerance, so at grazing angles its time of impact
        // can be off by more than 1e-4 along the motion; where the two disagree, parry's own
        // contact query must find our pose touching and the cast's pose farther from touch.
        let agree = (c.depth - pen).abs() <= 1e-4 * len;
        let ours_better = match (contact_dist(&ours), contact_dist(&cast_pose)) {
            (Some(d_ours), Some(d_cast)) => {
                d_ours.abs() <= 1e-5 * fixed.scale().max(moving.scale()) && d_cast.abs() > d_ours.abs()
            }
            _ => false,
        };
        prop_assert!(
            agree || ours_better,
            "depth {} vs cast {} (len {}): parry contact dist at the cast's pose {:?}, at ours {:?}",
            c.depth,
            pen,
            len,
            contact_dist(&cast_pose),
            contact_dist(&ours)
        );
        prop_assert!(!c.patches.is_empty());

        // Swapping which object moves: the other one moved by -D.
        let d = now.translation - prev.translation;
        let s = rec.reconstruct(&moving, &now, &fixed, &pose_f, &shifted(&pose_f, d)).unwrap();
        prop_assert_eq!(s.state, expected);
        prop_assert!((s.depth - c.depth).abs() <= 1e-5 * fixed.scale().max(moving.scale()));
        prop_assert!((s.reversing_vector + c.reversing_vector).length() <= 1e-5 * len);
        let mut k1: Vec<_> = c.patches.iter().map(|p| p.kind as u8).collect();
        let mut k2: Vec<_> = s.patches.iter().map(|p| p.kind as u8).collect();
        k1.sort();
        k2.sort();
        prop_assert_eq!(k1, k2);
    }

    #[test]
    fn non_convex_pairs_touch_after_reversal(
        fixed in lumpy_sphere(), moving in lumpy_sphere(), rf in rotation(), rm in rotation(),
        u in direction(), lateral in vec3(), frac in 0.02f32..0.3,
    ) {
        let pose_f = Pose::from_parts(Vector::ZERO, rf);
        let pen = frac;
        let Some((prev, now, _)) = approach(
            fixed.trimesh(), &pose_f, moving.trimesh(), rm, u, lateral, pen,
        ) else {
            return Err(TestCaseError::reject("path misses"));
        };
        let mut rec = Reconstructor::default();
        let c = rec.reconstruct(&fixed, &pose_f, &moving, &now, &prev).unwrap();
        prop_assert!(c.needs_correction(), "state {:?}", c.state);
        prop_assert!((c.depth - pen).abs() <= 1e-4 * (4.0 + pen), "depth {} vs cast {}", c.depth, pen);
        check_touching(&fixed, &pose_f, &moving, &now, &c, u, None)?;

        let d = now.translation - prev.translation;
        let s = rec.reconstruct(&moving, &now, &fixed, &pose_f, &shifted(&pose_f, d)).unwrap();
        prop_assert!((s.depth - c.depth).abs() <= 1e-5 * fixed.scale().max(moving.scale()));
        prop_assert_eq!(s.patches.len(), c.patches.len());
    }

    /// With no translation the fallback direction still ends touching.
    #[test]
    fn zero_motion_falls_back_and_ends_touching(
        (a, fixed) in convex(), (b, moving) in convex(), rm in rotation(), u in direction(), frac in 0.05f32..0.4,
    ) {
        let pen = frac * safe_step_length(&fixed, &moving);
        let Some((_, now, _)) = approach(&a, &Pose::IDENTITY, &b, rm, u, Vector::ZERO, pen) else {
            return Err(TestCaseError::reject("path misses"));
        };
        if !matches!(query::contact(&Pose::IDENTITY, &a, &now, &b, 0.0), Ok(Some(k)) if k.dist < -1e-5) {
            return Err(TestCaseError::reject("passed through a thin part: nothing to undo"));
        }
        let c = Reconstructor::default()
            .reconstruct(&fixed, &Pose::IDENTITY, &moving, &now, &now)
            .unwrap();
        prop_assert_eq!(c.direction_source, DirectionSource::ZeroMotionFallback);
        prop_assert_eq!(c.state, TouchState::Penetrating);
        check_touching(&fixed, &Pose::IDENTITY, &moving, &now, &c, c.direction, None)?;
    }

    /// The convex path (GJK first touch, local exact events) and the general branch-and-bound
    /// search give the same state, depth and contact kinds for random convex pairs in random
    /// poses: separated, touching, penetrating, perforated, with and without motion.
    #[test]
    fn convex_path_agrees_with_the_general_search(
        fixed in convex_mesh(), moving in convex_mesh(), rf in rotation(), rm in rotation(),
        offset in vec3(), d in vec3(), still in prop::bool::weighted(0.1),
    ) {
        prop_assert!(fixed.is_convex() && moving.is_convex());
        let pose_f = Pose::from_parts(Vector::new(0.1, -0.2, 0.05), rf);
        let now = Pose::from_parts(pose_f.translation + offset * 0.8, rm);
        let prev = if still { now } else { shifted(&now, -d) };
        let general = ReconstructionOptions { convex_fast_path: false, ..Default::default() };
        let g = Reconstructor::new(general).reconstruct(&fixed, &pose_f, &moving, &now, &prev).unwrap();
        let f = Reconstructor::default().reconstruct(&fixed, &pose_f, &moving, &now, &prev).unwrap();
        let tol = 1e-6 * fixed.scale().max(moving.scale());
        prop_assert_eq!(f.state, g.state, "fast {:?} vs general {:?}", f, g);
        prop_assert!((f.depth - g.depth).abs() <= 10.0 * tol, "depth {} vs {}", f.depth, g.depth);
        prop_assert!((f.reversing_vector - g.reversing_vector).length() <= 10.0 * tol);
        prop_assert_eq!(f.on_trajectory, g.on_trajectory);
        let kinds = |c: &ContactConfiguration| {
            let mut k: Vec<u8> = c.patches.iter().map(|p| p.kind as u8).collect();
            k.sort();
            k
        };
        prop_assert_eq!(kinds(&f), kinds(&g), "fast {:?} vs general {:?}", f.patches, g.patches);
    }
}
