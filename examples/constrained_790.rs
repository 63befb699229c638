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

use integrators::{print_runs, run_side_by_side, BARAFF_WITKIN, EXACT, NEIGHBOUR};
use rapier_touch::prelude::*;
use rapier_touch::scenes::{Fig7Organ, COMPARED_INTEGRATORS as INTEGRATORS};

#[path = "common/integrators.rs"]
mod integrators;
#[path = "common/progress.rs"]
mod progress;

const DT: Real = Fig7Organ::DT;
const STEPS: usize = 600; // 10 s
const SAMPLE_EVERY: usize = 150; // t = 0, 2.5, 5, 7.5, 10 s
const MASS: Real = Fig7Organ::MASS;
const K: Real = Fig7Organ::K;
const C: Real = Fig7Organ::C;

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

    let bar = progress::bar(STEPS as u64 + 1, "constrained_790");
    let runs = run_side_by_side(&mut surfaces, STEPS, DT, SAMPLE_EVERY, |step, surfaces| {
        bar.inc(1);
        // The constrained internal boundary never moves, whatever the integrator does.
        for (s, (name, _)) in surfaces.iter().zip(INTEGRATORS) {
            for &p in polyline {
                assert_eq!(
                    s.position(p),
                    s.home(p),
                    "{name}: pinned vertex {p} moved at step {step}"
                );
            }
        }
    });
    bar.finish_and_clear();
    print_runs(&runs, STEPS, DT, SAMPLE_EVERY);

    // Physics checks (the pins were checked at every step above).
    assert!(
        runs[EXACT].max_displacement > 0.0,
        "the forces deform the organ"
    );
    for k in [EXACT, NEIGHBOUR, BARAFF_WITKIN] {
        assert!(
            runs[k].diverged_at.is_none() && surfaces[k].is_finite(),
            "{} stays finite",
            INTEGRATORS[k].0
        );
        assert!(
            runs[k].max_displacement <= 2.0 * runs[EXACT].max_displacement,
            "{} stays bounded",
            INTEGRATORS[k].0
        );
    }
    assert!(
        runs[NEIGHBOUR].max_rms <= 0.01 * runs[EXACT].max_displacement,
        "the neighbour filter stays close to the exact one ({} m)",
        runs[NEIGHBOUR].max_rms
    );
    assert!(
        runs[BARAFF_WITKIN].max_rms <= 1e-4 * runs[EXACT].max_displacement,
        "Baraff-Witkin with linear springs is the exact implicit step"
    );
}
