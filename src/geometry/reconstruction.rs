//! Inverse trajectory mapping: the paper's eq. (1)-(3), corrected for 3D.
//!
//! # The method (section 2 of the paper)
//! The moving object `M` went from its previous pose to its current one by a translation `D`
//! (a motion that also turns is handled in `motion.rs`, which brackets the first touch on the
//! rotating path and finishes with this file's method over a sub-step that is a translation to
//! within the tolerance). Walking it back along `-D` by a
//! distance `s` gives the configuration `M(s)`. The first touch on the trajectory is the largest
//! `s` in `[0, |D|]` at which the two surfaces meet. In 3D the surfaces of two polyhedra first
//! meet in one of three ways, and each gives `s` by a scalar product:
//!
//! 1. a vertex `V_m` of the moving object reaches a triangle of the fixed one: the line
//!    `l_m` through `V_m` parallel to `D` cuts the triangle at `P`, `V = P - V_m` (eq. 1) and
//!    `d = V · (-D_u)` (eq. 2);
//! 2. a vertex `V_f` of the fixed object reaches a triangle of the moving one: the paper's
//!    "special situation", `d = V · D_u` (eq. 3);
//! 3. an edge of one reaches an edge of the other. The paper's 2D argument does not need this
//!    case, but in 3D two crossing edges can penetrate with no vertex of either object inside
//!    the other (two boxes crossed like an X). `d` is the third unknown of the 3x3 system
//!    `V_m0 + α E_m - d D_u = V_f0 + β E_f`.
//!
//! The reversing vector is `-d_max D_u` where `d_max` is the maximum over all three kinds
//! (Fig. 5's `max(d_maxf, d_maxm)`, plus the edge-edge term).
//!
//! # What is done beyond the paper
//! - All arithmetic runs in `f64` in the fixed object's frame, from the `f32` inputs.
//! - Candidates are pruned by a simultaneous traversal of both parry BVHs with the moving
//!   object's boxes swept over the trajectory, bounded per triangle pair by an exact plane
//!   bound (branch and bound). The first-touch path tests features per triangle pair (a shared
//!   vertex or edge can be tested by each triangle holding it; the classification merges the
//!   duplicates); the full event scan used for perforation tests each vertex-triangle and
//!   edge-edge pair once (stamp arrays, no hashing).
//! - The state (Fig. 1) is decided by tests of the pose itself: a transversal crossing of the
//!   two surfaces, or one object inside the other (the outer one closed).
//! - If the previous pose already penetrated (or a rotation caused the penetration) the first
//!   touch is not on the step: the reversing vector then goes to the nearest non-penetrating
//!   position along `-D` beyond the start of the step ([`ContactConfiguration::on_trajectory`]
//!   is `false`).
//! - With no translation (`D = 0`) the direction falls back to
//!   [`ReconstructionOptions::zero_motion_direction`].
//!
//! # Where
//! This file holds the entry points; `reconstruction/translate.rs` the walk back along a
//! translation; `reconstruction/primitives.rs` the
//! feature tests (eq. 1-3 as a ray against a triangle, the edge-edge solve, the pose tests),
//! `reconstruction/events.rs` their application to the triangle pairs the BVHs cannot rule
//! out, `reconstruction/convex.rs` the GJK path for two convex meshes,
//! `reconstruction/walk.rs` how far a walk back goes (the whole backward ray, or only the
//! step).

use super::classify::{build_patches, Event};
use super::contact::{ContactConfiguration, DirectionSource, TouchState};
use super::motion::{bounding_radius, RigidMotion};
use super::touch_mesh::{Feature, TouchMesh};
use crate::math::{Pose, Real, Vector};
use glamx::{DQuat, DVec3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::partitioning::{BvhNode, TraversalAction};
use parry3d::query::gjk::{self, VoronoiSimplex};
use parry3d::query::{PointQuery, Ray, RayCast};
use parry3d::shape::SupportMap;
use std::cell::Cell;

mod boxes;
mod convex;
mod events;
mod primitives;
mod translate;
mod walk;
mod workspace;

use boxes::aabb_overlap_range;
use convex::*;
use events::*;
pub(crate) use primitives::{edge_edge, ray_triangle};
pub(in crate::geometry) use walk::Walk;
use workspace::Workspace;

/// Why a reconstruction could not run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ReconstructionError {
    /// A pose (translation or rotation) is NaN or infinite.
    #[error("a pose is not finite (NaN or infinite component)")]
    NonFinitePose,
    /// The zero-motion fallback direction given in the options is zero or not finite.
    #[error("the zero-motion fallback direction is zero or not finite")]
    InvalidFallbackDirection,
}

