//! Articulated bodies in the step guard: rapier solves a body's joints together with its
//! contacts, so the guard moves a jointed body only where nothing else would stop it.
//!
//! - A link of an articulation held by impulse joints is corrected only where it may have
//!   passed through its partner, and never against another link of its own articulation.
//!   Moving one link alone, and stopping it, tears at its joints, which rapier's next step
//!   pulls back together with a kick.
//! - A multibody's links are never moved ([`TouchPipeline::movers`]): rapier computes their
//!   poses from the multibody's joint coordinates at every step.

use super::*;

/// The most bodies [`same_articulation`] walks through before it gives up (answers `false`):
/// a ragdoll has ten, a rope or a chain bridge may have hundreds.
const MAX_LINKS: usize = 256;

/// Whether dynamic body `bh` is held by an impulse joint.
pub(super) fn articulated(world: &PhysicsWorld, bh: RigidBodyHandle) -> bool {
    world.bodies.get(bh).is_some_and(|b| b.is_dynamic())
        && world.impulse_joints.attached_joints(bh).next().is_some()
}

/// Whether body `bh` is a multibody's link, whose pose rapier computes from the multibody's
/// joint coordinates: the guard never moves it ([`TouchPipeline::movers`], and no share of a
/// correction).
pub(super) fn multibody_link(world: &PhysicsWorld, bh: RigidBodyHandle) -> bool {
    world.multibody_joints.rigid_body_link(bh).is_some()
}

/// Whether bodies `a` and `b` are joined through a path of impulse joints (within
/// [`MAX_LINKS`] bodies of `a`).
pub(super) fn same_articulation(
    world: &PhysicsWorld,
    a: RigidBodyHandle,
    b: RigidBodyHandle,
) -> bool {
    let mut seen = vec![a];
    let mut next = 0;
    while next < seen.len() && seen.len() <= MAX_LINKS {
        let h = seen[next];
        next += 1;
        for (b1, b2, _, _) in world.impulse_joints.attached_joints(h) {
            for o in [b1, b2] {
                if o == b {
                    return true;
                }
                if !seen.contains(&o) {
                    seen.push(o);
                }
            }
        }
    }
    false
}
