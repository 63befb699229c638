//! The servo loop and its local contact model (issue 14): on plates the tests build (sizes,
//! meshes, stiffnesses and tools varied, none tuned for the model), a simulated hand on a
//! servo loop presses and drags a linked tool. Checked against independent answers: the
//! model's force at the proxy it sent agrees with the full surface solution the next world
//! update computes at that proxy; the proxy balances the coupling spring and the model (solved
//! by hand); a hand pressing a stiff surface over repeated cycles never gets energy back from
//! the rendering; a world that steps irregularly and slower than its clock is eased in (no
//! jump over 5 % of the peak, no energy to the hand); with the passivity controller on, no
//! energy to the hand at any plate scale, stiffness or mass (property test); threads
//! exchanging models while the world steps, refactors and swaps tools never deadlock, tear a
//! model or panic.

use crate::common::plate_scene;
use proptest::prelude::*;
use rapier_touch::haptics::{haptic_link, Servo, ServoModel, SimulatedHand, VirtualCoupling};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::math::Matrix;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::scenes::HapticScene;
use std::time::{Duration, Instant};

/// What a synchronous run (servo ticks between world steps, on one thread) saw.
struct Run {
    /// Largest |model force at the proxy sent − full solution there| over the updates (N).
    worst_error: f32,
    /// Per update with a contact: (the model's error, the full solution's change since the
    /// last update) (N).
    errors: Vec<(f32, f32)>,
    /// Largest full-solution force (N).
    peak: f32,
    /// The hand's books.
    rendered_work: f64,
    damping_loss: f64,
    /// Updates with a contact.
    contacts: usize,
}

/// Drives a linked tool with a simulated hand served at `rate` following `arm` for `seconds`,
/// the world at 60 Hz; compares, at every world update, the force the servo's model gave at
/// the last proxy it sent with the full solution the world then computed at that proxy.
/// `aids`: the update ramp and the passivity controller on (both change the hand's path and
/// what the servo renders, not the model).
fn run_linked(
    scene: (PhysicsWorld, SurfaceSet, ColliderHandle, SurfaceHandle),
    aids: bool,
    coupling: VirtualCoupling,
    rate: f32,
    seconds: f32,
    arm: impl Fn(f32) -> Pose + Send + 'static,
) -> Run {
    let (mut world, mut set, tool, _) = scene;
    let (world_end, servo_end) = haptic_link();
    set.connect_haptic(tool, world_end, &mut world).unwrap();
    let hand = SimulatedHand::new(rate, arm).unwrap();
    let mut servo = Servo::new(hand, servo_end, coupling, rate).unwrap();
    servo.set_update_ramp(aids);
    servo.set_passivity(aids);
    let world_dt = world.integration_parameters.dt;
    let ticks_per_step = (rate * world_dt).round() as usize;
    let mut run = Run {
        worst_error: 0.0,
        errors: Vec::new(),
        peak: 0.0,
        rendered_work: 0.0,
        damping_loss: 0.0,
        contacts: 0,
    };
    let steps = (seconds / world_dt).round() as usize;
    let mut last = Vector::ZERO;
    for _ in 0..steps {
        let mut predicted = Vector::ZERO;
        for _ in 0..ticks_per_step {
            predicted = servo.tick().surface_force;
        }
        set.step(&mut world);
        let actual = set.tool_reaction(tool).unwrap().force;
        run.peak = run.peak.max(actual.length());
        if actual != Vector::ZERO {
            run.contacts += 1;
        }
        let error = (predicted - actual).length();
        if actual != Vector::ZERO || predicted != Vector::ZERO {
            run.errors.push((error, (actual - last).length()));
        }
        last = actual;
        run.worst_error = run.worst_error.max(error);
    }
    run.rendered_work = servo.device().rendered_work();
    run.damping_loss = servo.device().damping_loss();
    run
}

/// A press 2-4 cm into the plate over a second, a drag sideways, a lift-off.
fn press_drag_lift(depth: f32, radius: f32) -> impl Fn(f32) -> Pose + Send + 'static {
    move |t: f32| {
        let top = radius + 0.02;
        let down = (t / 1.0).min(1.0);
        let drag = ((t - 1.5) / 1.0).clamp(0.0, 1.0);
        let up = ((t - 3.0) / 0.5).clamp(0.0, 1.0);
        let y = top - (top - (radius - depth)) * down + (top - (radius - depth)) * up;
        Pose::from_translation(Vector::new(0.03 * drag, y, 0.0))
    }
}

/// One scene of the agreement test: a plate `size` wide of `cells` per side, edges of `k`,
/// `mass` in all, `substeps` per world step, a tool of `shape` pressed `depth` in; at least
/// `least_share` of the updates must be within 5 %, and the worst no further off than
/// `hold_factor` times what holding the last full solution would have been.
struct Case {
    size: f32,
    cells: u32,
    k: f32,
    mass: f32,
    substeps: u32,
    shape: SharedShape,
    depth: f32,
    least_share: f32,
    hold_factor: f32,
}

