//! rapier's own soft body against this crate's filtered surface, in one process: the same pinned
//! plate pressed by the same kinematic ball tools, at two mesh sizes, with 1 and 6 tools, at
//! dt = 1/60 s and 1/1000 s.
//!
//! **Surface.** `plate(0.3, 0.3, n, n)`: a 0.3 m square in the xz-plane, 28 × 28 = 784 or
//! 55 × 55 = 3025 nodes, its rim pinned (108 or 216 vertices). Both engines get the same vertex
//! positions, the same triangles and the same edges (the crate's `MassSpringSurface::edges()`,
//! handed to rapier), the same total mass, 0.2 kg split evenly over the vertices (m = 0.2 kg / N: a
//! sheet of soft tissue about 2 mm thick), and no gravity.
//!
//! - `touch`: `MassSpringSurfaceBuilder` with k = 30 N/m and c = 0.05 N·s/m per edge, the
//!   paper's linear springs, the **exact** filter (`Integrator::EXACT`), attached to a fixed body
//!   with `SurfaceSet::insert` (1 substep, with its TriMesh collider); the tools are registered
//!   with `SurfaceSet::add_tool` and the world is stepped by `SurfaceSet::step`. The per-vertex
//!   `s = dt² Σk/m + dt Σc/m` is printed: at dt = 1/60 it is about 216 (784 nodes) and 832
//!   (3025 nodes) on average, at dt = 1/1000 about 1.9 and 7.3: beyond explicit Euler's limit
//!   (s of order 1) everywhere, checked below. `Integrator::NEIGHBOUR` would fall back to the
//!   exact filter at these s (its error bound `(s/(1+s))²` exceeds the default 0.05), so the
//!   exact filter is used. Tools hold vertices as moving pins inside the filter (the
//!   capacitance solve of `MassSpringSurface::hold`), which keeps contact stable at any s.
//! - `rapier`: `SoftBodyBuilder::new(vertices).edges(edges).surface(triangles)`, the rim in
//!   `pinned_particles`, `mass(0.2)`, with no bending edges, dihedrals, shape matching or cells:
//!   the same spring network, solved by rapier's default `Constraints` soft solver inside its
//!   step (default 4 solver substeps, default impact-adaptive extra substeps). The contact skin
//!   (`particle_radius`) is 1 mm.
//!
//! **Stiffness mapping.** rapier's edge softness is a natural frequency `f` (Hz) and a damping
//! ratio `ζ`, normalised by the constraint's effective mass. For an edge between two free
//! particles of mass m that mass is m/2, so a spring k with a damper c maps to
//! `f = √(2k/m) / 2π` and `ζ = c / (2 √(k m/2))`: 784 nodes f ≈ 77 Hz, ζ ≈ 0.40; 3025 nodes
//! f ≈ 152 Hz, ζ ≈ 0.79 (printed). The mapping is exact only for stretching an edge between two
//! free particles. An edge to a pinned particle has twice that effective mass, so rapier makes
//! it twice as stiff as k. rapier's edges are **distance** constraints: a flat sheet has no
//! out-of-plane stiffness until it stretches. The crate's linear springs (`SpringModel::Linear`,
//! eq. 3) pull on the displacement difference in every direction. The tools impose the same
//! indentation on both, so the displacements compare. The forces do not: a membrane pressed
//! 5 mm pushes back far less than the linear-spring plate.
//!
//! **Tools.** Kinematic position-based balls of radius 25 mm, at the plate's centre (1 tool) or
//! at six spots 70 mm and 100 mm apart (6 tools). Every configuration runs frictionless and
//! with friction μ = 0.5: for rapier the balls' collider friction (combined with the soft
//! body's surface collider, rapier's default 0.5, by `Min`), for the crate the tools'
//! `Friction::new(0.5, 0.5)` (the vertices they press stick: each is held in all three
//! directions instead of along the normal). Each starts with its bottom
//! 3 mm above the plate, goes down to 5 mm below it over 0.15 s, and holds there. rapier's balls
//! ride 1 mm higher (its contact skin), so both plates are pressed 5 mm in.
//!
//! **Measured**, per engine and configuration:
//! - `ms_per_step`: the mean wall time of the whole step after a 10 % warm-up
//!   (`SurfaceSet::step`, i.e. rapier's pipeline plus the surface, for `touch`;
//!   `PhysicsWorld::step` with the soft body for `rapier`);
//! - `max_displacement_m`: the largest vertex displacement from home over the run;
//! - `stable`: every position finite at every step and the displacement below 0.1 m;
//! - `tool_force_available`: while the tools hold their press (t ≥ 0.15 s), every tool read a
//!   finite, nonzero force at some step, and no reading was non-finite. For `touch` that reading
//!   is `SurfaceSet::tool_reaction`. For `rapier` it is the impulse rapier writes back into the
//!   tool's contact pairs with the soft surface, `ContactPair::total_impulse() / dt` (what
//!   contact force events report).
//!
//! The readable table also gives the share of hold steps × tools with a nonzero force and the
//! mean upward force on a tool over the hold. Runs are 60 steps (1 s) at dt = 1/60 and 300 steps
//! (0.3 s) at dt = 1/1000. Before the table, a free crate surface of each size (same k, c, m and
//! pins, a 10 mN load on the centre vertex) is stepped 300 times with `Integrator::ExplicitEuler`
//! and with the exact filter: explicit Euler diverges with this stiffness.
//!
//! Asserted: explicit Euler diverges at dt = 1/60 while the exact filter stays bounded at both
//! dt, and in every configuration `touch` is stable and has a tool force. The speed ratio
//! rapier/touch is printed, not asserted (timing).
//!
//! A progress bar on stderr counts the checks and configurations (`--quiet` hides it).
//!
//! Run with `cargo run --release --example soft_compare [-- --csv] [--quiet]`. With `--csv` only the
//! header `engine,nodes,tools,dt,friction,ms_per_step,max_displacement_m,stable,tool_force_available`
//! and the rows are printed (`engine` is `rapier` or `touch`, `dt` in seconds, `friction` the
//! tools' coefficient).

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim, SurfaceMesh};
use std::time::Instant;

