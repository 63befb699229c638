//! The paper's Table II: how much of the exact global filter `W = S⁻¹ M` (eq. 8) sits on a
//! vertex and its immediate (edge) neighbours, and how far the paper's immediate-neighbour
//! filter is from the exact one.
//!
//! **Meshes** (no pins, 1 kg on every vertex, the paper's linear spring model):
//! - 8 nodes: `box_surface(Vector::splat(0.5), 1)`, a closed cube, 12 triangles, 18 edges
//!   (the 12 cube edges and one diagonal per face);
//! - 112 nodes: `plate(0.07, 0.13, 7, 13)`, an 8 × 14 vertex grid, 10 mm cells;
//! - 512 nodes: `plate(0.15, 0.31, 15, 31)`, a 16 × 32 vertex grid;
//! - 738 nodes: `plate(0.17, 0.40, 17, 40)`, an 18 × 41 vertex grid.
//!
//! Plates split their cells along alternating diagonals, so interior vertices have 4 or 8
//! neighbours (6 on average, as in a Delaunay mesh). With linear springs `W` depends only on
//! the connectivity, not on the geometry.
//!
//! **Parameters.** The paper gives none. `W` depends on them only through the per-edge ratio
//! `(dt² k + dt c)/m`, i.e. on the paper's `s = (dt² Σk + dt Σc)/m` per vertex. The table uses
//! k = 48 N/m, c = 0.2 N·s/m, m = 1 kg, dt = 1/60 s: `dt² k + dt c = 1/60` per edge, so
//! `s = 0.1` at a vertex with 6 edges (mean s 0.075 on the box, 0.087-0.095 on the plates,
//! whose boundary vertices have fewer edges). That is the regime `K dt² + C dt < I` the paper
//! assumes for its simplification. The sweep shows that the paper's non-neighbour sums
//! (0.006, 0.002, 0.0017) correspond to a mean s of about 0.11 down to 0.06 on these meshes.
//!
//! **Columns** (per mesh, averages over the rows `i` of `W`):
//! - neighbour weight sum: `w_ii + Σ_{j ~ i} w_ij` (the vertex itself plus its edge
//!   neighbours);
//! - non-neighbour weight sum: `Σ` of the other `w_ij` (every row of `W` sums to 1 with no pins
//!   and uniform masses, so the two add up to 1);
//! - max_rel_error_neighbour_filter: one step from rest under a seeded pseudo-random force field
//!   (1 N scale per component, SplitMix64 of the vertex index), with `Integrator::EXACT` and with
//!   `Integrator::NEIGHBOUR` (the paper's first-order Neumann filter, with the crate's rigid-motion
//!   correction; `neighbour_max_error(f32::INFINITY)` so it never falls back to the exact one):
//!   `max_i |Δv_nb,i − Δv_exact,i| / max_i |Δv_exact,i|`.
//!
//! Then a sweep of the mean s from 0.01 to 100 on the 512-node mesh, scaling k and c together
//! (dt and m fixed), with the same columns.
//!
//! Checks (asserts): each row of `W` sums to 1 within 1e-9; the exact step equals
//! `Δv = W M⁻¹ dt F` computed from the dense `W` (within 1e-5 of the largest Δv); the
//! neighbour weight sum is above 0.99 on the three plates; in the sweep it decreases and the
//! neighbour filter's error increases as s grows.
//!
//! A progress bar on stderr counts the measurements (`--quiet` hides it).
//!
//! Run with `cargo run --release --example table2 [-- --csv] [--quiet]`. With `--csv` it prints only
//! `nodes,s,neighbour_weight_sum,non_neighbour_weight_sum,max_rel_error_neighbour_filter` and
//! one row per measurement (the four table rows, then the nine sweep rows).

use rapier_touch::prelude::*;
use rapier_touch::surface::meshing::{box_surface, plate, SurfaceMesh};

#[path = "common/progress.rs"]
mod progress;

const K: Real = 48.0;
const C: Real = 0.2;
const MASS: Real = 1.0;
const DT: Real = 1.0 / 60.0;

/// One measurement on one mesh.
struct Measure {
    nodes: usize,
    s_mean: f64,
    s_max: f64,
    neighbour_sum: f64,
    non_neighbour_sum: f64,
    min_neighbour_sum: f64,
    max_row_sum_error: f64,
    max_rel_error: f64,
    error_bound: f64,
}

/// SplitMix64 of `i`, mapped to [-1, 1).
fn hash_unit(i: u64) -> f32 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    ((z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) as f32
}

/// The seeded force field: about 1 N per component.
fn force(i: u32) -> Vector {
    let i = i as u64;
    Vector::new(hash_unit(3 * i), hash_unit(3 * i + 1), hash_unit(3 * i + 2))
}

