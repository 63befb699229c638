//! Plots of numbers over time (cargo feature `render`: `plotters`' bitmap backend, labelled with
//! the crate's built-in pixel font, so no system font library is needed):
//!
//! - `multi_tool_forces.png`: the force magnitude on each of the six tools of
//!   `scenes::MultiToolScene` (the `multi_tool` example) at every 60 Hz step of its 7.5 s run:
//!   each tool's force rises as it comes down, stays while it is pressed and dragged, and
//!   drops to zero at lift-off;
//! - `constrained_790_energy.png`: the total (kinetic + elastic) energy of `scenes::Fig7Organ`
//!   at every step of the `constrained_790` run, per integrator, and each integrator's energy
//!   minus the exact filter's;
//! - `penetration.png`: how deep the dropped box of `scenes::drop_world` is below the floor
//!   after each step (`scenes::run_drop`, as in `penetration_compare`), rapier alone (dashed)
//!   and with the crate (solid), for both floors and every speed. A box that went through the
//!   floor is drawn at the plot's top.
//!
//! A progress bar on stderr follows the runs (`--quiet` hides it).
//!
//! Run with `cargo run --release --features render --example plots [-- output dir] [--quiet]`
//! (default `docs/img`).

use rapier_touch::prelude::*;
use rapier_touch::render::plot::{render_row, LinePlot};
use rapier_touch::render::Color;
use rapier_touch::scenes::{
    diverged, run_drop, DropFloor, Fig7Organ, MultiToolScene, COMPARED_INTEGRATORS,
};
use std::error::Error;
use std::path::{Path, PathBuf};

#[path = "common/progress.rs"]
mod progress;

/// Steps of the `constrained_790` run (10 s).
const ORGAN_STEPS: usize = 600;
/// Steps of each `penetration_compare` drop.
const DROP_STEPS: usize = 180;
const SPEEDS: [Real; 5] = [1.0, 5.0, 20.0, 50.0, 100.0];
const FLOORS: [(DropFloor, &str); 2] = [
    (DropFloor::Cuboid, "CUBOID FLOOR"),
    (DropFloor::ThinTriMesh, "THIN TRIMESH FLOOR"),
];

/// Distinct colours for up to six lines.
const PALETTE: [(u8, u8, u8); 6] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
];

fn colour(k: usize) -> Color {
    let (r, g, b) = PALETTE[k % PALETTE.len()];
    Color::from_rgba8(r, g, b, 255)
}

fn multi_tool_forces(dir: &Path, bar: &indicatif::ProgressBar) -> Result<(), Box<dyn Error>> {
    bar.set_message("multi_tool");
    let mut scene = MultiToolScene::new();
    let tools = scene.tools.len();
    let mut forces: Vec<Vec<(f64, f64)>> = vec![Vec::new(); tools];
    for f in &mut forces {
        f.push((0.0, 0.0));
    }
    for _ in 0..MultiToolScene::total_steps() {
        scene.step();
        let t = scene.time() as f64;
        for (k, f) in forces.iter_mut().enumerate() {
            f.push((t, scene.tool_reaction(k).force.length() as f64));
        }
        bar.inc(1);
    }
    let mut plot = LinePlot::new(
        "MULTI_TOOL: FORCE ON EACH TOOL (788-NODE ORGAN DOME, 60 HZ STEPS)",
        "T S",
        "|F| N",
    );
    for (k, f) in forces.into_iter().enumerate() {
        let label = format!("T{} {}", k + 1, short(scene.tools[k].spec.shape));
        plot.line(label, colour(k), f);
    }
    plot.x_range = Some((0.0, MultiToolScene::END_TIME as f64));
    plot.notes = vec![
        "TOOLS START 0.5 S APART".into(),
        "EACH TOOL:".into(),
        "DOWN IN 0.3 S".into(),
        "PRESSES 0.35 S".into(),
        "DRAGGED 1.5 S".into(),
        "HOLDS 0.35 S".into(),
        "LIFTS IN 0.3 S".into(),
    ];
    save(&plot.render(1000, 520)?, dir, "multi_tool_forces.png")
}

/// `ball r = 10 mm` as `BALL R10`, the cuboid as `SLED`.
fn short(shape: rapier_touch::scenes::ToolShape) -> String {
    match shape {
        rapier_touch::scenes::ToolShape::Ball(r) => format!("BALL R{:.0}", r * 1e3),
        rapier_touch::scenes::ToolShape::Cuboid(..) => "CUBOID SLED".into(),
    }
}

