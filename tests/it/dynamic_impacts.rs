//! Fresh impacts of two dynamic bodies (`TouchOptions::rewind_dynamic_impacts`): two bodies
//! apart when a step begins close by less than their safe step over it. rapier's solver never
//! sees them (no contact point at the step's start) or sees them only through a speculative
//! point (within its prediction distance, 2 cm by default: a known failure, below), and
//! vanilla rapier ends the step with them deep in each other. Through the crate,
//! in both opt-in modes, they end the step touching (parry's contact query, not the crate's),
//! with the momentum they had (no gravity: nothing else acts), no more kinetic energy, and no
//! velocity still closing along the contact normal. A pair rapier does not solve (a sensor,
//! collision or solver groups that exclude it) is left as vanilla leaves it.

use proptest::prelude::*;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

#[derive(Copy, Clone, Debug, PartialEq)]
enum Side {
    Rapier,
    Hooks,
    Tracked,
}

#[derive(Copy, Clone, Debug)]
struct Impact {
    /// Half-size of the first body (a cuboid); the second is a cuboid or a ball of `ratio`
    /// times its size.
    h: f32,
    ratio: f32,
    ball: bool,
    /// Density of the second body over the first's.
    density_ratio: f32,
    /// Gap at the step's start and closing over the step, in the smaller body's thickness.
    gap: f32,
    closing: f32,
    /// Sideways offset of the second body, in the first's size.
    offset: f32,
    /// Spin of the second body (rad/s about z).
    spin: f32,
}

struct After {
    depth: f32,
    normal: Vector,
    momentum: (Vector, Vector),
    /// The bodies' momenta's magnitudes summed, at the step's start.
    momentum_scale: f32,
    energy: (f32, f32),
    velocities: (Vector, Vector),
}

/// What rapier is told about the pair (the second body's collider).
#[derive(Copy, Clone, Debug, PartialEq)]
enum Pairing {
    Solid,
    Sensor,
    /// Collision groups that exclude the pair.
    Groups,
    /// Solver groups that exclude the pair (contacts computed, not solved).
    SolverGroups,
}

/// One step of the two bodies, in zero gravity, on `side` with the crate's rewind `rewind`.
fn one_step(c: Impact, side: Side, rewind: bool) -> After {
    one_step_paired(c, side, rewind, Pairing::Solid)
}

/// [`one_step`] with the pair set up as `pairing` says.
fn one_step_paired(c: Impact, side: Side, rewind: bool, pairing: Pairing) -> After {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    let h2 = c.h * c.ratio;
    let thin = 2.0 * c.h.min(h2);
    let dt = world.integration_parameters.dt;
    let speed = c.closing * thin / dt;
    let a = world.insert_body(RigidBodyBuilder::dynamic().linvel(Vector::X * 0.5 * speed));
    let (g1, g2) = (
        InteractionGroups::new(Group::GROUP_1, Group::GROUP_1, InteractionTestMode::And),
        InteractionGroups::new(Group::GROUP_2, Group::GROUP_2, InteractionTestMode::And),
    );
    let first = ColliderBuilder::cuboid(c.h, c.h, c.h);
    let first = match pairing {
        Pairing::Groups => first.collision_groups(g1),
        Pairing::SolverGroups => first.solver_groups(g1),
        _ => first,
    };
    let ca = world.insert_collider(first, Some(a));
    let b = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(c.h + h2 + c.gap * thin, c.offset * c.h, 0.0))
            .linvel(-Vector::X * 0.5 * speed)
            .angvel(Vector::Z * c.spin),
    );
    let shape = if c.ball {
        ColliderBuilder::ball(h2)
    } else {
        ColliderBuilder::cuboid(h2, h2, h2)
    };
    let shape = match pairing {
        Pairing::Solid => shape,
        Pairing::Sensor => shape.sensor(true),
        Pairing::Groups => shape.collision_groups(g2),
        Pairing::SolverGroups => shape.solver_groups(g2),
    };
    let cb = world.insert_collider(shape.density(c.density_ratio), Some(b));
    let mut touch = TouchPipeline::default();
    touch.options.rewind_dynamic_impacts = rewind;
    match side {
        Side::Rapier => {}
        Side::Hooks => {
            for h in [ca, cb] {
                world.colliders[h].set_active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS);
            }
        }
        Side::Tracked => {
            touch.track_collider(ca);
            touch.track_collider(cb);
        }
    }
    if side != Side::Rapier {
        TouchPipeline::configure(&mut world.integration_parameters);
    }
    let v0 = (world.bodies[a].linvel(), world.bodies[b].linvel());
    if side == Side::Rapier {
        world.step();
    } else {
        touch.step(&mut world);
    }
    // Momentum and translational energy before and after, with the masses rapier computed
    // from the colliders during the step (before it, a body's mass is not yet set).
    let (ma, mb) = (world.bodies[a].mass(), world.bodies[b].mass());
    let v1 = (world.bodies[a].linvel(), world.bodies[b].linvel());
    let momentum = |(va, vb): (Vector, Vector)| va * ma + vb * mb;
    let energy =
        |(va, vb): (Vector, Vector)| 0.5 * (ma * va.length_squared() + mb * vb.length_squared());
    let momentum_scale = (v0.0 * ma).length() + (v0.1 * mb).length();
    let (pa, pb) = (world.bodies[a].position(), world.bodies[b].position());
    let contact = parry3d::query::contact(
        pa,
        world.colliders[ca].shape(),
        pb,
        world.colliders[cb].shape(),
        0.1 * thin,
    )
    .unwrap();
    let (depth, normal) = contact.map_or((-0.1 * thin, Vector::X), |c| (-c.dist, c.normal1));
    After {
        depth,
        normal,
        momentum: (momentum(v0), momentum(v1)),
        momentum_scale,
        energy: (energy(v0), energy(v1)),
        velocities: v1,
    }
}

