//! Step overhead of the touch pipeline: 100 dynamic boxes (never sleeping) resting on a fixed
//! TriMesh floor, in the same run:
//! - `rapier`: vanilla `PhysicsWorld::step`, no hooks;
//! - `rapier_hook_flags`: vanilla step with `ActiveHooks::MODIFY_SOLVER_CONTACTS` set on every
//!   collider (rapier then never recycles their contacts: rapier's own cost of hooks);
//! - `touch_hooks`: `TouchPipeline::step` with the hook flags (hooks, guard, reports);
//! - `touch_tracked`: `TouchPipeline::step` with the colliders tracked instead (guard and
//!   reports, no rapier hooks).
//!
//! Run with `cargo bench --bench step_overhead`.

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
    g.bench_function("touch_hooks", |b| b.iter(|| touch.step(&mut world)));

    // The step guard and reports without rapier hooks: colliders tracked by the pipeline.
    let mut world = boxes_on_trimesh_floor(100, false);
    let mut touch = TouchPipeline::default();
    let handles: Vec<_> = world.colliders.iter().map(|(h, _)| h).collect();
    for h in handles {
        touch.track_collider(h);
    }
    for _ in 0..60 {
        touch.step(&mut world);
    }
    g.bench_function("touch_tracked", |b| b.iter(|| touch.step(&mut world)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
