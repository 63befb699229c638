//! Which bodies the step guard looks at, and the pair states it forgets.

use super::articulations::multibody_link;
use super::*;

impl<H: PhysicsHooks> TouchPipeline<H> {
    /// Forgets the pair states of colliders that left the world, when there are twice as many
    /// as when they were last pruned (looking every step cost a sleeping pile as much as the
    /// rest of the guard).
    pub(super) fn prune_pair_states(&mut self, world: &PhysicsWorld) {
        if self.pair_states.len() > self.pair_states_pruned_at.max(64) * 2 {
            self.pair_states
                .retain(|(a, b), _| world.colliders.contains(*a) && world.colliders.contains(*b));
            self.pair_states_pruned_at = self.pair_states.len();
        }
        if self.pairs_read_at.len() > 2 * world.colliders.len().max(32) {
            self.pairs_read_at
                .retain(|c, _| world.colliders.contains(*c));
        }
    }

    /// The bodies the guard's first pass looks at: awake dynamic bodies and tools with a touch
    /// mesh. Not a multibody's links: rapier computes their poses from the multibody's joint
    /// coordinates at every step (its forward kinematics) and their velocities from its
    /// generalized velocities, so the guard's moves would be undone (a chain of four such links
    /// dropped on a plate, moved back every step, ended 23 % of its half-size in it, against
    /// vanilla rapier's 11 %). They are rapier's alone.
    pub(super) fn movers(&self, world: &PhysicsWorld) -> Vec<RigidBodyHandle> {
        world
            .bodies
            .iter()
            .filter(|(h, b)| {
                (b.is_dynamic() || self.tools.contains_key(h))
                    && !b.is_sleeping()
                    && !multibody_link(world, *h)
                    && b.colliders()
                        .iter()
                        .any(|c| self.hooks.meshes.contains_key(c))
            })
            .map(|(h, _)| h)
            .collect()
    }
}