#[test]
fn the_servo_model_agrees_with_each_full_surface_update() {
    // The capsule is as wide as a mesh cell: dragged sideways, the one or two vertices it
    // holds slide round its end, turning their normals within a world step, and the model
    // gets that tangential force a step late (86 % of its updates within 5 % when measured;
    // see the module docs of `haptics`).
    let case = |size, cells, k, mass, substeps, shape, depth, least_share| Case {
        size,
        cells,
        k,
        mass,
        substeps,
        shape,
        depth,
        least_share,
        hold_factor: 1.0,
    };
    let cases = [
        case(0.4, 16, 100.0, 0.2, 4, SharedShape::ball(0.04), 0.03, 0.95),
        case(0.3, 24, 400.0, 0.05, 4, SharedShape::ball(0.03), 0.02, 0.95),
        case(
            0.3,
            24,
            400.0,
            0.05,
            17,
            SharedShape::ball(0.03),
            0.02,
            0.95,
        ),
        case(0.3, 24, 400.0, 0.5, 1, SharedShape::ball(0.03), 0.02, 0.95),
        case(
            0.5,
            12,
            40.0,
            0.5,
            8,
            SharedShape::cuboid(0.03, 0.03, 0.03),
            0.03,
            0.95,
        ),
        // The capsule sinks while it slides: the force along the normal drops where the
        // model's normal stiffness says it rises, and the model misses by up to twice what
        // holding the last solution would (0.56 N against 0.28 N, measured).
        Case {
            hold_factor: 2.0,
            ..case(
                0.4,
                20,
                1000.0,
                0.1,
                2,
                SharedShape::capsule_y(0.02, 0.02),
                0.015,
                0.8,
            )
        },
    ];
    for Case {
        size,
        cells,
        k,
        mass,
        substeps,
        shape,
        depth,
        least_share,
        hold_factor,
    } in cases
    {
        let radius = shape.compute_local_aabb().half_extents().y;
        let scene = plate_scene(size, cells, k, mass, substeps, shape);
        let k_max = VirtualCoupling::max_passive_stiffness(2000.0, 2.0);
        let coupling = VirtualCoupling {
            stiffness: 0.5 * k_max,
            damping: 0.0,
            max_force: 50.0,
        };
        // The model itself, without the ramp that eases each update in or the passivity
        // controller (they change the hand's path, and so the updates this compares).
        let run = run_linked(
            scene,
            false,
            coupling,
            2000.0,
            4.0,
            press_drag_lift(depth, radius),
        );
        assert!(
            run.contacts > 60,
            "{size} m plate: touched in {} updates",
            run.contacts
        );
        assert!(run.peak > 0.05, "{size} m plate: peak {} N", run.peak);
        // Within 5 % of the peak at nearly every update; at the few where the full solution
        // itself jumps (a vertex captured or let go under a tool holding a handful, the
        // impact of a first touch), no worse than holding the last full solution.
        let tolerance = 0.05 * run.peak;
        let within = run.errors.iter().filter(|(e, _)| *e <= tolerance).count();
        let share = within as f32 / run.errors.len() as f32;
        let (e, jump) = run
            .errors
            .iter()
            .copied()
            .max_by(|a, b| (a.0 - hold_factor * a.1).total_cmp(&(b.0 - hold_factor * b.1)))
            .unwrap();
        println!(
            "{size} m plate, k {k}, {substeps} substeps: {within}/{} updates within 5 % of the {:.2} N peak, worst {:.3} N",
            run.errors.len(),
            run.peak,
            run.worst_error
        );
        assert!(
            share >= least_share,
            "{size} m plate, k {k}: only {within} of {} updates within 5 %",
            run.errors.len()
        );
        assert!(
            e <= tolerance + hold_factor * jump,
            "{size} m plate, k {k}: missed by {e} N where the full solution moved {jump} N"
        );
    }
}

