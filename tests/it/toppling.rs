//! A body balanced on an edge of a floor, turning, topples (found in rapier's CCD stress scene,
//! where cubes lay frozen on their edges for hundreds of steps): in a real rapier pipeline
//! through the touch pipeline in both opt-in modes, a cube set on an edge and spun never gains
//! more energy than vanilla rapier gives it (kinetic plus potential, computed in the test from
//! the body's state), and the case the scene showed ends resting on a face (its centre one
//! half-extent above the floor), as vanilla rapier's does.

use proptest::prelude::*;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

/// Total mechanical energy of cube `body` of half-extent `half` (J): translational, rotational
/// (a cube's inertia is `m (2 half)² / 6` about any axis through its centre) and potential above
/// `y = 0`.
fn energy(world: &PhysicsWorld, body: RigidBodyHandle, half: f32) -> f32 {
    let b = &world.bodies[body];
    let m = b.mass();
    let inertia = m * (2.0 * half).powi(2) / 6.0;
    0.5 * m * b.linvel().length_squared() + 0.5 * inertia * b.angvel().length_squared()
        - m * world.gravity.y * b.center_of_mass().y
}

/// Sets a cube of half-extent `half` on an edge (turned `lean` degrees about z, so it leans and
/// its weight topples it) with spin `spin` (rad/s) about z through its centre, and steps it
/// 8 s (`mode`: `None`
/// vanilla rapier, `Some(hooks)` the touch pipeline, opted in by hook flag or tracked); returns
/// the largest energy gain over the initial energy (relative), and the centre's height over
/// `half` at the end.
fn topple(half: f32, spin: f32, lean: f32, hooks: bool, mode: Option<bool>) -> (f32, f32) {
    let mut world = PhysicsWorld::default();
    let flags = if hooks {
        ActiveHooks::MODIFY_SOLVER_CONTACTS
    } else {
        ActiveHooks::empty()
    };
    if mode.is_some() {
        TouchPipeline::configure(&mut world.integration_parameters);
    }
    let floor = world.insert_collider(
        ColliderBuilder::cuboid(100.0 * half, half, 100.0 * half)
            .translation(Vector::new(0.0, -half, 0.0))
            .active_hooks(flags),
        None,
    );
    let angle = lean.to_radians();
    // The edge at the origin: the centre is `half·√2` from it, at 45° + lean from the floor.
    let lift = half * 2f32.sqrt() * (45f32.to_radians() + angle).sin() + 1e-4 * half;
    let body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, lift, 0.0))
            .rotation(Vector::new(0.0, 0.0, angle))
            .angvel(Vector::new(0.0, 0.0, spin)),
    );
    let cube = world.insert_collider(
        ColliderBuilder::cuboid(half, half, half).active_hooks(flags),
        Some(body),
    );
    let mut touch = TouchPipeline::default();
    if mode == Some(false) {
        touch.track_collider(floor);
        touch.track_collider(cube);
    }
    let start = energy(&world, body, half);
    let mut most = start;
    for _ in 0..480 {
        match mode {
            Some(_) => touch.step(&mut world),
            None => world.step(),
        }
        most = most.max(energy(&world, body, half));
    }
    let height = world.bodies[body].center_of_mass().y / half;
    ((most - start) / start.abs().max(f32::MIN_POSITIVE), height)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Cubes of 4 cm to 40 m, leaning 5-40° on an edge, spinning either way about z with their
    /// edges moving at up to 25 m/s: the touch pipeline never gives the cube more energy than
    /// vanilla rapier's solver does (plus 5 %). Where they end is chaotic (a violently spun
    /// cube bounces for seconds on either side), so it is checked on the fixed case below.
    #[test]
    fn a_cube_spinning_on_its_edge_gains_no_energy(
        log_half in (0.02f32).log10()..(20.0f32).log10(),
        edge_speed in -25.0f32..25.0,
        lean in 5.0f32..40.0,
    ) {
        let half = 10f32.powf(log_half);
        let spin = edge_speed / (half * 2f32.sqrt());
        let (vanilla, _) = topple(half, spin, lean, false, None);
        for hooks in [true, false] {
            let (gain, height) = topple(half, spin, lean, hooks, Some(hooks));
            // A frozen body gained its weight's free fall every step (three times what it
            // started with in 6 s).
            prop_assert!(
                gain <= vanilla.max(0.0) + 0.05,
                "hooks {hooks}: energy +{:.1} % (vanilla +{:.1} %), ends at {height} half-extents",
                gain * 100.0,
                vanilla * 100.0
            );
        }
    }
}

/// The case rapier's CCD stress scene showed: a 2 m cube leaning 25° and spun at 8 rad/s was
/// held on its edge, walked back whole every step, by the hook-flag mode (+304 % energy at
/// 1.42 half-extents). It topples onto a face, as vanilla rapier's does.
#[test]
fn a_2_m_cube_spun_onto_its_edge_does_not_freeze_there() {
    let (_, vanilla) = topple(2.0, 8.0, 25.0, false, None);
    assert!((vanilla - 1.0).abs() < 0.02, "vanilla: {vanilla}");
    for hooks in [true, false] {
        let (gain, height) = topple(2.0, 8.0, 25.0, hooks, Some(hooks));
        assert!(
            gain <= 0.05 && (height - 1.0).abs() < 0.02,
            "hooks {hooks}: +{gain}, {height}"
        );
    }
}