/// Tuning of [`Reconstructor`].
///
/// # Example
/// A cube that did not move over the step (`D = 0`) but overlaps a slab by 0.1 m, off the
/// slab's centre: by default it is pushed out away from the slab's centre (diagonally, further
/// than 0.1 m); with [`ReconstructionOptions::zero_motion_direction`] set to "down" it is
/// pushed straight up by the overlap.
/// ```
/// use rapier_touch::prelude::*;
/// let slab = TouchMesh::from_shape(&Cuboid::new(Vector::new(2.0, 0.5, 2.0))).unwrap();
/// let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.5))).unwrap();
/// let slab_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
/// let pose = Pose::from_translation(Vector::new(1.0, 0.4, 0.0)); // bottom at y = -0.1
///
/// let mut rec = Reconstructor::default();
/// let c = rec.reconstruct(&slab, &slab_pose, &cube, &pose, &pose).unwrap();
/// assert_eq!(c.direction_source, DirectionSource::ZeroMotionFallback);
/// assert!(c.reversing_vector.x > 0.0 && c.depth > 0.1 + 1e-3);
///
/// rec.options = ReconstructionOptions {
///     zero_motion_direction: Some(Vector::NEG_Y),
///     ..Default::default()
/// };
/// let c = rec.reconstruct(&slab, &slab_pose, &cube, &pose, &pose).unwrap();
/// assert_eq!(c.state, TouchState::Penetrating);
/// assert!((c.reversing_vector - Vector::new(0.0, 0.1, 0.0)).length() < 1e-5);
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ReconstructionOptions {
    /// Relative tolerance, times the larger mesh's bounding-box diagonal: touches closer than
    /// this in `d` are simultaneous (one contact set), and a crossing shallower than this is a
    /// touch, not a penetration. Valid range `1e-9 ..= 1e-3`; default `1e-6` (about ten `f32`
    /// ulps of the mesh scale). Larger values merge near-parallel contacts into edge and face
    /// contacts; smaller ones split them into vertex contacts.
    pub tolerance: Real,
    /// World-space direction of travel to assume when the object did not translate over the
    /// step (`D = 0`); the reversing vector then points along its opposite. `None` (default)
    /// uses the direction from the moving object's bounding-box centre toward the fixed
    /// object's, so the reversal pushes the objects apart (straight up when the centres
    /// coincide).
    pub zero_motion_direction: Option<Vector>,
    /// How many intermediate poses are tested, at most, to tell a perforation (the object went
    /// through during the step) from a mere graze. Default 32.
    pub max_perforation_samples: usize,
    /// Use the convex path when both meshes are convex ([`TouchMesh::is_convex`]): parry's GJK
    /// ray cast on the Minkowski difference gives the first touch, and only the triangles
    /// around its witness points, then the touching region grown through mesh adjacency, are
    /// tested exactly. Default `true`. The general branch-and-bound search runs instead when
    /// this is `false`, when GJK does not converge, when the exact test disagrees with it, and
    /// for perforations (the convex path only decides separated, touching and penetrating).
    pub convex_fast_path: bool,
}

impl Default for ReconstructionOptions {
    fn default() -> Self {
        Self {
            tolerance: 1.0e-6,
            zero_motion_direction: None,
            max_perforation_samples: 32,
            convex_fast_path: true,
        }
    }
}

/// Reconstructs contact configurations; owns reusable scratch memory so repeated queries do
/// not allocate once warmed up.
///
/// # Example
/// A unit cube that moved 0.5 m down and now sinks 0.2 m into a fixed slab:
/// ```
/// use rapier_touch::prelude::*;
/// let slab = TouchMesh::from_shape(&Cuboid::new(Vector::new(2.0, 0.5, 2.0))).unwrap();
/// let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.5))).unwrap();
/// let slab_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
/// let now = Pose::from_translation(Vector::new(0.0, 0.3, 0.0));
/// let before = Pose::from_translation(Vector::new(0.0, 0.8, 0.0));
/// let mut rec = Reconstructor::default();
/// let c = rec.reconstruct(&slab, &slab_pose, &cube, &now, &before).unwrap();
/// assert_eq!(c.state, TouchState::Penetrating);
/// assert!((c.reversing_vector - Vector::new(0.0, 0.2, 0.0)).length() < 1e-5);
/// assert_eq!(c.patches.len(), 1);
/// assert_eq!(c.patches[0].kind, ContactKind::Face);
/// ```
#[derive(Default, Clone)]
pub struct Reconstructor {
    /// The options used by every query.
    pub options: ReconstructionOptions,
    ws: Workspace,
    /// Whether a motion whose first touch is not on the step is answered without its way out
    /// ([`Reconstructor::set_first_touch_only`]).
    pub(super) first_touch_only: bool,
}