#[test]
fn the_patch_near_a_hovering_tool_is_every_vertex_near_it() {
    // A ball pressed into a plate and lifted off while the plate swings back: out of contact,
    // each published model's patch (taken from the contact search's BVH) must be exactly the
    // unpinned vertices within one tool size of the tool's box, found here by brute force.
    let (mut world, mut set, tool, soft) =
        plate_scene(0.3, 24, 400.0, 0.05, 4, SharedShape::ball(0.03));
    let (world_end, _servo_end) = haptic_link();
    set.connect_haptic(tool, world_end, &mut world).unwrap();
    let body = world.colliders[tool].parent().unwrap();
    let (mut compared, mut nonempty) = (0, 0);
    for step in 0..120 {
        // Down 2 cm into the plate over half a second, then up to 1-3 cm above it, sideways.
        let t = step as f32 / 60.0;
        let y = if t < 0.5 {
            0.03 - 0.04 * t
        } else {
            0.04 + 0.02 * (t - 0.5)
        };
        let x = 0.04 * (t - 0.5).max(0.0);
        world.bodies[body].set_next_kinematic_translation(Vector::new(x, y, 0.0));
        set.step(&mut world);
        let model = set.haptic_model(tool).unwrap();
        if model.in_contact() {
            continue;
        }
        let co = &world.colliders[tool];
        let aabb = co.compute_aabb();
        let reach = co.shape().compute_local_aabb().half_extents().max_element();
        let (lo, hi) = (
            aabb.mins - Vector::splat(reach),
            aabb.maxs + Vector::splat(reach),
        );
        let surface = &set.get(soft).unwrap().surface;
        // Bitwise, with -0 and +0 as one (the model's positions went through the body's pose).
        let key = |p: Vector| {
            let p = p + Vector::ZERO;
            (p.x.to_bits(), p.y.to_bits(), p.z.to_bits())
        };
        let mut expected: Vec<_> = (0..surface.num_vertices() as u32)
            .filter(|&i| !surface.is_pinned(i))
            .map(|i| surface.position(i))
            .filter(|p| p.cmpge(lo).all() && p.cmple(hi).all())
            .map(key)
            .collect();
        let mut got: Vec<_> = model.patch.iter().map(|v| key(v.position)).collect();
        expected.sort_unstable();
        got.sort_unstable();
        assert_eq!(got, expected, "step {step}");
        compared += 1;
        nonempty += usize::from(!got.is_empty());
    }
    assert!(
        compared > 20 && nonempty > 10,
        "{compared} compared, {nonempty} with vertices"
    );
}

#[test]
fn the_proxy_rests_where_the_coupling_and_the_model_balance() {
    // A contact at the origin pushing 3 N up, stiff 400 N/m along y and 100 N/m along x;
    // the device 2 cm below it and 1 cm aside, a 2 kN/m coupling.
    let model = ServoModel {
        sequence: 1,
        force: Vector::new(0.0, 3.0, 0.0),
        stiffness: Matrix::from_diagonal(Vector::new(100.0, 400.0, 0.0)),
        ..ServoModel::default()
    };
    let device = Vector::new(0.01, -0.02, 0.0);
    let kc = 2000.0;
    let (proxy, f) = model.proxy(device, kc);
    // By hand, per axis: kc (d - p) + f0 - k p = 0, p = (kc d + f0) / (kc + k).
    let expect = Vector::new(
        kc * 0.01 / (kc + 100.0),
        (kc * -0.02 + 3.0) / (kc + 400.0),
        0.0,
    );
    assert!((proxy - expect).length() < 1e-6, "{proxy:?} vs {expect:?}");
    assert!((f - (device - proxy) * -kc).length() < 1e-3);
    // Pulled 5 cm out: the contact lets go, the proxy is the device.
    let up = Vector::new(0.0, 0.05, 0.0);
    assert_eq!(model.proxy(up, kc), (up, Vector::ZERO));
    // A grasp pulls back.
    let grasp = ServoModel {
        grasping: true,
        ..model.clone()
    };
    let (p, f) = grasp.proxy(up, kc);
    assert!(f.y < 0.0 && p.y < up.y, "a grasp holds: {f:?}");
    // Out of contact, a patch vertex 1 cm inside a 5 cm ball pushes it out by its stiffness.
    let touch = ServoModel {
        sequence: 2,
        shape: Some(SharedShape::ball(0.05)),
        patch: vec![rapier_touch::haptics::PatchVertex {
            position: Vector::new(0.0, -0.04, 0.0),
            stiffness: 200.0,
        }],
        ..ServoModel::default()
    };
    let f = touch.force_at(Vector::ZERO);
    assert!((f - Vector::new(0.0, 2.0, 0.0)).length() < 1e-4, "{f:?}");
    // No world update yet, or a link dropped: nothing.
    assert_eq!(ServoModel::default().force_at(Vector::ZERO), Vector::ZERO);
    let gone = ServoModel {
        attached: false,
        ..model
    };
    assert_eq!(gone.force_at(Vector::new(0.0, -0.02, 0.0)), Vector::ZERO);
}

