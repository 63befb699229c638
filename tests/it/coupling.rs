//! Soft surfaces in a real rapier pipeline: a tool pressed a known depth gets the static spring
//! solution's force; several tools each get their own force and, with the pins' reactions, sum
//! to zero; a released surface returns home; a dynamic ball comes to rest on a soft plate; a
//! surface on a moving kinematic body follows it.

use crate::common::{dirichlet_solve, edge_laplacian};
use rapier_touch::coupling::SURFACE_SOLVER_GROUP;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

const N: u32 = 10; // cells per side: 11 x 11 vertices, 0.1 m apart

fn plate_mesh() -> (Vec<Vector>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for i in 0..=N {
        for j in 0..=N {
            v.push(Vector::new(i as f32 * 0.1, 0.0, j as f32 * 0.1));
        }
    }
    let mut t = Vec::new();
    for i in 0..N {
        for j in 0..N {
            let a = i * (N + 1) + j;
            let b = a + N + 1;
            t.push([a, b, a + 1]);
            t.push([b, b + 1, a + 1]);
        }
    }
    (v, t)
}

fn vid(i: u32, j: u32) -> u32 {
    i * (N + 1) + j
}

fn boundary() -> Vec<u32> {
    (0..=N)
        .flat_map(|i| (0..=N).map(move |j| (i, j)))
        .filter(|&(i, j)| i == 0 || j == 0 || i == N || j == N)
        .map(|(i, j)| vid(i, j))
        .collect()
}

const K: f32 = 100.0;

fn world_with_plate(substeps: u32) -> (PhysicsWorld, SurfaceSet, SurfaceHandle) {
    world_with_plate_of_mass(substeps, 0.01)
}

fn world_with_plate_of_mass(substeps: u32, mass: f32) -> (PhysicsWorld, SurfaceSet, SurfaceHandle) {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    let body = world.insert_body(RigidBodyBuilder::fixed());
    let (v, t) = plate_mesh();
    let surface = MassSpringSurfaceBuilder::new(v, t)
        .stiffness(K)
        .damping(1.0)
        .mass(MassDistribution::PerVertex(mass))
        .pinned(boundary())
        .integrator(Integrator::EXACT)
        .build()
        .unwrap();
    let mut set = SurfaceSet::new();
    let h = set
        .insert(
            surface,
            body,
            &mut world,
            AttachOptions {
                substeps,
                collider: true,
            },
        )
        .unwrap();
    (world, set, h)
}

fn add_ball_tool(
    world: &mut PhysicsWorld,
    set: &mut SurfaceSet,
    at: Vector,
    r: f32,
) -> (RigidBodyHandle, ColliderHandle) {
    let b = world.insert_body(RigidBodyBuilder::kinematic_position_based().translation(at));
    let c = world.insert_collider(ColliderBuilder::ball(r), Some(b));
    set.add_tool(c, world).unwrap();
    (b, c)
}

/// Static reference: vertex `c` held at displacement `-depth` (y), pins at zero, the others
/// free in equilibrium; the force the surface pushes the holder with (linear springs).
fn static_force(held: &[(u32, f64)]) -> Vec<f64> {
    let (v, t) = plate_mesh();
    let n = v.len();
    let lap = edge_laplacian(&t, n, K as f64);
    let pins = boundary();
    let mut u = vec![0.0; n];
    for &(c, d) in held {
        u[c as usize] = -d;
    }
    let known: Vec<bool> = (0..n as u32)
        .map(|i| pins.contains(&i) || held.iter().any(|h| h.0 == i))
        .collect();
    dirichlet_solve(&lap, &known, &mut u);
    // Internal force at each held vertex: -(L u)_c; the tool receives it.
    held.iter()
        .map(|&(c, _)| -(0..n).map(|j| lap[(c as usize, j)] * u[j]).sum::<f64>())
        .collect()
}

