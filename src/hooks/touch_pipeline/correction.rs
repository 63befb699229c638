//! How the step guard applies one correction: the moving body goes back to first touch (its
//! share of the way when the partner is dynamic too), and the velocity that still closes on
//! the partner is taken off, as a plastic impact would.

use super::articulations::multibody_link;
use super::pair_view::PairState;
use super::rapier_contacts::{collider_pose_now, supported};
use super::*;
use crate::geometry::ContactConfiguration;

impl<H: PhysicsHooks> TouchPipeline<H> {
    /// Counts a correction of collider `ch` against collider `ph`, and records the pair as
    /// touching at the poses the correction left.
    pub(super) fn record_correction(
        &mut self,
        world: &PhysicsWorld,
        ch: ColliderHandle,
        ph: ColliderHandle,
    ) {
        self.corrections += 1;
        let (Some(partner), Some(co)) = (world.colliders.get(ph), world.colliders.get(ch)) else {
            return;
        };
        let partner_pose = collider_pose_now(&world.bodies, partner);
        let pose = collider_pose_now(&world.bodies, co);
        self.pair_states
            .insert((ch, ph), PairState::new(0.0, &pose, &partner_pose));
    }
}

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
    // (Nor is a multibody's link moved: rapier computes its pose from the multibody's joint
    // coordinates, `movers`.)
    let partner_mass = partner_body
        .filter(|pb| !multibody_link(world, *pb))
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
                // The spin that turned the body into the partner, as far as it still closes at
                // the contact (a body rolling on its partner closes nothing there and keeps
                // its spin). Left, it turned the body in again at every step and the guard
                // turned it back: a cube held so on the TriMesh stress scene's floor spun up
                // from 2.8 to 7.5 rad/s at one pose while a ball, whose contact with it rapier
                // solved against that spinning surface, fell 1 m into it (hook side, gravity
                // × (1 - 1e-5)).
                let back = (p.rotation * now.rotation.inverse()).to_scaled_axis();
                if let (Some(axis), Some(n), Some(patch)) =
                    (back.try_normalize(), n, config.patches.first())
                {
                    stop_turn_at(b, patch.center(), n, -axis, partner_v);
                }
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

/// Takes off what body `b`'s spin about `forward` (the axis of the turn the guard just walked
/// back) closes on a partner moving at `partner_v` along `n` at the point `at`, no more than
/// that spin: the spin is reduced, never reversed, the velocity kept. A body rolling on its
/// partner closes nothing at its contact and keeps its spin.
fn stop_turn_at(
    b: &mut rapier3d::dynamics::RigidBody,
    at: Vector,
    n: Vector,
    forward: Vector,
    partner_v: Vector,
) {
    let com = b.mass_properties().world_com;
    let n = if (com - at).dot(n) < 0.0 { -n } else { n };
    let closing = (b.velocity_at_point(at) - partner_v).dot(n);
    let w = b.angvel();
    let spin = w.dot(forward);
    // How much the point's normal velocity changes per unit of spin about `forward`.
    let lever = forward.cross(at - com).dot(n);
    if !(closing < 0.0 && spin > 0.0 && lever < 0.0) {
        return;
    }
    let less = (closing / lever).min(spin);
    if less.is_finite() && less > 0.0 {
        b.set_angvel(w - forward * less, true);
    }
}

#[cfg(test)]
mod tests {
    use super::stop_turn_at;
    use crate::math::{Real, Vector};
    use rapier3d::prelude::*;

