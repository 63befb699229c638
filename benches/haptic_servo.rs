//! The servo loop's latency (issue 14): plates of 784, 10,000 and 100,000 nodes
//! ([`HapticScene::plate`]: the exact filter, one surface step per 60 Hz world step) with 1
//! and 2 ball tools pressed 1 cm in and held there by simulated hands, each linked to a servo
//! loop, while another thread steps the world at 60 Hz.
//!
//! Per configuration, in the same run:
//! - `servo_tick`: criterion times tool 0's `Servo::tick` (device read, model read, proxy
//!   solve, force out, sample back) on this thread while the world thread steps;
//! - latency percentiles: every servo spawned on its own thread at 5 kHz for 2 s
//!   (`Servo::spawn`), each tick timed; p50 and p99 printed with the world's mean step;
//! - `haptic_step`: the previous device path, `SurfaceSet::haptic_step` (a whole surface step
//!   per device tick), on the same scene: the ratio the servo loop is quoted against.
//!
//! Targets: p99 ≤ 200 µs at 100,000 nodes, ≤ 20 µs at 784.
//!
//! Run with `cargo bench --bench haptic_servo`.

use criterion::{criterion_group, criterion_main, Criterion};
use rapier_touch::haptics::{Servo, ServoLink, SimulatedHand, VirtualCoupling};
use rapier_touch::scenes::HapticScene;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

const RATE: f32 = 5000.0;

/// A hand that presses tool `k` in from where it starts to its pressed pose (the script at
/// 1.8 s: pressed, not yet dragging) in half a second and holds it there. It presses in from
/// outside: a hand that started inside the plate would have put no energy in, and the
/// passivity controller would render it nothing.
fn pressed_servo(scene: &HapticScene, k: usize, link: ServoLink) -> Servo<SimulatedHand> {
    let (start, pose) = (scene.script(k)(0.0), scene.script(k)(1.8));
    let hand = SimulatedHand::new(RATE, move |t| {
        let s = (t / 0.5).min(1.0);
        rapier_touch::prelude::Pose::from_translation(start.translation.lerp(pose.translation, s))
    })
    .expect("a hand");
    let coupling = VirtualCoupling {
        stiffness: 0.5 * VirtualCoupling::max_passive_stiffness(RATE, hand.device_damping),
        damping: 0.0,
        max_force: 20.0,
    };
    Servo::new(hand, link, coupling, RATE).expect("a rate")
}

/// The world thread: steps at 60 Hz until `stop`; returns the scene and its mean step (s).
fn world_thread(
    mut scene: HapticScene,
    stop: Arc<AtomicBool>,
) -> std::thread::JoinHandle<(HapticScene, f64)> {
    std::thread::spawn(move || {
        let dt = Duration::from_secs_f32(scene.world.integration_parameters.dt);
        let (mut steps, mut busy) = (0u32, Duration::ZERO);
        while !stop.load(Ordering::Acquire) {
            let t0 = Instant::now();
            scene.set.step(&mut scene.world);
            let took = t0.elapsed();
            busy += took;
            steps += 1;
            if let Some(rest) = dt.checked_sub(took) {
                std::thread::sleep(rest);
            }
        }
        (scene, busy.as_secs_f64() / steps.max(1) as f64)
    })
}

fn bench(c: &mut Criterion) {
    for (cells, label) in [(27u32, "784"), (99, "10k"), (315, "100k")] {
        for tools in [1usize, 2] {
            let mut scene = HapticScene::plate(cells, tools);
            let links: Vec<ServoLink> = (0..tools).map(|k| scene.link(k)).collect();
            let mut servos: Vec<Servo<SimulatedHand>> = links
                .into_iter()
                .enumerate()
                .map(|(k, l)| pressed_servo(&scene, k, l))
                .collect();
            // Into contact: the hands settle while the world catches up, one step at a time.
            for _ in 0..90 {
                for s in servos.iter_mut() {
                    for _ in 0..(RATE / 60.0) as usize {
                        s.tick();
                    }
                }
                scene.set.step(&mut scene.world);
            }
            let nodes = scene.vertices();
            let stop = Arc::new(AtomicBool::new(false));
            let world = world_thread(scene, stop.clone());
            // Latency percentiles, every servo on its own thread at 5 kHz.
            let threads: Vec<_> = servos
                .into_iter()
                .map(|s| s.spawn((2.2 * RATE) as usize))
                .collect();
            std::thread::sleep(Duration::from_secs(2));
            let mut back = Vec::new();
            for t in threads {
                let (servo, report) = t.stop().expect("a servo thread");
                println!(
                    "haptic_servo {nodes} nodes, {tools} tool(s): {:.0} Hz, tick p50 {:.2} µs, p99 {:.2} µs, force {:.3} N",
                    report.rate_hz(),
                    1e6 * report.latency_quantile(0.5),
                    1e6 * report.latency_quantile(0.99),
                    report.force_quantile(0.5)
                );
                back.push(servo);
            }
            let mut servo = back.swap_remove(0);
            c.bench_function(
                &format!("haptic_servo/{label}_nodes_{tools}_tools/servo_tick"),
                |b| b.iter(|| servo.tick()),
            );
            stop.store(true, Ordering::Release);
            let (mut scene, step) = world.join().expect("the world thread");
            println!(
                "haptic_servo {nodes} nodes, {tools} tool(s): world step {:.2} ms",
                1e3 * step
            );
            if tools == 1 {
                let tool = scene.tools[0];
                let pose = scene.script(0)(1.8);
                scene.set.disconnect_haptic(tool);
                c.bench_function(
                    &format!("haptic_servo/{label}_nodes_1_tools/haptic_step"),
                    |b| b.iter(|| scene.set.haptic_step(&scene.world, tool, pose)),
                );
            }
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
