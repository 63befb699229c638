//! What the step guard reads from rapier's narrow phase: its contact points of a pair at the
//! step's poses (and the rotation they were computed at, for a manifold rapier recycled), how
//! far a turn may have brought the mover past them (`corner_reach`), its contact normal,
//! whether a body rests on something fixed, and how deep a body resting on something fixed may
//! sit (the pile rule).

use super::*;
use crate::math::{Matrix, Rotation};

/// Whether collider `c` has a contact with a fixed or kinematic collider in rapier's narrow
/// phase (a body resting on the floor).
pub(super) fn supported(world: &PhysicsWorld, c: ColliderHandle) -> bool {
    world.narrow_phase.contact_pairs_with(c).any(|p| {
        p.has_any_active_contact() && on_dynamic_body(world, other_of(p, c)) == Some(false)
    })
}

/// The collider of contact pair `p` that is not `c`.
pub(super) fn other_of(p: &rapier3d::geometry::ContactPair, c: ColliderHandle) -> ColliderHandle {
    if p.collider1 == c {
        p.collider2
    } else {
        p.collider1
    }
}

/// Whether collider `h` is on a dynamic body (`Some(false)` with no body, or a fixed or
/// kinematic one); `None` for a collider not in the world.
fn on_dynamic_body(world: &PhysicsWorld, h: ColliderHandle) -> Option<bool> {
    let co = world.colliders.get(h)?;
    Some(
        co.parent()
            .and_then(|b| world.bodies.get(b))
            .is_some_and(|b| b.is_dynamic()),
    )
}

/// The least resting slop of a body that rests in a pile on a convex floor, in resting slops
/// ([`TouchOptions::resting_slop`]): 9 mm at the default, above the 6.5 mm rapier's soft
/// contacts let the two lowest planks of its plank tower overlap.
const PILE_SLOP: Real = 10.0;

/// The most of the smaller extent of a body and its floor that the pile rule lets the body
/// rest in the floor: its centre stays above the floor's surface, and it never pokes through
/// the floor.
const PILE_SLOP_OF_EXTENT: Real = 0.4;

/// The overlap tolerated for collider `c` (of a body that moved `d` over the step) resting on
/// the fixed or kinematic `partner` before the guard pushes it back. A still body in a pile,
/// resting on a convex floor, rests in it as deep as rapier lets the pile's own contacts sink
/// (the deepest of its contacts with the pile, at least [`PILE_SLOP`] resting slops): held
/// harder against the floor than its neighbours hold each other, the bottom of a pile was
/// pushed out each step into the body above, and the pile's compression went there (rapier's
/// plank tower: 11.4 mm between the two lowest planks against 6.5 mm in vanilla rapier). Not
/// on a TriMesh or other composite floor: rapier's contacts there let a loaded body sink
/// through internal edges (its TriMesh stress scene went to 0.9 m), and a body that moves is
/// not resting. Otherwise [`TouchOptions::resting_slop`]. `extent`: the smaller of the
/// smallest extents of the body's collider and of `partner`.
pub(super) fn resting_slop(
    options: &TouchOptions,
    world: &PhysicsWorld,
    (c, extent): (ColliderHandle, Real),
    partner: &rapier3d::geometry::Collider,
    d: Vector,
) -> Real {
    if d.length() > options.resting_slop || !partner.shape().is_convex() {
        return options.resting_slop;
    }
    match pile_depth(world, c) {
        Some(pile) => (PILE_SLOP * options.resting_slop)
            .max(pile)
            .min(PILE_SLOP_OF_EXTENT * extent)
            .max(options.resting_slop),
        None => options.resting_slop,
    }
}

/// The deepest overlap rapier's manifolds hold between collider `c` and the dynamic colliders
/// it has an active contact with (it carries a pile, or rests in one), as its narrow phase
/// last saw them; `None` when it touches no dynamic collider.
fn pile_depth(world: &PhysicsWorld, c: ColliderHandle) -> Option<Real> {
    let mut deepest: Option<Real> = None;
    for p in world.narrow_phase.contact_pairs_with(c) {
        if !(on_dynamic_body(world, other_of(p, c)) == Some(true) && p.has_any_active_contact()) {
            continue;
        }
        let d = p
            .manifolds()
            .iter()
            .flat_map(|m| m.points.iter())
            .map(|pt| -pt.dist)
            .filter(|d| d.is_finite())
            .fold(0.0, Real::max);
        deepest = Some(deepest.map_or(d, |x: Real| x.max(d)));
    }
    deepest
}

