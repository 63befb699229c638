//! Bad input gets a clear error or a documented behaviour, never a panic: empty, degenerate,
//! duplicated, open and non-manifold meshes, NaN and infinite poses, perforation.

use crate::common::{shifted, surface_distance};
use proptest::prelude::*;
use rapier_touch::prelude::*;

fn cube(h: f32) -> TouchMesh {
    TouchMesh::from_shape(&Cuboid::new(Vector::splat(h))).unwrap()
}

#[test]
fn empty_and_invalid_meshes_are_errors() {
    assert_eq!(
        TouchMesh::new(vec![], vec![]).unwrap_err(),
        TouchMeshError::Empty
    );
    assert_eq!(
        TouchMesh::new(vec![Vector::ZERO; 3], vec![]).unwrap_err(),
        TouchMeshError::Empty
    );
    let v = vec![Vector::ZERO, Vector::X, Vector::new(f32::NAN, 0.0, 0.0)];
    assert_eq!(
        TouchMesh::new(v, vec![[0, 1, 2]]).unwrap_err(),
        TouchMeshError::NonFiniteVertex(2)
    );
    let v = vec![Vector::ZERO, Vector::X, Vector::Y];
    assert!(matches!(
        TouchMesh::new(v.clone(), vec![[0, 1, 7]]),
        Err(TouchMeshError::IndexOutOfBounds { vertex: 7, .. })
    ));
    // Only degenerate triangles (repeated index, collinear points).
    let collinear = vec![Vector::ZERO, Vector::X, Vector::X * 2.0];
    assert_eq!(
        TouchMesh::new(collinear, vec![[0, 1, 2], [0, 0, 1]]).unwrap_err(),
        TouchMeshError::AllTrianglesDegenerate(2)
    );
    assert!(matches!(
        TouchMesh::from_shape(&parry3d::shape::HalfSpace::new(Vector::Y)).unwrap_err(),
        TouchMeshError::UnsupportedShape {
            shape: parry3d::shape::ShapeType::HalfSpace,
            ..
        }
    ));
}

#[test]
fn degenerate_and_duplicate_triangles_are_dropped_and_reported() {
    let v = vec![Vector::ZERO, Vector::X, Vector::Y, Vector::X * 2.0];
    let m = TouchMesh::new(v, vec![[0, 1, 2], [0, 1, 3], [2, 1, 0], [1, 1, 2]]).unwrap();
    assert_eq!(m.num_triangles(), 1);
    assert_eq!(m.dropped_triangles(), &[1, 2, 3]);
    assert!(!m.is_closed());
}

#[test]
fn non_manifold_mesh_is_accepted_and_counted() {
    let v = vec![Vector::ZERO, Vector::X, Vector::Y, Vector::Z, -Vector::Y];
    let m = TouchMesh::new(v, vec![[0, 1, 2], [0, 1, 3], [0, 1, 4]]).unwrap();
    assert_eq!(m.non_manifold_edges(), 1);
    assert!(!m.is_closed());
}

#[test]
fn non_finite_poses_are_errors() {
    let (a, b) = (cube(0.5), cube(0.5));
    let mut rec = Reconstructor::default();
    let bad = Pose::from_translation(Vector::new(f32::NAN, 0.0, 0.0));
    let inf = Pose::from_translation(Vector::new(0.0, f32::INFINITY, 0.0));
    let id = Pose::IDENTITY;
    assert_eq!(
        rec.reconstruct(&a, &bad, &b, &id, &id),
        Err(ReconstructionError::NonFinitePose)
    );
    assert_eq!(
        rec.reconstruct(&a, &id, &b, &inf, &id),
        Err(ReconstructionError::NonFinitePose)
    );
    assert_eq!(
        rec.reconstruct(&a, &id, &b, &id, &bad),
        Err(ReconstructionError::NonFinitePose)
    );
    rec.options.zero_motion_direction = Some(Vector::ZERO);
    assert_eq!(
        rec.reconstruct(&a, &id, &b, &id, &id),
        Err(ReconstructionError::InvalidFallbackDirection)
    );
}

