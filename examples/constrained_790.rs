//! The paper's Fig. 7: a deformable object of about 790 nodes with a constrained internal
//! boundary and 6 external forces, run with each integrator side by side.
//!
//! **Set-up.** `paper_organ_outline()` meshed with its own target edge (5.28 mm):
//! `triangulate_planar` gives 788 nodes (spade 2.15.1), a kidney shape about 0.14 m × 0.10 m
//! in the plane y = 0. The vertices of its internal constraint polyline
//! (`PlanarMesh::constrained[0]`, 29 vertices: a vessel or ligament crossing the organ) are
//! pinned: the constrained internal boundary. The outer boundary is **free**, so the whole
//! organ hangs on the polyline. The paper's linear springs, 1 g per vertex, k = 0.1 N/m,
//! c = 0.001 N·s/m per edge, dt = 1/60 s, no gravity: the soft regime of `plate_step_force`
//! (`(dt² k + dt c)/m` = 0.044 per edge, s = 0.27 at a vertex with 6 edges; mean and max s
//! printed), where explicit Euler is stable and the immediate-neighbour filter is close to
//! the exact one.
//!
//! **Forces**: 6 vertex groups, each the free vertex nearest to a site (u, v) and its edge
//! neighbours (disjoint, none pinned), every vertex of a group receiving:
//! 1. (0.04, 0.03): step, 1 mN down (-y), from t = 0;
//! 2. (-0.02, 0.03): ramp to 1 mN up (+y) over 2 s from t = 0;
//! 3. (0.07, 0.0): step, 1 mN outward in the plane (+x), from t = 1 s to t = 6 s;
//! 4. (0.0, -0.035): ramp to 1 mN in the plane (-z) over 3 s from t = 0.5 s;
//! 5. (-0.035, -0.03): step, 1 mN along (-x, -y)/√2, from t = 2 s;
//! 6. (0.055, -0.03): ramp to 1 mN along (0, -0.6, 0.8) over 2 s from t = 3 s.
//!
//! **Output**: per integrator (`ExplicitEuler`, `EXACT`, `NEIGHBOUR` with
//! `neighbour_max_error(f32::INFINITY)` so it never falls back, `BARAFF_WITKIN`) at
//! t = 0, 2.5, 5, 7.5 and 10 s: the largest displacement, the RMS difference of the positions
//! from the exact-filter run and the total (kinetic + elastic) energy, or "diverged"; then the
//! largest RMS difference over the run and the wall-clock time per step (information only).
//!
//! Checks (asserts): the pinned polyline vertices never leave their home position, for every
//! integrator at every step; every filtered run (exact, neighbour, Baraff-Witkin) stays finite;
//! the neighbour filter's RMS difference from the exact run stays below 1 % of the exact run's
//! largest displacement (measured: 0.085 %); Baraff-Witkin with linear springs matches the exact
//! filter (below 1e-4 of the displacement).
//!
//! The organ, its pins and forces are the library's `rapier_touch::scenes::Fig7Organ` (also
//! drawn by `pictures` and plotted by `plots`). A progress bar runs on stderr while it steps
//! (`--quiet` hides it).
//!
//! Run with `cargo run --release --example constrained_790 [-- --quiet]`.

use rapier_touch::prelude::*;
use rapier_touch::scenes::{diverged, Fig7Organ, COMPARED_INTEGRATORS as INTEGRATORS};
use std::time::{Duration, Instant};

#[path = "common/progress.rs"]
mod progress;

const DT: Real = Fig7Organ::DT;
const STEPS: usize = 600; // 10 s
const SAMPLE_EVERY: usize = 150; // t = 0, 2.5, 5, 7.5, 10 s
const MASS: Real = Fig7Organ::MASS;
const K: Real = Fig7Organ::K;
const C: Real = Fig7Organ::C;

const EXACT: usize = 1;
const NEIGHBOUR: usize = 2;
const BARAFF_WITKIN: usize = 3;