/// Drives the tool from `start` to `end` over `ramp` steps, then holds it for `hold` steps.
fn press(
    world: &mut PhysicsWorld,
    set: &mut SurfaceSet,
    tools: &[(RigidBodyHandle, Vector, Vector)],
    ramp: usize,
    hold: usize,
) {
    for s in 0..ramp + hold {
        let a = ((s + 1) as f32 / ramp as f32).min(1.0);
        for (b, from, to) in tools {
            world.bodies[*b].set_next_kinematic_translation(from.lerp(*to, a));
        }
        set.step(world);
    }
}

#[test]
fn pressed_tool_force_matches_the_static_spring_solution() {
    // s ≈ 0.3 per substep (8 substeps), and s ≈ 1700 (one 60 Hz step of a light plate), where
    // the held vertex must act as a pin inside the filter.
    for (substeps, mass) in [(8, 0.01), (1, 1e-4)] {
        press_one_tool(substeps, mass);
    }
}

fn press_one_tool(substeps: u32, mass: f32) {
    let (mut world, mut set, _) = world_with_plate_of_mass(substeps, mass);
    let r = 0.02;
    let depth = 0.01;
    let c = Vector::new(0.5, 0.0, 0.5);
    let (b, tool) = add_ball_tool(&mut world, &mut set, c + Vector::Y * 0.1, r);
    press(
        &mut world,
        &mut set,
        &[(b, c + Vector::Y * 0.1, c + Vector::Y * (r - depth))],
        30,
        240,
    );
    let reaction = set.tool_reaction(tool).unwrap();
    assert_eq!(reaction.held_vertices, 1);
    let expected = static_force(&[(vid(5, 5), depth as f64)])[0];
    let got = reaction.force.y as f64;
    assert!(expected > 0.0);
    assert!(
        (got - expected).abs() <= 0.05 * expected,
        "{substeps} substeps, {mass} kg: force {got} N vs static {expected} N"
    );
    assert!(
        reaction.force.x.abs() < 1e-3 * got as f32 && reaction.force.z.abs() < 1e-3 * got as f32
    );
}

#[test]
fn several_tools_get_their_own_forces_and_balance_the_pins() {
    for count in [2usize, 6] {
        let (mut world, mut set, h) = world_with_plate(4);
        let spots = [(2, 2), (2, 7), (7, 2), (7, 7), (5, 4), (4, 6)];
        let mut tools = Vec::new();
        let mut drives = Vec::new();
        let mut held = Vec::new();
        for (k, &(i, j)) in spots.iter().take(count).enumerate() {
            let depth = 0.004 + 0.002 * k as f32;
            let c = Vector::new(i as f32 * 0.1, 0.0, j as f32 * 0.1);
            let (b, t) = add_ball_tool(&mut world, &mut set, c + Vector::Y * 0.1, 0.02);
            drives.push((b, c + Vector::Y * 0.1, c + Vector::Y * (0.02 - depth)));
            tools.push(t);
            held.push((vid(i, j), depth as f64));
        }
        press(&mut world, &mut set, &drives, 30, 300);
        let expected = static_force(&held);
        let mut total = Vector::ZERO;
        for (k, t) in tools.iter().enumerate() {
            let f = set.tool_reaction(*t).unwrap().force;
            assert!(
                (f.y as f64 - expected[k]).abs() <= 0.05 * expected[k],
                "{count} tools, tool {k}: {} vs {}",
                f.y,
                expected[k]
            );
            total += f;
        }
        let s = &set.get(h).unwrap().surface;
        let pins: Vector = boundary().iter().map(|&p| s.internal_force(p)).sum();
        let sum_abs: f32 = tools
            .iter()
            .map(|t| set.tool_reaction(*t).unwrap().force.length())
            .sum();
        assert!(
            (total + pins).length() <= 0.01 * sum_abs,
            "{count} tools: tools {total:?} + pins {pins:?}"
        );
    }
}