#[path = "../common/progress.rs"]
mod progress;
mod runs;
mod scene;

use runs::*;
use scene::*;

/// Side of the square plate (m).
pub(crate) const SIZE: Real = 0.3;
/// Mass of the whole plate, pinned rim included (kg).
pub(crate) const TOTAL_MASS: Real = 0.2;
/// Stiffness of every edge (N/m).
pub(crate) const K: Real = 30.0;
/// Damping of every edge (N·s/m).
pub(crate) const C: Real = 0.05;
pub(crate) const TOOL_RADIUS: Real = 0.025;
/// rapier's contact skin (the soft body's particle radius, m).
pub(crate) const SKIN: Real = 0.001;
/// Tool bottom above the plate at the start (m).
pub(crate) const START_GAP: Real = 0.003;
/// How far the tools press below the plate (m).
pub(crate) const PRESS_DEPTH: Real = 0.005;
/// Time the tools take from the start to full depth (s); they hold from then on.
pub(crate) const DESCENT: Real = 0.15;
/// The tools' friction coefficient in the rows with friction.
pub(crate) const MU: Real = 0.5;
/// Larger displacements than this count as unstable (m).
pub(crate) const STABLE_BOUND: Real = 0.1;
/// Steps of the free-surface divergence check.
pub(crate) const CHECK_STEPS: usize = 300;

/// A time step: value (s), label, number of steps.
pub(crate) const DTS: [(Real, &str, usize); 2] =
    [(1.0 / 60.0, "1/60", 60), (1.0 / 1000.0, "1/1000", 300)];

#[derive(Copy, Clone)]
pub(crate) struct Config {
    pub(crate) tools: usize,
    pub(crate) dt: Real,
    pub(crate) dt_label: &'static str,
    pub(crate) steps: usize,
    /// The tools' friction coefficient.
    pub(crate) friction: Real,
}

