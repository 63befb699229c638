//! Unit tests of the reconstruction's crate-private parts.

use super::*;
use crate::math::Rotation;
use parry3d::shape::Cuboid;

/// With the first touch only, a motion that touched on the step is answered as before
/// (the analytic first touch), turning or not, and one whose start already penetrated is
/// `Penetrating` off the trajectory with no way out, where the full answer walks out. On
/// an open floor (two triangles): the general search, not the convex path.
#[test]
fn the_first_touch_only_answers_on_the_step_as_before_and_leaves_the_way_out() {
    let floor = vec![
        Vector::new(-2.0, 0.0, -2.0),
        Vector::new(2.0, 0.0, -2.0),
        Vector::new(2.0, 0.0, 2.0),
        Vector::new(-2.0, 0.0, 2.0),
    ];
    let slab = TouchMesh::new(floor, vec![[0, 2, 1], [0, 3, 2]]).unwrap();
    assert!(!slab.is_convex());
    let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.5))).unwrap();
    let slab_pose = Pose::IDENTITY;
    let turn = Rotation::from_rotation_y(0.5);
    let down = |from: Real, to: Real, turned: bool| {
        let r = if turned { turn } else { Rotation::IDENTITY };
        RigidMotion::new(
            Pose::from_translation(Vector::new(0.0, from, 0.0)),
            Pose::from_parts(Vector::new(0.0, to, 0.0), r),
            Vector::ZERO,
        )
    };
    let mut rec = Reconstructor::default();
    let mut answer = |motion: &RigidMotion, first_touch_only: bool| {
        rec.set_first_touch_only(first_touch_only);
        rec.reconstruct_motion(&slab, &slab_pose, &cube, motion)
            .unwrap()
    };
    for turned in [false, true] {
        // From 0.8 m down to 0.3 m: the cube's bottom (0.5 m below its centre) met the
        // slab's top (y = 0) 0.2 m back, a turn about the vertical changing none of it.
        let on_step = down(0.8, 0.3, turned);
        let (full, first) = (answer(&on_step, false), answer(&on_step, true));
        for c in [&full, &first] {
            assert_eq!(c.state, TouchState::Penetrating);
            assert!(c.on_trajectory);
            assert!((c.touch_pose.translation.y - 0.5).abs() < 1e-5, "{c:?}");
        }
        assert_eq!(full.reversing_vector, first.reversing_vector);
        // From 0.4 m (already 0.1 m in) down to 0.3 m: not a first touch of this step.
        let deep = down(0.4, 0.3, turned);
        let (full, first) = (answer(&deep, false), answer(&deep, true));
        assert_eq!(first.state, TouchState::Penetrating);
        assert!(!first.on_trajectory && first.patches.is_empty());
        assert_eq!(first.reversing_vector, Vector::ZERO);
        assert_eq!(full.state, TouchState::Penetrating);
        assert!(!full.on_trajectory);
        // The way out along the motion: up 0.2 m to the slab's top.
        assert!((full.reversing_vector.y - 0.2).abs() < 1e-4, "{full:?}");
    }
}