#[test]
fn tool_pulled_away_leaves_the_surface_returning_home() {
    let (mut world, mut set, h) = world_with_plate(4);
    let c = Vector::new(0.5, 0.0, 0.5);
    let (b, tool) = add_ball_tool(&mut world, &mut set, c + Vector::Y * 0.1, 0.05);
    let down = c + Vector::Y * 0.02;
    press(
        &mut world,
        &mut set,
        &[(b, c + Vector::Y * 0.1, down)],
        30,
        60,
    );
    let d0 = set.get(h).unwrap().surface.max_displacement();
    assert!(d0 > 0.02);
    press(
        &mut world,
        &mut set,
        &[(b, down, c + Vector::new(0.3, 0.5, 0.0))],
        30,
        600,
    );
    assert_eq!(set.tool_reaction(tool).unwrap().held_vertices, 0);
    let d1 = set.get(h).unwrap().surface.max_displacement();
    assert!(d1 < 1e-3 * d0, "still {d1} m from home");
}

#[test]
fn dynamic_ball_comes_to_rest_on_a_soft_plate() {
    let (mut world, mut set, h) = world_with_plate(8);
    world.gravity = Vector::new(0.0, -9.81, 0.0);
    let r = 0.06;
    let ball =
        world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.5, 0.4, 0.5)));
    let c = world.insert_collider(ColliderBuilder::ball(r).density(100.0), Some(ball));
    set.add_tool(c, &mut world).unwrap();
    let weight = world.bodies[ball].mass() * 9.81;
    let mut lowest = f32::MAX;
    let (mut support, mut ys) = (0.0f32, Vec::new());
    for k in 0..600 {
        set.step(&mut world);
        let y = world.bodies[ball].translation().y;
        lowest = lowest.min(y);
        if k >= 480 {
            support += set.tool_reaction(c).unwrap().mean_force.y / 120.0;
            ys.push(y);
        }
    }
    // At rest: the last two seconds stay within a millimetre, in a dent of the surface, never
    // through it.
    let (lo, hi) = ys
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), y| (a.min(*y), b.max(*y)));
    assert!(hi - lo < 1e-3, "still moving: y in [{lo}, {hi}]");
    assert!(lo > -r && lowest > -r, "ball centre reached {lowest}");
    assert!(set.get(h).unwrap().surface.max_displacement() > 1e-3);
    // On average the surface carries the ball's weight.
    assert!(
        (support - weight).abs() <= 0.05 * weight,
        "support {support} N vs weight {weight} N"
    );
}

/// `remove_tool` undoes what `add_tool` did: a ball resting on the plate is carried by the
/// surface while it is a tool (the surface's impulses reach it in the same step: no user force
/// is ever added to its body); removed, its solver-group filter holds the surfaces' group
/// again, so rapier solves its contact with the plate's collider and it stays on the plate
/// instead of sinking through.
#[test]
fn removing_a_tool_gives_back_its_solver_groups() {
    let (mut world, mut set, _) = world_with_plate(8);
    world.gravity = Vector::new(0.0, -9.81, 0.0);
    let ball =
        world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.5, 0.2, 0.5)));
    let c = world.insert_collider(ColliderBuilder::ball(0.06).density(100.0), Some(ball));
    let groups = world.colliders[c].solver_groups();
    assert!(groups.filter.contains(SURFACE_SOLVER_GROUP));
    set.add_tool(c, &mut world).unwrap();
    set.add_tool(c, &mut world).unwrap(); // twice: no further change
    assert!(!world.colliders[c]
        .solver_groups()
        .filter
        .contains(SURFACE_SOLVER_GROUP));
    for _ in 0..240 {
        set.step(&mut world);
    }
    let weight = world.bodies[ball].mass() * 9.81;
    // Resting: the surface carries (about) its weight, and no user force was added.
    let carried = set.tool_reaction(c).unwrap().mean_force.y;
    assert!(
        (carried - weight).abs() < 0.05 * weight,
        "{carried} N vs {weight} N"
    );
    assert!(world.bodies[ball].user_force().length() == 0.0);
    assert!(world.bodies[ball].user_torque().length() == 0.0);
    set.remove_tool(c, &mut world);
    assert_eq!(world.colliders[c].solver_groups(), groups);
    assert!(set.tool_reaction(c).is_none());
    // rapier now holds the ball on the plate's collider (rigidly, as any collider).
    for _ in 0..120 {
        set.step(&mut world);
    }
    assert!(
        world.bodies[ball].translation().y > 0.0,
        "fell through the plate's collider"
    );
}

