//! The step guard at every scale: a tumbling box dropped onto a fixed cuboid floor and onto a
//! zero-thickness TriMesh floor, with every length, speed and the gravity scaled by `s` from
//! 0.1 mm to 10 km and rapier's `length_unit` set to `s` (as rapier's docs ask), in both
//! opt-in modes. The guard's slops are in rapier's length unit, so the scene is the same at
//! every scale in units of `s`: the box never goes through and never ends a step deeper than
//! the 1 mm a 10 cm box may reach at 1 m, a hundredth of its size.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::scenes::box_depth_below_floor;

/// The deepest the box's lowest corner went below the floor's top over 2 s, in units of
/// `s`, and whether its centre went below it. The box (half-side 0.05 s, turned) starts
/// 0.3 s up, falling at `speed` s per second.
fn drop(s: f32, speed: f32, trimesh: bool, tracked: bool) -> (f32, bool) {
    let mut w = PhysicsWorld::default();
    w.integration_parameters.dt = 1.0 / 60.0;
    w.integration_parameters.length_unit = s;
    w.gravity *= s;
    TouchPipeline::configure(&mut w.integration_parameters);
    let hooks = if tracked {
        ActiveHooks::empty()
    } else {
        ActiveHooks::MODIFY_SOLVER_CONTACTS
    };
    let floor =
        if trimesh {
            let h = 5.0 * s;
            let v = vec![
                Vector::new(-h, 0.0, -h),
                Vector::new(h, 0.0, -h),
                Vector::new(h, 0.0, h),
                Vector::new(-h, 0.0, h),
            ];
            let shape = ColliderBuilder::trimesh(v, vec![[0, 2, 1], [0, 3, 2]]).unwrap();
            w.insert_collider(shape.active_hooks(hooks), None)
        } else {
            let shape = ColliderBuilder::cuboid(5.0 * s, 0.5 * s, 5.0 * s)
                .translation(Vector::new(0.0, -0.5 * s, 0.0));
            w.insert_collider(shape.active_hooks(hooks), None)
        };
    let half = 0.05 * s;
    let body = w.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 0.3 * s, 0.0))
            .rotation(Vector::new(0.2, 0.1, 0.3))
            .linvel(Vector::new(0.0, -speed * s, 0.0)),
    );
    let cube = ColliderBuilder::cuboid(half, half, half).active_hooks(hooks);
    let cube = w.insert_collider(cube, Some(body));
    let mut touch = TouchPipeline::default();
    if tracked {
        touch.track_collider(cube);
        touch.track_collider(floor);
    }
    let (mut deepest, mut through) = (0.0f32, false);
    for _ in 0..120 {
        touch.step(&mut w);
        let pose = *w.bodies[body].position();
        through |= pose.translation.y < 0.0;
        deepest = deepest.max(box_depth_below_floor(&pose, half));
    }
    (deepest / s, through)
}

/// At 20 s per second onto the TriMesh floor, a box 1 mm across went 0.1 mm deep
/// (a hundredth of its size, against 1.8e-4 of it at 1 m) while the slops were in metres:
/// 0.2 mm, a fifth of the box, went uncorrected.
#[test]
fn a_dropped_box_stops_alike_at_every_scale() {
    for tracked in [false, true] {
        for trimesh in [false, true] {
            for speed in [1.0, 20.0] {
                for s in [1e-4, 1e-2, 1.0, 1e2, 1e4] {
                    let (deepest, through) = drop(s, speed, trimesh, tracked);
                    let case = format!(
                        "{s} m, {speed} s/s, TriMesh floor {trimesh}, tracked {tracked}: \
                         {deepest} s deep"
                    );
                    assert!(!through, "{case}: through");
                    assert!(deepest <= 1e-3, "{case}");
                }
            }
        }
    }
}
