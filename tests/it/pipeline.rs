//! The touch pipeline in a real rapier pipeline (dt = 1/60, rapier's CCD off): boxes dropped
//! at up to 100 m/s onto a fixed cuboid and onto a zero-thickness TriMesh floor never tunnel and
//! never penetrate more than 1 mm after any step; a U-shaped TriMesh body rests on both legs
//! over a bump; a resting stack stays still; removals, sleeping bodies and bodies without
//! colliders do not break the hooks; degenerate bodies (massless, zero-size, NaN or infinite
//! velocity) and `dt = 0` neither panic nor put a NaN pose into rapier. Hook flags managed on
//! demand: `pipeline/hook_flags.rs`.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::scenes::{box_depth_below_floor, drop_world, DropFloor, DROP_BOX_HALF};

const HOOKS: ActiveHooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;

fn world() -> PhysicsWorld {
    let mut w = PhysicsWorld::default();
    w.integration_parameters.dt = 1.0 / 60.0;
    w.integration_parameters.max_ccd_substeps = 0; // rapier's CCD off
    TouchPipeline::configure(&mut w.integration_parameters);
    w
}

fn add_floor(w: &mut PhysicsWorld) {
    w.insert_collider(
        ColliderBuilder::cuboid(5.0, 0.5, 5.0)
            .translation(Vector::new(0.0, -0.5, 0.0))
            .active_hooks(HOOKS),
        None,
    );
}

struct DropResult {
    tunneled: bool,
    max_penetration: f32,
}

fn drop_box(speed: f32, floor: DropFloor, with_crate: bool, steps: usize) -> DropResult {
    let (mut w, b) = drop_world(speed, floor);
    let mut touch = TouchPipeline::default();
    let mut r = DropResult {
        tunneled: false,
        max_penetration: 0.0,
    };
    for _ in 0..steps {
        if with_crate {
            touch.step(&mut w);
        } else {
            w.step();
        }
        let pose = *w.bodies[b].position();
        if pose.translation.y < 0.0 {
            r.tunneled = true;
        } else {
            r.max_penetration = r
                .max_penetration
                .max(box_depth_below_floor(&pose, DROP_BOX_HALF));
        }
    }
    r
}

#[test]
fn fast_boxes_never_tunnel_and_penetrate_at_most_1mm() {
    for floor in [DropFloor::Cuboid, DropFloor::ThinTriMesh] {
        for speed in [1.0, 5.0, 20.0, 50.0, 100.0] {
            let r = drop_box(speed, floor, true, 120);
            assert!(!r.tunneled, "{floor:?} at {speed} m/s tunneled");
            assert!(
                r.max_penetration <= 1e-3,
                "{floor:?} at {speed} m/s: penetration {} m",
                r.max_penetration
            );
        }
    }
}

/// The scenario is a real stress: without the crate, rapier (CCD off) lets the box through the
/// thin floor at 100 m/s.
#[test]
fn vanilla_rapier_without_ccd_tunnels_through_the_thin_floor() {
    assert!(drop_box(100.0, DropFloor::ThinTriMesh, false, 30).tunneled);
}

#[test]
fn resting_stack_of_three_boxes_stays_still() {
    let mut w = world();
    add_floor(&mut w);
    let h = 0.25;
    let boxes: Vec<RigidBodyHandle> = (0..3)
        .map(|i| {
            let b = w.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(
                0.0,
                h + 2.0 * h * i as f32,
                0.0,
            )));
            w.insert_collider(
                ColliderBuilder::cuboid(h, h, h).active_hooks(HOOKS),
                Some(b),
            );
            b
        })
        .collect();
    let mut touch = TouchPipeline::default();
    // Let rapier's contacts settle for a second, then watch for ten.
    for _ in 0..60 {
        touch.step(&mut w);
    }
    let start: Vec<Vector> = boxes.iter().map(|b| w.bodies[*b].translation()).collect();
    let mut worst = 0.0f32;
    for _ in 0..600 {
        touch.step(&mut w);
        for (b, s) in boxes.iter().zip(&start) {
            worst = worst.max((w.bodies[*b].translation() - *s).length());
        }
    }
    assert!(worst <= 1e-4, "stack moved {worst} m");
}

