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
//! Run with `cargo run --release --example stress_scenes [-- STEPS] [--csv]` (default 300
//! steps, 5 s).

use rapier_touch::scenes::{run_stress, StressScene, StressSide};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let csv = args.iter().any(|a| a == "--csv");
    let steps = args
        .iter()
        .find_map(|a| a.parse::<usize>().ok())
        .unwrap_or(300);
    let only: Vec<&String> = args
        .iter()
        .filter(|a| a.parse::<usize>().is_err() && *a != "--csv")
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
        let mut base = None;
        for side in [
            StressSide::Rapier,
            StressSide::TouchHooks,
            StressSide::TouchTracked,
        ] {
            let r = run_stress(scene, side, steps);
            let base_ms = *base.get_or_insert(r.ms_per_step);
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