/// An open mesh (a two-triangle floor of zero thickness) is a shell: a cube that went 0.1 m
/// through it is brought back on top of it.
#[test]
fn open_floor_is_a_shell() {
    let v = vec![
        Vector::new(-2.0, 0.0, -2.0),
        Vector::new(2.0, 0.0, -2.0),
        Vector::new(2.0, 0.0, 2.0),
        Vector::new(-2.0, 0.0, 2.0),
    ];
    let floor = TouchMesh::new(v, vec![[0, 2, 1], [0, 3, 2]]).unwrap();
    assert_eq!(floor.min_extent(), 0.0);
    let c = cube(0.5);
    let now = Pose::from_translation(Vector::new(0.0, 0.4, 0.0));
    let prev = Pose::from_translation(Vector::new(0.0, 0.9, 0.0));
    let r = Reconstructor::default()
        .reconstruct(&floor, &Pose::IDENTITY, &c, &now, &prev)
        .unwrap();
    assert_eq!(r.state, TouchState::Penetrating);
    assert!((r.depth - 0.1).abs() < 1e-5);
    assert_eq!(r.patches[0].kind, ContactKind::Face);
}

/// A small fast cube that went right through a thin slab in one step: perforated (Fig. 1 c);
/// the reversing vector leads back to where it first touched the slab's top.
#[test]
fn passing_through_a_thin_slab_is_a_perforation() {
    let slab = TouchMesh::from_shape(&Cuboid::new(Vector::new(2.0, 0.05, 2.0))).unwrap();
    let c = cube(0.1);
    let prev = Pose::from_translation(Vector::new(0.0, 1.0, 0.0));
    let now = Pose::from_translation(Vector::new(0.0, -1.0, 0.0));
    let r = Reconstructor::default()
        .reconstruct(&slab, &Pose::IDENTITY, &c, &now, &prev)
        .unwrap();
    assert_eq!(r.state, TouchState::Perforated);
    // First touch: cube bottom (centre - 0.1) at slab top (0.05): centre at 0.15.
    assert!((r.depth - 1.15).abs() < 1e-5, "depth {}", r.depth);
    assert!((r.time_of_impact.unwrap() - 0.425).abs() < 1e-5);
    assert!(safe_step_length(&slab, &c) < 2.0);
    let at = shifted(&now, r.reversing_vector);
    assert!(surface_distance(&slab, &Pose::IDENTITY, &c, &at) < 1e-5);
}

#[test]
fn a_small_cube_swallowed_by_a_big_one_is_penetrating() {
    let big = cube(2.0);
    let small = cube(0.1);
    // It entered through the top (y = 2) during the step and is now wholly inside.
    let prev = Pose::from_translation(Vector::new(0.0, 2.5, 0.0));
    let now = Pose::from_translation(Vector::new(0.0, 1.5, 0.0));
    let r = Reconstructor::default()
        .reconstruct(&big, &Pose::IDENTITY, &small, &now, &prev)
        .unwrap();
    assert_eq!(r.state, TouchState::Penetrating);
    assert!((r.depth - 0.6).abs() < 1e-5, "depth {}", r.depth);
}

#[test]
fn separated_and_touching_states() {
    let (a, b) = (cube(0.5), cube(0.5));
    let mut rec = Reconstructor::default();
    let far = Pose::from_translation(Vector::new(0.0, 3.0, 0.0));
    let r = rec
        .reconstruct(&a, &Pose::IDENTITY, &b, &far, &shifted(&far, Vector::Y))
        .unwrap();
    assert_eq!(r.state, TouchState::Separated);
    assert!(r.patches.is_empty() && r.depth == 0.0);
    let touch = Pose::from_translation(Vector::new(0.2, 1.0, 0.0));
    let r = rec
        .reconstruct(&a, &Pose::IDENTITY, &b, &touch, &shifted(&touch, Vector::Y))
        .unwrap();
    assert_eq!(r.state, TouchState::Touching);
    assert_eq!(r.reversing_vector, Vector::ZERO);
    assert_eq!(r.patches.len(), 1);
    assert_eq!(r.patches[0].kind, ContactKind::Face);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    /// Garbage meshes and poses never panic, and what comes back is finite.
    #[test]
    fn garbage_never_panics(
        verts in prop::collection::vec(
            prop_oneof![
                8 => (-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0).prop_map(|(x, y, z)| Vector::new(x, y, z)),
                1 => Just(Vector::new(f32::NAN, 0.0, 0.0)),
                1 => Just(Vector::ZERO),
            ],
            0..12,
        ),
        tris in prop::collection::vec((0u32..14, 0u32..14, 0u32..14), 0..20),
        t in (-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0),
        d in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
    ) {
        let idx: Vec<[u32; 3]> = tris.iter().map(|&(a, b, c)| [a, b, c]).collect();
        if let Ok(m) = TouchMesh::new(verts, idx) {
            let other = cube(0.5);
            let now = Pose::from_translation(Vector::new(t.0, t.1, t.2));
            let prev = shifted(&now, Vector::new(d.0, d.1, d.2));
            let mut rec = Reconstructor::default();
            for (f, pf, mv) in [(&m, Pose::IDENTITY, &other), (&other, Pose::IDENTITY, &m)] {
                let r = rec.reconstruct(f, &pf, mv, &now, &prev).unwrap();
                prop_assert!(r.reversing_vector.is_finite() && r.depth.is_finite());
                for p in &r.patches {
                    prop_assert!(p.normal.is_finite());
                    prop_assert!(p.polygon.iter().all(|v| v.is_finite()));
                }
            }
        }
    }
}