#[test]
fn surface_on_a_moving_kinematic_body_follows_it() {
    let mut world = PhysicsWorld::default();
    let body = world.insert_body(
        RigidBodyBuilder::kinematic_velocity_based().linvel(Vector::new(1.0, 0.0, 0.0)),
    );
    let (v, t) = plate_mesh();
    let surface = MassSpringSurfaceBuilder::new(v, t)
        .pinned(boundary())
        .build()
        .unwrap();
    let mut set = SurfaceSet::new();
    let h = set
        .insert(surface, body, &mut world, AttachOptions::default())
        .unwrap();
    for _ in 0..60 {
        set.step(&mut world);
    }
    let x = world.bodies[body].translation().x;
    assert!((x - 1.0).abs() < 1e-3);
    let collider = set.get(h).unwrap().collider().unwrap();
    let aabb = world.colliders[collider].compute_aabb();
    assert!((aabb.mins.x - x).abs() < 1e-3 && (aabb.maxs.x - (x + 1.0)).abs() < 1e-3);
    // A ray cast sees the surface where the body took it.
    world.step();
    let hit = world.query_pipeline().cast_ray(
        &Ray::new(Vector::new(x + 0.5, 1.0, 0.5), -Vector::Y),
        10.0,
        true,
    );
    assert!(matches!(hit, Some((c, toi)) if c == collider && (toi - 1.0).abs() < 1e-3));
}

#[test]
fn removing_a_tool_or_the_surface_mid_run_works() {
    let (mut world, mut set, h) = world_with_plate(4);
    let c = Vector::new(0.5, 0.0, 0.5);
    let (b, tool) = add_ball_tool(&mut world, &mut set, c + Vector::Y * 0.1, 0.05);
    let (b2, tool2) = add_ball_tool(&mut world, &mut set, c + Vector::new(0.2, 0.1, 0.0), 0.05);
    press(
        &mut world,
        &mut set,
        &[
            (b, c + Vector::Y * 0.1, c + Vector::Y * 0.03),
            (
                b2,
                c + Vector::new(0.2, 0.1, 0.0),
                c + Vector::new(0.2, 0.03, 0.0),
            ),
        ],
        20,
        20,
    );
    assert!(set.tool_reaction(tool).unwrap().held_vertices > 0);
    // Remove one tool's collider from the world, and the other from the set.
    world.remove_collider(tool);
    set.remove_tool(tool2, &mut world);
    for _ in 0..300 {
        set.step(&mut world);
    }
    assert!(set.tool_reaction(tool).is_none() && set.tool_reaction(tool2).is_none());
    let s = &set.get(h).unwrap().surface;
    assert!(
        s.max_displacement() < 1e-4,
        "released surface at {}",
        s.max_displacement()
    );
    // Remove the surface: its collider goes too, stepping goes on.
    let collider = set.get(h).unwrap().collider().unwrap();
    assert!(set.remove(h, &mut world).is_some());
    assert!(set.get(h).is_none() && !world.colliders.contains(collider));
    for _ in 0..10 {
        set.step(&mut world);
    }
}