#[test]
fn a_hand_pressing_a_stiff_surface_for_ten_seconds_never_gains_energy() {
    // A stiff plate (2 kN/m edges), a 1 kHz coupling at 90 % of the passive bound, five press
    // and release cycles in 10 s. After each release the rendering must have taken energy
    // from the hand, never given it.
    let rate = 1000.0;
    let k_max = VirtualCoupling::max_passive_stiffness(rate, 2.0);
    let coupling = VirtualCoupling {
        stiffness: 0.9 * k_max,
        damping: 0.0,
        max_force: 40.0,
    };
    let scene = plate_scene(0.3, 16, 2000.0, 0.1, 4, SharedShape::ball(0.03));
    let (mut world, mut set, tool, _) = scene;
    let (world_end, servo_end) = haptic_link();
    set.connect_haptic(tool, world_end, &mut world).unwrap();
    let arm = |t: f32| {
        let phase = (t % 2.0) / 2.0;
        let press = (std::f32::consts::PI * phase).sin().powi(2);
        Pose::from_translation(Vector::new(0.0, 0.05 - 0.04 * press, 0.0))
    };
    let hand = SimulatedHand::new(rate, arm).unwrap();
    let mut servo = Servo::new(hand, servo_end, coupling, rate).unwrap();
    let ticks_per_step = (rate * world.integration_parameters.dt).round() as usize;
    let mut peak = 0.0f32;
    // The work the hand put in (the deepest the rendered work went in a cycle), and what the
    // device's own damping took while the hand was in contact.
    let (mut deepest, mut contact_loss, mut cycle_start) = (0.0f64, 0.0f64, 0.0f64);
    for step in 1..=600 {
        for _ in 0..ticks_per_step {
            let loss = servo.device().damping_loss();
            let f = servo.tick().force;
            if f != Vector::ZERO {
                contact_loss += servo.device().damping_loss() - loss;
            }
            peak = peak.max(f.length());
            deepest = deepest.min(servo.device().rendered_work());
        }
        set.step(&mut world);
        // The end of each 2 s cycle: released, the surface at rest again.
        if step % 120 == 0 {
            let work = servo.device().rendered_work();
            println!(
                "cycle {}: rendered work {work:.3e} J, contact damping {contact_loss:.3e} J, deepest {deepest:.3e} J",
                step / 120
            );
            // Passive as Colgate and Schenkel define it: with the device's own damping, the
            // display never gives the hand energy.
            assert!(
                work <= contact_loss,
                "cycle {}: the rendering gave the hand {work} J, more than the {contact_loss} J its damping took in contact",
                step / 120
            );
            // And over the cycle the surface gives back at most 2 % more than the hand pushed
            // into it (the model's force lags the full solution by up to a world step).
            let (gained, put_in) = (work - cycle_start, cycle_start - deepest);
            assert!(
                gained <= 0.02 * put_in,
                "cycle {}: {gained} J back beyond the {put_in} J put in",
                step / 120
            );
            (cycle_start, deepest) = (work, work);
        }
    }
    assert!(peak > 1.0, "the presses were felt: peak {peak} N");
}

