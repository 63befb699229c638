//! rapier against rapier with `rapier_touch`, in one process: a 0.5 m box dropped at 1, 5, 20,
//! 50 and 100 m/s onto a fixed cuboid and onto a zero-thickness TriMesh floor, dt = 1/60, 180
//! steps. Three sides: `rapier_ccd` is rapier as users run it (its default integration
//! parameters: CCD on, `max_ccd_substeps = 1`, fast bodies swept against fixed colliders),
//! `rapier` is the same with CCD off (`max_ccd_substeps = 0`), `touch` is the touch pipeline
//! (rapier's CCD off: the guard alone). Contact clustering is off on every side.
//!
//! Prints a table; with `--csv`, the same rows as CSV with the header
//! `side,scene,speed_mps,tunneled,max_penetration_m,resting_penetration_m,steps_to_rest,ms_per_step`.
//! A tunneled run has no resting penetration (`NaN`) and never rests (`-1`).
//!
//! Each run is `rapier_touch::scenes::run_drop` (also plotted step by step by the `plots`
//! example).
//!
//! Run with `cargo run --release --example penetration_compare [-- --csv]`.

use rapier_touch::scenes::{run_drop_side, DropFloor, DropSide};

const STEPS: usize = 180;

struct Row {
    side: &'static str,
    scene: &'static str,
    speed: f32,
    tunneled: bool,
    max_penetration: f32,
    resting_penetration: f32,
    steps_to_rest: i64,
    ms_per_step: f64,
}

fn run(speed: f32, floor: DropFloor, side: DropSide) -> Row {
    let r = run_drop_side(speed, floor, side, STEPS);
    Row {
        side: match side {
            DropSide::Rapier => "rapier",
            DropSide::RapierDefaults => "rapier_ccd",
            DropSide::Touch => "touch",
        },
        scene: match floor {
            DropFloor::Cuboid => "cuboid",
            DropFloor::ThinTriMesh => "thin_trimesh",
        },
        speed,
        tunneled: r.tunneled(),
        max_penetration: r.max_penetration,
        resting_penetration: r.resting_penetration,
        steps_to_rest: r.steps_to_rest.map_or(-1, |s| s as i64),
        ms_per_step: r.seconds * 1e3 / STEPS as f64,
    }
}

fn main() {
    let csv = std::env::args().any(|a| a == "--csv");
    let mut rows = Vec::new();
    for floor in [DropFloor::Cuboid, DropFloor::ThinTriMesh] {
        for speed in [1.0, 5.0, 20.0, 50.0, 100.0] {
            for side in [DropSide::RapierDefaults, DropSide::Rapier, DropSide::Touch] {
                rows.push(run(speed, floor, side));
            }
        }
    }
    if csv {
        println!("side,scene,speed_mps,tunneled,max_penetration_m,resting_penetration_m,steps_to_rest,ms_per_step");
        for r in &rows {
            println!(
                "{},{},{},{},{:.6},{:.6},{},{:.4}",
                r.side,
                r.scene,
                r.speed,
                r.tunneled,
                r.max_penetration,
                r.resting_penetration,
                r.steps_to_rest,
                r.ms_per_step
            );
        }
    } else {
        println!(
            "{:<10} {:<13} {:>9} {:>9} {:>16} {:>16} {:>14} {:>11}",
            "side",
            "scene",
            "speed m/s",
            "tunneled",
            "max penetr. m",
            "rest penetr. m",
            "steps to rest",
            "ms/step"
        );
        for r in &rows {
            println!(
                "{:<10} {:<13} {:>9} {:>9} {:>16.6} {:>16.6} {:>14} {:>11.4}",
                r.side,
                r.scene,
                r.speed,
                if r.tunneled { "yes" } else { "no" },
                r.max_penetration,
                r.resting_penetration,
                r.steps_to_rest,
                r.ms_per_step
            );
        }
    }
    // The crate's side never tunnels and never penetrates more than 1 mm.
    for r in rows.iter().filter(|r| r.side == "touch") {
        assert!(
            !r.tunneled && r.max_penetration <= 1e-3,
            "{} at {} m/s",
            r.scene,
            r.speed
        );
    }
}