#[test]
fn haptic_force_is_continuous_when_the_tool_turns_back() {
    // A tool pressing in with a tremor turns back every half period; the vertices it holds
    // must stay in contact (no force drop to zero) and its force must not drift.
    let (mut world, mut set, _) = world_with_plate(17);
    let c = Vector::new(0.5, 0.0, 0.5);
    let r = 0.02;
    let (_, tool) = add_ball_tool(&mut world, &mut set, c + Vector::Y * 0.1, r);
    let rate = 60.0 * 17.0;
    let device = |t: f32| {
        let depth = (t / 0.5).min(1.0) * 0.01 + 0.002 * (std::f32::consts::TAU * 2.0 * t).sin();
        Pose::from_translation(c + Vector::Y * (r - depth))
    };
    let (mut last, mut max_jump, mut max_force) = (Vector::ZERO, 0.0f32, 0.0f32);
    let mut at_phase = Vec::new();
    for k in 0..(3.0 * rate) as usize {
        let t = k as f32 / rate;
        let f = set.haptic_step(&world, tool, device(t)).unwrap().force;
        if t > 0.6 {
            assert!(f.y > 0.0, "lost contact at t = {t}");
            max_jump = max_jump.max((f - last).length());
        }
        if k >= 1020 && k % 510 == 0 {
            at_phase.push(f.y);
        }
        max_force = max_force.max(f.length());
        last = f;
    }
    assert!(
        max_jump < 0.05 * max_force,
        "largest jump {max_jump} N of {max_force} N"
    );
    // Same phase of the tremor, same force.
    let (lo, hi) = at_phase
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), y| (a.min(*y), b.max(*y)));
    assert!(hi - lo < 0.01 * hi, "force drifts: {at_phase:?}");
}

#[test]
fn capsule_and_cylinder_tools_get_steady_normal_forces() {
    // A capsule with a ball's tip presses like the ball; a flat-bottomed cylinder holds the
    // vertices under it with a vertical force. Both steady from step to step.
    let c = Vector::new(0.5, 0.0, 0.5);
    let depth = 0.01;
    let mut forces = Vec::new();
    for (shape, bottom) in [
        (ColliderBuilder::ball(0.02), 0.02),
        (ColliderBuilder::capsule_y(0.03, 0.02), 0.05),
        (ColliderBuilder::cylinder(0.01, 0.15), 0.01),
    ] {
        let (mut world, mut set, _) = world_with_plate(8);
        let top = c + Vector::Y * (bottom + 0.05);
        let b = world.insert_body(RigidBodyBuilder::kinematic_position_based().translation(top));
        let tool = world.insert_collider(shape, Some(b));
        set.add_tool(tool, &mut world).unwrap();
        let end = c + Vector::Y * (bottom - depth);
        press(&mut world, &mut set, &[(b, top, end)], 30, 240);
        let f0 = set.tool_reaction(tool).unwrap();
        for _ in 0..5 {
            set.step(&mut world);
            let f = set.tool_reaction(tool).unwrap();
            assert!(
                (f.force - f0.force).length() < 1e-3 * f0.force.length(),
                "{:?} -> {:?}",
                f0.force,
                f.force
            );
        }
        assert!(f0.force.y > 0.0);
        assert!(f0.force.x.abs() < 1e-3 * f0.force.y && f0.force.z.abs() < 1e-3 * f0.force.y);
        forces.push(f0);
    }
    // Same tip, same force.
    assert!((forces[1].force - forces[0].force).length() < 1e-3 * forces[0].force.y);
    // The flat cylinder (radius 0.15) holds the centre vertex and most of its ring.
    assert!(forces[2].held_vertices >= 5, "{}", forces[2].held_vertices);
}

