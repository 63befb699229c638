//! Step overhead of the touch pipeline: 100 dynamic boxes (never sleeping) resting on a fixed
//! TriMesh floor, in the same run:
//! - `rapier`: vanilla `PhysicsWorld::step`, no hooks;
//! - `rapier_hook_flags`: vanilla step with `ActiveHooks::MODIFY_SOLVER_CONTACTS` set on every
//!   collider (rapier then never recycles their contacts: rapier's own cost of hooks);
//! - `touch_hooks`: `TouchPipeline::step` with the hook flags (hooks, guard, reports);
//! - `touch_tracked`: `TouchPipeline::step` with the colliders tracked instead (guard and
//!   reports, no rapier hooks).
//!
//! After criterion's medians (each function timed over its own stretch of the machine's time),
//! the bench prints the four sides' ratios to vanilla timed interleaved: every side steps
//! `BLOCK` steps in turn, the first side changing at every round, and a side's time is its
//! fastest round (on a machine whose speed drifts by tens of percent over seconds, criterion's
//! sequential medians moved the ratios by ±0.2 between runs).
//!
//! Run with `cargo bench --bench step_overhead`.

use criterion::{criterion_group, criterion_main, Criterion};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::PhysicsWorld;
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
    interleaved();
}

/// Steps each side takes per round of the interleaved timing.
const BLOCK: usize = 20;
/// Rounds of the interleaved timing.
const ROUNDS: usize = 30;

/// The four sides timed in turn, `BLOCK` steps each per round; prints each side's fastest
/// round per step and its ratio to vanilla's.
fn interleaved() {
    let names = [
        "rapier",
        "rapier_hook_flags",
        "touch_hooks",
        "touch_tracked",
    ];
    let mut sides: Vec<(PhysicsWorld, Option<TouchPipeline>)> = (0..names.len())
        .map(|i| {
            let mut world = boxes_on_trimesh_floor(100, i == 1 || i == 2);
            let mut touch = (i >= 2).then(TouchPipeline::default);
            if i == 3 {
                let handles: Vec<_> = world.colliders.iter().map(|(h, _)| h).collect();
                for h in handles {
                    touch.as_mut().unwrap().track_collider(h);
                }
            }
            for _ in 0..60 {
                match touch.as_mut() {
                    Some(t) => t.step(&mut world),
                    None => world.step(),
                }
            }
            (world, touch)
        })
        .collect();
    let mut best = vec![f64::INFINITY; sides.len()];
    for round in 0..ROUNDS {
        for k in 0..sides.len() {
            let i = (k + round) % sides.len();
            let (world, touch) = &mut sides[i];
            let t0 = std::time::Instant::now();
            for _ in 0..BLOCK {
                match touch.as_mut() {
                    Some(t) => t.step(world),
                    None => world.step(),
                }
            }
            best[i] = best[i].min(t0.elapsed().as_secs_f64() / BLOCK as f64);
        }
    }
    println!("interleaved ({ROUNDS} rounds of {BLOCK} steps, fastest round):");
    for (name, t) in names.iter().zip(&best) {
        println!("  {name:<18} {:8.1} µs  {:.3}x", t * 1e6, t / best[0]);
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
