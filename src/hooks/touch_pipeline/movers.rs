//! Which bodies the step guard looks at, and how far each may have travelled since a pair's
//! contact was last measured (the odometers that let calm pairs go unmeasured).

use super::*;
use crate::hooks::step_motion::{collider_reach, point_travel};

impl<H: PhysicsHooks> TouchPipeline<H> {
    /// Advances the odometers (the distance every point of each moving body may have
    /// travelled) by this step's motion, and forgets the bodies and pairs that left the world.
    pub(super) fn advance_odometers(&mut self, world: &PhysicsWorld) {
        for (h, b) in world.bodies.iter() {
            // A fixed body, or one that did not move (a sleeping pile), adds nothing: its
            // colliders' reach is not worth computing (a third of a sleeping pyramid's
            // guard time went to it).
            if b.is_fixed() {
                continue;
            }
            let Some(prev) = self.hooks.prev_poses.get(&h) else {
                continue;
            };
            let pose = b.position();
            if pose == prev {
                continue;
            }
            let radius = b
                .colliders()
                .iter()
                .filter_map(|c| Some((*c, world.colliders.get(*c)?)))
                .map(|(c, co)| collider_reach(&self.hooks.meshes, c, co))
                .fold(0.0, Real::max);
            let step = point_travel(prev, pose, radius);
            if step > 0.0 && step.is_finite() {
                *self.odometers.entry(h).or_insert(0.0) += step;
            }
        }
        // Forgets what left the world, when something did (looking every step cost a
        // sleeping pile as much as the rest of the guard).
        if self.odometers.len() > world.bodies.len() {
            self.odometers.retain(|h, _| world.bodies.contains(*h));
        }
        if self.pair_states.len() > self.pair_states_pruned_at.max(64) * 2 {
            self.pair_states
                .retain(|(a, b), _| world.colliders.contains(*a) && world.colliders.contains(*b));
            self.pair_states_pruned_at = self.pair_states.len();
        }
    }

    /// The bodies the guard's first pass looks at: awake dynamic bodies and tools with a touch
    /// mesh.
    pub(super) fn movers(&self, world: &PhysicsWorld) -> Vec<RigidBodyHandle> {
        world
            .bodies
            .iter()
            .filter(|(h, b)| {
                (b.is_dynamic() || self.tools.contains_key(h))
                    && !b.is_sleeping()
                    && b.colliders()
                        .iter()
                        .any(|c| self.hooks.meshes.contains_key(c))
            })
            .map(|(h, _)| h)
            .collect()
    }
}
