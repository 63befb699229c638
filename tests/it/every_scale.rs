//! Exact first touch at every scale: for random convex pairs scaled log-uniformly from 1e-4 m
//! to 1e4 m, both the convex path (GJK) and the general search give the depth of an exact
//! brute-force reference written in the test to 1e-5 of the scale, a scaled scene gives the
//! scaled answer, and swapping which object moves gives the same depth.

use crate::common::strategies::{direction, rotation, vec3};
use crate::common::{reference_first_touch, scaled_mesh, scaled_pose};
use proptest::prelude::*;
use rapier_touch::geometry::generators::{icosphere, subdivided_box};
use rapier_touch::prelude::*;

/// Unit-size convex meshes: hulls of random points, split boxes, icospheres.
fn convex_mesh() -> impl Strategy<Value = TouchMesh> {
    prop_oneof![
        prop::collection::vec(vec3(), 8..16).prop_filter_map("non-degenerate hull", |pts| {
            let (v, i) = parry3d::transformation::convex_hull(&pts);
            let m = TouchMesh::new(v, i).ok()?;
            (m.min_extent() > 0.3).then_some(m)
        }),
        (vec3(), 1u32..3).prop_map(|(h, n)| {
            let (v, i) = subdivided_box(h.abs() * 0.5 + Vector::splat(0.1), n);
            TouchMesh::new(v, i).unwrap()
        }),
        (0.2f32..0.8, 1u32..2).prop_map(|(r, n)| {
            let (v, i) = icosphere(r, n);
            TouchMesh::new(v, i).unwrap()
        }),
    ]
}

/// The scene at unit scale: the fixed pose, the moving object's pose before and after the step
/// (it ends `frac` of the safe step length past its first touch, found by the reference).
fn scene(
    fixed: &TouchMesh,
    moving: &TouchMesh,
    rf: Rotation,
    rm: Rotation,
    u: Vector,
    lateral: Vector,
    frac: f32,
) -> Option<(Pose, Pose, Pose)> {
    let pose_f = Pose::from_parts(Vector::new(0.3, -0.2, 0.1), rf);
    let prev = Pose::from_parts(
        pose_f.translation - 4.0 * u + lateral.reject_from(u) * 0.4,
        rm,
    );
    let far = Pose::from_parts(prev.translation + 8.0 * u, rm);
    let s = reference_first_touch(fixed, &pose_f, moving, &far, u, 8.0)?;
    let pen = frac * safe_step_length(fixed, moving);
    let now = Pose::from_parts(prev.translation + (8.0 - s as f32 + pen) * u, rm);
    Some((pose_f, prev, now))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn both_paths_exact_from_1e_minus_4_to_1e4_m(
        fixed in convex_mesh(), moving in convex_mesh(), rf in rotation(), rm in rotation(),
        u in direction(), lateral in vec3(), frac in 0.02f32..0.4, exp in -4.0f64..4.0,
    ) {
        let Some((pose_f, prev, now)) = scene(&fixed, &moving, rf, rm, u, lateral, frac) else {
            return Err(TestCaseError::reject("path misses"));
        };
        let k = 10f64.powf(exp) as f32;
        let (fk, mk) = (scaled_mesh(&fixed, k), scaled_mesh(&moving, k));
        let (pf, pv, pn) = (scaled_pose(&pose_f, k), scaled_pose(&prev, k), scaled_pose(&now, k));
        let scale = fk.scale().max(mk.scale()) as f64;
        let len = (pn.translation - pv.translation).length() as f64;
        let reference = reference_first_touch(&fk, &pf, &mk, &pn, u, len)
            .expect("the scene was built to touch");
        let unit = Reconstructor::default().reconstruct(&fixed, &pose_f, &moving, &now, &prev).unwrap();
        for fast in [true, false] {
            let opts = ReconstructionOptions { convex_fast_path: fast, ..Default::default() };
            let c = Reconstructor::new(opts).reconstruct(&fk, &pf, &mk, &pn, &pv).unwrap();
            prop_assert!(c.needs_correction(), "scale {k}, fast {fast}: state {:?}", c.state);
            prop_assert!(c.on_trajectory);
            prop_assert!(
                (c.depth as f64 - reference).abs() <= 1e-5 * scale,
                "scale {k}, fast {fast}: depth {} vs reference {} ({} of the scale)",
                c.depth, reference, (c.depth as f64 - reference).abs() / scale
            );
            // The scaled scene gives the scaled answer.
            prop_assert_eq!(c.state, unit.state);
            prop_assert!(
                ((c.depth / k) - unit.depth).abs() <= 1e-5 * fixed.scale().max(moving.scale()),
                "scaled depth {} vs unit {}", c.depth / k, unit.depth
            );
            prop_assert!(!c.patches.is_empty());
            // Swapping which object moves: the other one moved by -D.
            let d = pn.translation - pv.translation;
            let back = Pose::from_parts(pf.translation + d, pf.rotation);
            let w = Reconstructor::new(opts).reconstruct(&mk, &pn, &fk, &pf, &back).unwrap();
            prop_assert_eq!(w.state, c.state);
            prop_assert!(
                (w.depth - c.depth).abs() as f64 <= 1e-5 * scale,
                "swapped depth {} vs {}", w.depth, c.depth
            );
        }
    }
}
