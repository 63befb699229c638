//! rapier against rapier with `rapier_touch`, in one process. Three sides: `rapier_ccd` is rapier
//! as users run it (its default integration parameters: CCD on, `max_ccd_substeps = 1`, fast
//! bodies swept against fixed colliders), `rapier` is the same with CCD off
//! (`max_ccd_substeps = 0`), `touch` is the touch pipeline with its default options (rapier's
//! CCD off: the guard alone). dt = 1/60, 180 steps, contact clustering off on every side.
//!
//! Scenes (`scene` column):
//! - `cuboid`, `thin_trimesh`: a 0.5 m box dropped at 1, 5, 20, 50 and 100 m/s onto a fixed
//!   10 m cuboid and onto a zero-thickness TriMesh floor (`rapier_touch::scenes::run_drop_side`,
//!   also plotted step by step by the `plots` example).
//! - the scenes of `rapier_touch::scenes::CompareScene` (`run_compare_side`), at 5, 20 and
//!   100 m/s: `spinning` (the box spinning at 20 rad/s about x and 5 rad/s about y, onto a fixed
//!   100 m cuboid; depth of the rotated box), `dynamic_plate` (the box onto a 2 cm thick, 4 m
//!   wide *dynamic* plate lying on the fixed floor; depth: the deepest box-plate or plate-floor
//!   overlap from parry's contact query; through: the box below the plate or the plate below
//!   the floor), `trimesh_mover` (a non-convex ∩-shaped TriMesh body, tilted, onto the fixed
//!   floor; depth of its lowest vertex: rapier's CCD never sweeps TriMesh movers).
//! - `small_scale`: the `cuboid` drop with every length, speed and gravity times 1e-2 (a 5 mm
//!   box at 0.05, 0.2 and 1 m/s, the speed column being the actual speed) and rapier's
//!   `IntegrationParameters::length_unit = 0.01` on **every** side (rapier: the size of a
//!   typical object relative to a metre), so rapier's run is the `cuboid` run in other units.
//!   The touch pipeline's slops are in rapier's length unit too (`TouchOptions`).
//!
//! Prints a table; with `--csv`, the same rows as CSV with the header
//! `side,scene,speed_mps,tunneled,max_penetration_m,resting_penetration_m,steps_to_rest,ms_per_step`.
//! Penetrations are in metres at every scale. A tunneled run has no resting penetration (`NaN`)
//! and never rests (`-1`).
//!
//! Asserts that no `touch` row tunnels or penetrates more than 1 mm, and that the `small_scale`
//! touch rows also stay within 2 % of the box's size (0.1 mm).
//!
//! Run with `cargo run --release --example penetration_compare [-- --csv]`.

use rapier_touch::scenes::{
    run_compare_side, run_drop_side, CompareScene, DropFloor, DropRun, DropSide, DROP_BOX_HALF,
};

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

fn side_name(side: DropSide) -> &'static str {
    match side {
        DropSide::Rapier => "rapier",
        DropSide::RapierDefaults => "rapier_ccd",
        DropSide::Touch => "touch",
    }
}

fn row(side: DropSide, scene: &'static str, speed: f32, r: DropRun) -> Row {
    Row {
        side: side_name(side),
        scene,
        speed,
        tunneled: r.tunneled(),
        max_penetration: r.max_penetration,
        resting_penetration: r.resting_penetration,
        steps_to_rest: r.steps_to_rest.map_or(-1, |s| s as i64),
        ms_per_step: r.seconds * 1e3 / STEPS as f64,
    }
}

fn run(speed: f32, floor: DropFloor, side: DropSide) -> Row {
    let scene = match floor {
        DropFloor::Cuboid => "cuboid",
        DropFloor::ThinTriMesh => "thin_trimesh",
    };
    row(side, scene, speed, run_drop_side(speed, floor, side, STEPS))
}

const SIDES: [DropSide; 3] = [DropSide::RapierDefaults, DropSide::Rapier, DropSide::Touch];

fn main() {
    let csv = std::env::args().any(|a| a == "--csv");
    let mut rows = Vec::new();
    for floor in [DropFloor::Cuboid, DropFloor::ThinTriMesh] {
        for speed in [1.0, 5.0, 20.0, 50.0, 100.0] {
            for side in SIDES {
                rows.push(run(speed, floor, side));
            }
        }
    }
    for scene in CompareScene::ALL {
        for speed in scene.speeds() {
            for side in SIDES {
                let r = run_compare_side(scene, speed, side, STEPS);
                rows.push(row(side, scene.name(), speed, r));
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
    // The crate's side never tunnels and never penetrates more than 1 mm; at 1/100 scale, not
    // more than 2 % of the 5 mm box either.
    let small_bound = 0.02 * 2.0 * DROP_BOX_HALF * CompareScene::SmallScale.scale();
    let failures: Vec<String> = rows
        .iter()
        .filter(|r| r.side == "touch")
        .filter(|r| {
            let bound = if r.scene == CompareScene::SmallScale.name() {
                small_bound.min(1e-3)
            } else {
                1e-3
            };
            r.tunneled || r.max_penetration > bound
        })
        .map(|r| {
            format!(
                "{} at {} m/s: tunneled {}, max penetration {} m",
                r.scene, r.speed, r.tunneled, r.max_penetration
            )
        })
        .collect();
    assert!(
        failures.is_empty(),
        "touch rows failed:\n{}",
        failures.join("\n")
    );
}
