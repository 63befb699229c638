//! Dynamic bodies dropped on a soft plate (issue 13, item 4's proof): balls of 1 g to 10 kg
//! dropped from 0.05 m to 2 m onto plates with edges of 1 to 1000 N/m, 1 and 17 substeps. Each
//! drop must create no energy (the first rebound no faster than the impact), never go through
//! the plate, and be at rest within 10 s with the plate carrying the ball's weight within 2 %.
//!
//! Known failure, kept as an ignored test: the surface's reaction reaches a dynamic body as a
//! rapier force one rigid step later (`SurfaceSet`'s docs), and the body's mass does not enter
//! the contact solve. Measured on this file's scene at 48 points of the ranges (1 g, 30 g,
//! 1 kg, 10 kg; 5 cm, 2 m; 1, 30, 1000 N/m; 1 and 17 substeps), every one fails:
//! - balls of 1 g and 30 g left the plate at up to 360 times their impact speed (some at
//!   rapier's 400 m/s velocity cap);
//! - balls of 1 kg and 10 kg went through plates of 1 and 30 N/m, and through 1000 N/m plates
//!   with 17 substeps (10 kg with 1 substep too);
//! - the closest, 30 g from 5 cm onto 30 N/m with 17 substeps, rebounded at 0.66 of its
//!   impact speed and carried its weight within 0.2 %, but still moved at 3.7 cm/s after 10 s.
//!
//! The fix is item 4's implicit coupling (the body's mass in the constraint solve of the same
//! step); not built.

use crate::common::pinned_plate;
use proptest::prelude::*;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

/// What one drop saw.
struct Drop {
    /// The ball's downward speed the step before it first touched the plate (m/s).
    impact: f32,
    /// Its largest upward speed on leaving the plate (m/s).
    rebound: f32,
    /// Whether its centre went below the pinned rim's plane by more than its radius plus the
    /// plate's deepest dent (through the plate).
    through: bool,
    /// Its speed at the end (m/s).
    speed_at_end: f32,
    /// The plate's mean upward force on it over the last second, relative to its weight.
    support: f32,
}

/// A 1 m plate of 16 × 16 cells ([`pinned_plate`]: rim pinned, edges of `k`, the default areal
/// density), a ball of 8 cm radius and `mass` dropped from `height` above it, `substeps` per
/// rigid step, 10 s.
fn drop(mass: f32, height: f32, k: f32, substeps: u32) -> Drop {
    let mut world = PhysicsWorld::default();
    let (mut set, soft) = pinned_plate(&mut world, 1.0, 16, k, None, substeps);
    let r = 0.08;
    let density = mass / (4.0 / 3.0 * std::f32::consts::PI * r * r * r);
    let body = world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(
        0.0,
        height + r,
        0.0,
    )));
    let ball = world.insert_collider(ColliderBuilder::ball(r).density(density), Some(body));
    set.add_tool(ball, &mut world).unwrap();
    let weight = world.bodies[body].mass() * world.gravity.length();
    let dt = world.integration_parameters.dt;
    let steps = (10.0 / dt).round() as usize;
    let last_second = (1.0 / dt).round() as usize;
    let mut run = Drop {
        impact: 0.0,
        rebound: 0.0,
        through: false,
        speed_at_end: 0.0,
        support: 0.0,
    };
    let (mut touched, mut touching) = (false, false);
    for s in 0..steps {
        let before = world.bodies[body].linvel().y;
        set.step(&mut world);
        let reaction = set.tool_reaction(ball).unwrap();
        let now = reaction.held_vertices + reaction.pressed_points > 0;
        if now && !touched {
            run.impact = -before;
            touched = true;
        }
        if touching && !now {
            run.rebound = run.rebound.max(world.bodies[body].linvel().y);
        }
        touching = now;
        let dent = set.get(soft).unwrap().surface.max_displacement();
        run.through |= world.bodies[body].translation().y < -(r + dent);
        if s + last_second >= steps {
            run.support += reaction.mean_force.y / (weight * last_second as f32);
        }
    }
    run.speed_at_end = world.bodies[body].linvel().length();
    run
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    #[ignore = "known failure, issue 13 item 4: the reaction reaches a dynamic body a step late"]
    fn dropped_bodies_create_no_energy_never_pass_and_come_to_rest(
        log_mass in -3.0f32..1.0,
        height in 0.05f32..2.0,
        log_k in 0.0f32..3.0,
        seventeen in any::<bool>(),
    ) {
        let (mass, k) = (10f32.powf(log_mass), 10f32.powf(log_k));
        let substeps = if seventeen { 17 } else { 1 };
        let d = drop(mass, height, k, substeps);
        prop_assert!(d.impact > 0.0, "{mass} kg never touched");
        prop_assert!(
            d.rebound <= d.impact,
            "{mass} kg from {height} m on {k} N/m: left at {} m/s after hitting at {} m/s",
            d.rebound,
            d.impact
        );
        prop_assert!(!d.through, "{mass} kg from {height} m on {k} N/m went through");
        prop_assert!(d.speed_at_end < 1e-2, "still moving at {} m/s", d.speed_at_end);
        prop_assert!((d.support - 1.0).abs() <= 0.02, "carried {} of its weight", d.support);
    }
}