fn dt() -> f32 {
    IntegrationParameters::default().dt
}

fn impact() -> impl Strategy<Value = Impact> {
    (
        -1.3f32..0.7,
        0.5f32..2.0,
        any::<bool>(),
        -2.0f32..2.0,
        0.05f32..0.2,
        0.35f32..0.9,
        -0.5f32..0.5,
        -3.0f32..3.0,
    )
        .prop_map(
            |(log_h, ratio, ball, log_density, gap, closing, offset, spin)| Impact {
                h: 10f32.powf(log_h),
                ratio,
                ball,
                density_ratio: 10f32.powf(log_density),
                gap,
                closing,
                offset,
                spin,
            },
        )
}

/// Impact `c` through the crate, in both modes, against vanilla rapier: `Ok(false)` when
/// vanilla rapier held the pair (it ends less than 5 % of the thinner body deep: not a case);
/// otherwise each mode ends it touching (within the slop), with its momentum, no more kinetic
/// energy and nothing still closing along the normal, or says what failed.
fn check_impact(c: Impact) -> Result<bool, String> {
    let thin = 2.0 * c.h.min(c.h * c.ratio);
    let vanilla = one_step(c, Side::Rapier, true);
    if vanilla.depth <= 0.05 * thin {
        return Ok(false);
    }
    for side in [Side::Hooks, Side::Tracked] {
        let r = one_step(c, side, true);
        let slop = TouchOptions::default().penetration_slop;
        if r.depth > slop + 1e-4 * thin {
            return Err(format!(
                "{c:?} {side:?}: {} m deep (vanilla {} m)",
                r.depth, vanilla.depth
            ));
        }
        let (p0, p1) = r.momentum;
        if (p1 - p0).length() > 1e-4 * r.momentum_scale {
            return Err(format!("{c:?} {side:?}: momentum {p0:?} -> {p1:?}"));
        }
        let (e0, e1) = r.energy;
        if e1 > e0 * (1.0 + 1e-4) {
            return Err(format!("{c:?} {side:?}: energy {e0} -> {e1}"));
        }
        // Nothing still closes along the normal (out of the first body), within 5 % of the
        // speed they met at: where a box touches with an edge or a corner, the normal is one
        // of a cone, and parry's answer at the touching poses is one of its directions, not
        // necessarily the one the impact was measured along.
        let (va, vb) = r.velocities;
        let met_at = c.closing * thin / dt();
        let closing = (vb - va).dot(r.normal);
        if closing < -0.05 * met_at {
            return Err(format!("{c:?} {side:?}: closing at {closing} m/s"));
        }
    }
    Ok(true)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Boxes and balls of 5 cm to 20 m, one to a hundred times heavier than the other,
    /// closing by 35-90 % of the thinner's thickness over the step from 5-20 % of it apart,
    /// offset sideways and spinning (at most 270 m/s each: rapier caps a body's speed at its
    /// `normalized_max_linear_velocity`, 400 m/s). Only a case vanilla rapier leaves deep is
    /// one (it saw some small pairs coming).
    #[test]
    fn two_dynamic_bodies_end_an_impact_touching_with_their_momentum(c in impact()) {
        let checked = check_impact(c);
        prop_assert!(checked.is_ok(), "{}", checked.clone().unwrap_err());
        prop_assume!(checked == Ok(true), "vanilla rapier held the pair");
    }
}

