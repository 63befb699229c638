//! Touch events of rigid pairs through the touch pipeline: a 30 m/s box the guard stops at a
//! thin floor starts touching it at the step the guard walks it back (parry's distance then
//! ~0), stays touching while it rests (no stray events), and stops when it is lifted off or
//! removed; a sensor floor and pairs with no opted-in collider give no events.

use parry3d::query;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

fn distance(world: &PhysicsWorld, a: ColliderHandle, b: ColliderHandle) -> f32 {
    let (ca, cb) = (&world.colliders[a], &world.colliders[b]);
    query::distance(ca.position(), ca.shape(), cb.position(), cb.shape())
        .unwrap()
        .distance
}

#[test]
fn a_guarded_fast_box_starts_touching_once_and_stops_when_lifted_or_removed() {
    let mut world = PhysicsWorld::default();
    TouchPipeline::configure(&mut world.integration_parameters);
    let floor = world.insert_collider(ColliderBuilder::cuboid(5.0, 0.01, 5.0), None);
    let sensor = world.insert_collider(
        ColliderBuilder::cuboid(5.0, 0.01, 5.0)
            .translation(Vector::new(0.0, 2.0, 0.0))
            .sensor(true),
        None,
    );
    let body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 3.0, 0.0))
            .linvel(Vector::new(0.0, -30.0, 0.0)),
    );
    let cube = world.insert_collider(ColliderBuilder::cuboid(0.2, 0.2, 0.2), Some(body));
    // Two boxes nobody opted in, resting on each other far away: no events.
    for y in [0.2f32, 0.6] {
        let b =
            world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(8.0, y, 0.0)));
        world.insert_collider(ColliderBuilder::cuboid(0.2, 0.2, 0.2), Some(b));
    }
    world.insert_collider(
        ColliderBuilder::cuboid(1.0, 0.01, 1.0).translation(Vector::new(8.0, -0.01, 0.0)),
        None,
    );
    let mut touch = TouchPipeline::default();
    for c in [floor, sensor] {
        touch.track_collider(c);
    }
    let mut all = Vec::new();
    for step in 0..120 {
        touch.step(&mut world);
        let events: Vec<PairTouchEvent> = touch.drain_touch_events().collect();
        if events.iter().any(|e| e.started()) {
            // The box touches where the event says so.
            let d = distance(&world, floor, cube);
            assert!(d <= 1e-3, "step {step}: started at a distance {d}");
        }
        all.extend(events);
    }
    assert_eq!(
        all,
        [PairTouchEvent::Started {
            collider1: floor,
            collider2: cube
        }],
        "one start, nothing else (resting, the sensor, the boxes nobody opted in)"
    );
    assert!(world.bodies[body].translation().y > 0.2);
    // Lifted off: stopped.
    world.bodies[body].set_translation(Vector::new(0.0, 1.0, 0.0), true);
    world.bodies[body].set_linvel(Vector::ZERO, true);
    touch.step(&mut world);
    let events: Vec<PairTouchEvent> = touch.drain_touch_events().collect();
    assert_eq!(
        events,
        [PairTouchEvent::Stopped {
            collider1: floor,
            collider2: cube
        }]
    );
    // Falls back, touches again, then is removed: stopped.
    for _ in 0..90 {
        touch.step(&mut world);
    }
    let events: Vec<PairTouchEvent> = touch.drain_touch_events().collect();
    assert_eq!(
        events.iter().filter(|e| e.started()).count(),
        1,
        "{events:?}"
    );
    world.remove_collider(cube);
    touch.step(&mut world);
    assert!(touch
        .drain_touch_events()
        .any(|e| !e.started() && e.pair() == (floor, cube)));
}