/// Huge but finite poses never panic (parry's f32 GJK, used for convex pairs, asserts finite
/// bounds) and give finite results; two cubes overlapping far from the origin are still found
/// penetrating by the right depth while f32 resolves it.
#[test]
fn huge_finite_poses_do_not_panic() {
    let (a, b) = (cube(0.5), cube(0.5));
    let mut rec = Reconstructor::default();
    for far in [1.0e3f32, 1.0e7, 1.0e12, 1.0e20, 1.0e30, f32::MAX / 4.0] {
        for base in [Vector::new(far, 0.0, 0.0), Vector::new(0.0, 0.0, 0.0)] {
            let fixed = Pose::from_translation(base);
            let now = Pose::from_translation(Vector::new(far, 0.9, 0.0));
            let before = Pose::from_translation(Vector::new(far, 1.4, 0.0));
            let c = rec.reconstruct(&a, &fixed, &b, &now, &before).unwrap();
            assert!(
                c.reversing_vector.is_finite() && c.depth.is_finite(),
                "{far}: {c:?}"
            );
            if far <= 1.0e3 && base.x == far {
                assert_eq!(c.state, TouchState::Penetrating);
                assert!((c.depth - 0.1).abs() < 1e-4, "{far}: depth {}", c.depth);
            }
        }
    }
    // Huge meshes overlapping: coordinates whose squares overflow f32.
    for h in [1.0e10f32, 1.0e15, 1.0e20, 1.0e30] {
        // Past about 1e18 the mesh itself is refused (its triangle areas overflow f32).
        let Ok(a) = TouchMesh::from_shape(&Cuboid::new(Vector::splat(h))) else {
            assert!(h > 1.0e18, "{h}");
            continue;
        };
        let b = a.clone();
        let now = Pose::from_translation(Vector::new(0.0, 1.8 * h, 0.0));
        let before = Pose::from_translation(Vector::new(0.0, 2.8 * h, 0.0));
        let c = rec
            .reconstruct(&a, &Pose::IDENTITY, &b, &now, &before)
            .unwrap();
        assert!(
            c.reversing_vector.is_finite() && c.depth.is_finite(),
            "{h}: {c:?}"
        );
    }
}