/// Where collider `co` is now: its body's pose times its offset (the guard moves bodies; their
/// colliders follow only when it syncs them after its passes).
pub(super) fn collider_pose_now(
    bodies: &rapier3d::dynamics::RigidBodySet,
    co: &rapier3d::geometry::Collider,
) -> Pose {
    match (
        co.parent().and_then(|pb| bodies.get(pb)),
        co.position_wrt_parent(),
    ) {
        (Some(b), Some(rel)) => *b.position() * *rel,
        _ => *co.position(),
    }
}

/// rapier's contact manifold of a pair, read at the step's poses: the deepest of its contact
/// points at the poses now and rapier's normal there (out of `partner` toward `mover`), and
/// whether the pair was in contact at the start of the step (a point overlapping, or closer
/// than `touch`: a body the guard left at first touch is in contact, and walking it back to a
/// first touch at the very start of the next step would undo that whole step, freezing a
/// rolling or sliding body in place). The points are local to the colliders,
/// so they are re-read at any pose as rapier's solver does; a recycled manifold (rapier keeps
/// a pair's points while its relative pose drifts little) is read the same way.
#[derive(Copy, Clone, Debug)]
pub(super) struct RapierContact {
    pub(super) depth: Real,
    pub(super) depth_at_start: Real,
    pub(super) normal: Vector,
    pub(super) in_contact_at_start: bool,
    /// The point deepest when the step began, on the mover, local to its collider.
    pub(super) deepest_at_start: Vector,
    /// The mover collider's rotation at the narrow-phase update that computed the manifolds,
    /// where the manifolds show it ([`body_rotation_at_update`]); `None` where they do not.
    /// rapier recycles a pair's manifolds while the pair moves little (up to 5 cm and about
    /// 11° at its defaults), and a turn since the update brings corners down that they do not
    /// hold: a 46 cm box settling across a tile seam, 4° of tilt after its manifold was
    /// computed, read 0.5 mm apart at rapier's points with an edge 1.47 mm in.
    pub(super) rotation_at_update: Option<Rotation>,
}

/// The [`RapierContact`] of `pair`, `None` when rapier's manifolds hold no contact point for
/// it. `*_prev` are the colliders' poses at the start of the step.
pub(super) fn rapier_contact_of(
    pair: &rapier3d::geometry::ContactPair,
    partner: ColliderHandle,
    (partner_pose, partner_prev): (&Pose, &Pose),
    (mover_pose, mover_prev, mover_offset): (&Pose, &Pose, Rotation),
    touch: Real,
) -> Option<RapierContact> {
    let partner_first = pair.collider1 == partner;
    let ((pos1, prev1), (pos2, prev2)) = if partner_first {
        ((partner_pose, partner_prev), (mover_pose, mover_prev))
    } else {
        ((mover_pose, mover_prev), (partner_pose, partner_prev))
    };
    let mut in_contact_at_start = false;
    let mut rotation_at_update: Option<Rotation> = None;
    let mut deepest: Option<(Real, Vector)> = None;
    // The deepest overlap when the step began and the mover's point there.
    let mut deepest_at_start: Option<(Real, Vector)> = None;
    for m in pair.manifolds() {
        if m.points.is_empty() {
            continue;
        }
        // The manifold's frames (a composite shape's part) at the poses now and at the start.
        let frames = |a: &Pose, b: &Pose| {
            let w1 = m.subshape_pos1().map_or(*a, |s| *a * *s);
            let w2 = m.subshape_pos2().map_or(*b, |s| *b * *s);
            (w1, w2, w1.rotation * m.local_n1)
        };
        let (w1, w2, n1) = frames(pos1, pos2);
        let (v1, v2, m1) = frames(prev1, prev2);
        if rotation_at_update.is_none() {
            rotation_at_update =
                body_rotation_at_update(m, !partner_first).map(|r| r * mover_offset);
        }
        for p in &m.points {
            // Signed distances along collider 1's normal.
            let before = (v2.transform_point(p.local_p2) - v1.transform_point(p.local_p1)).dot(m1);
            in_contact_at_start |= before < touch;
            // (A NaN best gives way, as `max` ignores NaN.)
            if deepest_at_start.is_none_or(|(best, _)| -before > best || best.is_nan()) {
                let on_mover = if partner_first {
                    m.subshape_pos2()
                        .map_or(p.local_p2, |s| s.transform_point(p.local_p2))
                } else {
                    m.subshape_pos1()
                        .map_or(p.local_p1, |s| s.transform_point(p.local_p1))
                };
                deepest_at_start = Some((-before, on_mover));
            }
            let now = (w2.transform_point(p.local_p2) - w1.transform_point(p.local_p1)).dot(n1);
            if deepest.is_none_or(|(best, _)| -now > best) {
                deepest = Some((-now, n1));
            }
        }
    }
    let (depth, n1) = deepest?;
    let normal = if partner_first { n1 } else { -n1 }.try_normalize()?;
    depth.is_finite().then_some(RapierContact {
        depth,
        depth_at_start: deepest_at_start.map_or(0.0, |(d, _)| d.max(0.0)),
        normal,
        in_contact_at_start,
        deepest_at_start: deepest_at_start.map_or(Vector::ZERO, |(_, p)| p),
        rotation_at_update,
    })
}

