//! One full soft-surface step (spring and damper forces plus the integrator) per node count and
//! integrator: plates of about 100, 790, 3000, 10,000 and 20,000 nodes (square grids), pinned
//! on one edge, stiffness 50 N/m, damping 0.01 N·s/m, 10 g per node, dt = 1/1000 s (a haptic
//! rate): s = dt²Σk/m + dtΣc/m ≈ 0.036, the regime where the neighbour filter is accurate (and
//! explicit Euler still stable, so it can be timed too). The setup asserts every state is still
//! finite after the warm-up steps, so no timing is of a diverged (skipped) step. Targets (one core): neighbour filter 790 nodes ≤ 20 µs and 10k ≤ 250 µs; exact
//! prefactored filter 790 ≤ 60 µs and 10k ≤ 1 ms.
//!
//! Run with `cargo bench --bench soft_step`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use rapier_touch::prelude::*;
use rapier_touch::surface::meshing::plate;
use std::time::Duration;

fn surface(side: u32, integrator: Integrator) -> MassSpringSurface {
    let mesh = plate(1.0, 1.0, side, side);
    let pinned: Vec<u32> = (0..=side).collect(); // the x = -0.5 edge
    let mut s = MassSpringSurfaceBuilder::new(mesh.vertices, mesh.triangles)
        .stiffness(50.0)
        .damping(0.01)
        .mass(MassDistribution::PerVertex(0.01))
        .pinned(pinned)
        .gravity(Vector::new(0.0, -9.81, 0.0))
        .dt(1.0 / 1000.0)
        .integrator(integrator)
        .neighbour_max_error(f32::INFINITY)
        .build()
        .expect("valid plate");
    let centre = (side / 2) * (side + 1) + side / 2;
    s.set_force(centre, Vector::new(0.0, -0.5, 0.0)).unwrap();
    s
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("soft_step");
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    // (nodes - 1)^(1/2) cells per side: 100, 784, 3025, 10000, 19881 nodes.
    for side in [9u32, 27, 54, 99, 140] {
        let nodes = (side + 1) * (side + 1);
        for (name, integrator) in [
            ("explicit", Integrator::ExplicitEuler),
            ("neighbour", Integrator::NEIGHBOUR),
            ("exact", Integrator::EXACT),
            ("baraff_witkin", Integrator::BARAFF_WITKIN),
        ] {
            let mut s = surface(side, integrator);
            for _ in 0..50 {
                s.step();
            }
            assert!(
                s.is_finite() && s.max_displacement() > 0.0,
                "{name} {nodes}"
            );
            g.bench_with_input(BenchmarkId::new(name, nodes), &nodes, |b, _| {
                b.iter(|| s.step())
            });
            assert!(s.is_finite(), "{name} {nodes} diverged while timed");
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
