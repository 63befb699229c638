//! The servo loop's energy (issue 14): a hand pressing a stiff surface, a world that steps
//! slower than its clock and irregularly, struck and dragged plates, the passivity controller
//! on scenes nobody tuned. A hand's books (`SimulatedHand::rendered_work` against its damping's
//! loss in contact) are the independent measure.

use super::haptic_agreement::press_drag_lift;
use crate::common::plate_scene;
use proptest::prelude::*;
use rapier_touch::haptics::{haptic_link, Servo, SimulatedHand, VirtualCoupling};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::scenes::HapticScene;

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

impl SlowRun {
    /// The most the passivity controller lets the rendering give the hand: the sampled
    /// spring's give-back, half of what the hand's damping took in contact at half the
    /// passive stiffness (a relative 1e-6 for rounding).
    fn give_back_bound(&self) -> f64 {
        0.5 * self.contact_loss * (1.0 + 1e-6)
    }

    /// Panics unless the rendering gave the hand at most [`SlowRun::give_back_bound`];
    /// `case` names the run in the message.
    fn assert_passive(&self, case: &str) {
        assert!(
            self.rendered_work <= self.give_back_bound(),
            "{case}the rendering gave the hand {} J, its damping took {} J",
            self.rendered_work,
            self.contact_loss
        );
    }
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
            coupling_damping: 0.0,
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
    /// The coupling's damper (N·s/m).
    coupling_damping: f32,
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
        coupling_damping,
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
        damping: coupling_damping,
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
    /// scaled with them), soft to stiff edges, 10 g to 1 t, ball, cube and capsule tools, the
    /// update ramp on or off, a coupling damper of 0 to 1 N·s/m, any irregular schedule of
    /// slow world steps. With the passivity controller on (`slow_world_run_on`) the rendering
    /// gives the hand at most the sampled spring's give-back, half of what its own damping
    /// takes while in contact at half the passive stiffness (the tick that enters the contact
    /// counted). Without a controller this failed on heavy, stiff plates even without the
    /// update ramp (0.3 m, 883 N/m, 750 kg: the hand got 0.025 J, its damping took 0.0092 J;
    /// the cases it found are kept in tests/proptest-regressions/haptic_energy.txt and
    /// replayed).
    #[test]
    fn the_servo_model_never_gives_the_hand_energy_at_any_scale(
        log_scale in -3.0f32..4.0,
        k in 10.0f32..2000.0,
        log_mass in -2.0f32..3.0,
        seed in any::<u32>(),
        ramp in any::<bool>(),
        shape in 0u8..3,
        coupling_damping in prop_oneof![Just(0.0f32), 0.0f32..1.0],
    ) {
        let scale = 10f32.powf(log_scale);
        let r = 0.03 * scale;
        let tool = match shape {
            0 => SharedShape::ball(r),
            1 => SharedShape::cuboid(r, r, r),
            _ => SharedShape::capsule_x(r, 0.5 * r),
        };
        let mass = 10f32.powf(log_mass);
        let r = slow_world_run_on(
            ramp,
            SlowScene { scale, k, mass, tool, seed, coupling_damping },
        );
        prop_assert!(r.peak.is_finite() && r.across.is_finite() && r.within.is_finite());
        prop_assert!(
            r.rendered_work <= r.give_back_bound() + 1e-15,
            "scale {} m, k {} N/m, {} kg, schedule {}, ramp {}, shape {}, coupling damper {} N s/m: the rendering gave the hand {} J, its damping took {} J",
            0.3 * scale, k, mass, seed, ramp, shape, coupling_damping, r.rendered_work, r.contact_loss
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
        coupling_damping: 0.0,
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
    on.assert_passive("");
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
        coupling_damping: 0.0,
    };
    let r = slow_world_run_on(true, scene);
    r.assert_passive("");
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
            coupling_damping: 0.0,
        };
        let r = slow_world_run_on(true, scene);
        r.assert_passive(&format!("k {k}: "));
    }
}
