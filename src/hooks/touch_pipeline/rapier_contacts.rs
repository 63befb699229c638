//! What the step guard reads from rapier's narrow phase: its contact points of a pair at the
//! step's poses, its contact normal, whether a body rests on something fixed, and how deep a
//! body resting on something fixed may sit (the pile rule).

use super::*;

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
}

/// The [`RapierContact`] of `pair`, `None` when rapier's manifolds hold no contact point for
/// it. `*_prev` are the colliders' poses at the start of the step.
pub(super) fn rapier_contact_of(
    pair: &rapier3d::geometry::ContactPair,
    partner: ColliderHandle,
    (partner_pose, partner_prev): (&Pose, &Pose),
    (mover_pose, mover_prev): (&Pose, &Pose),
    touch: Real,
) -> Option<RapierContact> {
    let partner_first = pair.collider1 == partner;
    let ((pos1, prev1), (pos2, prev2)) = if partner_first {
        ((partner_pose, partner_prev), (mover_pose, mover_prev))
    } else {
        ((mover_pose, mover_prev), (partner_pose, partner_prev))
    };
    let mut in_contact_at_start = false;
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
    })
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
