//! A world slower than the servo loop over a damped surface (issue 14): a simulated hand on a
//! 5 kHz servo presses, drags and lifts a ball on the 10,000-node sphere of `HapticScene`
//! (edges of 100 N/m and 1 N·s/m: the dampers carry most of a moving press's force) while the
//! world, asked for 60 Hz, steps once every 200 to 500 ticks (a step that takes 40-100 ms, as
//! the 100,000-node sphere's did on a loaded machine). The model reaches the servo either as
//! the next step begins or a step late (a world thread that reads the proxy, steps for that
//! long while the servo ticks on, then publishes). Synchronous, so each case is the same at
//! every run.
//!
//! Before the model left out what the held vertices' dampers put on the tool's last move (and
//! before its normal stiffness was kept from collapsing), the full solution swung from one
//! update to the next and the hand with it: the rendered force jumped between ticks by 6.8 %
//! of its peak at 200 ticks a step late and by 51 % at 500 ticks with no delay (3.0-3.7 % at
//! 300). The limit: at 700 ticks here, and from 500 ticks on the 100,000-node sphere, the
//! hand still bounces (a step that long captures a hundred vertices or more at once). Also
//! here: the model read against the next update of a press that stops.

use rapier_touch::haptics::{haptic_link, Servo, SimulatedHand, VirtualCoupling};
use rapier_touch::prelude::*;
use rapier_touch::scenes::HapticScene;

const RATE: f32 = 5000.0;

/// The largest change of the rendered force between two ticks, the rendered peak, and the
/// median full-solution force over the updates in contact.
fn run(ticks_per_update: usize, late: bool) -> (f32, f32, f32) {
    let mut scene = HapticScene::sphere(10_000, 1);
    // The set's link is relayed, so that a model can reach the servo a step late.
    let mut world_side = scene.link(0);
    let (mut relay, servo_end) = haptic_link();
    let hand = SimulatedHand::new(RATE, scene.script(0)).unwrap();
    let coupling = VirtualCoupling {
        stiffness: 0.5 * VirtualCoupling::max_passive_stiffness(RATE, hand.device_damping),
        damping: 0.0,
        max_force: 20.0,
    };
    let mut servo = Servo::new(hand, servo_end, coupling, RATE).unwrap();
    let tool = scene.tools[0];
    let total = (HapticScene::SCRIPT_SECONDS * RATE) as usize;
    let (mut last, mut jump, mut peak) = (Vector::ZERO, 0.0f32, 0.0f32);
    let mut full = Vec::new();
    let mut t = 0;
    while t < total {
        // The step reads the proxy the servo sent last.
        world_side.send(relay.device());
        scene.set.step(&mut scene.world);
        let f = scene.set.tool_reaction(tool).unwrap().force.length();
        if f > 0.0 {
            full.push(f);
        }
        if !late {
            relay.publish(world_side.model().clone());
        }
        for _ in 0..ticks_per_update {
            let force = servo.tick().force;
            jump = jump.max((force - last).length());
            peak = peak.max(force.length());
            last = force;
            t += 1;
        }
        if late {
            relay.publish(world_side.model().clone());
        }
    }
    full.sort_by(f32::total_cmp);
    (jump, peak, full.get(full.len() / 2).copied().unwrap_or(0.0))
}

#[test]
fn a_slow_world_over_a_damped_surface_does_not_shake_the_hand() {
    for (ticks, late) in [(200, true), (300, false), (300, true), (500, false)] {
        let (jump, peak, median) = run(ticks, late);
        println!(
            "{ticks} ticks per update, late {late}: largest jump {jump:.4} N of a {peak:.3} N peak ({:.2} %), median full solution {median:.3} N",
            100.0 * jump / peak
        );
        assert!(median > 0.5, "{ticks}, {late}: pressed with {median} N");
        // A shaken hand also presses far harder than the surface holds it (2.5-9 N peaks
        // against a median of 1.1 N before).
        assert!(
            peak < 2.0 * median,
            "{ticks}, {late}: a peak of {peak} N against {median} N"
        );
        assert!(
            jump <= 0.05 * peak,
            "{ticks} ticks per update, late {late}: jumped {jump} N of a {peak} N peak"
        );
    }
}

/// The model's force is what the next update reads if the tool stops: a ball pressed into the
/// damped 3,000-node sphere at a steady speed, then held, on surfaces of three dampings. At the
/// last moving update the full solution holds the dampers' resistance to the press, which
/// goes at the next update; the model (published at that last moving update) must be nearer
/// the next update's full solution than the moving one was: within half the change.
#[test]
fn the_model_reads_what_the_next_update_gives_a_tool_that_stops() {
    for c in [0.3f32, 1.0, 3.0] {
        for speed in [0.02f32, 0.05] {
            let mut scene = HapticScene::sphere(3_000, 1);
            let surface = scene.surface;
            scene
                .set
                .get_mut(surface)
                .unwrap()
                .surface
                .set_spring(100.0, c)
                .unwrap();
            let mut link = scene.link(0);
            let (p, n) = scene.press[0];
            let dt = scene.world.integration_parameters.dt;
            let tool = scene.tools[0];
            // From just over the surface, pressed along the normal for 0.4 s, then held.
            let start = p + n * (scene.radius + 0.002);
            let steps = (0.4 / dt).round() as u64;
            let mut moving = None;
            let mut stopped = None;
            for k in 0..steps + 2 {
                let depth = speed * dt * (k.min(steps) as f32);
                let at = Pose::from_translation(start - n * depth);
                link.send(rapier_touch::haptics::DeviceSample {
                    tick: k + 1,
                    device: at,
                    proxy: at,
                    ..Default::default()
                });
                scene.set.step(&mut scene.world);
                let full = scene.set.tool_reaction(tool).unwrap().force;
                if k == steps {
                    moving = Some((full, link.model().force));
                } else if k == steps + 1 {
                    stopped = Some(full);
                }
            }
            let ((moving, model), stopped) = (moving.unwrap(), stopped.unwrap());
            let change = (moving - stopped).length();
            let miss = (model - stopped).length();
            println!(
                "c {c}, {speed} m/s: moving {moving:.4}, stopped {stopped:.4}, model {model:.4}"
            );
            assert!(stopped.length() > 0.05, "c {c}, {speed} m/s: {stopped}");
            assert!(
                miss <= 0.5 * change,
                "c {c}, {speed} m/s: the model {model} misses the stopped tool's {stopped} by {miss} N; the moving one read {moving} ({change} N off)"
            );
        }
    }
}
