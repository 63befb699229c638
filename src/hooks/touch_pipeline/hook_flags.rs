//! The hook flags [`TouchPipeline`] manages ([`TouchOptions::hook_flags_on_demand`]): raised
//! only on the colliders of bodies that moved farther than rapier's prediction distance and
//! whose pairs the hooks can rewrite, since rapier recomputes every hooked pair's contacts
//! every step.

use super::*;
use crate::hooks::step_motion::{collider_reach, point_travel};

impl<H: PhysicsHooks> TouchPipeline<H> {
    /// With [`TouchOptions::hook_flags_on_demand`]: raises the hook flag on the managed
    /// colliders whose body moved more than rapier's prediction distance (and the slop) over
    /// this step (translation plus the arc of its rotation) and whose pairs the hooks can
    /// rewrite, clears it on the others.
    ///
    /// While the guard corrects poses ([`TouchOptions::correct_poses`]), it puts every pair
    /// it sees deeper than the slop back to first touch, and the next step's hooks find
    /// nothing deep to rewrite (they rewrote nothing over 300 steps of five of rapier's six
    /// stress scenes): then only the bodies `unsettled` (moved by the guard's last pass, with
    /// no pass left to look at them again) get the flag.
    pub(super) fn sync_hook_flags(
        &mut self,
        world: &mut PhysicsWorld,
        unsettled: &HashSet<RigidBodyHandle>,
    ) {
        if !self.options.hook_flags_on_demand {
            return;
        }
        // A body that moved less than rapier's prediction distance met nothing rapier had not
        // already seen coming (its speculative contacts); the guard corrects the others, so the
        // hooks only matter for the fast ones.
        let slop = self
            .options
            .penetration_slop
            .max(world.integration_parameters.prediction_distance());
        for h in &self.hooked {
            let Some(co) = world.colliders.get(*h) else {
                continue;
            };
            // A collider whose pairs the hooks never rewrite (`TouchHooks::rewritable`: a ball,
            // a rounded shape, a TriMesh, a compound) gets no flag, and rapier does not
            // recompute its pairs every step for nothing (hook side of the stress scenes:
            // rounded hulls 1.47-1.49× -> 1.38-1.40× vanilla, ragdolls 1.17× -> 1.10-1.12×,
            // TriMesh floor 1.64× -> 1.59-1.60×).
            let moved = self.hooks.rewritable(&world.colliders, *h)
                && co.parent().is_some_and(|bh| {
                    if self.options.correct_poses && !unsettled.contains(&bh) {
                        return false;
                    }
                    match (world.bodies.get(bh), self.hooks.prev_poses.get(&bh)) {
                        // A body that did not move (a sleeping pile's) is not measured.
                        (Some(b), Some(prev)) if b.position() != prev => {
                            let reach = collider_reach(&self.hooks.meshes, *h, co);
                            point_travel(prev, b.position(), reach) > slop
                        }
                        _ => false,
                    }
                });
            let flags = co.active_hooks();
            let want = if moved {
                flags | ActiveHooks::MODIFY_SOLVER_CONTACTS
            } else {
                flags - ActiveHooks::MODIFY_SOLVER_CONTACTS
            };
            if want != flags {
                if let Some(co) = world.colliders.get_mut(*h) {
                    co.set_active_hooks(want);
                }
            }
        }
    }
}