/// A U-shaped (non-convex) TriMesh body dropped over a bump comes to rest touching the floor
/// on both legs, the bump between them.
#[test]
fn u_shaped_trimesh_rests_on_both_legs_over_a_bump() {
    use rapier_touch::geometry::generators::extruded_polygon;
    let mut w = world();
    // Floor: a slab with a bump (extruded profile), top at y = 0, bump up to y = 0.3.
    let (fv, fi) = extruded_polygon(
        &[
            [-3.0, -0.5],
            [3.0, -0.5],
            [3.0, 0.0],
            [0.3, 0.0],
            [0.3, 0.3],
            [-0.3, 0.3],
            [-0.3, 0.0],
            [-3.0, 0.0],
        ],
        4.0,
    )
    .unwrap();
    w.insert_collider(
        ColliderBuilder::trimesh(fv, fi)
            .unwrap()
            .active_hooks(HOOKS),
        None,
    );
    // The U: legs at x in [-1.2, -0.8] and [0.8, 1.2], 0.6 tall, joined on top.
    let (uv, ui) = extruded_polygon(
        &[
            [-1.2, 0.0],
            [-0.8, 0.0],
            [-0.8, 0.6],
            [0.8, 0.6],
            [0.8, 0.0],
            [1.2, 0.0],
            [1.2, 0.9],
            [-1.2, 0.9],
        ],
        1.0,
    )
    .unwrap();
    let b = w.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 1.0, 0.0))
            .linvel(Vector::new(0.0, -8.0, 0.0)),
    );
    let leg_ids = w.insert_collider(
        ColliderBuilder::trimesh(uv, ui)
            .unwrap()
            .active_hooks(HOOKS)
            .density(1.0),
        Some(b),
    );
    let mut touch = TouchPipeline::default();
    let (mut left, mut right) = (false, false);
    for _ in 0..240 {
        touch.step(&mut w);
        for r in touch.reports().iter().filter(|r| r.moving == leg_ids) {
            for p in &r.patches {
                left |= p.center().x < -0.5;
                right |= p.center().x > 0.5;
            }
        }
    }
    let pose = *w.bodies[b].position();
    // Both leg bottoms at the floor (y = 0) within 1 mm.
    for x in [-1.0, 1.0] {
        let foot = pose.transform_point(Vector::new(x, 0.0, 0.0));
        assert!(foot.y.abs() <= 1e-3, "leg at x = {x} is at y = {}", foot.y);
    }
    assert!(w.bodies[b].linvel().length() < 0.05, "still moving");
    // The reports saw contact patches under both legs.
    assert!(
        left && right,
        "patches under the left leg: {left}, right leg: {right}"
    );
}

#[test]
fn removals_sleep_and_colliderless_bodies_do_not_break_the_hooks() {
    let mut w = world();
    add_floor(&mut w);
    let mut bodies = Vec::new();
    for i in 0..4 {
        let b = w.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(
            i as f32 - 1.5,
            0.5 + i as f32,
            0.0,
        )));
        w.insert_collider(
            ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(HOOKS),
            Some(b),
        );
        bodies.push(b);
    }
    // A body with no collider, and one that falls asleep on the floor.
    let bare = w.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(3.0, 2.0, 0.0)));
    let mut touch = TouchPipeline::default();
    for step in 0..400 {
        if step == 30 {
            w.remove_body(bodies[1]);
        }
        if step == 60 {
            let c = w.bodies[bodies[2]].colliders()[0];
            w.remove_collider(c);
        }
        touch.step(&mut w);
    }
    // The untouched boxes rest on the floor; the one without a collider fell through freely.
    for b in [bodies[0], bodies[3]] {
        let y = w.bodies[b].translation().y;
        assert!((y - 0.25).abs() < 1e-3, "box at {y}");
        assert!(w.bodies[b].is_sleeping());
    }
    // rapier leaves a body without mass alone; the hooks must not have touched it either.
    assert!(w.bodies[bare].position().is_finite());
    // The box that lost its collider is no longer guarded (and has no mass left for rapier to
    // move): no report names it.
    assert!(w.bodies[bodies[2]].position().is_finite());
    assert!(touch
        .reports()
        .iter()
        .all(|r| w.colliders.get(r.moving).is_some()));
}