    /// A body of `shape` at rest height `y`, moving at `v` and spinning at `w`, in a set (its
    /// mass properties computed).
    fn body(shape: SharedShape, y: Real, v: Vector, w: Vector) -> (RigidBodySet, RigidBodyHandle) {
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let h = bodies.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, y, 0.0))
                .linvel(v)
                .angvel(w),
        );
        colliders.insert_with_parent(ColliderBuilder::new(shape).density(1.0), h, &mut bodies);
        (bodies, h)
    }

    /// A cube on a floor (normal +y), turning about z so that its corner at (-1, -1) goes
    /// down: the spin that closes at the corner goes, exactly as far as the corner stops
    /// closing (its normal velocity, from the body's own velocity at that point, is zero), and
    /// the spin is reduced, not reversed. A ball rolling without slipping (its contact point
    /// still) keeps its spin, and so does a cube whose turn lifts the corner.
    #[test]
    fn the_spin_closing_at_the_contact_goes_and_rolling_keeps_its_spin() {
        let corner = Vector::new(-1.0, 0.0, 0.0);
        let (mut bodies, h) = body(
            SharedShape::cuboid(1.0, 1.0, 1.0),
            1.0,
            Vector::new(0.3, 0.0, 0.0),
            Vector::new(0.0, 0.0, 4.0),
        );
        let b = &mut bodies[h];
        assert!(
            b.velocity_at_point(corner).y < -1.0,
            "the corner closes before"
        );
        stop_turn_at(b, corner, Vector::Y, Vector::Z, Vector::ZERO);
        let after = b.velocity_at_point(corner).y;
        assert!(after.abs() < 1e-5, "the corner still closes at {after} m/s");
        let w = b.angvel();
        assert!(w.z >= 0.0 && w.z < 4.0, "spin {w:?}");
        assert_eq!(
            b.linvel(),
            Vector::new(0.3, 0.0, 0.0),
            "the velocity is kept"
        );

        // The same turn lifting the corner: nothing closes, nothing goes.
        let (mut bodies, h) = body(
            SharedShape::cuboid(1.0, 1.0, 1.0),
            1.0,
            Vector::ZERO,
            Vector::new(0.0, 0.0, -4.0),
        );
        stop_turn_at(&mut bodies[h], corner, Vector::Y, Vector::Z, Vector::ZERO);
        assert_eq!(bodies[h].angvel(), Vector::new(0.0, 0.0, -4.0));

        // A ball of radius 1 rolling along x: its contact point at the origin is still.
        let (mut bodies, h) = body(
            SharedShape::ball(1.0),
            1.0,
            Vector::new(2.0, 0.0, 0.0),
            Vector::new(0.0, 0.0, -2.0),
        );
        let at = Vector::ZERO;
        assert!(bodies[h].velocity_at_point(at).length() < 1e-6);
        stop_turn_at(&mut bodies[h], at, Vector::Y, -Vector::Z, Vector::ZERO);
        assert_eq!(bodies[h].angvel(), Vector::new(0.0, 0.0, -2.0));
    }

    /// The same corner at sizes from 0.1 mm to 10 km (the corner's closing speed taken off to
    /// a relative 1e-5 of what it was), and bad input: a NaN normal, point or spin, or a zero
    /// axis, changes nothing and puts no NaN into the velocity.
    #[test]
    fn the_corner_stops_at_every_scale_and_bad_input_changes_nothing() {
        for scale in [1e-4f32, 1.0, 1e4] {
            let corner = Vector::new(-scale, 0.0, 0.0);
            let (mut bodies, h) = body(
                SharedShape::cuboid(scale, scale, scale),
                scale,
                Vector::ZERO,
                Vector::new(0.0, 0.0, 4.0),
            );
            let before = bodies[h].velocity_at_point(corner).y;
            stop_turn_at(&mut bodies[h], corner, Vector::Y, Vector::Z, Vector::ZERO);
            let after = bodies[h].velocity_at_point(corner).y;
            assert!(
                before < 0.0 && after.abs() <= 1e-5 * before.abs(),
                "scale {scale}: {before} -> {after}"
            );
        }
        let corner = Vector::new(-1.0, 0.0, 0.0);
        let spin = Vector::new(0.0, 0.0, 4.0);
        for (at, n, forward) in [
            (corner, Vector::NAN, Vector::Z),
            (Vector::NAN, Vector::Y, Vector::Z),
            (corner, Vector::Y, Vector::NAN),
            (corner, Vector::Y, Vector::ZERO),
        ] {
            let (mut bodies, h) = body(SharedShape::cuboid(1.0, 1.0, 1.0), 1.0, Vector::ZERO, spin);
            stop_turn_at(&mut bodies[h], at, n, forward, Vector::ZERO);
            assert_eq!(bodies[h].angvel(), spin, "{at} {n} {forward}");
            assert_eq!(bodies[h].linvel(), Vector::ZERO);
        }
        let (mut bodies, h) = body(
            SharedShape::cuboid(1.0, 1.0, 1.0),
            1.0,
            Vector::ZERO,
            Vector::splat(Real::NAN),
        );
        stop_turn_at(&mut bodies[h], corner, Vector::Y, Vector::Z, Vector::ZERO);
        assert!(bodies[h].linvel().is_finite());
    }
}