fn constrained_790_energy(dir: &Path, bar: &indicatif::ProgressBar) -> Result<(), Box<dyn Error>> {
    bar.set_message("constrained_790");
    let organ = Fig7Organ::new();
    let mut surfaces: Vec<MassSpringSurface> = COMPARED_INTEGRATORS
        .iter()
        .map(|&(_, integrator)| organ.surface(integrator))
        .collect();
    // Energy per integrator at every step (mJ), NaN once diverged.
    let mut energy: Vec<Vec<(f64, f64)>> = vec![Vec::new(); surfaces.len()];
    for step in 0..=ORGAN_STEPS {
        let t = step as f64 * Fig7Organ::DT as f64;
        for (s, e) in surfaces.iter().zip(&mut energy) {
            let joules = if diverged(s) {
                f64::NAN
            } else {
                s.total_energy()
            };
            e.push((t, joules * 1e3));
        }
        if step < ORGAN_STEPS {
            surfaces.iter_mut().for_each(MassSpringSurface::step);
        }
        bar.inc(1);
    }
    const EXACT: usize = 1;
    let widths = [2, 5, 2, 2];
    let dashed = [false, false, true, false];
    let mut total = LinePlot::new(
        "CONSTRAINED_790: TOTAL ENERGY (KINETIC + ELASTIC)\nFIG. 7 ORGAN, 788 NODES, 6 FORCES, DT = 1/60 S",
        "T S",
        "ENERGY MJ",
    );
    let mut difference = LinePlot::new(
        "|ENERGY - EXACT FILTER'S ENERGY|\nTHE SAME RUNS (LOG SCALE)",
        "T S",
        "|DIFFERENCE| UJ",
    );
    for (k, (name, _)) in COMPARED_INTEGRATORS.iter().enumerate() {
        let label = name.to_uppercase();
        let line = total.line(label.clone(), colour(k), energy[k].clone());
        line.width = widths[k];
        line.dashed = dashed[k];
        if k != EXACT {
            let diff: Vec<(f64, f64)> = energy[k]
                .iter()
                .zip(&energy[EXACT])
                .map(|(a, b)| (a.0, (a.1 - b.1).abs() * 1e3))
                .collect();
            difference.line(label, colour(k), diff);
        }
    }
    difference.log_y = true;
    difference.y_range = Some((1e-8, 1e3));
    total.notes = vec![
        "EXACT FILTER +".into(),
        "NEIGHBOUR FILTER +".into(),
        "BARAFF-WITKIN:".into(),
        "ON TOP OF EACH OTHER".into(),
    ];
    save(
        &render_row(&[total, difference], 1400, 520)?,
        dir,
        "constrained_790_energy.png",
    )
}

fn penetration(dir: &Path, bar: &indicatif::ProgressBar) -> Result<(), Box<dyn Error>> {
    bar.set_message("penetration");
    let mut panels = Vec::new();
    for (floor, name) in FLOORS {
        let mut plot = LinePlot::new(
            format!(
                "PENETRATION PER STEP, {name}\n0.5 M BOX DROPPED FROM 3 M, DT = 1/60 S, CCD OFF"
            ),
            "STEP",
            "DEPTH BELOW THE FLOOR MM",
        );
        for (k, speed) in SPEEDS.iter().enumerate() {
            for with_crate in [false, true] {
                let run = run_drop(*speed, floor, with_crate, DROP_STEPS);
                bar.inc(1);
                // Not touching: no point (a log axis has no 0).
                let points = (0..=DROP_STEPS)
                    .map(|i| {
                        let d = if i == 0 { 0.0 } else { run.depth[i - 1] };
                        let mm = if d > 0.0 { d as f64 * 1e3 } else { f64::NAN };
                        (i as f64, mm)
                    })
                    .collect();
                let side = if with_crate { "TOUCH" } else { "RAPIER" };
                let through = if run.tunneled() { " TUNNELED" } else { "" };
                let line = plot.line(format!("{side} {speed} M/S{through}"), colour(k), points);
                line.dashed = !with_crate;
            }
        }
        plot.log_y = true;
        plot.y_range = Some((1e-2, 2e3));
        plot.x_range = Some((0.0, DROP_STEPS as f64));
        plot.notes = vec![
            "DASHED: RAPIER ALONE".into(),
            "SOLID: WITH RAPIER_TOUCH".into(),
            "NOT TOUCHING: NO LINE".into(),
            String::new(),
            "TUNNELED: THE BOX CENTRE".into(),
            "WENT BELOW THE FLOOR".into(),
            match floor {
                DropFloor::Cuboid => "(RAPIER PUSHES IT BACK OUT)".into(),
                DropFloor::ThinTriMesh => "(IT FALLS: AT THE TOP)".into(),
            },
        ];
        panels.push(plot);
    }
    save(&render_row(&panels, 1600, 600)?, dir, "penetration.png")
}

fn save(pm: &rapier_touch::render::Pixmap, dir: &Path, name: &str) -> Result<(), Box<dyn Error>> {
    let path: PathBuf = dir.join(name);
    pm.save_png(&path)?;
    println!("wrote {}", path.display());
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let dir = progress::output_dir("docs/img")?;
    let work = MultiToolScene::total_steps() + ORGAN_STEPS + 1 + 2 * 2 * SPEEDS.len();
    let bar = progress::bar(work as u64, "plots");
    multi_tool_forces(&dir, &bar)?;
    constrained_790_energy(&dir, &bar)?;
    penetration(&dir, &bar)?;
    bar.finish_and_clear();
    Ok(())
}