impl std::fmt::Debug for Reconstructor {
    /// The options; the scratch memory is left out.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Reconstructor")
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

/// The relative frame of one query: the moving mesh expressed in the fixed mesh's frame.
pub(crate) struct Frame {
    /// Rotation of the moving mesh in the fixed frame.
    pub rot: DQuat,
    /// Translation of the moving mesh in the fixed frame.
    pub tra: DVec3,
    /// Unit direction of travel, fixed frame.
    pub u: DVec3,
    /// Absolute tolerance.
    pub tol: f64,
    /// Query stamp for lazily transformed moving vertices.
    stamp: u32,
}

impl Frame {
    pub fn moving_point(&self, p: Vector) -> DVec3 {
        self.rot * p.as_dvec3() + self.tra
    }
    /// The moving mesh's pose in the fixed frame, in `f32` (for parry's boxes).
    pub fn pose12(&self) -> Pose {
        Pose::from_parts(self.tra.as_vec3(), self.rot.as_quat())
    }
    /// How much the `f32` bounding boxes are loosened so that no touch within the tolerance
    /// is pruned.
    pub fn box_margin(&self, fixed: &TouchMesh, moving: &TouchMesh) -> Real {
        (self.tol as Real) * 4.0 + 1e-6 * fixed.scale().max(moving.scale())
    }
}

fn dpose(p: &Pose) -> (DQuat, DVec3) {
    (p.rotation.as_dquat().normalize(), p.translation.as_dvec3())
}

const BARY_EPS: f64 = 1.0e-9;

impl Reconstructor {
    /// A reconstructor with the given options.
    pub fn new(options: ReconstructionOptions) -> Self {
        Self {
            options,
            ws: Workspace::default(),
            first_touch_only: false,
        }
    }

    /// With `on`, the reconstructor answers a motion whose first touch is not on the
    /// step (its start pose already penetrates) `Penetrating`, off the trajectory, without
    /// the way out along `-D` ([`ContactConfiguration::on_trajectory`]): no reversing vector,
    /// no patches (two convex meshes still get it: [`Walk::FirstTouch`]). For a caller that
    /// corrects such a pair otherwise (the step guard pushes it out along rapier's contact
    /// normal): the way out walks the whole backward ray, across the 60 m TriMesh floor of
    /// rapier's stress scene.
    pub(crate) fn set_first_touch_only(&mut self, on: bool) {
        self.first_touch_only = on;
    }

    /// Reconstructs the contact configuration of `moving` against `fixed`.
    ///
    /// - `pos_fixed`: the fixed object's pose;
    /// - `pos_moving`: the moving object's pose now;
    /// - `prev_pos_moving`: its pose at the previous step.
    ///
    /// The object is walked back along its motion between the two poses, a [`RigidMotion`]
    /// turning about the centre of its bounding box: a pure translation `D` when the two
    /// orientations agree (the paper's method: the reversing vector is parallel to `-D`), a
    /// translation and rotation otherwise (the result is then a touch pose on that path,
    /// [`ContactConfiguration::touch_pose`]). Use [`Reconstructor::reconstruct_motion`] to turn
    /// about the body's real centre of mass, as the rapier integration does.
    ///
    /// # Errors
    /// [`ReconstructionError::NonFinitePose`] if a pose has a NaN or infinite component.
    pub fn reconstruct(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        pos_moving: &Pose,
        prev_pos_moving: &Pose,
    ) -> Result<ContactConfiguration, ReconstructionError> {
        let center = moving.local_aabb().center();
        let motion = RigidMotion::new(*prev_pos_moving, *pos_moving, center);
        self.reconstruct_motion(fixed, pos_fixed, moving, &motion)
    }

