//! Runs of the stress scenes ([`super::stress`]): a side's mean step time, the deepest overlap
//! of any pair rapier solves, the bodies asleep and those through the floor.

use super::stress::{stress_world, StressScene, StressSide, StressWorld};
use crate::hooks::{TouchOptions, TouchPipeline};
use crate::math::{Real, Rotation, Vector};
use rapier3d::prelude::*;
use std::collections::HashSet;

/// What one run of a stress scene measured.
#[derive(Clone, Debug, PartialEq)]
pub struct StressRun {
    /// Dynamic bodies in the scene.
    pub bodies: usize,
    /// Mean wall-clock time of one step (ms), measurements excluded.
    pub ms_per_step: f64,
    /// The deepest overlap of any contact pair rapier solves, after any step (m), measured
    /// with parry's contact query on the colliders' poses.
    pub max_penetration: Real,
    /// Dynamic bodies asleep after the last step.
    pub asleep: usize,
    /// Dynamic bodies whose centre of mass went through the floor: above its surface at one
    /// step and below it at a later one, straight over the floor both times (a vertical ray
    /// cast on the floor's shape). A body flung off the floor's edge that falls past it is not
    /// counted (the CCD scene throws dozens over the edge).
    pub through_floor: usize,
}

/// Steps `scene` `steps` times with `side` and measures it.
pub fn run_stress(scene: StressScene, side: StressSide, steps: usize) -> StressRun {
    run_stress_with_gravity(scene, side, steps, 1.0)
}

/// [`run_stress`] with the scene's gravity scaled by `gravity_scale`. A pile's deepest
/// overlap is chaotic: scaling gravity by 1 ± 1e-6 moves vanilla rapier's pyramid between
/// 93.2 and 99.0 mm (its plank tower between 6.43 and 6.48 mm), so a comparison with vanilla
/// takes its spread over a few such runs.
pub fn run_stress_with_gravity(
    scene: StressScene,
    side: StressSide,
    steps: usize,
    gravity_scale: Real,
) -> StressRun {
    run_stress_with_options(scene, side, steps, gravity_scale, |_| {})
}

/// [`run_stress_with_gravity`] with the touch pipeline's options changed by `options` (unused
/// by vanilla rapier's side), such as [`TouchOptions::rewind_dynamic_impacts`] switched on.
pub fn run_stress_with_options(
    scene: StressScene,
    side: StressSide,
    steps: usize,
    gravity_scale: Real,
    options: impl FnOnce(&mut TouchOptions),
) -> StressRun {
    let mut runner = StressRunner::new(scene, side, gravity_scale, options);
    runner.step(steps);
    runner.finish()
}

/// One side's run of a stress scene, stepped a few steps at a time: several sides' runners
/// stepped in turn, a block of steps each, are timed over the same stretch of the machine's
/// time (the `stress_scenes` example; a noisy machine's speed drifts by tens of percent over
/// the seconds one side's whole run takes).
pub struct StressRunner {
    world: PhysicsWorld,
    floor: ColliderHandle,
    side: StressSide,
    touch: TouchPipeline,
    steps: usize,
    elapsed: std::time::Duration,
    max_penetration: Real,
    /// Bodies last seen straight above the floor's surface, and those seen below it after.
    above: HashSet<RigidBodyHandle>,
    through: HashSet<RigidBodyHandle>,
}

impl std::fmt::Debug for StressRunner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StressRunner")
            .field("side", &self.side)
            .field("steps", &self.steps)
            .field("elapsed", &self.elapsed)
            .finish_non_exhaustive()
    }
}

impl StressRunner {
    /// `scene` built for `side` (its touch meshes too: see [`StressSide::pipeline`]), gravity
    /// scaled by `gravity_scale`, the touch pipeline's options changed by `options`.
    pub fn new(
        scene: StressScene,
        side: StressSide,
        gravity_scale: Real,
        options: impl FnOnce(&mut TouchOptions),
    ) -> Self {
        let StressWorld { mut world, floor } = stress_world(scene);
        world.gravity *= gravity_scale;
        let mut touch = side.pipeline(&mut world);
        options(&mut touch.options);
        let above = world
            .bodies
            .iter()
            .filter(|(_, b)| b.is_dynamic())
            .filter(|(_, b)| floor_side(&world, floor, b.center_of_mass()) == Some(true))
            .map(|(h, _)| h)
            .collect();
        StressRunner {
            world,
            floor,
            side,
            touch,
            steps: 0,
            elapsed: std::time::Duration::ZERO,
            max_penetration: 0.0,
            above,
            through: HashSet::new(),
        }
    }