pub(crate) struct Row {
    pub(crate) engine: &'static str,
    pub(crate) nodes: usize,
    pub(crate) cfg: Config,
    pub(crate) ms_per_step: f64,
    pub(crate) max_displacement: Real,
    pub(crate) stable: bool,
    pub(crate) force_available: bool,
    /// Share of hold steps × tools with a finite nonzero force.
    pub(crate) force_share: f64,
    /// Mean upward force on a tool over the hold (N).
    pub(crate) mean_force_y: f64,
}

/// Steps a free crate surface `CHECK_STEPS` times under a 10 mN load on its centre vertex:
/// `Some(largest displacement)`, or `None` once it is no longer finite.
fn free_run(p: &Plate, dt: Real, integrator: Integrator) -> Option<Real> {
    let mut s = p.surface(dt, integrator);
    let centre = (0..p.nodes() as u32)
        .min_by(|&a, &b| {
            let da = p.mesh.vertices[a as usize].length();
            let db = p.mesh.vertices[b as usize].length();
            da.total_cmp(&db)
        })
        .expect("vertices");
    s.add_force_schedule(
        vec![centre],
        ForceProfile::Step {
            force: Vector::new(0.0, -0.01, 0.0),
            start: 0.0,
            end: None,
        },
    )
    .expect("valid force");
    let mut max_disp: Real = 0.0;
    for _ in 0..CHECK_STEPS {
        s.step();
        let d = s.max_displacement();
        if !s.is_finite() || s.diverged() || !d.is_finite() {
            return None;
        }
        max_disp = max_disp.max(d);
    }
    Some(max_disp)
}

fn bounded(run: Option<Real>) -> bool {
    run.is_some_and(|d| d < STABLE_BOUND)
}

fn describe(run: Option<Real>) -> String {
    match run {
        Some(d) if d < STABLE_BOUND => format!("bounded (max {:.3} mm)", d * 1e3),
        Some(d) => format!("unbounded (max {d:.3e} m)"),
        None => "diverged (not finite)".to_string(),
    }
}

fn print_setup(plates: &[Plate]) {
    println!(
        "plate {SIZE} m square, rim pinned, {TOTAL_MASS} kg in all, k = {K} N/m and \
         c = {C} N*s/m per edge, no gravity; ball tools r = {} mm press {} mm in over {DESCENT} s, \
         then hold",
        TOOL_RADIUS * 1e3,
        PRESS_DEPTH * 1e3
    );
    for p in plates {
        let (f, zeta) = rapier_softness(p.vertex_mass());
        println!(
            "{} nodes: {} triangles, {} edges, {} pinned, m = {:.3e} kg per vertex; rapier edge \
             softness f = {f:.1} Hz, zeta = {zeta:.3}",
            p.nodes(),
            p.mesh.num_triangles(),
            p.surface(DTS[0].0, Integrator::EXACT).edges().len(),
            p.rim.len(),
            p.vertex_mass()
        );
        for (dt, label, _) in DTS {
            let s = p.surface(dt, Integrator::NEIGHBOUR);
            let free: Vec<Real> = s.s_values().into_iter().filter(|&v| v > 0.0).collect();
            println!(
                "  dt = {label}: s mean {:.3}, max {:.3}; NEIGHBOUR would fall back to exact: {}",
                free.iter().sum::<Real>() / free.len() as Real,
                free.iter().copied().fold(0.0, Real::max),
                s.filter_fallback()
            );
        }
    }
    println!();
}