/// Touch mode: a kinematic tool driven 30 cm into a fixed block stops at first touch (its
/// proxy), and the device-to-proxy offset is the distance the device went in.
#[test]
fn tool_proxy_stops_at_first_touch_and_reports_the_offset() {
    let mut w = world();
    add_floor(&mut w);
    let tool = w.insert_body(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.0, 1.0, 0.0)),
    );
    w.insert_collider(
        ColliderBuilder::cuboid(0.1, 0.1, 0.1).active_hooks(HOOKS),
        Some(tool),
    );
    let mut touch = TouchPipeline::default();
    let mut y = 1.0;
    let mut saw_face = false;
    for _ in 0..120 {
        y -= 0.01; // 0.6 m/s down, ending at y = -0.2
        touch.set_tool_target(tool, Pose::from_translation(Vector::new(0.0, y, 0.0)));
        touch.step(&mut w);
        let proxy_bottom = w.bodies[tool].translation().y - 0.1;
        assert!(
            proxy_bottom >= -1e-3,
            "tool went {} m into the block",
            -proxy_bottom
        );
        saw_face |= touch
            .reports()
            .iter()
            .any(|r| r.patches.iter().any(|p| p.kind == ContactKind::Face));
    }
    let fb = touch.tool_feedback(tool).unwrap();
    assert!(
        (fb.proxy.translation.y - 0.1).abs() < 1e-3,
        "proxy at {}",
        fb.proxy.translation.y
    );
    assert!((fb.device.translation.y - y).abs() < 1e-6);
    assert!(
        (fb.offset.y - (0.1 - y)).abs() < 1e-3,
        "offset {:?}",
        fb.offset
    );
    assert!(saw_face, "the tool's bottom face touched the block");
}

/// The guard works without rapier hooks for tracked colliders.
#[test]
fn tracked_colliders_are_guarded_without_hooks() {
    let (mut w, b) = drop_world(100.0, DropFloor::ThinTriMesh);
    let handles: Vec<_> = w.colliders.iter().map(|(h, _)| h).collect();
    for h in &handles {
        w.colliders[*h].set_active_hooks(ActiveHooks::empty());
    }
    let mut touch = TouchPipeline::default();
    for h in handles {
        touch.track_collider(h);
    }
    for _ in 0..60 {
        touch.step(&mut w);
        let pose = *w.bodies[b].position();
        assert!(pose.translation.y > 0.0, "tunneled");
        assert!(box_depth_below_floor(&pose, DROP_BOX_HALF) <= 1e-3);
    }
    assert_eq!(touch.hooks.counters().rewritten, 0);
}

/// A moving TriMesh body (which rapier's CCD never sweeps) dropped at 100 m/s onto the
/// zero-thickness TriMesh floor does not go through.
#[test]
fn fast_trimesh_body_does_not_tunnel() {
    use rapier_touch::geometry::generators::subdivided_box;
    let (mut w, _) = drop_world(0.0, DropFloor::ThinTriMesh);
    let (v, i) = subdivided_box(Vector::splat(0.25), 2);
    let b = w.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(2.0, 3.0, 0.0))
            .linvel(Vector::new(0.0, -100.0, 0.0)),
    );
    w.insert_collider(
        ColliderBuilder::trimesh(v, i).unwrap().active_hooks(HOOKS),
        Some(b),
    );
    let mut touch = TouchPipeline::default();
    for _ in 0..60 {
        touch.step(&mut w);
        let pose = *w.bodies[b].position();
        assert!(
            pose.translation.y > 0.0,
            "tunneled: y = {}",
            pose.translation.y
        );
        assert!(box_depth_below_floor(&pose, 0.25) <= 1e-3);
    }
}

