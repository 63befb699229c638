//! Poses in sync: after the guard moved bodies, their colliders and broad-phase boxes are
//! moved with them, so what renderers and the query pipeline read is the corrected pose.

use super::*;

/// Puts the colliders of the bodies the guard moved where their bodies now are, and their
/// broad-phase boxes with them, so renderers, ray casts and the query pipeline see the
/// corrected poses right after the step (rapier would only sync them at the next step).
pub(crate) fn sync_moved_colliders(world: &mut PhysicsWorld, moved: &mut Vec<RigidBodyHandle>) {
    if moved.is_empty() {
        return;
    }
    world
        .bodies
        .propagate_modified_body_positions_to_colliders(&mut world.colliders);
    moved.sort_unstable_by_key(|h| h.into_raw_parts());
    moved.dedup();
    let params = world.integration_parameters;
    for h in moved.iter() {
        let Some(body) = world.bodies.get(*h) else {
            continue;
        };
        for ch in body.colliders() {
            if let Some(co) = world.colliders.get(*ch) {
                if co.is_enabled() {
                    let aabb = co.compute_broad_phase_aabb(&params, &world.bodies);
                    if aabb.mins.is_finite() && aabb.maxs.is_finite() {
                        world.broad_phase.set_aabb(&params, *ch, aabb);
                    }
                }
            }
        }
    }
}