#[test]
fn servo_threads_and_a_busy_world_never_block_tear_or_panic() {
    // Two tools on servo threads at 2 kHz; the world thread steps, refactors the surface's
    // springs, removes a tool and links a new one, at random, for a bounded time. Every
    // model a servo loop reads must be one the world published whole.
    use std::collections::HashMap;
    use std::sync::mpsc;
    let (mut world, mut set, tool_a, plate_h) =
        plate_scene(0.4, 20, 200.0, 0.2, 2, SharedShape::ball(0.04));
    let body_b = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.1, 0.4, 0.0)),
    );
    let tool_b = world.insert_collider(ColliderBuilder::ball(0.03), Some(body_b));
    let rate = 2000.0;
    let coupling = VirtualCoupling {
        stiffness: 2000.0,
        damping: 0.0,
        max_force: 30.0,
    };
    // Each servo reports (sequence, force, pose) of the models it read, checked afterwards
    // against what the world published.
    let spawn = |link: rapier_touch::haptics::ServoLink,
                 x: f32,
                 tx: mpsc::Sender<(u64, Vector, Vector)>| {
        let arm = move |t: f32| {
            Pose::from_translation(Vector::new(x, 0.06 - 0.05 * (3.0 * t).sin().abs(), 0.0))
        };
        let hand = SimulatedHand::new(rate, arm).unwrap();
        let mut servo = Servo::new(hand, link, coupling, rate).unwrap();
        std::thread::spawn(move || {
            let start = Instant::now();
            let mut ticks = 0u64;
            while start.elapsed() < Duration::from_millis(1500) {
                let t = servo.tick();
                assert!(t.force.is_finite() && t.force.length() <= 30.0 + 1e-3);
                ticks += 1;
                if ticks.is_multiple_of(16) {
                    tx.send((t.model_sequence, t.model_force, t.proxy)).ok();
                }
                std::thread::sleep(Duration::from_micros(300));
            }
            ticks
        })
    };
    let (tx, rx) = mpsc::channel();
    let (wa, sa) = haptic_link();
    let (wb, sb) = haptic_link();
    set.connect_haptic(tool_a, wa, &mut world).unwrap();
    set.connect_haptic(tool_b, wb, &mut world).unwrap();
    let (tx_b, _rx_b) = mpsc::channel();
    let threads = [spawn(sa, 0.0, tx.clone()), spawn(sb, 0.1, tx_b.clone())];
    let mut published_a: HashMap<u64, Vector> = HashMap::new();
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        rng
    };
    let start = Instant::now();
    let mut steps = 0;
    let mut late_threads = Vec::new();
    while start.elapsed() < Duration::from_millis(1200) {
        match next() % 10 {
            0 => {
                let k = 50.0 + (next() % 400) as f32;
                set.get_mut(plate_h)
                    .unwrap()
                    .surface
                    .set_spring(k, 1.0)
                    .unwrap();
            }
            1 => {
                // Tool b leaves and comes back on a fresh link and a fresh servo thread.
                set.remove_tool(tool_b, &mut world);
                let (w, s) = haptic_link();
                set.connect_haptic(tool_b, w, &mut world).unwrap();
                late_threads.push(spawn(s, 0.1, tx_b.clone()));
            }
            _ => {}
        }
        set.step(&mut world);
        steps += 1;
        let m = set.haptic_model(tool_a).unwrap();
        published_a.insert(m.sequence, m.force);
        for h in [tool_a, tool_b] {
            let f = set.tool_reaction(h).map_or(Vector::ZERO, |r| r.force);
            assert!(f.is_finite());
        }
    }
    drop((tx, tx_b));
    for t in threads.into_iter().chain(late_threads) {
        let ticks = t.join().expect("a servo thread panicked");
        assert!(ticks > 100, "a servo thread was starved: {ticks} ticks");
    }
    assert!(steps > 10, "the world was blocked: {steps} steps");
    // Whole models only: every model tool a's servo read carries the force the world
    // published under its number.
    let reads: Vec<(u64, Vector, Vector)> = rx.iter().collect();
    let mut seen = 0;
    for (seq, f, _) in &reads {
        if let Some(published) = published_a.get(seq) {
            assert_eq!(f, published, "model {seq} read torn");
            seen += 1;
        }
    }
    assert!(seen > 10, "only {seen} models of tool a checked");
}

/// What [`slow_world_run`] saw: the largest rendered-force change between two ticks across a
/// world update and within one (N), the peak rendered force (N), the rendered work and the
/// device damping's loss while in contact (J).
struct SlowRun {
    across: f32,
    within: f32,
    peak: f32,
    rendered_work: f64,
    contact_loss: f64,
}

/// A 5 kHz servo on a world that steps irregularly and slower than its 60 Hz clock: between
/// two world steps the servo ticks 40 to 200 times (8-40 ms of the hand's time; 24 ms on
/// average for a 16.7 ms step), as when a large surface's step outlasts its `dt`.
fn slow_world_run(ramp: bool) -> SlowRun {
    let ball = SharedShape::ball(0.03);
    slow_world_run_on(
        ramp,
        SlowScene {
            scale: 1.0,
            k: 400.0,
            mass: 0.5,
            tool: ball,
            seed: 12345,
        },
    )
}

/// The scene of [`slow_world_run_on`]: the 0.3 m plate of 24 cells and the 3 cm tool scaled by
/// `scale` (the hand's path with them), edges of `k`, `mass` in all, the schedule from `seed`.
struct SlowScene {
    scale: f32,
    k: f32,
    mass: f32,
    tool: SharedShape,
    seed: u32,
}

/// [`slow_world_run`] on any [`SlowScene`], the passivity controller on.
fn slow_world_run_on(ramp: bool, scene: SlowScene) -> SlowRun {
    slow_world_run_with(ramp, true, scene)
}

