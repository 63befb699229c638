//! The partners a fast body's swept box may meet, without walking rapier's broad phase for it
//! when the answer is known to be only the guarded colliders that do not move freely.
//!
//! A fast body's pairs come from a box query over its path. Of what the query finds, the step
//! guard leaves every dynamic partner that moved less than the pair's safe step relative to
//! the body to rapier (`left_to_rapier` in `guard.rs`), and in a falling pile that is nearly
//! all of them: the query walked rapier's broad-phase tree through the pile's neighbours to
//! hand back bodies the guard then skipped (a fifth of the guard on rapier's TriMesh-floor
//! stress scene, 130 queries a step). When the body's motion plus the largest motion of any
//! dynamic body with a touch mesh is under the smallest safe step it can have with one, no
//! dynamic partner can be kept, and only the fixed, kinematic and parentless guarded
//! colliders are looked at, by their boxes over the step.

use super::*;
use parry3d::bounding_volume::Aabb;

/// Above this many fixed, kinematic and parentless guarded colliders, a scan of their boxes
/// per fast body is no cheaper than rapier's tree: the query is used.
const MAX_STILL: usize = 64;

/// The guarded colliders that are not on a dynamic body, with their boxes over the step, and
/// the bound on the dynamic bodies' motion that decides when they are all a fast body needs.
pub(super) struct StillPartners {
    /// `None` when there are more than [`MAX_STILL`] (the world's query is used then).
    boxes: Option<Vec<(ColliderHandle, Aabb)>>,
    /// The largest translation over the step of a dynamic body with a touch mesh.
    max_dynamic_motion: Real,
    /// The smallest positive `min_extent` of a touch mesh on a dynamic body.
    min_dynamic_extent: Real,
    /// How many of the guard's moved bodies `max_dynamic_motion` has taken in.
    seen: usize,
}

impl StillPartners {
    /// Reads the guarded colliders of `world` (those with a touch mesh in `meshes`).
    pub(super) fn collect<H: PhysicsHooks>(
        world: &PhysicsWorld,
        hooks: &TouchHooks<H>,
        margin: Real,
    ) -> Self {
        let (meshes, prev_poses) = (&hooks.meshes, &hooks.prev_poses);
        let mut boxes = Some(Vec::new());
        let mut max_dynamic_motion: Real = 0.0;
        let mut min_dynamic_extent = Real::INFINITY;
        for (&ch, cached) in meshes {
            let Some(co) = world.colliders.get(ch) else {
                continue;
            };
            let body = co.parent().and_then(|b| world.bodies.get(b));
            if body.is_some_and(|b| b.is_dynamic()) {
                let d = body_motion(prev_poses, &world.bodies, co.parent());
                max_dynamic_motion = max_dynamic_motion.max(d.length());
                let extent = cached.mesh.min_extent();
                if extent > 0.0 {
                    min_dynamic_extent = min_dynamic_extent.min(extent);
                }
                continue;
            }
            let Some(list) = boxes.as_mut() else {
                continue;
            };
            if list.len() == MAX_STILL {
                boxes = None;
                continue;
            }
            let pose = rapier_contacts::collider_pose_now(&world.bodies, co);
            let prev = previous_collider_pose(prev_poses, co, pose);
            let aabb = co
                .shape()
                .compute_aabb(&pose)
                .merged(&co.shape().compute_aabb(&prev))
                .loosened(margin);
            list.push((ch, aabb));
        }
        if let Some(list) = boxes.as_mut() {
            // In handle order, as stable as rapier's own (the hash map's is not).
            list.sort_unstable_by_key(|(h, _)| h.into_raw_parts());
        }
        Self {
            boxes,
            max_dynamic_motion,
            min_dynamic_extent,
            seen: 0,
        }
    }

    /// The partners whose boxes meet `swept`, the box of a dynamic body that moved by
    /// `motion` with a touch mesh of `min_extent`; `None` when a dynamic partner may be one
    /// the guard keeps (the world's query is needed).
    pub(super) fn partners(
        &self,
        swept: &Aabb,
        motion: Real,
        min_extent: Real,
    ) -> Option<Vec<ColliderHandle>> {
        let boxes = self.boxes.as_ref()?;
        let safe = if self.min_dynamic_extent.is_finite() {
            min_extent.min(self.min_dynamic_extent)
        } else {
            min_extent
        };
        // `left_to_rapier`: a dynamic partner is the guard's only when the two moved apart by
        // at least the pair's safe step, and `|d - dp| <= |d| + max |dp|`.
        (motion + self.max_dynamic_motion < safe).then(|| {
            boxes
                .iter()
                .filter(|(_, b)| b.intersects(swept))
                .map(|(h, _)| *h)
                .collect()
        })
    }

    /// Takes in the motion of the dynamic bodies the guard moved since it last looked (`moved`,
    /// the guard's list, growing): a push out can take a body farther from where it began
    /// the step.
    pub(super) fn take_in_moved(
        &mut self,
        world: &PhysicsWorld,
        prev_poses: &PoseHistory,
        moved: &[RigidBodyHandle],
    ) {
        for &bh in moved.get(self.seen..).unwrap_or_default() {
            if world.bodies.get(bh).is_some_and(|b| b.is_dynamic()) {
                let d = body_motion(prev_poses, &world.bodies, Some(bh));
                self.max_dynamic_motion = self.max_dynamic_motion.max(d.length());
            }
        }
        self.seen = moved.len();
    }
}

/// The colliders a fast collider `co` may have met on its path `(pose now, pose at the
/// step's start, how far its turn moved a point)`: `still`'s when it answers for the body's
/// motion and its mesh (`(|d|, mesh)`), else rapier's broad phase queried with the path's
/// box (every collider, sensors and groups included: the guard asks rapier's pair rules
/// after).
pub(super) fn swept_partners<'a>(
    world: &'a PhysicsWorld,
    still: Option<&StillPartners>,
    co: &rapier3d::geometry::Collider,
    (pose, prev_pose, turn): (&Pose, &Pose, Real),
    (motion, mesh): (Real, &TouchMesh),
) -> Box<dyn Iterator<Item = ColliderHandle> + 'a> {
    let swept = co
        .shape()
        .compute_aabb(pose)
        .merged(&co.shape().compute_aabb(prev_pose))
        .loosened(turn);
    match still.and_then(|s| s.partners(&swept, motion, mesh.min_extent())) {
        Some(list) => Box::new(list.into_iter()),
        None => Box::new(
            world
                .intersect_aabb_conservative(swept, QueryFilter::default())
                .map(|(h, _)| h),
        ),
    }
}