/// The rotation of body `first` (collider 1's when `true`, else collider 2's) of manifold `m`
/// at rapier's last full update of the manifold, from its solver contacts; `None` where fewer
/// than two of them hold an arm of this side in the body's frame, or their arms are nearly
/// parallel.
///
/// At a full update rapier keeps each solver contact's lever arm in world space
/// (`ContactData::solver_dp1`, `solver_dp2`: from the body's centre of mass to the midpoint of
/// the contact's two anchors) and its anchor in the body's frame (`SolverContact::anchor1`,
/// `anchor2`), and keeps both while it recycles the pair. The body's rotation then carried
/// each anchor onto its arm (less half the contact's distance along the normal: the arm ends
/// at the midpoint); two anchors that are not parallel fix that rotation (the TRIAD method).
/// rapier keeps a dominant side's anchors (a fixed body's) in world space: `None` for those.
fn body_rotation_at_update(
    m: &rapier3d::geometry::ContactManifold,
    first: bool,
) -> Option<Rotation> {
    let data = &m.data;
    let local = if first {
        data.rigid_body1.is_some() && data.relative_dominance <= 0
    } else {
        data.rigid_body2.is_some() && data.relative_dominance >= 0
    };
    if !local {
        return None;
    }
    // (body frame, world) pairs of anchor and arm.
    let pairs = || {
        data.solver_contacts.iter().filter_map(|sc| {
            let [id] = sc.contact_indices();
            let point = m.points.get(id as usize)?;
            let (anchor, arm) = if first {
                (sc.anchor1, point.data.solver_dp1)
            } else {
                (sc.anchor2, point.data.solver_dp2)
            };
            // The arm runs to the midpoint of the anchors: body 2's anchor lies half the
            // contact's distance beyond it along the normal, body 1's as far short of it.
            let half = 0.5 * sc.dist * data.normal;
            let arm = if first { arm - half } else { arm + half };
            (anchor.is_finite() && arm.is_finite()).then_some((anchor, arm))
        })
    };
    let (u1, w1) = pairs().max_by(|a, b| a.0.length_squared().total_cmp(&b.0.length_squared()))?;
    let (u2, w2) = pairs().max_by(|a, b| {
        u1.cross(a.0)
            .length_squared()
            .total_cmp(&u1.cross(b.0).length_squared())
    })?;
    // Well apart: the sine between the two anchors at least a tenth.
    let (c, l) = (u1.cross(u2).length(), u1.length() * u2.length());
    if !(c > 0.1 * l && w1.cross(w2).length() > 0.1 * w1.length() * w2.length()) {
        return None;
    }
    let triad = |a: Vector, b: Vector| {
        let x = a.normalize();
        let y = a.cross(b).normalize();
        Matrix::from_cols(x, y, x.cross(y))
    };
    let r = triad(w1, w2) * triad(u1, u2).transpose();
    let q = Rotation::from_mat3(&r).normalize();
    q.is_finite().then_some(q)
}

/// How much deeper than rapier's contact points, re-read now, another point of the mover may
/// have come over the step, for a partner locally flat along rapier's normal `normal` (world,
/// out of the partner). rapier's manifold of two polyhedra holds the features deepest along
/// its normal when the step began, and a turn brings other corners down: an L-shaped TriMesh
/// rocking on a TriMesh floor read 8 µm above it at rapier's points and ended its step with
/// another corner 1.12 mm in.
///
/// `prev_pose` is the mover's pose when rapier computed the manifold: the step's start, or for
/// a manifold rapier recycled since, the rotation it shows it was computed at
/// (`RapierContact::rotation_at_update`).
///
/// In the partner's frame the mover turned from `R0` to `R1`: a mover point `u` got deeper
/// than the point `a` deepest at the start by `(a - u) · m`, `m = R1ᵀ n - R0ᵀ n` (the
/// translations cancel). The most is `a · m` less the mover's lowest vertex along `m`, one
/// support query. A turn about the normal (a box spinning flat on a floor) gives `m = 0`.
/// The partner's own turn is bounded by twice its arc, `partner_turn` (two of its points lie
/// at most twice its reach apart).
pub(super) fn corner_reach(
    mesh: &TouchMesh,
    a: Vector,
    (pose_now, prev_pose): (&Pose, &Pose),
    (partner_pose, partner_prev): (&Pose, &Pose),
    normal: Vector,
    partner_turn: Real,
) -> Real {
    let n = partner_pose.rotation.inverse() * normal;
    let r0 = (partner_prev.inverse() * *prev_pose).rotation;
    let r1 = (partner_pose.inverse() * *pose_now).rotation;
    let m = r1.inverse() * n - r0.inverse() * n;
    // The lowest vertex lies on the hull: hill climbing on a convex mesh, a pass over the
    // hull's vertices on another (over every vertex past the hull's size limit).
    let v = mesh.vertices();
    let lowest = match mesh.convex_support(-m, 0) {
        Some(i) => v[i as usize].dot(m),
        None => match mesh.hull_vertices() {
            Some(hull) => hull
                .iter()
                .map(|&i| v[i as usize].dot(m))
                .fold(Real::INFINITY, Real::min),
            None => v.iter().map(|p| p.dot(m)).fold(Real::INFINITY, Real::min),
        },
    };
    let reach = (a.dot(m) - lowest).max(0.0) + 2.0 * partner_turn;
    if reach.is_finite() {
        reach
    } else {
        Real::INFINITY
    }
}