/// Bad input on rotating paths: a NaN or infinite centre of rotation or rotation is an error,
/// not a NaN pose; a zero-thickness floor (no smallest extent) and a zero-length rotation
/// about a far centre still give finite answers.
#[test]
fn bad_rotating_motions_are_errors_or_finite() {
    let (floor, c) = (cube(2.0), cube(0.5));
    let id = Pose::IDENTITY;
    let mut rec = Reconstructor::default();
    let start = Pose::from_translation(Vector::new(0.0, 3.0, 0.0));
    let end = Pose::from_parts(Vector::new(0.0, 2.2, 0.0), Rotation::from_rotation_z(0.7));
    for center in [
        Vector::new(f32::NAN, 0.0, 0.0),
        Vector::new(0.0, f32::INFINITY, 0.0),
    ] {
        let m = RigidMotion::new(start, end, center);
        assert_eq!(
            rec.reconstruct_motion(&floor, &id, &c, &m),
            Err(ReconstructionError::NonFinitePose)
        );
    }
    let nan_rot = Pose::from_parts(
        end.translation,
        Rotation::from_xyzw(f32::NAN, 0.0, 0.0, 1.0),
    );
    let m = RigidMotion::new(start, nan_rot, Vector::ZERO);
    assert_eq!(
        rec.reconstruct_motion(&floor, &id, &c, &m),
        Err(ReconstructionError::NonFinitePose)
    );
    // A flat floor (one quad, no thickness) under a cube that turns while it falls through it.
    let quad = TouchMesh::new(
        vec![
            Vector::new(-5.0, 0.0, -5.0),
            Vector::new(5.0, 0.0, -5.0),
            Vector::new(5.0, 0.0, 5.0),
            Vector::new(-5.0, 0.0, 5.0),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
    )
    .unwrap();
    assert_eq!(quad.min_extent(), 0.0);
    let below = Pose::from_parts(Vector::new(0.0, -2.0, 0.0), Rotation::from_rotation_z(0.7));
    let r = rec
        .reconstruct_motion(
            &quad,
            &id,
            &c,
            &RigidMotion::new(start, below, Vector::ZERO),
        )
        .unwrap();
    assert_eq!(r.state, TouchState::Perforated);
    assert!(r.touch_pose.is_finite());
    // It stopped on the floor: its lowest corner at y = 0 within the tolerance.
    let lowest = c
        .vertices()
        .iter()
        .map(|&v| r.touch_pose.transform_point(v).y)
        .fold(f32::MAX, f32::min);
    assert!(lowest.abs() < 1e-4, "lowest corner at {lowest}");
    // A tiny turn about a centre 1e6 m away: a huge but finite sweep.
    let far = RigidMotion::new(start, end, Vector::new(1.0e6, 0.0, 0.0));
    let r = rec.reconstruct_motion(&floor, &id, &c, &far).unwrap();
    assert!(r.touch_pose.is_finite() && r.reversing_vector.is_finite());
}

/// The curved-shape methods (`reconstruct_shapes`, `push_out_shapes`): NaN and infinite poses,
/// a zero or NaN push direction are errors; a zero-size ball, a degenerate motion (no travel)
/// and a shape parry has no distance query for give a finite answer or `None` (the mesh
/// method's turn), never a panic or a NaN pose.
#[test]
fn curved_shape_methods_reject_bad_input() {
    use parry3d::shape::{Ball, HalfSpace};
    let slab = Cuboid::new(Vector::new(1.0, 0.5, 1.0));
    let ball = Ball::new(0.25);
    let at = |y: f32| Pose::from_translation(Vector::new(0.0, y, 0.0));
    let mut rec = Reconstructor::default();
    let nan = Pose::from_translation(Vector::new(f32::NAN, 0.0, 0.0));
    let inf = Pose::from_translation(Vector::new(0.0, f32::INFINITY, 0.0));
    for (fixed_pose, motion) in [
        (nan, RigidMotion::new(at(1.0), at(0.6), Vector::ZERO)),
        (at(-0.5), RigidMotion::new(inf, at(0.6), Vector::ZERO)),
        (
            at(-0.5),
            RigidMotion::new(at(1.0), at(0.6), Vector::splat(f32::NAN)),
        ),
    ] {
        assert_eq!(
            rec.reconstruct_shapes(&slab, &fixed_pose, &ball, &motion),
            Err(ReconstructionError::NonFinitePose)
        );
    }
    assert_eq!(
        rec.push_out_shapes(&slab, &nan, &ball, &at(0.1), Vector::Y),
        Err(ReconstructionError::NonFinitePose)
    );
    for out in [Vector::ZERO, Vector::new(f32::NAN, 1.0, 0.0)] {
        assert_eq!(
            rec.push_out_shapes(&slab, &at(-0.5), &ball, &at(0.1), out),
            Err(ReconstructionError::InvalidFallbackDirection)
        );
    }
    let finite = |c: &ContactConfiguration| {
        c.touch_pose.is_finite() && c.reversing_vector.is_finite() && c.depth.is_finite()
    };
    // A zero-size ball, a motion that does not move, a half-space (no finite surface).
    let point = Ball::new(0.0);
    let still = RigidMotion::new(at(0.1), at(0.1), Vector::ZERO);
    let fall = RigidMotion::new(at(1.0), at(-0.2), Vector::ZERO);
    let half = HalfSpace::new(Vector::Y);
    for c in [
        rec.reconstruct_shapes(&slab, &at(-0.5), &point, &fall),
        rec.reconstruct_shapes(&slab, &at(-0.5), &ball, &still),
        rec.reconstruct_shapes(&half, &at(-0.5), &ball, &fall),
        rec.push_out_shapes(&slab, &at(-0.5), &point, &at(-0.1), Vector::Y),
    ] {
        if let Some(c) = c.unwrap() {
            assert!(finite(&c), "{c:?}");
        }
    }
    // Still and overlapping by 0.15: not on a path, pushed out along the contact normal.
    let c = rec
        .reconstruct_shapes(&slab, &at(-0.5), &ball, &still)
        .unwrap()
        .unwrap();
    assert!(!c.on_trajectory);
    assert_eq!(c.state, TouchState::Penetrating);
    assert!((c.reversing_vector - Vector::new(0.0, 0.15, 0.0)).length() < 1e-4);
}
