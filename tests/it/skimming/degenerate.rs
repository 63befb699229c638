//! Degenerate bodies skimming the thin plate (massless, of no size, NaN or infinite spin,
//! `dt = 0`): no panic, no NaN handed to rapier.

use super::*;

/// Degenerate skimmers, in both opt-in modes, against vanilla rapier on the same world: a
/// massless capsule (density 0), a ball of no size, a cone with a NaN spin and a cuboid with an
/// infinite spin, each sliding at 40 m/s over the plate (faster than its safe step, so the
/// fast-pair check and the re-measure of a turned ball or capsule are asked), and the same at
/// `dt = 0`. The pipeline never panics, and every body whose pose vanilla rapier keeps finite
/// stays finite (the guard hands no NaN to rapier).
#[test]
fn degenerate_skimmers_neither_panic_nor_hand_nan_to_rapier() {
    let bodies = [
        (
            ColliderBuilder::capsule_x(0.5, 0.3).density(0.0),
            Vector::new(0.0, 0.0, 9.0),
        ),
        (ColliderBuilder::ball(0.0), Vector::new(0.0, 0.0, 9.0)),
        (
            ColliderBuilder::cone(0.5, 0.5),
            Vector::new(f32::NAN, 3.0, 0.0),
        ),
        (
            ColliderBuilder::cuboid(0.5, 0.2, 0.35),
            Vector::new(f32::INFINITY, 0.0, 0.0),
        ),
    ];
    for dt in [1.0 / 60.0, 0.0] {
        for (collider, spin) in bodies.iter().cloned() {
            let run = |mode: Option<bool>| {
                let mut world = PhysicsWorld::default();
                world.integration_parameters.dt = dt;
                if mode.is_some() {
                    TouchPipeline::configure(&mut world.integration_parameters);
                }
                let flags = if mode == Some(true) {
                    ActiveHooks::MODIFY_SOLVER_CONTACTS
                } else {
                    ActiveHooks::empty()
                };
                let plate = world.insert_collider(
                    ColliderBuilder::cuboid(100.0, 0.02, 100.0)
                        .translation(Vector::new(0.0, -0.02, 0.0))
                        .active_hooks(flags),
                    None,
                );
                let body = world.insert_body(
                    RigidBodyBuilder::dynamic()
                        .translation(Vector::new(0.0, 0.52, 0.0))
                        .linvel(Vector::new(40.0, -2.0, 0.0))
                        .angvel(spin),
                );
                let co = world.insert_collider(collider.clone().active_hooks(flags), Some(body));
                let mut touch = TouchPipeline::default();
                if mode == Some(false) {
                    touch.track_collider(co);
                    touch.track_collider(plate);
                }
                for _ in 0..30 {
                    match mode {
                        Some(_) => touch.step(&mut world),
                        None => world.step(),
                    }
                }
                *world.bodies[body].position()
            };
            let vanilla = run(None);
            for mode in [Some(true), Some(false)] {
                let pose = run(mode);
                assert!(
                    !vanilla.is_finite() || pose.is_finite(),
                    "{:?} spun {spin}, dt {dt}, {mode:?}: {pose:?} (vanilla {vanilla:?})",
                    collider.shape.shape_type()
                );
            }
        }
    }
}