/// rapier's contact normal for the pair (from its deepest contact), oriented out of `fixed`
/// toward `moving`.
pub(super) fn rapier_normal(
    world: &PhysicsWorld,
    fixed: ColliderHandle,
    moving: ColliderHandle,
) -> Option<Vector> {
    // Looked up from the mover's side: rapier scans the first collider's pairs.
    let pair = world.narrow_phase.contact_pair(moving, fixed)?;
    let (manifold, _) = pair.find_deepest_contact()?;
    let n = manifold.data.normal;
    let n = if pair.collider1 == fixed { n } else { -n };
    n.try_normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::dynamics::RigidBodyBuilder;
    use rapier3d::geometry::ColliderBuilder;

    /// A box resting on a frictionless floor, spinning about the vertical at 0.03 rad a step:
    /// rapier computes its manifold at the first step (at the tilt it was placed at) and
    /// recycles it at the second (the spin moved the pair's points up to 21 mm, under rapier's
    /// 5 cm). The rotation the manifold shows after each step is the tilt it was placed at (set
    /// here), within 1e-4 rad, not the box's rotation when the second step began, 0.03 rad
    /// from it.
    /// Placed again, turned 0.3 rad about the vertical (past rapier's 11°), rapier computes the
    /// manifold again, and it shows the new placement.
    #[test]
    fn a_recycled_manifold_shows_the_rotation_it_was_computed_at() {
        let mut world = PhysicsWorld {
            gravity: Vector::ZERO,
            ..Default::default()
        };
        let floor = world.insert_collider(
            ColliderBuilder::cuboid(0.5, 0.1, 0.5)
                .translation(Vector::new(0.2, -0.1, -0.1))
                .friction(0.0),
            None,
        );
        let body = world.insert_body(RigidBodyBuilder::dynamic());
        let co = world.insert_collider(
            ColliderBuilder::cuboid(0.3, 0.2, 0.25).friction(0.0),
            Some(body),
        );
        let spin = 0.03 / world.integration_parameters.dt;
        // The box at `tilt`, its lowest corner 0.5 mm into the floor's top (y = 0), spinning.
        let place = |world: &mut PhysicsWorld, tilt: Rotation| {
            let low = world.colliders[co]
                .shape()
                .compute_aabb(&Pose::from_rotation(tilt))
                .mins
                .y;
            let b = &mut world.bodies[body];
            b.set_position(
                Pose::from_parts(Vector::new(0.1, -low - 5e-4, 0.05), tilt),
                true,
            );
            b.set_linvel(Vector::ZERO, true);
            b.set_angvel(Vector::Y * spin, true);
        };
        let read = |world: &PhysicsWorld| {
            let pair = world.narrow_phase.contact_pair(co, floor).expect("a pair");
            let first = pair.collider1 == co;
            pair.manifolds()
                .iter()
                .find_map(|m| body_rotation_at_update(m, first))
                .expect("a rotation")
        };
        let tilt0 = Rotation::from_axis_angle(Vector::new(1.0, 0.0, 0.3).normalize(), 0.02);
        place(&mut world, tilt0);
        world.step();
        assert!(read(&world).angle_between(tilt0) < 1e-4);
        let before = *world.bodies[body].rotation();
        assert!(before.angle_between(tilt0) > 0.025, "the box spun");
        world.step();
        let at_update = read(&world);
        assert!(
            at_update.angle_between(tilt0) < 1e-4,
            "{} rad from the tilt the manifold was computed at",
            at_update.angle_between(tilt0)
        );
        let tilt1 = Rotation::from_rotation_y(0.3) * tilt0;
        place(&mut world, tilt1);
        world.step();
        assert!(read(&world).angle_between(tilt1) < 1e-4);
    }
}