    /// `steps` more steps, each timed (the measurements after it are not).
    pub fn step(&mut self, steps: usize) {
        for _ in 0..steps {
            let t0 = std::time::Instant::now();
            self.side.step(&mut self.world, &mut self.touch);
            self.elapsed += t0.elapsed();
            self.steps += 1;
            let world = &self.world;
            self.max_penetration = self.max_penetration.max(deepest_solved_overlap(world));
            for (h, b) in world.bodies.iter().filter(|(_, b)| b.is_dynamic()) {
                match floor_side(world, self.floor, b.center_of_mass()) {
                    Some(true) => {
                        self.above.insert(h);
                    }
                    Some(false) if self.above.contains(&h) => {
                        self.through.insert(h);
                    }
                    _ => {}
                }
            }
        }
    }

    /// What the run measured so far.
    pub fn finish(&self) -> StressRun {
        let dynamic: Vec<&RigidBody> = self
            .world
            .bodies
            .iter()
            .map(|(_, b)| b)
            .filter(|b| b.is_dynamic())
            .collect();
        StressRun {
            bodies: dynamic.len(),
            ms_per_step: self.elapsed.as_secs_f64() * 1e3 / self.steps.max(1) as f64,
            max_penetration: self.max_penetration,
            asleep: dynamic.iter().filter(|b| b.is_sleeping()).count(),
            through_floor: self.through.len(),
        }
    }
}

/// The deepest overlap among the pairs rapier solves (a manifold with rigid impulses) on the
/// current collider poses. Against a cuboid floor it is the depth of the other shape's lowest
/// point (its support point along -y) below the floor's top, over the floor's extent: parry's
/// contact query is unreliable between a small box and a 200 m ground box (answers near a
/// metre were seen for a plate lying on it). Other pairs get parry's contact query.
pub fn deepest_solved_overlap(world: &PhysicsWorld) -> Real {
    let mut deepest: Real = 0.0;
    for pair in world.narrow_phase.contact_pairs() {
        let solved = pair.manifolds().iter().any(|m| {
            !m.points.is_empty()
                && m.data
                    .solver_flags
                    .contains(SolverFlags::COMPUTE_RIGID_IMPULSES)
        });
        if !solved {
            continue;
        }
        let (Some(c1), Some(c2)) = (
            world.colliders.get(pair.collider1),
            world.colliders.get(pair.collider2),
        ) else {
            continue;
        };
        let flat_floor = |floor: &Collider, other: &Collider| -> Option<Real> {
            let cuboid = floor.shape().as_cuboid()?;
            let fixed = floor
                .parent()
                .and_then(|h| world.bodies.get(h))
                .is_none_or(|b| b.is_fixed());
            let pose = floor.position();
            // Only an axis-aligned floor with its top face up.
            if !fixed || pose.rotation.angle_between(Rotation::IDENTITY) > 1e-6 {
                return None;
            }
            let top = pose.translation.y + cuboid.half_extents.y;
            let low = other
                .shape()
                .as_support_map()?
                .support_point(other.position(), -Vector::Y);
            let inside = (low.x - pose.translation.x).abs() <= cuboid.half_extents.x
                && (low.z - pose.translation.z).abs() <= cuboid.half_extents.z;
            Some(if inside { top - low.y } else { 0.0 })
        };
        let depth = flat_floor(c1, c2)
            .or_else(|| flat_floor(c2, c1))
            .or_else(|| {
                parry3d::query::contact(c1.position(), c1.shape(), c2.position(), c2.shape(), 0.0)
                    .ok()
                    .flatten()
                    .map(|c| -c.dist)
            });
        if let Some(d) = depth {
            deepest = deepest.max(d);
        }
    }
    deepest
}

/// Where `p` is against the floor's surface straight above or below it: `Some(true)` above,
/// `Some(false)` below, `None` off the floor's footprint.
fn floor_side(world: &PhysicsWorld, floor: ColliderHandle, p: Vector) -> Option<bool> {
    let co = world.colliders.get(floor)?;
    let top = co.compute_aabb().maxs.y;
    let ray = parry3d::query::Ray::new(Vector::new(p.x, top + 1.0, p.z), -Vector::Y);
    let t = co.shape().cast_ray(co.position(), &ray, Real::MAX, false)?;
    Some(p.y >= top + 1.0 - t)
}