/// Degenerate worlds through the pipeline, in both opt-in modes, against vanilla rapier on the
/// same world: a massless dynamic body (density 0) sunk into the floor, a zero-size cuboid, a
/// body with a NaN velocity, a body with an infinite angular velocity, a cone with a NaN spin,
/// a rolling ball of no size, and `dt = 0`. The
/// pipeline never panics; every body vanilla rapier keeps finite stays finite (the guard hands
/// no NaN to rapier); with `dt = 0` nothing moves, so nothing is corrected.
#[test]
fn degenerate_bodies_and_zero_dt_neither_panic_nor_hand_nan_to_rapier() {
    let build = |mode: Option<bool>, dt: f32| {
        let mut w = world();
        w.integration_parameters.dt = dt;
        add_floor(&mut w);
        let flags = if mode == Some(true) {
            HOOKS
        } else {
            ActiveHooks::empty()
        };
        let mut add = |at: Vector, linvel: Vector, angvel: Vector, co: ColliderBuilder| {
            let b = w.insert_body(
                RigidBodyBuilder::dynamic()
                    .translation(at)
                    .linvel(linvel)
                    .angvel(angvel),
            );
            w.insert_collider(co.active_hooks(flags), Some(b));
            b
        };
        let bodies = [
            add(
                Vector::new(-2.0, 0.2, 0.0),
                Vector::new(0.0, -5.0, 0.0),
                Vector::ZERO,
                ColliderBuilder::cuboid(0.25, 0.25, 0.25).density(0.0),
            ),
            add(
                Vector::new(0.0, 1.0, 0.0),
                Vector::new(0.0, -30.0, 0.0),
                Vector::ZERO,
                ColliderBuilder::cuboid(0.0, 0.0, 0.0),
            ),
            add(
                Vector::new(2.0, 1.0, 0.0),
                Vector::new(f32::NAN, -5.0, 0.0),
                Vector::ZERO,
                ColliderBuilder::cuboid(0.25, 0.25, 0.25),
            ),
            add(
                Vector::new(0.0, 1.0, 2.0),
                Vector::new(0.0, -5.0, 0.0),
                Vector::new(f32::INFINITY, 0.0, 0.0),
                ColliderBuilder::cuboid(0.25, 0.25, 0.25),
            ),
            // Curved shapes (the guard's rolling and spinning rules): a cone resting on its
            // side with a NaN spin, and a ball of no size rolling on the floor.
            add(
                Vector::new(-2.0, 0.25, 2.0),
                Vector::ZERO,
                Vector::new(0.0, f32::NAN, 3.0),
                ColliderBuilder::cone(0.25, 0.25).rotation(Vector::new(0.0, 0.0, 1.1)),
            ),
            add(
                Vector::new(2.0, 0.0, 2.0),
                Vector::new(1.0, -1.0, 0.0),
                Vector::new(0.0, 0.0, -5.0),
                ColliderBuilder::ball(0.0),
            ),
        ];
        (w, bodies)
    };
    for dt in [1.0 / 60.0, 0.0] {
        let (mut vanilla, bodies) = build(None, dt);
        for _ in 0..30 {
            vanilla.step();
        }
        for mode in [Some(true), Some(false)] {
            let (mut w, bodies_t) = build(mode, dt);
            assert_eq!(bodies, bodies_t);
            let mut touch = TouchPipeline::default();
            if mode == Some(false) {
                let all: Vec<_> = w.colliders.iter().map(|(h, _)| h).collect();
                for h in all {
                    touch.track_collider(h);
                }
            }
            for _ in 0..30 {
                touch.step(&mut w);
                if dt == 0.0 {
                    assert_eq!(touch.corrections(), 0, "{mode:?}: a correction at dt = 0");
                }
            }
            for b in bodies {
                if vanilla.bodies[b].position().is_finite() {
                    assert!(
                        w.bodies[b].position().is_finite(),
                        "{mode:?} dt {dt}: {:?} finite in vanilla, not through the pipeline",
                        vanilla.bodies[b].position()
                    );
                }
            }
        }
    }
}

