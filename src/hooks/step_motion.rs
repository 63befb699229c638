//! How far colliders moved over the step: the motion the hooks and the step guard read from
//! the pose history ([`super::pose_history`]), and how far a collider's points reach from its
//! body's origin (the arc a turn sweeps).

use super::pose_history::PoseHistory;
use super::touch_hooks::CachedMesh;
use crate::geometry::{RigidMotion, TouchMesh};
use crate::math::{Pose, Vector};
use parry3d::utils::hashmap::HashMap;
use rapier3d::dynamics::{RigidBodyHandle, RigidBodySet};
use rapier3d::geometry::{ColliderHandle, ColliderSet};

pub(crate) use crate::geometry::shape_reach;

/// How far a point of collider `co` (handle `h`) can be from its body's origin: the offset to
/// its parent plus its shape's reach (a turn by `θ` moves it by at most `θ` times this). The
/// reach is read from the collider's touch mesh in `meshes` when it has one.
pub(crate) fn collider_reach(
    meshes: &HashMap<ColliderHandle, CachedMesh>,
    h: ColliderHandle,
    co: &rapier3d::geometry::Collider,
) -> crate::math::Real {
    co.position_wrt_parent()
        .map_or(0.0, |p| p.translation.length())
        + meshes
            .get(&h)
            .map_or_else(|| shape_reach(co.shape()), |m| m.reach)
}

/// How far a point `reach` from a body's origin can have moved when the body went from
/// `prev` to `now`: the translation plus the arc of the rotation.
pub(crate) fn point_travel(prev: &Pose, now: &Pose, reach: crate::math::Real) -> crate::math::Real {
    (now.translation - prev.translation).length()
        + prev.rotation.angle_between(now.rotation) * reach
}

/// The motion of a body over the last step (zero without history).
pub(crate) fn body_motion(
    prev_poses: &PoseHistory,
    bodies: &RigidBodySet,
    body: Option<RigidBodyHandle>,
) -> Vector {
    body.and_then(|h| Some(bodies.get(h)?.translation() - prev_poses.get(&h)?.translation))
        .filter(|d| d.is_finite())
        .unwrap_or(Vector::ZERO)
}

/// An upper bound on how far any point of collider `c2` moved relative to collider `c1` over
/// the last step: both bodies' translations plus the arcs of their rotations (infinite when
/// a pose is not finite).
pub(crate) fn relative_travel(
    meshes: &HashMap<ColliderHandle, CachedMesh>,
    prev_poses: &PoseHistory,
    bodies: &RigidBodySet,
    colliders: &ColliderSet,
    c1: ColliderHandle,
    c2: ColliderHandle,
) -> crate::math::Real {
    let arc = |c: ColliderHandle| -> (Vector, crate::math::Real) {
        let Some(co) = colliders.get(c) else {
            return (Vector::ZERO, 0.0);
        };
        let Some((body, prev)) = co
            .parent()
            .and_then(|h| Some((bodies.get(h)?, prev_poses.get(&h)?)))
        else {
            return (Vector::ZERO, 0.0);
        };
        let now = body.position();
        let reach = collider_reach(meshes, c, co);
        (
            now.translation - prev.translation,
            prev.rotation.angle_between(now.rotation) * reach,
        )
    };
    let ((d1, a1), (d2, a2)) = (arc(c1), arc(c2));
    let t = (d2 - d1).length() + a1 + a2;
    if t.is_finite() {
        t
    } else {
        crate::math::Real::INFINITY
    }
}

/// Where collider `c` was at the start of the step: its body's recorded pose times the
/// collider's offset, or `pos` (its pose now) when the body has no history or it has no body.
pub(crate) fn previous_collider_pose(
    prev_poses: &PoseHistory,
    co: &rapier3d::geometry::Collider,
    pos: Pose,
) -> Pose {
    co.parent()
        .and_then(|b| prev_poses.get(&b))
        .filter(|p| p.is_finite())
        .map_or(pos, |p| match co.position_wrt_parent() {
            Some(rel) => *p * *rel,
            None => *p,
        })
}

/// The motion of collider 2 relative to collider 1 over the last step, with collider 1 held
/// at `pos1`: collider 2 starts where it was relative to collider 1 at the start of the step,
/// ends at `pos2`, and turns about its body's centre of mass (the bounding-box centre of its
/// mesh when the body has no mass).
pub(crate) fn relative_motion(
    prev_poses: &PoseHistory,
    bodies: &RigidBodySet,
    co1: &rapier3d::geometry::Collider,
    pos1: Pose,
    co2: &rapier3d::geometry::Collider,
    pos2: Pose,
    mesh2: &TouchMesh,
) -> RigidMotion {
    let prev1 = previous_collider_pose(prev_poses, co1, pos1);
    let prev2 = previous_collider_pose(prev_poses, co2, pos2);
    let start = pos1 * (prev1.inverse() * prev2);
    let center = co2
        .parent()
        .and_then(|h| bodies.get(h))
        .filter(|b| b.mass() > 0.0)
        .map(|b| {
            let com = b.local_center_of_mass();
            co2.position_wrt_parent()
                .map_or(com, |rel| rel.inverse_transform_point(com))
        })
        .filter(|c| c.is_finite())
        .unwrap_or_else(|| mesh2.local_aabb().center());
    RigidMotion::new(start, pos2, center)
}