/// [`slow_world_run_on`] with the passivity controller on or off.
fn slow_world_run_with(ramp: bool, passivity: bool, scene: SlowScene) -> SlowRun {
    let rate = 5000.0;
    let SlowScene {
        scale,
        k,
        mass,
        tool,
        seed,
    } = scene;
    let (mut world, mut set, tool, _) = plate_scene(0.3 * scale, 24, k, mass, 1, tool);
    let (world_end, servo_end) = haptic_link();
    set.connect_haptic(tool, world_end, &mut world).unwrap();
    let path = press_drag_lift(0.02, 0.03);
    let hand = SimulatedHand::new(rate, move |t| {
        Pose::from_translation(path(t).translation * scale)
    })
    .unwrap();
    let coupling = VirtualCoupling {
        stiffness: 0.5 * VirtualCoupling::max_passive_stiffness(rate, 2.0),
        damping: 0.0,
        max_force: 50.0,
    };
    let mut servo = Servo::new(hand, servo_end, coupling, rate).unwrap();
    servo.set_update_ramp(ramp);
    servo.set_passivity(passivity);
    let mut run = SlowRun {
        across: 0.0,
        within: 0.0,
        peak: 0.0,
        rendered_work: 0.0,
        contact_loss: 0.0,
    };
    // A fixed linear congruential sequence: the same irregular schedule on every run.
    let mut state = seed;
    let (mut ticks, mut last) = (0usize, Vector::ZERO);
    let (mut was_touching, mut entry_loss) = (false, 0.0);
    while ticks < (4.5 * rate) as usize {
        state = state.wrapping_mul(1_103_515_245).wrapping_add(12_345);
        let n = 40 + (state >> 16) as usize % 161;
        for i in 0..n {
            let loss = servo.device().damping_loss();
            let tick = servo.tick();
            let f = tick.force;
            let loss = servo.device().damping_loss() - loss;
            let touching = f != Vector::ZERO || tick.surface_force != Vector::ZERO;
            if touching {
                // The tick that entered the contact counts: its move put the device there.
                run.contact_loss += loss + if was_touching { 0.0 } else { entry_loss };
            }
            (was_touching, entry_loss) = (touching, loss);
            let jump = (f - last).length();
            if i == 0 {
                run.across = run.across.max(jump);
            } else {
                run.within = run.within.max(jump);
            }
            run.peak = run.peak.max(f.length());
            last = f;
        }
        ticks += n;
        set.step(&mut world);
    }
    run.rendered_work = servo.device().rendered_work();
    run
}

