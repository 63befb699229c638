//! How the step guard applies one correction: the moving body goes back to first touch (its
//! share of the way when the partner is dynamic too), and the velocity that still closes on
//! the partner is taken off, as a plastic impact would.

use super::rapier_contacts::supported;
use super::*;
use crate::geometry::ContactConfiguration;

/// Whether `config` walks its body back almost the whole step (its first touch in the first
/// tenth of the step): a blocked motion.
pub(super) fn undone_almost_whole(config: &ContactConfiguration) -> bool {
    config.time_of_impact.is_some_and(|t| t < 0.1)
}

/// The normal of `config`'s first contact patch, turned to the side the moving body came
/// from (an open mesh's triangle normal may face either side); `None` without a patch.
pub(super) fn normal_toward_mover(config: &ContactConfiguration) -> Option<Vector> {
    let p = config.patches.first()?;
    Some(if p.normal.dot(config.reversing_vector) < 0.0 {
        -p.normal
    } else {
        p.normal
    })
}

/// Moves body `bh` (its collider's offset `co_rel`, the collider's pose now `pose_now`) by the
/// correction `config` against collider `ph` (on body `partner_body`), and removes the
/// velocity into the partner. Returns the partner's body when it took a share of the way.
pub(super) fn apply_correction(
    world: &mut PhysicsWorld,
    config: &ContactConfiguration,
    (bh, co_rel, pose_now): (RigidBodyHandle, Option<Pose>, &Pose),
    (ph, partner_body): (ColliderHandle, Option<RigidBodyHandle>),
) -> Option<RigidBodyHandle> {
    let r = config.reversing_vector;
    // (A translation keeps the current orientation exactly.)
    let turned = config.touch_pose.rotation != pose_now.rotation;
    // The contact normal, out of the partner toward this body, turned to the side the body came
    // from (an open mesh's triangle normal may face either side). A configuration with no patch
    // (a path that overlaps from its very start, undone whole) is blocked along the way back:
    // that is its normal. Left without one, its velocity was never removed: eight cubes of the
    // CCD scene lay frozen on the floor for hundreds of steps, walked back whole every step
    // while gravity grew their speed to 36 m/s.
    let blocked = undone_almost_whole(config);
    let n = normal_toward_mover(config).or_else(|| r.try_normalize().filter(|_| blocked));
    // Split the correction by inverse mass when the partner is dynamic too, unless the partner
    // rests on a fixed or kinematic collider: its share would push it into what supports it
    // (seen: a thin dynamic plate pushed 2.25 mm into the floor under it). The moving body then
    // takes it all, walked back along its own path as in the paper.
    let partner_mass = partner_body
        .and_then(|pb| world.bodies.get(pb))
        .filter(|b| b.is_dynamic())
        .filter(|_| !supported(world, ph))
        .map(|b| b.mass());
    let own_mass = world.bodies.get(bh).map_or(1.0, |b| b.mass());
    let share = match partner_mass {
        Some(mp) if mp > 0.0 && own_mass > 0.0 => (1.0 / own_mass) / (1.0 / own_mass + 1.0 / mp),
        _ => 1.0,
    };
    // The velocity into the partner, relative to it: removed as a plastic impact along the
    // normal would, shared as the correction is (momentum conserved). Left as it was, it kept
    // driving a body the guard held at first touch, and whatever rested on it, deeper every
    // step.
    let partner_v = partner_body
        .and_then(|pb| world.bodies.get(pb))
        .map_or(Vector::ZERO, |b| b.linvel());
    // A step undone almost whole (first touch right where it began) is a blocked motion: what
    // still closes along the way back goes too (a body sliding into a concave corner of a
    // TriMesh had velocity tangent to the patch normal, and the guard held it there for good).
    let closing = n.and_then(|n| {
        let b = world.bodies.get(bh)?;
        let vrel = b.linvel() - partner_v;
        let mut dv = n * vrel.dot(n).min(0.0);
        if let Some(back) = r.try_normalize().filter(|_| blocked) {
            dv += back * (vrel - dv).dot(back).min(0.0);
        }
        (dv != Vector::ZERO && dv.is_finite()).then_some(dv)
    });
    if let Some(b) = world.bodies.get_mut(bh) {
        if turned {
            // A rotating path: the body goes to its pose at first touch (its share of the way
            // when the partner moves too).
            let rel = co_rel.unwrap_or(Pose::IDENTITY);
            let target = config.touch_pose * rel.inverse();
            let now = *b.position();
            let p = Pose::from_parts(
                now.translation.lerp(target.translation, share),
                now.rotation.slerp(target.rotation, share),
            );
            if p.is_finite() {
                b.set_position(p, true);
            }
        } else {
            let t = b.translation() + r * share;
            if t.is_finite() {
                b.set_translation(t, true);
            }
        }
        if let (Some(dv), true) = (closing, b.is_dynamic()) {
            b.set_linvel(b.linvel() - dv * share, true);
        }
    }
    let pb = partner_body.filter(|_| share < 1.0)?;
    if let Some(b) = world.bodies.get_mut(pb) {
        let t = b.translation() - r * (1.0 - share);
        if t.is_finite() {
            b.set_translation(t, true);
        }
        if let Some(dv) = closing {
            b.set_linvel(b.linvel() + dv * (1.0 - share), true);
        }
    }
    Some(pb)
}
