//! Step overhead of the touch pipeline: 100 dynamic boxes (never sleeping) resting on a fixed
//! TriMesh floor, one `step` of vanilla rapier (`PhysicsWorld::step`, no hooks) against one
//! `TouchPipeline::step` (hooks opted in, step guard, reports), in the same run. The ratio
//! touch / rapier is the overhead. Run with `cargo bench --bench step_overhead`.

use criterion::{criterion_group, criterion_main, Criterion};
use rapier_touch::prelude::*;
use rapier_touch::scenes::boxes_on_trimesh_floor;
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("step_100_boxes_trimesh_floor");
    g.sample_size(30)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));

    let mut world = boxes_on_trimesh_floor(100, false);
    for _ in 0..60 {
        world.step();
    }
    g.bench_function("rapier", |b| b.iter(|| world.step()));

    // Vanilla rapier with the hook flags set (and no-op hooks): rapier never recycles the
    // contacts of a pair with active hooks, so part of the overhead is rapier's own.
    let mut world = boxes_on_trimesh_floor(100, true);
    for _ in 0..60 {
        world.step();
    }
    g.bench_function("rapier_hook_flags", |b| b.iter(|| world.step()));

    let mut world = boxes_on_trimesh_floor(100, true);
    let mut touch = TouchPipeline::default();
    for _ in 0..60 {
        touch.step(&mut world);
    }
    g.bench_function("touch", |b| b.iter(|| touch.step(&mut world)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