fn main() {
    let organ = Fig7Organ::new();
    let (planar, polyline, groups) = (&organ.planar, &organ.polyline, &organ.groups);
    let n = planar.mesh.num_vertices();
    let mut surfaces: Vec<MassSpringSurface> = INTEGRATORS
        .iter()
        .map(|&(_, integrator)| organ.surface(integrator))
        .collect();
    assert!(!surfaces[NEIGHBOUR].filter_fallback());
    let s_free: Vec<Real> = surfaces[EXACT]
        .s_values()
        .into_iter()
        .filter(|&s| s > 0.0)
        .collect();
    println!(
        "Fig. 7 organ: {n} nodes, {} triangles, {} outer-boundary vertices free, {} polyline \
         vertices pinned",
        planar.mesh.num_triangles(),
        planar.boundary.len(),
        polyline.len()
    );
    println!(
        "k = {K} N/m, c = {C} N*s/m, {MASS} kg per vertex, dt = 1/60 s; mean s {:.3}, max s \
         {:.3}, neighbour error bound {:.3}",
        s_free.iter().sum::<Real>() / s_free.len() as Real,
        s_free.iter().copied().fold(0.0, Real::max),
        surfaces[EXACT].neighbour_error_bound(1)
    );
    for (k, (g, ([u, v], profile))) in groups.iter().zip(Fig7Organ::forces()).enumerate() {
        println!(
            "force {}: {} vertices around ({u}, {v}): {profile:?}",
            k + 1,
            g.len()
        );
    }
    println!();

    let samples_per_run = STEPS / SAMPLE_EVERY + 1;
    let mut samples: Vec<Vec<Option<(Real, Real, f64)>>> =
        vec![Vec::with_capacity(samples_per_run); INTEGRATORS.len()];
    let mut max_rms: [Real; 4] = [0.0; 4];
    let mut max_disp: [Real; 4] = [0.0; 4];
    let mut diverged_at: [Option<Real>; 4] = [None; 4];
    let mut time = [Duration::ZERO; 4];
    let bar = progress::bar(STEPS as u64 + 1, "constrained_790");
    for step in 0..=STEPS {
        bar.inc(1);
        for (k, s) in surfaces.iter().enumerate() {
            // The constrained internal boundary never moves, whatever the integrator does.
            for &p in polyline {
                assert_eq!(
                    s.position(p),
                    s.home(p),
                    "{}: pinned vertex {p} moved at step {step}",
                    INTEGRATORS[k].0
                );
            }
            if diverged_at[k].is_none() && diverged(s) {
                diverged_at[k] = Some(step as Real * DT);
            }
            let state = diverged_at[k].is_none().then(|| {
                (
                    s.max_displacement(),
                    s.rms_difference(&surfaces[EXACT]),
                    s.total_energy(),
                )
            });
            if let Some((d, rms, _)) = state {
                max_rms[k] = max_rms[k].max(rms);
                max_disp[k] = max_disp[k].max(d);
            }
            if step % SAMPLE_EVERY == 0 {
                samples[k].push(state);
            }
        }
        if step < STEPS {
            for (k, s) in surfaces.iter_mut().enumerate() {
                let t0 = Instant::now();
                s.step();
                time[k] += t0.elapsed();
            }
        }
    }

    bar.finish_and_clear();
    println!(
        "{:<17} {:>5} {:>16} {:>18} {:>14}",
        "integrator", "t s", "max disp mm", "RMS vs exact mm", "energy J"
    );
    for ((name, _), run) in INTEGRATORS.iter().zip(&samples) {
        for (k, sample) in run.iter().enumerate() {
            let t = (k * SAMPLE_EVERY) as Real * DT;
            match sample {
                Some((d, rms, e)) => println!(
                    "{name:<17} {t:>5.1} {:>16.4} {:>18.3e} {e:>14.4e}",
                    d * 1000.0,
                    rms * 1000.0
                ),
                None => println!(
                    "{name:<17} {t:>5.1} {:>16} {:>18} {:>14}",
                    "diverged", "-", "-"
                ),
            }
        }
    }
    for (k, (name, _)) in INTEGRATORS.iter().enumerate() {
        let us = time[k].as_secs_f64() * 1e6 / STEPS as f64;
        match diverged_at[k] {
            Some(t) => println!("{name:<17} diverged at t = {t:.3} s; {us:.0} us/step"),
            None => println!(
                "{name:<17} max RMS vs exact over the run {:.3e} mm = {:.3} % of the exact run's \
                 max displacement; {us:.0} us/step",
                max_rms[k] * 1000.0,
                100.0 * max_rms[k] / max_disp[EXACT],
            ),
        }
    }

    // Physics checks (the pins were checked at every step above).
    assert!(max_disp[EXACT] > 0.0, "the forces deform the organ");
    for k in [EXACT, NEIGHBOUR, BARAFF_WITKIN] {
        assert!(
            diverged_at[k].is_none() && surfaces[k].is_finite(),
            "{} stays finite",
            INTEGRATORS[k].0
        );
        assert!(
            max_disp[k] <= 2.0 * max_disp[EXACT],
            "{} stays bounded",
            INTEGRATORS[k].0
        );
    }
    assert!(
        max_rms[NEIGHBOUR] <= 0.01 * max_disp[EXACT],
        "the neighbour filter stays close to the exact one ({} m)",
        max_rms[NEIGHBOUR]
    );
    assert!(
        max_rms[BARAFF_WITKIN] <= 1e-4 * max_disp[EXACT],
        "Baraff-Witkin with linear springs is the exact implicit step"
    );
}