fn main() {
    let csv = std::env::args().any(|a| a == "--csv");
    let plates = [Plate::new(27), Plate::new(54)];
    if !csv {
        print_setup(&plates);
    }

    // Progress: the free-surface checks, then every configuration.
    let configs = plates.len() * 2 * DTS.len() * 2;
    let bar = progress::bar((plates.len() * DTS.len() + configs) as u64, "soft_compare");

    // The premise: with this stiffness explicit integration diverges at dt = 1/60, the filter
    // does not.
    for p in &plates {
        for (dt, label, _) in DTS {
            let explicit = free_run(p, dt, Integrator::ExplicitEuler);
            let exact = free_run(p, dt, Integrator::EXACT);
            bar.inc(1);
            if !csv {
                bar.suspend(|| {
                    println!(
                        "free surface, {} nodes, dt = {label}, {CHECK_STEPS} steps, 10 mN on the \
                         centre: explicit Euler {}; exact filter {}",
                        p.nodes(),
                        describe(explicit),
                        describe(exact)
                    )
                });
            }
            assert!(
                bounded(exact),
                "the exact filter stays bounded ({} nodes, dt = {label})",
                p.nodes()
            );
            if label == "1/60" {
                assert!(
                    !bounded(explicit),
                    "explicit Euler diverges at dt = 1/60 ({} nodes)",
                    p.nodes()
                );
            }
        }
    }
    if !csv {
        bar.suspend(|| println!());
    }

    let mut rows = Vec::new();
    for p in &plates {
        let edges = p.surface(DTS[0].0, Integrator::EXACT).edges().to_vec();
        for tools in [1, 6] {
            for ((dt, dt_label, steps), friction) in
                DTS.into_iter().flat_map(|d| [(d, 0.0), (d, MU)])
            {
                let cfg = Config {
                    tools,
                    dt,
                    dt_label,
                    steps,
                    friction,
                };
                bar.set_message(format!(
                    "{} nodes, {tools} tools, dt = {dt_label}, friction {friction}",
                    p.nodes()
                ));
                let rapier = run_rapier(p, &edges, cfg);
                let touch = run_touch(p, cfg);
                bar.inc(1);
                assert!(
                    touch.stable,
                    "touch is stable ({} nodes, {tools} tools, dt = {dt_label}): max \
                     displacement {} m",
                    p.nodes(),
                    touch.max_displacement
                );
                assert!(
                    touch.force_available,
                    "touch has a tool force ({} nodes, {tools} tools, dt = {dt_label})",
                    p.nodes()
                );
                rows.push((rapier, touch));
            }
        }
    }

    bar.finish_and_clear();

    if csv {
        println!(
            "engine,nodes,tools,dt,friction,ms_per_step,max_displacement_m,stable,tool_force_available"
        );
        for r in rows.iter().flat_map(|(a, b)| [a, b]) {
            println!(
                "{},{},{},{:.6},{},{:.4},{:.6},{},{}",
                r.engine,
                r.nodes,
                r.cfg.tools,
                r.cfg.dt,
                r.cfg.friction,
                r.ms_per_step,
                r.max_displacement,
                r.stable,
                r.force_available
            );
        }
        return;
    }
    println!(
        "{:>5} {:>5} {:>6} {:>3} {:>7} {:>9} {:>11} {:>7} {:>11} {:>13} {:>12}",
        "nodes",
        "tools",
        "dt",
        "mu",
        "engine",
        "ms/step",
        "max disp mm",
        "stable",
        "tool force",
        "F>0 on hold %",
        "mean Fy N"
    );
    let mut min_ratio = f64::INFINITY;
    for (rapier, touch) in &rows {
        for r in [rapier, touch] {
            println!(
                "{:>5} {:>5} {:>6} {:>3} {:>7} {:>9.4} {:>11.3} {:>7} {:>11} {:>13.0} {:>12.3e}",
                r.nodes,
                r.cfg.tools,
                r.cfg.dt_label,
                r.cfg.friction,
                r.engine,
                r.ms_per_step,
                r.max_displacement * 1e3,
                r.stable,
                r.force_available,
                r.force_share * 100.0,
                r.mean_force_y
            );
        }
        let ratio = rapier.ms_per_step / touch.ms_per_step;
        min_ratio = min_ratio.min(ratio);
        println!(
            "{:>5} {:>5} {:>6} {:>3} rapier/touch time per step: {ratio:.1}x",
            touch.nodes, touch.cfg.tools, touch.cfg.dt_label, touch.cfg.friction
        );
    }
    println!(
        "smallest speed ratio rapier/touch: {min_ratio:.1}x (target 10x; timing, not asserted)"
    );
}
