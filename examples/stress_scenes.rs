//! rapier's own stress-test scenes (its repository's `examples3d/stress_tests/`: pyramid,
//! plank tower, ragdolls, TriMesh floor, convex hulls, CCD), scaled to a few hundred bodies,
//! each stepped by vanilla rapier and through the touch pipeline in both opt-in modes:
//! - `rapier`: `PhysicsWorld::step`, rapier's default integration parameters (CCD on, contact
//!   clustering on), no hooks;
//! - `touch_hooks`: `TouchPipeline::step`, every collider with
//!   `ActiveHooks::MODIFY_SOLVER_CONTACTS`, contact clustering off;
//! - `touch_tracked`: `TouchPipeline::step`, every collider tracked, contact clustering off.
//!
//! Columns: mean ms per step (measurements excluded) and its ratio to rapier's, the deepest
//! overlap of any pair rapier solves after any step (parry's contact query), dynamic bodies
//! asleep at the end, bodies through the floor.
//!
//! Each scene is run three times, and the fastest of the three runs of a side is its ms per
//! step (the other columns are the same in every run: the runs are deterministic). Within a
//! run the three sides are stepped in turn, ten steps each (the side that goes first turning
//! at every block), so that all three are timed over the same stretch of the machine's time:
//! run one after the other, on a machine whose speed drifts by tens of percent over seconds,
//! the ratios moved by 0.3-0.8 between runs of the same binary. `--repeat N` changes the
//! count of runs.
//!
//! Run with `cargo run --release --example stress_scenes [-- STEPS] [SCENES] [--csv]
//! [--repeat N] [--rewind]` (default 300 steps, 5 s). `--rewind` switches on
//! `TouchOptions::rewind_dynamic_impacts` on the touch sides.

use rapier_touch::scenes::{StressRun, StressRunner, StressScene, StressSide};

/// Steps each side takes before the next side's turn.
const BLOCK: usize = 10;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let csv = args.iter().any(|a| a == "--csv");
    let rewind = args.iter().any(|a| a == "--rewind");
    let repeat = args
        .iter()
        .position(|a| a == "--repeat")
        .and_then(|i| args.get(i + 1)?.parse::<usize>().ok())
        .unwrap_or(3)
        .max(1);
    let steps = args
        .iter()
        .enumerate()
        .filter(|(i, _)| *i == 0 || args[i - 1] != "--repeat")
        .find_map(|(_, a)| a.parse::<usize>().ok())
        .unwrap_or(300);
    let only: Vec<&String> = args
        .iter()
        .filter(|a| a.parse::<usize>().is_err() && !a.starts_with("--"))
        .collect();
    if csv {
        println!("scene,side,bodies,ms_per_step,ratio,max_penetration_m,asleep,through_floor");
    } else {
        println!(
            "{:<14} {:<14} {:>6} {:>9} {:>7} {:>14} {:>7} {:>8}",
            "scene", "side", "bodies", "ms/step", "ratio", "max penetr. mm", "asleep", "through"
        );
    }
    for scene in StressScene::ALL {
        if !only.is_empty() && !only.iter().any(|o| *o == scene.name()) {
            continue;
        }
        let sides = [
            StressSide::Rapier,
            StressSide::TouchHooks,
            StressSide::TouchTracked,
        ];
        let mut runs: Vec<Option<StressRun>> = vec![None; sides.len()];
        for _ in 0..repeat {
            let mut runners: Vec<StressRunner> = sides
                .iter()
                .map(|side| {
                    StressRunner::new(scene, *side, 1.0, |o| o.rewind_dynamic_impacts = rewind)
                })
                .collect();
            for (block, start) in (0..steps).step_by(BLOCK).enumerate() {
                for k in 0..runners.len() {
                    let i = (k + block) % runners.len();
                    runners[i].step(BLOCK.min(steps - start));
                }
            }
            for (i, runner) in runners.iter().enumerate() {
                let r = runner.finish();
                match &mut runs[i] {
                    Some(best) => best.ms_per_step = best.ms_per_step.min(r.ms_per_step),
                    slot => *slot = Some(r),
                }
            }
        }
        let base_ms = runs[0].as_ref().map_or(1.0, |r| r.ms_per_step);
        for (side, r) in sides.iter().zip(runs.into_iter().flatten()) {
            let ratio = r.ms_per_step / base_ms;
            if csv {
                println!(
                    "{},{},{},{:.4},{:.3},{:.6},{},{}",
                    scene.name(),
                    side.name(),
                    r.bodies,
                    r.ms_per_step,
                    ratio,
                    r.max_penetration,
                    r.asleep,
                    r.through_floor
                );
            } else {
                println!(
                    "{:<14} {:<14} {:>6} {:>9.3} {:>6.2}x {:>14.2} {:>7} {:>8}",
                    scene.name(),
                    side.name(),
                    r.bodies,
                    r.ms_per_step,
                    ratio,
                    r.max_penetration * 1e3,
                    r.asleep,
                    r.through_floor
                );
            }
        }
    }
}