/// A case a random seed of the property test found ending as deep as in vanilla rapier, the
/// rewind not acting (seed 8158): two boxes of 5 cm, 20.2 mm apart, each moving 1.8 cm toward
/// the other. Neither moved as far as rapier's prediction distance (2 cm), so the guard
/// looked only at rapier's pairs, and rapier had none (15.5 mm deep at the end). With the
/// rewind on, a body that moved half the prediction distance is now looked at.
#[test]
fn two_slow_bodies_closing_past_the_prediction_distance_end_touching() {
    let c = Impact {
        h: 0.050_985_98,
        ratio: 1.096_855,
        ball: false,
        density_ratio: 1.0,
        gap: 0.197_849_53,
        closing: 0.35,
        offset: 0.0,
        spin: 0.0,
    };
    assert_eq!(check_impact(c), Ok(true));
}

/// Known failure, kept ignored (random seeds 8106, 8138, 9814 and 9961 of the property
/// test): a ball of 8-22 cm meeting a box of 5-14 cm off its centre line, 5 % of the
/// thinner's thickness apart, closing by 79-90 % of it. That is within rapier's prediction
/// distance, so rapier held a speculative contact point for the pair when the step began,
/// the guard leaves it to rapier's solver, and rapier's soft contact lets it end 6-15 mm
/// deep, as in vanilla. Taking a point that was not touching as no contact (so the rewind
/// acts) passed all four, but made every pile of the stress scenes with the rewind on worse:
/// the TriMesh floor's deepest overlap 141 -> 326 mm hooked, the hulls' 312 -> 675 mm at 26
/// times vanilla's cost, the ragdolls' 44 -> 68 mm. Not kept. Run with `cargo test --release
/// -- --ignored a_ball_rapier_saw_coming`.
#[test]
#[ignore = "known failure: a pair rapier held a speculative point for is left to its soft contact"]
fn a_ball_rapier_saw_coming_ends_touching() {
    let cases = [
        (
            0.060_911_97,
            1.713_947_3,
            0.775_714_3,
            0.831_610_7,
            -0.413_619,
            1.763_872_5,
        ),
        (
            0.072_461_68,
            1.528_275_7,
            1.0,
            0.897_806_1,
            -0.408_877_6,
            2.460_846_7,
        ),
        (
            0.136_686_58,
            1.640_401_8,
            0.678_963_6,
            0.822_972_9,
            0.418_266_2,
            -2.391_59,
        ),
        (
            0.103_336_64,
            1.747_102,
            0.348_753_6,
            0.794_848_5,
            -0.475_052,
            1.880_058_4,
        ),
    ];
    let failed: Vec<String> = cases
        .into_iter()
        .filter_map(|(h, ratio, density_ratio, closing, offset, spin)| {
            let c = Impact {
                h,
                ratio,
                ball: true,
                density_ratio,
                gap: 0.05,
                closing,
                offset,
                spin,
            };
            check_impact(c).err()
        })
        .collect();
    assert!(failed.is_empty(), "{failed:#?}");
}

/// Two 1 m boxes a tenth of their size apart, closing by 60 % of it, slightly offset.
const HEAD_ON: Impact = Impact {
    h: 0.5,
    ratio: 1.0,
    ball: false,
    density_ratio: 1.0,
    gap: 0.1,
    closing: 0.6,
    offset: 0.1,
    spin: 0.0,
};

/// The option off leaves such a pair to rapier, as vanilla does.
#[test]
fn with_the_rewind_off_a_fresh_impact_is_left_as_vanilla_leaves_it() {
    let c = HEAD_ON;
    let vanilla = one_step(c, Side::Rapier, true).depth;
    assert!(vanilla > 0.4, "vanilla {vanilla} m");
    for side in [Side::Hooks, Side::Tracked] {
        let off = one_step(c, side, false).depth;
        assert!(
            (off - vanilla).abs() < 0.05 * vanilla,
            "{side:?}: {off} m, vanilla {vanilla} m"
        );
        assert!(one_step(c, side, true).depth < 1e-3, "{side:?}");
    }
}

/// rapier's collision semantics hold for the rewind: a sensor, collision groups and solver
/// groups that exclude the pair let the two bodies pass into each other as vanilla rapier
/// does, in both modes.
#[test]
fn a_pair_rapier_does_not_solve_is_not_rewound() {
    let c = HEAD_ON;
    for pairing in [Pairing::Sensor, Pairing::Groups, Pairing::SolverGroups] {
        let vanilla = one_step_paired(c, Side::Rapier, true, pairing).depth;
        assert!(vanilla > 0.4, "{pairing:?}: vanilla {vanilla} m");
        for side in [Side::Hooks, Side::Tracked] {
            let r = one_step_paired(c, side, true, pairing);
            assert!(
                (r.depth - vanilla).abs() < 0.01 * vanilla,
                "{pairing:?} {side:?}: {} m, vanilla {vanilla} m",
                r.depth
            );
        }
    }
}