#[test]
fn bad_tool_input_is_refused_or_harmless() {
    let (mut world, mut set, h) = world_with_plate(4);
    let c = Vector::new(0.5, 0.0, 0.5);
    let (_, tool) = add_ball_tool(&mut world, &mut set, c + Vector::Y * 0.01, 0.02);
    // A NaN device pose or an unknown tool: no step, no reaction.
    let nan = Pose::from_translation(Vector::splat(f32::NAN));
    assert!(set.haptic_step(&world, tool, nan).is_none());
    let other = world.insert_collider(ColliderBuilder::ball(0.1), None);
    assert!(set.haptic_step(&world, other, Pose::IDENTITY).is_none());
    // A tool of no size (a zero-radius ball, a zero cuboid) or not in the world is refused,
    // and its solver groups stay as they were.
    for shape in [
        ColliderBuilder::ball(0.0),
        ColliderBuilder::cuboid(0.0, 0.0, 0.0),
    ] {
        let b0 = world.insert_body(RigidBodyBuilder::kinematic_position_based());
        let t0 = world.insert_collider(shape, Some(b0));
        let groups = world.colliders[t0].solver_groups();
        assert_eq!(
            set.add_tool(t0, &mut world),
            Err(CouplingError::ZeroSizeTool)
        );
        assert_eq!(world.colliders[t0].solver_groups(), groups);
        assert!(set.tool_reaction(t0).is_none());
    }
    let gone = world.insert_collider(ColliderBuilder::ball(0.1), None);
    world.remove_collider(gone);
    assert_eq!(
        set.add_tool(gone, &mut world),
        Err(CouplingError::NoSuchCollider)
    );
    set.step(&mut world);
    assert!(set.get(h).unwrap().surface.is_finite());
    // A sliding hold with a zero or NaN normal is a full hold; a bad vertex is an error.
    let s = &mut set.get_mut(h).unwrap().surface;
    s.release_all();
    let free = vid(3, 3);
    let p = s.position(free);
    s.set_state(free, p, Vector::X).unwrap();
    s.hold_sliding(free, Vector::splat(f32::NAN)).unwrap();
    s.step();
    assert!((s.position(free) - (p + Vector::X * s.dt())).length() < 1e-6);
    assert!(s.hold_sliding(10_000, Vector::Y).is_err());
}

/// Touch events follow what the tools hold, step by step: two kinematic balls press the plate
/// at different times, one leaves, the other is removed from the set while pressing. The events
/// drained after each step are checked against the held-vertex counts read after that step.
#[test]
fn touch_events_follow_the_held_vertices() {
    let (mut world, mut set, h) = world_with_plate(4);
    let ball = |world: &mut PhysicsWorld, x: Real| {
        let b = world.insert_body(
            RigidBodyBuilder::kinematic_velocity_based().translation(Vector::new(x, 0.2, 0.5)),
        );
        world.insert_collider(ColliderBuilder::ball(0.06), Some(b));
        b
    };
    let (a, b) = (ball(&mut world, 0.3), ball(&mut world, 0.7));
    let tool = |world: &PhysicsWorld, body: RigidBodyHandle| world.bodies[body].colliders()[0];
    let (ta, tb) = (tool(&world, a), tool(&world, b));
    set.add_tool(ta, &mut world).unwrap();
    set.add_tool(tb, &mut world).unwrap();
    let mut was = [false, false];
    let mut seen: Vec<ToolTouchEvent> = Vec::new();
    for step in 0..240 {
        // a: down from step 0, up from 60; b: down from step 40, removed at 150.
        let va = if step < 60 { -0.3 } else { 0.6 };
        let vb = if step < 40 { 0.0 } else { -0.3 };
        world.bodies[a].set_linvel(Vector::new(0.0, va, 0.0), true);
        world.bodies[b].set_linvel(Vector::new(0.0, vb, 0.0), true);
        if step == 150 {
            set.remove_tool(tb, &mut world);
        }
        set.step(&mut world);
        let now = [ta, tb].map(|t| set.tool_reaction(t).is_some_and(|r| r.held_vertices > 0));
        let events: Vec<ToolTouchEvent> = set.drain_touch_events().collect();
        for (i, t) in [ta, tb].into_iter().enumerate() {
            let expected = match (was[i], now[i]) {
                (false, true) => Some(ToolTouchEvent::Started {
                    tool: t,
                    surface: h,
                }),
                (true, false) => Some(ToolTouchEvent::Stopped {
                    tool: t,
                    surface: h,
                }),
                _ => None,
            };
            let got: Vec<_> = events.iter().filter(|e| e.pair().0 == t).copied().collect();
            assert_eq!(
                got,
                expected.into_iter().collect::<Vec<_>>(),
                "step {step}, tool {i}"
            );
        }
        was = now;
        seen.extend(events);
    }
    // Each ball touched once and stopped once (b by its removal).
    assert_eq!(seen.len(), 4, "{seen:?}");
    assert_eq!(seen.iter().filter(|e| e.started()).count(), 2);
}
