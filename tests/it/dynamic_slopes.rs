//! A dynamic ball on a tilted soft plate (implicit coupling with friction and rotation): it
//! rolls or slips down the slope at the rigid-body answer, written here. A solid ball on a
//! slope `θ` with friction `μ` rolls without slipping when `μ ≥ (2/7) tan θ`, at
//! `a = (5/7) g sin θ`; with less friction it slips, at `a = g (sin θ - μ cos θ)`, its spin
//! growing at `μ g cos θ / (2/5 r)`; frictionless it slides at `g sin θ` without turning. The
//! plate is stiff (its dent under the ball a fraction of a millimetre), so a rigid slope is
//! the reference; the dent it drags along costs the ball a little (measured: 0.5-4 %).

use proptest::prelude::*;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim};

/// What the ball did: its acceleration down the slope, and its spin's growth (times its
/// radius), both averaged over a third of a second once it got going.
struct Run {
    acceleration: f32,
    spin_up: f32,
}

/// A 2 m plate of 20 × 20 cells, edges of 30 kN/m, rim pinned, 17 substeps, on a fixed body
/// tilted by `deg` about z; a 0.26 kg ball of 5 cm radius placed on it at rest, with friction
/// `mu` (static and dynamic).
fn roll(deg: f32, mu: f32) -> Run {
    let theta = deg.to_radians();
    let tilt = Rotation::from_rotation_z(theta);
    let mut world = PhysicsWorld::default();
    let fixed = world.insert_body(RigidBodyBuilder::fixed().rotation(tilt.to_scaled_axis()));
    let cells = 20;
    let k: f32 = 30_000.0;
    let surface = MassSpringSurfaceBuilder::from_mesh(&plate(2.0, 2.0, cells, cells))
        .stiffness(k)
        .damping(0.1 * k.sqrt())
        .pinned(plate_rim(cells, cells))
        .build()
        .unwrap();
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: 17,
        collider: true,
    };
    set.insert(surface, fixed, &mut world, options).unwrap();
    let r = 0.05;
    let up = tilt * Vector::Y;
    let body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(up * (r + 0.002))
            .can_sleep(false),
    );
    let ball = world.insert_collider(ColliderBuilder::ball(r).density(500.0), Some(body));
    set.add_tool(ball, &mut world).unwrap();
    set.set_tool_friction(ball, Friction::new(mu, mu).unwrap())
        .unwrap();
    let down = tilt * Vector::new(-1.0, 0.0, 0.0);
    let axis = tilt * Vector::Z;
    let dt = world.integration_parameters.dt;
    let (mut v, mut w) = (Vec::new(), Vec::new());
    for _ in 0..27 {
        set.step(&mut world);
        v.push(world.bodies[body].linvel().dot(down));
        // Rolling down the slope turns the ball about +z (its bottom moves up the slope).
        w.push(world.bodies[body].angvel().dot(axis) * r);
    }
    let span = 20.0 * dt;
    Run {
        acceleration: (v[26] - v[6]) / span,
        spin_up: (w[26] - w[6]) / span,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]

    #[test]
    fn a_ball_rolls_or_slips_down_a_soft_slope_as_a_rigid_one_would(
        deg in 15.0f32..45.0,
        mu in 0.0f32..0.6,
    ) {
        let theta = deg.to_radians();
        let g = 9.81;
        // Within 3 % of the stick/slip boundary the ball's contacts deliver less friction than
        // the rigid answer needs (README, known limits; measured by
        // `at_the_stick_slip_boundary_the_spin_falls_short_by_at_most_a_seventh` below).
        prop_assume!((mu / (2.0 / 7.0 * theta.tan()) - 1.0).abs() >= 0.03);
        let rolls = mu >= 2.0 / 7.0 * theta.tan();
        let (a, spin) = if rolls {
            let a = 5.0 / 7.0 * g * theta.sin();
            (a, a)
        } else {
            (
                g * (theta.sin() - mu * theta.cos()),
                mu * g * theta.cos() / 0.4,
            )
        };
        let run = roll(deg, mu);
        let scale = g * theta.sin();
        prop_assert!(
            (run.acceleration - a).abs() <= 0.05 * scale,
            "{deg}° μ {mu}: {} m/s² down the slope, {a} expected ({})",
            run.acceleration,
            if rolls { "rolling" } else { "slipping" }
        );
        prop_assert!(
            (run.spin_up - spin).abs() <= 0.05 * scale,
            "{deg}° μ {mu}: spin grows {} m/s², {spin} expected",
            run.spin_up
        );
    }
}

/// The frictionless and the rolling ends of the range, at 30°.
#[test]
fn frictionless_slides_and_rough_rolls() {
    let theta = 30f32.to_radians();
    let g = 9.81;
    let slide = roll(30.0, 0.0);
    assert!((slide.acceleration - g * theta.sin()).abs() <= 0.03 * g * theta.sin());
    assert!(slide.spin_up.abs() <= 0.01 * g);
    let rough = roll(30.0, 0.5);
    let a = 5.0 / 7.0 * g * theta.sin();
    assert!(
        (rough.acceleration - a).abs() <= 0.03 * a,
        "{}",
        rough.acceleration
    );
    assert!((rough.spin_up - a).abs() <= 0.03 * a, "{}", rough.spin_up);
}

/// The stick/slip boundary `μ = (2/7) tan θ`, where rolling and slipping give the same spin:
/// there the ball's contacts need just about their static limit, and the friction they deliver
/// falls short of it (likely the solve's stick/slide decisions, which take a change found in
/// its second pass only at the next step; not traced).
/// Measured at 32°: the spin grows 7-11 % slower than the rigid answer within 0.5 % of the
/// boundary, and within 2 % of it at 3 % off (`a_ball_rolls_or_slips_down_a_soft_slope...`
/// leaves that band out). This bounds the shortfall, so that it cannot grow unnoticed.
#[test]
fn at_the_stick_slip_boundary_the_spin_falls_short_by_at_most_a_seventh() {
    let deg: f32 = 32.0;
    let theta = deg.to_radians();
    let g = 9.81;
    let boundary = 2.0 / 7.0 * theta.tan();
    let rigid = 5.0 / 7.0 * g * theta.sin();
    for f in [0.995, 1.0, 1.005] {
        let run = roll(deg, boundary * f);
        assert!(
            run.spin_up >= 6.0 / 7.0 * rigid && run.spin_up <= 1.02 * rigid,
            "μ {} x the boundary: spin grows {} m/s², the rigid ball's {rigid}",
            f,
            run.spin_up
        );
        // Whatever the spin, the ball does not speed down the slope faster than it would
        // slide with the friction it was given.
        let sliding = g * (theta.sin() - boundary * f * theta.cos());
        assert!(
            run.acceleration <= 1.05 * sliding,
            "μ {f} x the boundary: {} m/s² down the slope, {sliding} sliding",
            run.acceleration
        );
    }
}
