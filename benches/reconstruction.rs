//! Contact reconstruction on the four pairs of the paper's Table I
//! ([`rapier_touch::scenes::table1_scenes`]), against the narrow-phase work rapier itself does
//! for the same TriMesh pair at the same pose (parry's contact manifolds).
//!
//! Run with `cargo bench --bench reconstruction`. Groups:
//! - `reconstruction`: [`Reconstructor::reconstruct`] with a warmed-up reconstructor (scratch
//!   memory already sized): `reconstruct` with the default options, and for the convex pairs
//!   `general_search` with the convex path switched off
//!   ([`ReconstructionOptions::convex_fast_path`]);
//! - `parry_manifolds`: `PersistentQueryDispatcher::contact_manifolds` between the two
//!   TriMeshes with rapier's default prediction distance, `cold` (fresh manifold vector and
//!   workspace each call: a pair's first frame) and `warm` (both kept between calls, as rapier
//!   keeps them for a persistent pair).

use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion};
use parry3d::query::{ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher};
use rapier_touch::prelude::*;
use rapier_touch::scenes::{table1_scenes, Table1Scene};
use std::hint::black_box;
use std::time::Duration;

/// rapier 0.36's default `IntegrationParameters::prediction_distance()`:
/// `normalized_prediction_distance` (0.02) times `length_unit` (1). The narrow phase passes it
/// (plus the colliders' contact skins, zero by default) to `contact_manifolds`.
fn rapier_prediction() -> Real {
    rapier_touch::rapier3d::dynamics::IntegrationParameters::default().prediction_distance()
}

type Manifolds = Vec<ContactManifold<(), ()>>;

/// One call of the narrow-phase query rapier makes for a rigid TriMesh pair.
fn parry_manifolds(
    s: &Table1Scene,
    prediction: Real,
    manifolds: &mut Manifolds,
    workspace: &mut Option<parry3d::query::ContactManifoldsWorkspace>,
) {
    let pos12 = s.fixed_pose.inv_mul(&s.pose);
    DefaultQueryDispatcher
        .contact_manifolds(
            &pos12,
            s.fixed.trimesh(),
            s.moving.trimesh(),
            prediction,
            manifolds,
            workspace,
        )
        .expect("TriMesh-TriMesh manifolds are supported");
}

fn label(s: &Table1Scene) -> String {
    format!(
        "{}_{}e_{}v",
        s.name, s.known.colliding_edges, s.known.colliding_vertices
    )
}

/// Benchmarks [`Reconstructor::reconstruct`] on one scene, after a warm-up query that sizes the
/// scratch memory.
fn bench_reconstruct(
    group: &mut BenchmarkGroup<'_, WallTime>,
    id: &str,
    options: ReconstructionOptions,
    s: &Table1Scene,
) {
    let mut rec = Reconstructor::new(options);
    rec.reconstruct(&s.fixed, &s.fixed_pose, &s.moving, &s.pose, &s.prev_pose)
        .expect("finite poses");
    group.bench_with_input(BenchmarkId::new(id, label(s)), s, |b, s| {
        b.iter(|| {
            rec.reconstruct(
                black_box(&s.fixed),
                black_box(&s.fixed_pose),
                black_box(&s.moving),
                black_box(&s.pose),
                black_box(&s.prev_pose),
            )
        })
    });
}

fn bench(c: &mut Criterion) {
    let scenes = table1_scenes();
    let prediction = rapier_prediction();

    // Print what each scene reconstructs to once, so odd results show up next to the timings.
    for s in &scenes {
        let mut rec = Reconstructor::default();
        let cc = rec
            .reconstruct(&s.fixed, &s.fixed_pose, &s.moving, &s.pose, &s.prev_pose)
            .expect("finite poses");
        let (mut manifolds, mut ws) = (Manifolds::new(), None);
        parry_manifolds(s, prediction, &mut manifolds, &mut ws);
        let points: usize = manifolds.iter().map(|m| m.points.len()).sum();
        let deepest = manifolds
            .iter()
            .flat_map(|m| m.points.iter())
            .map(|p| p.dist)
            .fold(Real::INFINITY, Real::min);
        eprintln!(
            "{}: {} colliding edges / {} vertices (paper {}/{}), {} + {} triangles; \
             state {:?}, depth {:.6}, time of impact {:?}, {} patch(es) {:?}, {} candidate pairs; \
             parry: {} manifolds, {} points, deepest {:.6} (prediction {})",
            s.name,
            s.known.colliding_edges,
            s.known.colliding_vertices,
            s.known.paper_edges,
            s.known.paper_vertices,
            s.fixed.num_triangles(),
            s.moving.num_triangles(),
            cc.state,
            cc.depth,
            cc.time_of_impact,
            cc.patches.len(),
            cc.patches
                .iter()
                .map(|p| (p.kind, p.points.len()))
                .collect::<Vec<_>>(),
            cc.candidate_pairs,
            manifolds.len(),
            points,
            deepest,
            prediction,
        );
    }

    let mut group = c.benchmark_group("reconstruction");
    group
        .sample_size(30)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    for s in &scenes {
        bench_reconstruct(
            &mut group,
            "reconstruct",
            ReconstructionOptions::default(),
            s,
        );
        // The general branch-and-bound search on the same pair, for the convex pairs that the
        // default takes through the convex path.
        if s.fixed.is_convex() && s.moving.is_convex() {
            let general = ReconstructionOptions {
                convex_fast_path: false,
                ..Default::default()
            };
            bench_reconstruct(&mut group, "general_search", general, s);
        }
    }
    group.finish();

    let mut group = c.benchmark_group("parry_manifolds");
    group
        .sample_size(30)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    for s in &scenes {
        group.bench_with_input(BenchmarkId::new("cold", label(s)), s, |b, s| {
            b.iter(|| {
                let (mut manifolds, mut ws) = (Manifolds::new(), None);
                parry_manifolds(black_box(s), prediction, &mut manifolds, &mut ws);
                manifolds
            })
        });
        let (mut manifolds, mut ws) = (Manifolds::new(), None);
        group.bench_with_input(BenchmarkId::new("warm", label(s)), s, |b, s| {
            b.iter(|| {
                parry_manifolds(black_box(s), prediction, &mut manifolds, &mut ws);
                manifolds.len()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
