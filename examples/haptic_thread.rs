//! A simulated haptic device on its own thread at 5 kHz presses and drags a ball on the
//! 788-node organ and on a 100,000-node sphere, 5 s each, while the world steps at 60 Hz on
//! the main thread (issue 14). Prints the servo's achieved rate, its tick latency, force
//! percentiles and the largest force jumps between servo ticks and across world updates, and
//! ends with `rate_hz=<lowest achieved> max_force_jump_pct=<largest jump in % of the peak>`.
//!
//! `cargo run --release --example haptic_thread`

use rapier_touch::haptics::{Servo, ServoReport, SimulatedHand, VirtualCoupling};
use rapier_touch::scenes::HapticScene;
use std::time::{Duration, Instant};

const RATE: f32 = 5000.0;

fn main() {
    let mut lowest_rate = f64::MAX;
    let mut worst_jump = 0.0f64;
    for (name, scene) in [
        ("organ", HapticScene::organ(1)),
        ("sphere", HapticScene::sphere(100_000, 1)),
    ] {
        let (rate, jump) = run(name, scene);
        lowest_rate = lowest_rate.min(rate);
        worst_jump = worst_jump.max(jump);
    }
    println!("rate_hz={lowest_rate:.0} max_force_jump_pct={worst_jump:.2}");
}

/// Runs the script on `scene`; returns the achieved rate and the largest jump (% of peak).
fn run(name: &str, mut scene: HapticScene) -> (f64, f64) {
    let link = scene.link(0);
    let hand = SimulatedHand::new(RATE, scene.script(0)).expect("a valid hand");
    // At half the stiffest passive coupling for the hand's 2 N·s/m at 5 kHz (10 kN/m).
    let coupling = VirtualCoupling {
        stiffness: 0.5 * VirtualCoupling::max_passive_stiffness(RATE, hand.device_damping),
        damping: 0.0,
        max_force: 20.0,
    };
    let servo = Servo::new(hand, link, coupling, RATE).expect("a valid rate");
    let seconds = HapticScene::SCRIPT_SECONDS;
    let thread = servo.spawn((seconds * RATE * 1.2) as usize);
    let dt = Duration::from_secs_f32(scene.world.integration_parameters.dt);
    let start = Instant::now();
    let (mut steps, mut step_time) = (0u32, Duration::ZERO);
    while start.elapsed() < Duration::from_secs_f32(seconds) {
        let t0 = Instant::now();
        scene.set.step(&mut scene.world);
        let took = t0.elapsed();
        step_time += took;
        steps += 1;
        if let Some(rest) = dt.checked_sub(took) {
            std::thread::sleep(rest);
        }
    }
    let (_, report) = thread.stop().expect("the servo thread ran");
    summarise(name, &scene, &report, steps, step_time)
}

fn summarise(
    name: &str,
    scene: &HapticScene,
    report: &ServoReport,
    steps: u32,
    step_time: Duration,
) -> (f64, f64) {
    let peak = report.force_quantile(1.0);
    let (within, across) = report.largest_force_jumps();
    let pct = |x: f64| if peak > 0.0 { 100.0 * x / peak } else { 0.0 };
    println!(
        "{name} ({} nodes): world {steps} steps, {:.2} ms each",
        scene.vertices(),
        1e3 * step_time.as_secs_f64() / steps.max(1) as f64
    );
    println!(
        "  servo: {:.0} Hz achieved ({} ticks, {} overruns, longest gap {:.2} ms), tick latency p50 {:.1} µs p99 {:.1} µs",
        report.rate_hz(),
        report.ticks,
        report.overruns,
        1e3 * report.longest_gap(),
        1e6 * report.latency_quantile(0.5),
        1e6 * report.latency_quantile(0.99)
    );
    println!(
        "  force: p50 {:.3} N, p90 {:.3} N, p99 {:.3} N, peak {:.3} N",
        report.force_quantile(0.5),
        report.force_quantile(0.9),
        report.force_quantile(0.99),
        peak
    );
    println!(
        "  largest jump: {:.4} N between servo ticks ({:.2} %), {:.4} N across world updates ({:.2} %)",
        within,
        pct(within),
        across,
        pct(across)
    );
    (report.rate_hz(), pct(within.max(across)))
}