    /// Reconstructs the contact configuration of `moving`, which followed `motion` over the
    /// step (its current pose is `motion.end`), against `fixed` at `pos_fixed`.
    ///
    /// - When the motion turns every point of `moving` by less than the tolerance, it is a
    ///   translation and the paper's method runs unchanged (eq. 1-3 along `-D`).
    /// - Otherwise first touch is searched along the real path (`docs/method.md` §2.6):
    ///   samples of the path spaced so that neither object can be skipped, a bisection on
    ///   "penetrating" down to a sub-step over which the rotation moves no point by more than
    ///   the tolerance, and there the exact translation method, in `f64`, on the touching
    ///   features. The result is the pose on the path where the objects
    ///   first touch ([`ContactConfiguration::touch_pose`]), within the tolerance.
    /// - A corner that dips in and out between two samples (spacing below half the larger
    ///   smallest extent of the two objects) is not seen.
    ///
    /// # Errors
    /// [`ReconstructionError::NonFinitePose`] if a pose or the centre is NaN or infinite.
    ///
    /// # Example
    /// A cube spinning about the vertical axis while it falls onto a slab is walked back to the
    /// pose on its path where it first touched, orientation included:
    /// ```
    /// use rapier_touch::prelude::*;
    /// let slab = TouchMesh::from_shape(&Cuboid::new(Vector::new(2.0, 0.5, 2.0))).unwrap();
    /// let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.5))).unwrap();
    /// let slab_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
    /// let before = Pose::from_translation(Vector::new(0.0, 0.8, 0.0));
    /// let now = Pose::from_parts(Vector::new(0.0, 0.3, 0.0), Rotation::from_rotation_y(0.5));
    /// let motion = RigidMotion::new(before, now, Vector::ZERO);
    /// let c = Reconstructor::default().reconstruct_motion(&slab, &slab_pose, &cube, &motion).unwrap();
    /// assert_eq!(c.state, TouchState::Penetrating);
    /// // It touched 0.2 m back, when it had turned 0.5 * 0.3 / 0.5 = 0.3 rad.
    /// assert!((c.touch_pose.translation.y - 0.5).abs() < 1e-5);
    /// assert!((c.touch_pose.rotation.angle_between(Rotation::from_rotation_y(0.3))).abs() < 1e-4);
    /// ```
    pub fn reconstruct_motion(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        motion: &RigidMotion,
    ) -> Result<ContactConfiguration, ReconstructionError> {
        if !(pos_fixed.is_finite() && motion.is_finite()) {
            return Err(ReconstructionError::NonFinitePose);
        }
        let scale = fixed.scale().max(moving.scale()) as f64;
        let tol = (self.options.tolerance as f64).clamp(1e-9, 1e-3) * scale;
        let radius = bounding_radius(moving, motion.local_center);
        let angle = motion.dangle();
        if angle * radius <= tol {
            return self.translate_back_within(
                fixed,
                pos_fixed,
                moving,
                &motion.end,
                &motion.start,
                Walk::first_touch_if(self.first_touch_only),
            );
        }
        Ok(self.rotate_back(fixed, pos_fixed, moving, motion, tol, radius, angle))
    }

    /// The relative frame of `moving` at world pose `pose` against `fixed` at `pos_fixed`,
    /// travelling along world direction `u_world`, with a fresh stamp and a prepared workspace.
    pub(super) fn frame_at(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        pose: &Pose,
        u_world: DVec3,
        tol: f64,
    ) -> Frame {
        let (rf, tf) = dpose(pos_fixed);
        let (rm, tm) = dpose(pose);
        let rf_inv = rf.conjugate();
        self.ws.prepare(fixed, moving);
        Frame {
            rot: rf_inv * rm,
            tra: rf_inv * (tm - tf),
            u: rf_inv * u_world,
            tol,
            stamp: self.ws.stamp(),
        }
    }

    /// The features of `moving` at `pose` that touch `fixed` (within the tolerance), as events
    /// at `s = 0`: `Touching` with their patches, or separated when none touches. For a pose
    /// known to be at first touch (the end of the rotating path's bisection).
    ///
    /// Events are found along a direction, and along one that lies in or near a touch's plane
    /// (a face resting on a floor, looked at sideways) a point a rounding off the plane shows
    /// at a distance divided by the direction's small slope, past the tolerance, or not at
    /// all. The directions `along` (the best first: into `fixed` along the contact normal
    /// where one is known) are tried in turn, then the fixed mesh's three axes (no plane holds
    /// all three); the first that shows a touch is kept.
    ///
    /// This was a zero-length translation query, which looks along a fallback direction
    /// (toward the fixed mesh's box centre: sideways across a wide floor) for the first touch
    /// over the whole overlap of the boxes and collected every event there: 137 µs a call on
    /// the TriMesh floor of rapier's stress scene, and the features of a touch away from
    /// `pose` (a contact point 11 mm off a resting cube, `tests/it/rigid_motion.rs`).
    pub(super) fn touching_at(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        pose: &Pose,
        along: impl IntoIterator<Item = DVec3>,
        tol: f64,
    ) -> ContactConfiguration {
        let (rf, tf) = dpose(pos_fixed);
        let axes = [rf * DVec3::Y, rf * DVec3::X, rf * DVec3::Z];
        let mut result = ContactConfiguration::separated(
            axes[0].as_vec3(),
            DirectionSource::Trajectory,
            true,
            *pose,
        );
        for u in along.into_iter().chain(axes) {
            let Some(u) = u.try_normalize() else {
                continue;
            };
            let fr = self.frame_at(fixed, pos_fixed, moving, pose, u, tol);
            self.collect_events(fixed, moving, &fr, -tol, tol);
            result.candidate_pairs = self.ws.pairs.len();
            if self.ws.events.iter().any(|e| e.s.abs() <= tol) {
                result.state = TouchState::Touching;
                result.direction = u.as_vec3();
                return self.finish(result, fixed, moving, &fr, 0.0, f64::INFINITY, rf, tf);
            }
        }
        result
    }
}

#[cfg(test)]
mod tests;