#[test]
fn a_slow_irregular_world_is_eased_in_without_knocks_or_energy() {
    let (eased, stepped) = (slow_world_run(true), slow_world_run(false));
    for (name, r) in [("ramped", &eased), ("stepped", &stepped)] {
        println!(
            "{name}: peak {:.3} N, largest jump across updates {:.4} N ({:.2} %), within {:.4} N, rendered work {:.3e} J, contact damping {:.3e} J",
            r.peak,
            r.across,
            100.0 * r.across / r.peak,
            r.within,
            r.rendered_work,
            r.contact_loss
        );
    }
    assert!(eased.peak > 1.0 && stepped.peak > 1.0, "the press was felt");
    // The schedule does what a slow world does: without the ramp, updates knock.
    assert!(
        stepped.across > 0.05 * stepped.peak,
        "stepped: {} N across updates",
        stepped.across
    );
    assert!(
        eased.across <= 0.05 * eased.peak && eased.within <= 0.05 * eased.peak,
        "ramped: jumps {} N across and {} N within updates against a {} N peak",
        eased.across,
        eased.within,
        eased.peak
    );
    assert!(
        eased.rendered_work <= eased.contact_loss,
        "ramped: the rendering gave the hand {} J, more than the {} J its damping took",
        eased.rendered_work,
        eased.contact_loss
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    /// The servo's model on scenes nobody tuned: plates from 0.3 mm to 3 km (the hand's path
    /// scaled with them), soft to stiff edges, 10 g to 1 t, any irregular schedule of slow
    /// world steps. The rendering should never give the hand more energy than its own damping
    /// took while in contact, with the passivity controller on (`slow_world_run_on`). Without
    /// it this failed on heavy, stiff plates even without the update ramp (0.3 m, 883 N/m,
    /// 750 kg: the hand got 0.025 J, its damping took 0.0092 J; the cases it found are kept in
    /// tests/proptest-regressions/haptic_servo.txt and replayed).
    #[test]
    fn the_servo_model_never_gives_the_hand_energy_at_any_scale(
        log_scale in -3.0f32..4.0,
        k in 10.0f32..2000.0,
        log_mass in -2.0f32..3.0,
        seed in any::<u32>(),
        ramp in any::<bool>(),
        shape in 0u8..3,
    ) {
        let scale = 10f32.powf(log_scale);
        let r = 0.03 * scale;
        let tool = match shape {
            0 => SharedShape::ball(r),
            1 => SharedShape::cuboid(r, r, r),
            _ => SharedShape::capsule_x(r, 0.5 * r),
        };
        let mass = 10f32.powf(log_mass);
        let r = slow_world_run_on(ramp, SlowScene { scale, k, mass, tool, seed });
        prop_assert!(r.peak.is_finite() && r.across.is_finite() && r.within.is_finite());
        prop_assert!(
            r.rendered_work <= 0.5 * r.contact_loss * (1.0 + 1e-6) + 1e-15,
            "scale {} m, k {} N/m, {} kg, schedule {}, ramp {}, shape {}: the rendering gave the hand {} J, its damping took {} J",
            0.3 * scale, k, mass, seed, ramp, shape, r.rendered_work, r.contact_loss
        );
    }
}

/// The passivity controller on a case that pumps without it: a 6 cm cube on a 0.3 m plate of
/// 883 N/m and 1 kg under an irregular world, the update ramp off (found by the property test
/// above with the controller switched off: the hand got 209 J while its damping took 48 J).
///
/// The controller this replaced cut the push along the device's last motion (Hannaford and
/// Ryu's) and failed a case found with `PROPTEST_RNG_SEED=7` (a ball on a 1783 N/m plate): the
/// model's tangential force swung while the hand jittered along the drag and the cut landed
/// on the wrong side half the time. The controller now bounds the energy the proxy's moves
/// draw into the coupling spring (`Servo::bound_proxy`): the hand gets at most the sampled
/// spring's give-back, half of what its damping takes at half the passive stiffness.
#[test]
fn a_cube_on_a_stiff_plate_under_an_irregular_world_gives_the_hand_no_energy() {
    let scene = || SlowScene {
        scale: 1.0,
        k: 882.755,
        mass: 1.0,
        tool: SharedShape::cuboid(0.03, 0.03, 0.03),
        seed: 232_220_430,
    };
    let (off, on) = (
        slow_world_run_with(false, false, scene()),
        slow_world_run_with(false, true, scene()),
    );
    println!(
        "controller off: {:.4} J given, {:.4} J damped; on: {:.4} J given, {:.4} J damped",
        off.rendered_work, off.contact_loss, on.rendered_work, on.contact_loss
    );
    assert!(
        off.rendered_work > off.contact_loss,
        "without the controller the case no longer pumps: {} J given, {} J damped",
        off.rendered_work,
        off.contact_loss
    );
    assert!(
        on.rendered_work <= 0.5 * on.contact_loss * (1.0 + 1e-6),
        "the rendering gave the hand {} J, its damping took {} J",
        on.rendered_work,
        on.contact_loss
    );
}

#[test]
fn a_hand_striking_a_fine_damped_plate_comes_to_rest_on_it() {
    // The 100,000-node plate of the servo bench (edges of 100 N/m with 1 N·s/m dampers, on
    // a 0.95 mm mesh): a tool that arrives fast is met by the dampers of every edge around
    // it, tens of newtons that vanish once it stops. The world reports them a step late;
    // eased in by the ramp they pushed the hand out with more energy than it brought, and
    // a hand pressing on bounced for good (a limit cycle, 1.5 cm each way). The hand strikes
    // from outside: one that starts inside the plate has put no energy in, and the passivity
    // controller (on by default) renders it nothing.
    let mut scene = HapticScene::plate(315, 1);
    let link = scene.link(0);
    let (start, target) = (scene.script(0)(0.0), scene.script(0)(1.8));
    let rate = 5000.0;
    // A strike: from where the tool starts, 1 cm over the plate, to the scripted press in
    // 30 ms, then held there.
    let hand = SimulatedHand::new(rate, move |t| {
        let s = (t / 0.03).min(1.0);
        Pose::from_translation(start.translation.lerp(target.translation, s))
    })
    .unwrap();
    let arm = hand.arm_stiffness;
    let coupling = VirtualCoupling {
        stiffness: 0.5 * VirtualCoupling::max_passive_stiffness(rate, hand.device_damping),
        damping: 0.0,
        max_force: 20.0,
    };
    let mut servo = Servo::new(hand, link, coupling, rate).unwrap();
    let mut heights = Vec::new();
    let mut last = None;
    for _ in 0..90 {
        for _ in 0..83 {
            last = Some(servo.tick());
        }
        scene.set.step(&mut scene.world);
        heights.push(
            scene.world.colliders[scene.tools[0]]
                .position()
                .translation
                .y,
        );
    }
    let tick = last.unwrap();
    let reaction = scene.set.tool_reaction(scene.tools[0]).unwrap().force;
    // At rest over the last half second: the tool still, pressing the plate.
    let settled = &heights[60..];
    let spread = settled.iter().cloned().fold(f32::MIN, f32::max)
        - settled.iter().cloned().fold(f32::MAX, f32::min);
    assert!(spread < 1e-4, "the tool still moves {spread} m");
    assert!(reaction.y > 0.5, "reaction {reaction:?}");
    // The hand feels the plate's force and rests where its arm balances it.
    let rendered = tick.force.y;
    assert!(
        (rendered - reaction.y).abs() < 0.02 * reaction.y,
        "rendered {rendered} N, the plate's {} N",
        reaction.y
    );
    let held = arm * (tick.device.translation.y - target.translation.y);
    assert!(
        (held - rendered).abs() < 0.02 * rendered,
        "arm {held} N, rendered {rendered} N"
    );
}

#[test]
fn a_cube_dragged_deep_in_a_plate_gives_the_hand_no_energy() {
    // The property test's minimal failing case with a cube, before the passivity controller:
    // a 43 cm cube pressed 14 cm into a 2.15 m plate of 27.6 N/m edges and 1 kg, dragged
    // 21.5 cm. Without the controller the hand got 2.15 J from the rendering while its damping
    // took 1.11 J: the full solution spiked at the start of the drag (at 400 N/m a scripted
    // cube there, no servo, met 2 kN against a 436 N press: plate vertices lying on its
    // bottom face were thrown across it; fixed, `grazing_drag.rs`). It now passes with the
    // controller off as well; it runs with it on (`slow_world_run_on`).
    let scale = 10f32.powf(0.856_107_83);
    let tool = SharedShape::cuboid(0.03 * scale, 0.03 * scale, 0.03 * scale);
    let scene = SlowScene {
        scale,
        k: 27.639,
        mass: 1.0,
        tool,
        seed: 349_190_831,
    };
    let r = slow_world_run_on(true, scene);
    assert!(
        r.rendered_work <= 0.5 * r.contact_loss * (1.0 + 1e-6),
        "the rendering gave the hand {} J, its damping took {} J",
        r.rendered_work,
        r.contact_loss
    );
}

#[test]
fn the_eased_rendering_never_gives_the_hand_energy() {
    // Cases the property test above found with the ramp on (0.3 m plates, 1 kg, ball tools)
    // before the passivity controller: at 1602 N/m the hand got 0.053 J while its damping took
    // 0.020 J; at 770 N/m, 0.0071 J against 0.0061 J. The ramp's energy budget alone did not
    // hold them; the controller does.
    for (k, seed) in [(1_601.874_3, 630_297_028), (769.788_27, 1_600_801_739)] {
        let tool = SharedShape::ball(0.03);
        let scene = SlowScene {
            scale: 1.0,
            k,
            mass: 1.0,
            tool,
            seed,
        };
        let r = slow_world_run_on(true, scene);
        assert!(
            r.rendered_work <= 0.5 * r.contact_loss * (1.0 + 1e-6),
            "k {k}: the rendering gave the hand {} J, its damping took {} J",
            r.rendered_work,
            r.contact_loss
        );
    }
}

/// A device that reads `pose(tick)` and keeps every force it is sent.
struct Scripted {
    tick: usize,
    pose: fn(usize) -> Vector,
    forces: Vec<Vector>,
}

impl rapier_touch::haptics::HapticDevice for Scripted {
    fn state(&mut self) -> rapier_touch::haptics::DeviceState {
        self.tick += 1;
        rapier_touch::haptics::DeviceState {
            pose: Pose::from_translation((self.pose)(self.tick)),
            buttons: 0,
        }
    }

    fn set_force(&mut self, force: Vector) {
        self.forces.push(force);
    }
}

#[test]
fn a_device_that_reads_nan_mid_press_gets_no_force_and_moves_no_tool() {
    // Pressed 1 cm into a plate, then the device reads NaN (a dropped USB frame) for 200
    // ticks, then presses again: no NaN reaches the device or the world, the tool waits
    // where it was, and the press is felt again after.
    // With the passivity controller off and on.
    for passive in [false, true] {
        let (mut world, mut set, tool, _) =
            plate_scene(0.3, 24, 400.0, 0.5, 4, SharedShape::ball(0.03));
        let (world_end, servo_end) = haptic_link();
        set.connect_haptic(tool, world_end, &mut world).unwrap();
        let device = Scripted {
            tick: 0,
            pose: |t| {
                if (2000..2200).contains(&t) {
                    Vector::splat(f32::NAN)
                } else {
                    // Down from 2 cm over the plate to 1 cm into it over the first 500 ticks.
                    Vector::new(0.0, 0.02 + 0.03 * (1.0 - t as f32 / 500.0).max(0.0), 0.0)
                }
            },
            forces: Vec::new(),
        };
        let coupling = VirtualCoupling {
            stiffness: 2000.0,
            damping: 0.0,
            max_force: 30.0,
        };
        let mut servo = Servo::new(device, servo_end, coupling, 5000.0).unwrap();
        servo.set_passivity(passive);
        let mut before_gap = Vector::ZERO;
        for step in 0..60 {
            for _ in 0..83 {
                servo.tick();
            }
            set.step(&mut world);
            let at = world.colliders[tool].position().translation;
            assert!(at.is_finite(), "step {step}: tool at {at:?}");
            if servo.device().tick < 2000 {
                before_gap = at;
            } else if servo.device().tick < 2200 {
                assert_eq!(
                    at, before_gap,
                    "step {step}: the tool moved during the NaN reads"
                );
            }
        }
        let forces = &servo.device().forces;
        assert!(forces.iter().all(|f| f.is_finite()));
        assert!(forces[2000..2199].iter().all(|f| *f == Vector::ZERO));
        // Pressed before and after: the ball's centre 1 cm under its rest height pushes back.
        assert!(
            forces[1990].y > 0.5 && forces.last().unwrap().y > 0.5,
            "{:?}",
            forces.last()
        );
    }
}