fn surface(mesh: &SurfaceMesh, k: Real, c: Real, integrator: Integrator) -> MassSpringSurface {
    MassSpringSurfaceBuilder::new(mesh.vertices.clone(), mesh.triangles.clone())
        .stiffness(k)
        .damping(c)
        .mass(MassDistribution::PerVertex(MASS))
        .dt(DT)
        .integrator(integrator)
        .neighbour_max_error(Real::INFINITY)
        .build()
        .expect("valid mesh and parameters")
}

/// Δv of one step from rest under the seeded force field.
fn one_step_dv(mesh: &SurfaceMesh, k: Real, c: Real, integrator: Integrator) -> Vec<[f64; 3]> {
    let mut s = surface(mesh, k, c, integrator);
    assert!(!s.filter_fallback());
    for i in 0..s.num_vertices() as u32 {
        s.set_force(i, force(i)).expect("finite force");
    }
    s.step();
    (0..s.num_vertices() as u32)
        .map(|i| {
            let v = s.velocity(i);
            [v.x as f64, v.y as f64, v.z as f64]
        })
        .collect()
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

fn measure(mesh: &SurfaceMesh, k: Real, c: Real) -> Measure {
    let exact = surface(mesh, k, c, Integrator::EXACT);
    let n = exact.num_vertices();
    let (free, w) = exact.dense_filter().expect("S is positive definite");
    assert_eq!(free.len(), n, "no pins: every vertex is free");
    let mut adjacent = vec![Vec::new(); n];
    for &[a, b] in exact.edges() {
        adjacent[a as usize].push(b as usize);
        adjacent[b as usize].push(a as usize);
    }
    let (mut nb_total, mut non_total, mut min_nb, mut row_err) = (0.0, 0.0, f64::MAX, 0.0f64);
    for (i, row) in w.iter().enumerate() {
        let total: f64 = row.iter().sum();
        let nb = row[i] + adjacent[i].iter().map(|&j| row[j]).sum::<f64>();
        nb_total += nb;
        non_total += total - nb;
        min_nb = f64::min(min_nb, nb);
        row_err = row_err.max((total - 1.0).abs());
    }
    let s: Vec<f64> = exact.s_values().iter().map(|&x| x as f64).collect();

    // One step, exact and neighbour filter.
    let dv_exact = one_step_dv(mesh, k, c, Integrator::EXACT);
    let dv_nb = one_step_dv(mesh, k, c, Integrator::NEIGHBOUR);
    // The exact step must be eq. (8) with the dense W: Δv = W dt F / m (from rest).
    let scale = dv_exact.iter().map(|&d| norm(d)).fold(0.0, f64::max);
    for (i, row) in w.iter().enumerate() {
        let mut want = [0.0; 3];
        for (j, wij) in row.iter().enumerate() {
            let f = force(j as u32);
            for (d, fd) in [f.x, f.y, f.z].into_iter().enumerate() {
                want[d] += wij * fd as f64 * (DT as f64 / MASS as f64);
            }
        }
        let diff = [0, 1, 2].map(|d| want[d] - dv_exact[i][d]);
        assert!(
            norm(diff) <= 1e-5 * scale,
            "{n} nodes: exact step differs from W M⁻¹ dt F at vertex {i}"
        );
    }
    let max_diff = dv_exact
        .iter()
        .zip(&dv_nb)
        .map(|(a, b)| norm([a[0] - b[0], a[1] - b[1], a[2] - b[2]]))
        .fold(0.0, f64::max);
    Measure {
        nodes: n,
        s_mean: s.iter().sum::<f64>() / n as f64,
        s_max: s.iter().cloned().fold(0.0, f64::max),
        neighbour_sum: nb_total / n as f64,
        non_neighbour_sum: non_total / n as f64,
        min_neighbour_sum: min_nb,
        max_row_sum_error: row_err,
        max_rel_error: max_diff / scale,
        error_bound: exact.neighbour_error_bound(1) as f64,
    }
}

fn csv_row(m: &Measure) -> String {
    format!(
        "{},{:.4},{:.6},{:.6},{:.6e}",
        m.nodes, m.s_mean, m.neighbour_sum, m.non_neighbour_sum, m.max_rel_error
    )
}

fn main() {
    let csv = std::env::args().any(|a| a == "--csv");
    let meshes: [(&str, SurfaceMesh, &str, &str); 4] = [
        (
            "box_surface(0.5, 1)",
            box_surface(Vector::splat(0.5), 1),
            "0.0",
            "0.0",
        ),
        (
            "plate(7 x 13 cells)",
            plate(0.07, 0.13, 7, 13),
            "0.994",
            "0.006",
        ),
        (
            "plate(15 x 31 cells)",
            plate(0.15, 0.31, 15, 31),
            "0.998",
            "0.002",
        ),
        (
            "plate(17 x 40 cells)",
            plate(0.17, 0.40, 17, 40),
            "0.9983",
            "0.0017",
        ),
    ];
    let targets = [0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0];
    let bar = progress::bar((meshes.len() + targets.len()) as u64, "table2");
    let table: Vec<Measure> = meshes
        .iter()
        .map(|(_, m, _, _)| {
            let measured = measure(m, K, C);
            bar.inc(1);
            measured
        })
        .collect();
    for (m, want) in table.iter().zip([8, 112, 512, 738]) {
        assert_eq!(m.nodes, want, "mesh node count");
    }

    // The sweep: scale k and c so that the mean s of the 512-node mesh hits each target.
    let mesh512 = &meshes[2].1;
    let base_s = table[2].s_mean;
    let sweep: Vec<Measure> = targets
        .iter()
        .map(|&t| {
            let scale = (t / base_s) as Real;
            bar.set_message(format!("sweep s = {t}"));
            let measured = measure(mesh512, K * scale, C * scale);
            bar.inc(1);
            measured
        })
        .collect();
    bar.finish_and_clear();

    if csv {
        println!(
            "nodes,s,neighbour_weight_sum,non_neighbour_weight_sum,max_rel_error_neighbour_filter"
        );
        for m in table.iter().chain(&sweep) {
            println!("{}", csv_row(m));
        }
    } else {
        println!("Table II: weight sums of the exact filter W = S^-1 M (averages over rows)");
        println!(
            "k = {K} N/m, c = {C} N*s/m, m = {MASS} kg per vertex, dt = 1/60 s, no pins, \
             linear springs"
        );
        println!(
            "{:<22} {:>5} {:>7} {:>7} {:>10} {:>7} {:>11} {:>7} {:>10} {:>13} {:>9}",
            "mesh",
            "nodes",
            "mean s",
            "max s",
            "nb sum",
            "paper",
            "non-nb sum",
            "paper",
            "min nb sum",
            "nb filter err",
            "bound"
        );
        for ((name, _, p_nb, p_non), m) in meshes.iter().zip(&table) {
            println!(
                "{:<22} {:>5} {:>7.4} {:>7.4} {:>10.6} {:>7} {:>11.6} {:>7} {:>10.6} {:>13.3e} {:>9.3e}",
                name,
                m.nodes,
                m.s_mean,
                m.s_max,
                m.neighbour_sum,
                p_nb,
                m.non_neighbour_sum,
                p_non,
                m.min_neighbour_sum,
                m.max_rel_error,
                m.error_bound
            );
        }
        println!();
        println!(
            "Sweep on the 512-node plate: k and c scaled together (k/c = {}), m and dt fixed",
            K / C
        );
        println!(
            "{:>8} {:>9} {:>9} {:>10} {:>11} {:>10} {:>13} {:>9}",
            "mean s",
            "max s",
            "k N/m",
            "nb sum",
            "non-nb sum",
            "min nb sum",
            "nb filter err",
            "bound"
        );
        for (m, &t) in sweep.iter().zip(&targets) {
            println!(
                "{:>8.3} {:>9.3} {:>9.2} {:>10.6} {:>11.6} {:>10.6} {:>13.3e} {:>9.3e}",
                m.s_mean,
                m.s_max,
                K as f64 * t / base_s,
                m.neighbour_sum,
                m.non_neighbour_sum,
                m.min_neighbour_sum,
                m.max_rel_error,
                m.error_bound
            );
        }
        println!();
        println!(
            "nb filter err = max_i |dv_neighbour - dv_exact| / max_i |dv_exact|, one step from \
             rest, seeded force field; bound = max_i (s_i/(1+s_i))^2"
        );
    }

    // Physics checks.
    for m in table.iter().chain(&sweep) {
        assert!(
            m.max_row_sum_error <= 1e-9,
            "{} nodes, s = {}: a row of W sums to 1 ± {}",
            m.nodes,
            m.s_mean,
            m.max_row_sum_error
        );
        assert!(m.neighbour_sum > 0.0 && m.neighbour_sum <= 1.0 + 1e-9);
        assert!(m.max_rel_error.is_finite());
    }
    for pair in sweep.windows(2) {
        assert!(
            pair[1].neighbour_sum < pair[0].neighbour_sum,
            "the neighbour weight sum decreases as s grows ({} -> {})",
            pair[0].neighbour_sum,
            pair[1].neighbour_sum
        );
        assert!(
            pair[1].max_rel_error > pair[0].max_rel_error,
            "the neighbour filter's error grows with s (s = {}: {}, s = {}: {})",
            pair[0].s_mean,
            pair[0].max_rel_error,
            pair[1].s_mean,
            pair[1].max_rel_error
        );
    }
    // In the paper's regime (s about 0.1) the neighbours carry nearly all the weight.
    for m in &table[1..] {
        assert!(m.neighbour_sum > 0.99, "{} nodes", m.nodes);
    }
}
