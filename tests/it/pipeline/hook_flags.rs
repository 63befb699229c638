//! Hook flags managed on demand (`TouchOptions::hook_flags_on_demand`) go only to the fast
//! bodies whose pairs the hooks can rewrite, and bodies opted in so land within a millimetre
//! and rest without flags.

use super::*;

/// A box, a ball and a TriMesh body opted in with the hook flag, dropped at 12 m/s onto a
/// floor.
fn hooked_drop() -> (PhysicsWorld, Vec<(RigidBodyHandle, ColliderHandle)>) {
    let mut w = world();
    add_floor(&mut w);
    let (v, i) = parry3d::shape::Cuboid::new(Vector::splat(0.2)).to_trimesh();
    let shapes = [
        ColliderBuilder::cuboid(0.2, 0.2, 0.2),
        ColliderBuilder::ball(0.2),
        ColliderBuilder::trimesh(v, i).unwrap(),
    ];
    let bodies = shapes
        .into_iter()
        .enumerate()
        .map(|(k, co)| {
            let b = w.insert_body(
                RigidBodyBuilder::dynamic()
                    .translation(Vector::new(k as f32 * 1.5 - 1.5, 1.0, 0.0))
                    .linvel(Vector::new(0.0, -12.0, 0.0)),
            );
            let c = w.insert_collider(co.density(1000.0).active_hooks(HOOKS), Some(b));
            (b, c)
        })
        .collect();
    (w, bodies)
}

fn flagged(w: &PhysicsWorld, c: ColliderHandle) -> bool {
    w.colliders[c].active_hooks().contains(HOOKS)
}

/// With the hook flags managed on demand (`TouchPipeline::default()`) and the guard not
/// correcting poses, the hooks are the only correction: a fast body whose pairs they can
/// rewrite (a box) gets its flag; a ball (curved: its touch mesh is a tessellation) and a
/// TriMesh body (a composite shape, one manifold per triangle) get none, as the hooks never
/// rewrite their pairs.
#[test]
fn hook_flags_on_demand_go_only_where_the_hooks_can_rewrite() {
    let (mut w, bodies) = hooked_drop();
    let mut touch = TouchPipeline::default();
    touch.options.correct_poses = false;
    touch.step(&mut w);
    // 12 m/s for 1/60 s: 20 cm, far past rapier's prediction distance.
    assert!(
        flagged(&w, bodies[0].1),
        "the box got no flag while falling fast"
    );
    assert!(
        !flagged(&w, bodies[1].1),
        "the ball kept a flag the hooks never use"
    );
    assert!(
        !flagged(&w, bodies[2].1),
        "the TriMesh body kept a flag the hooks never use"
    );
}

/// With the guard correcting poses and one pass only, the box it corrects on landing is left
/// with no pass to look at it again: it gets the hook flag for the next step (the hooks back
/// the guard up), while the ball and the TriMesh body get none; at every other step none
/// has a flag.
#[test]
fn a_body_the_guards_last_pass_moved_gets_the_hook_flag() {
    let (mut w, bodies) = hooked_drop();
    let mut touch = TouchPipeline::default();
    touch.options.max_passes = 1;
    let (mut corrected, mut flags) = (0, 0);
    for _ in 0..60 {
        touch.step(&mut w);
        // The box's pair walked back from a penetration, and some pose corrected.
        let box_corrected = touch.corrections() > 0
            && touch
                .reports()
                .iter()
                .any(|r| r.moving == bodies[0].1 && r.state == TouchState::Penetrating);
        corrected += box_corrected as usize;
        if flagged(&w, bodies[0].1) {
            assert!(box_corrected, "a flag on a box the guard did not correct");
            flags += 1;
        }
        assert!(!flagged(&w, bodies[1].1) && !flagged(&w, bodies[2].1));
    }
    assert!(corrected > 0, "the guard never corrected the box");
    assert!(
        flags > 0,
        "the box the guard's only pass corrected never got the flag"
    );
}

/// With the guard correcting poses (the default), a box, a ball and a TriMesh body dropped
/// at 12 m/s land without going in deeper than 1 mm (parry's contact query) and come to rest
/// above the floor, with no hook flag left: the guard puts each pair back to first touch, and
/// the flag is raised only on a body its last pass moved.
#[test]
fn hooked_bodies_land_within_a_millimetre_and_rest_without_flags() {
    let (mut w, bodies) = hooked_drop();
    let mut touch = TouchPipeline::default();
    let floor = w
        .colliders
        .iter()
        .find(|(_, c)| c.parent().is_none())
        .map(|(h, _)| h)
        .unwrap();
    for _ in 0..240 {
        touch.step(&mut w);
        for &(_, c) in &bodies {
            let depth = parry_depth(&w, floor, c);
            assert!(
                depth <= 1e-3,
                "{:?} {depth} m into the floor",
                w.colliders[c].shape().shape_type()
            );
        }
    }
    for &(b, c) in &bodies {
        assert!(w.bodies[b].translation().y > 0.0, "went through the floor");
        assert!(w.bodies[b].linvel().length() < 0.05, "not at rest");
        assert!(!flagged(&w, c), "a flag left on a body at rest");
    }
}