/// The hooks' run totals are the sum of what they did step by step: boxes dropped one after the
/// other onto a slab (each one rewritten when it lands), counted by reading the per-step
/// counters after every step.
#[test]
fn hook_counters_add_up_over_the_run() {
    let mut w = world();
    // Hooks only (no step guard), so every landing reaches rapier and the hooks.
    let mut touch = TouchPipeline::new(());
    touch.options.correct_poses = false;
    let slab = ColliderBuilder::cuboid(4.0, 0.5, 4.0).translation(Vector::new(0.0, -0.5, 0.0));
    w.insert_collider(slab.active_hooks(HOOKS), None);
    let mut summed = HookCounters::default();
    for k in 0..6 {
        let x = -2.5 + k as Real;
        let body = w.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(x, 0.45, 0.0))
                .linvel(Vector::new(0.0, -12.0, 0.0)),
        );
        w.insert_collider(
            ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(HOOKS),
            Some(body),
        );
        for _ in 0..3 {
            touch.step(&mut w);
            let c = touch.hooks.counters();
            summed.rewritten += c.rewritten;
            summed.dropped += c.dropped;
            summed.skipped += c.skipped;
        }
    }
    // Every box's landing was rewritten once, and the totals match the per-step sum.
    assert!(summed.rewritten >= 6, "{summed:?}");
    assert_eq!(touch.hooks.total_counters(), summed);
    // The last step alone did less than the run.
    assert!(touch.hooks.counters().rewritten < summed.rewritten);
}

/// `prepare_meshes` on bad input: an empty world does nothing; a tracked half-space (no mesh)
/// and a zero-size cuboid are refused, listed by `refused_colliders`, and the step that
/// follows runs and keeps every pose finite; a hull prepared ahead is the mesh the step uses
/// (the cube dropped on it is held at its top, by the hull's own query).
#[test]
fn prepared_meshes_refuse_bad_shapes_and_serve_the_step() {
    let mut empty = world();
    let mut touch = TouchPipeline::default();
    touch.prepare_meshes(&empty.colliders);
    assert_eq!(touch.refused_colliders().count(), 0);
    touch.step(&mut empty);

    let mut w = world();
    let half_space = w.insert_collider(
        ColliderBuilder::new(SharedShape::halfspace(Vector::Y)),
        None,
    );
    let dot = w.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(5.0, 1.0, 0.0)));
    let zero = w.insert_collider(ColliderBuilder::cuboid(0.0, 0.0, 0.0), Some(dot));
    let points = [
        Vector::new(-1.0, -0.5, -1.0),
        Vector::new(1.0, -0.5, -1.0),
        Vector::new(0.0, -0.5, 1.0),
        Vector::new(0.0, 0.5, 0.0),
    ];
    let hull = w.insert_collider(ColliderBuilder::convex_hull(&points).unwrap(), None);
    let cube_body = w.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 0.9, 0.0))
            .linvel(Vector::new(0.0, -30.0, 0.0)),
    );
    let cube = w.insert_collider(ColliderBuilder::cuboid(0.1, 0.1, 0.1), Some(cube_body));
    let mut touch = TouchPipeline::default();
    for c in [half_space, zero, hull, cube] {
        touch.track_collider(c);
    }
    touch.prepare_meshes(&w.colliders);
    let mut refused: Vec<ColliderHandle> = touch.refused_colliders().map(|(h, _)| h).collect();
    refused.sort_by_key(|h| h.into_raw_parts());
    let mut expected = vec![half_space, zero];
    expected.sort_by_key(|h| h.into_raw_parts());
    assert_eq!(refused, expected);
    for _ in 0..30 {
        touch.step(&mut w);
        for (_, b) in w.bodies.iter() {
            assert!(b.position().is_finite() && b.linvel().is_finite());
        }
        let depth = parry_depth(&w, hull, cube);
        assert!(depth <= 1e-3, "the cube {depth} m into the prepared hull");
    }
}

/// How deep collider `b` is in collider `a` by parry's contact query (0 when apart).
fn parry_depth(w: &PhysicsWorld, a: ColliderHandle, b: ColliderHandle) -> f32 {
    parry3d::query::contact(
        w.colliders[a].position(),
        w.colliders[a].shape(),
        w.colliders[b].position(),
        w.colliders[b].shape(),
        0.0,
    )
    .unwrap()
    .map_or(0.0, |c| -c.dist)
}

mod hook_flags;
