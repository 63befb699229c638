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
use std::collections::HashSet;
use std::hash::{BuildHasherDefault, Hasher};

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
}

impl std::fmt::Debug for Reconstructor {
    /// The options; the scratch memory is left out.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Reconstructor")
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

#[derive(Default, Clone)]
struct Workspace {
    /// Candidate triangle pairs `(fixed, moving)`, internal numbering.
    pairs: Vec<(u32, u32)>,
    events: Vec<Event>,
    m_pts: Vec<DVec3>,
    m_pt_stamp: Vec<u32>,
    v_stamp_m: Vec<u32>,
    v_stamp_f: Vec<u32>,
    e_stamp_m: Vec<u32>,
    e_stamp_f: Vec<u32>,
    tm_range: Vec<(u32, u32)>,
    tm_range_stamp: Vec<u32>,
    counter: u32,
    /// Convex path: triangles near the witness points, visited triangle pairs, the touches
    /// found near the witnesses, touching pairs still to grow from, and the last support
    /// vertices (warm starts).
    near_f: Vec<u32>,
    near_m: Vec<u32>,
    visited: HashSet<u64, BuildHasherDefault<PairHasher>>,
    near_touches: Vec<(u32, u32, f64)>,
    grow: Vec<(u32, u32)>,
    warm: [u32; 2],
}

/// Hashes a packed triangle pair with one multiplication (the keys are already well spread).
#[derive(Default)]
struct PairHasher(u64);

impl Hasher for PairHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ b as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (x ^ (x >> 29)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

impl Workspace {
    fn prepare(&mut self, f: &TouchMesh, m: &TouchMesh) {
        fn fit<T: Clone + Default>(v: &mut Vec<T>, n: usize) {
            if v.len() < n {
                v.resize(n, T::default());
            }
        }
        fit(&mut self.m_pts, m.num_vertices());
        fit(&mut self.m_pt_stamp, m.num_vertices());
        fit(&mut self.v_stamp_m, m.num_vertices());
        fit(&mut self.v_stamp_f, f.num_vertices());
        fit(&mut self.e_stamp_m, m.num_edges());
        fit(&mut self.e_stamp_f, f.num_edges());
        fit(&mut self.tm_range, m.num_triangles());
        fit(&mut self.tm_range_stamp, m.num_triangles());
        self.pairs.clear();
        self.events.clear();
    }

    /// A fresh stamp value; stamp arrays are cleared when the counter wraps.
    fn stamp(&mut self) -> u32 {
        self.counter = self.counter.wrapping_add(1);
        if self.counter == 0 {
            for v in [
                &mut self.m_pt_stamp,
                &mut self.v_stamp_m,
                &mut self.v_stamp_f,
                &mut self.e_stamp_m,
                &mut self.e_stamp_f,
                &mut self.tm_range_stamp,
            ] {
                v.iter_mut().for_each(|x| *x = 0);
            }
            self.counter = 1;
        }
        self.counter
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
        }
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
            return self.translate_back(fixed, pos_fixed, moving, &motion.end, &motion.start);
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

    /// The paper's method along a translation (the orientation of `pos_moving` is kept).
    pub(super) fn translate_back(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        pos_moving: &Pose,
        prev_pos_moving: &Pose,
    ) -> Result<ContactConfiguration, ReconstructionError> {
        let mut c =
            self.translate_back_inner(fixed, pos_fixed, moving, pos_moving, prev_pos_moving)?;
        c.touch_pose = Pose::from_parts(
            pos_moving.translation + c.reversing_vector,
            pos_moving.rotation,
        );
        Ok(c)
    }

    fn translate_back_inner(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        pos_moving: &Pose,
        prev_pos_moving: &Pose,
    ) -> Result<ContactConfiguration, ReconstructionError> {
        let (rf, tf) = dpose(pos_fixed);
        let (rm, tm) = dpose(pos_moving);
        let scale = fixed.scale().max(moving.scale()) as f64;
        let tol = (self.options.tolerance as f64).clamp(1e-9, 1e-3) * scale;

        let d_world = tm - prev_pos_moving.translation.as_dvec3();
        let len = d_world.length();
        let (u_world, source, traj_len) = if len > 1e-9 * scale {
            (d_world / len, DirectionSource::Trajectory, len)
        } else {
            let dir = match self.options.zero_motion_direction {
                Some(d) => {
                    let d = d.as_dvec3();
                    if !d.is_finite() || d.length_squared() == 0.0 {
                        return Err(ReconstructionError::InvalidFallbackDirection);
                    }
                    d.normalize()
                }
                None => {
                    let cf = rf * fixed.local_aabb().center().as_dvec3() + tf;
                    let cm = rm * moving.local_aabb().center().as_dvec3() + tm;
                    (cf - cm).try_normalize().unwrap_or(DVec3::NEG_Y)
                }
            };
            (dir, DirectionSource::ZeroMotionFallback, f64::INFINITY)
        };

        let fr = self.frame_at(fixed, pos_fixed, moving, pos_moving, u_world, tol);
        let mut result =
            ContactConfiguration::separated(u_world.as_vec3(), source, true, *pos_moving);

        // The range of `s` over which the bounding boxes overlap.
        let Some((s_lo_box, s_hi)) = aabb_overlap_range(fixed, moving, &fr) else {
            return Ok(result);
        };
        if s_hi < -tol {
            return Ok(result);
        }
        if self.options.convex_fast_path && fixed.is_convex() && moving.is_convex() {
            match self.convex_touch(fixed, moving, &fr, s_lo_box, s_hi) {
                Some(ConvexTouch::Apart) => return Ok(result),
                Some(ConvexTouch::Penetrating(s)) => {
                    result.state = TouchState::Penetrating;
                    // The start pose penetrates too when the touch lies beyond it.
                    result.on_trajectory =
                        source == DirectionSource::Trajectory && s <= traj_len + tol;
                    result.candidate_pairs = self.ws.visited.len();
                    return Ok(self.finish(result, fixed, moving, &fr, s, traj_len, rf, tf));
                }
                Some(ConvexTouch::Touching) => {
                    result.state = TouchState::Touching;
                    result.candidate_pairs = self.ws.visited.len();
                    return Ok(self.finish(result, fixed, moving, &fr, 0.0, traj_len, rf, tf));
                }
                None => {}
            }
        }
        // A touch up to one tolerance before the start of the step still counts as on the step
        // (a start pose that overlaps by a rounding error).
        let s_max = s_hi.min(traj_len + tol);
        // Only the largest touch matters for the first touch: a bounded search.
        let first_touch = self.collect_first_touch(fixed, moving, &fr, -tol, s_max);
        result.candidate_pairs = self.ws.pairs.len();
        let pen0 = self.penetrating_at(fixed, moving, &fr, 0.0);

        let s_star;
        if pen0 {
            result.state = TouchState::Penetrating;
            // No surface meets the other between the first touch and the start of the step
            // (the first touch is the largest), so the configuration just before the first
            // touch is the start pose's: valid if the step started apart. The start pose is
            // the cheaper one to test (farther from contact), and needs no test at all when the
            // boxes were already apart there.
            let valid = first_touch > tol
                && (s_hi < traj_len || !self.penetrating_at(fixed, moving, &fr, traj_len));
            if valid && source == DirectionSource::Trajectory {
                s_star = first_touch;
            } else {
                // The first touch is not on this step: go back to the nearest separating pose,
                // the last touch on the whole backward ray.
                result.on_trajectory = false;
                s_star = if s_max < s_hi {
                    let s = self.collect_first_touch(fixed, moving, &fr, -tol, s_hi);
                    result.candidate_pairs = self.ws.pairs.len();
                    s
                } else {
                    first_touch
                };
                if !s_star.is_finite() {
                    // Containment with no surface on the ray: cannot happen for finite
                    // meshes, but never hand back a NaN.
                    return Ok(result);
                }
            }
        } else if first_touch > tol {
            // Not penetrating now but the surfaces met during the step: a perforation if the
            // objects overlapped in between, otherwise a graze (or a touch now). Rare, so every
            // touch of the step is collected here.
            self.collect_events(fixed, moving, &fr, -tol, s_max);
            result.candidate_pairs = self.ws.pairs.len();
            if self.perforated_between(fixed, moving, &fr, first_touch) {
                result.state = TouchState::Perforated;
                s_star = first_touch;
            } else if self.ws.events.iter().any(|e| e.s.abs() <= tol) {
                result.state = TouchState::Touching;
                s_star = 0.0;
            } else {
                return Ok(result);
            }
        } else if first_touch >= -tol {
            result.state = TouchState::Touching;
            s_star = 0.0;
        } else {
            return Ok(result);
        }

        Ok(self.finish(result, fixed, moving, &fr, s_star, traj_len, rf, tf))
    }

    /// Fills in the reversing vector, time of impact and contact patches for a touch at
    /// `s_star`, from the events in the workspace.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        mut result: ContactConfiguration,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_star: f64,
        traj_len: f64,
        rf: DQuat,
        tf: DVec3,
    ) -> ContactConfiguration {
        let to_world = |p: DVec3| -> Vector { (rf * p + tf).as_vec3() };
        let u_world = rf * fr.u;
        let s_star = s_star.max(0.0);
        if s_star > 0.0 {
            result.reversing_vector = (-s_star * u_world).as_vec3();
            result.depth = s_star as Real;
            if result.on_trajectory && traj_len.is_finite() {
                result.time_of_impact = Some((1.0 - s_star / traj_len).clamp(0.0, 1.0) as Real);
            }
        } else if result.state == TouchState::Touching && traj_len.is_finite() {
            result.time_of_impact = Some(1.0);
        }
        // Contact set: every event at s_star (within tolerance).
        let selected: Vec<Event> = self
            .ws
            .events
            .iter()
            .filter(|e| (e.s - s_star).abs() <= fr.tol)
            .cloned()
            .collect();
        result.patches = build_patches(fixed, moving, fr, selected, s_star, &to_world, rf);
        result
    }

    /// The convex path (see [`ReconstructionOptions::convex_fast_path`]). For two convex
    /// objects the poses at which they overlap form one interval `[s_lo, s_hi]` of the line
    /// (the line crosses the convex Minkowski difference once), so two GJK ray casts, one from
    /// each end of the bounding-box range, decide the state, and `s_hi` is the first touch.
    /// `None` hands the query to the general search.
    fn convex_touch(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_lo_box: f64,
        s_hi_box: f64,
    ) -> Option<ConvexTouch> {
        let tol = fr.tol;
        let scale = fixed.scale().max(moving.scale()) as f64;
        // parry's GJK runs in f32 and asserts finite bounds: keep its coordinates (and their
        // squares) far from overflow; huge scenes take the general search.
        let reach = |m: &TouchMesh| {
            let b = m.local_aabb();
            b.mins.abs().max(b.maxs.abs()).max_element() as f64
        };
        let extent =
            reach(fixed) + reach(moving) + fr.tra.length() + s_lo_box.abs() + s_hi_box.abs();
        // (The cast divides coordinates by the scale: what matters is the extent in scales.)
        if !extent.is_finite() || extent >= 1.0e6 * scale {
            return None;
        }
        // GJK runs in f32 on coordinates divided by `scale` (see `convex_cast`): its absolute
        // stopping distance, 1.2e-6, is then 1.2e-6 of the scale at every scale.
        let window = (1.0e-4 * scale).max(100.0 * tol);
        let pad = 1.0e-3 * scale + window;
        let s_from = s_hi_box + pad;
        let (t, w1, w2) = self.convex_cast(fixed, moving, fr, s_from, fr.u)?;
        let s_hi = s_from - t;
        if s_hi < -tol - window {
            return Some(ConvexTouch::Apart);
        }
        let deep = if s_hi > tol + window {
            let s_to = s_lo_box - pad;
            let (t_lo, ..) = self.convex_cast(fixed, moving, fr, s_to, -fr.u)?;
            let s_lo = s_to + t_lo;
            if s_lo > s_hi + window {
                return None;
            }
            if s_lo >= -tol - window {
                // Apart or touching at the front end now: passed through, or about to.
                return None;
            }
            true
        } else {
            false
        };
        let b = self.convex_events(fixed, moving, fr, w1, w2, s_hi, window)?;
        if (b - s_hi).abs() > window {
            return None;
        }
        if deep {
            (b > tol).then_some(ConvexTouch::Penetrating(b))
        } else if b < -tol {
            Some(ConvexTouch::Apart)
        } else if b <= tol {
            Some(ConvexTouch::Touching)
        } else {
            None
        }
    }

    /// GJK ray cast of the moving mesh, walked back to `s_from`, travelling along unit `dir`
    /// (fixed frame): the distance to contact, the witness on the fixed mesh (fixed frame) and
    /// on the moving mesh (its own frame). `None` if GJK misses or does not converge.
    ///
    /// parry's GJK stops at an absolute distance (`gjk::eps_tol()`, 1.2e-6): at a centimetre
    /// that is 1e-4 of the object, at 0.1 mm it is 1 %. The cast therefore runs on coordinates
    /// divided by the pair's scale, so its tolerances are relative at every scale.
    fn convex_cast(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_from: f64,
        dir: DVec3,
    ) -> Option<(f64, Vector, Vector)> {
        let (scale, pos12, g1, g2) = self.scaled_pair(fixed, moving, fr, -s_from * fr.u);
        let hit =
            gjk::directional_distance(&pos12, &g1, &g2, dir.as_vec3(), &mut VoronoiSimplex::new());
        self.ws.warm = [g1.warm.get(), g2.warm.get()];
        let (t, _, w1, w2) = hit?;
        // A zero distance means the cast started in contact: no witnesses.
        let (t, w1, w2) = (t as f64 * scale, w1 * scale as Real, w2);
        (t.is_finite() && t > 0.0 && w1.is_finite() && w2.is_finite())
            .then(|| (t, w1, pos12.inverse_transform_point(w2) * scale as Real))
    }

    /// Exact events of the convex path: every touch within `window` of the GJK estimate `s_g`
    /// among the triangles near the witness points `w1` (fixed mesh, fixed frame) and `w2`
    /// (moving mesh, its frame), then the whole touching region, grown pair by pair through
    /// triangles sharing a vertex. Leaves the events at the largest touch in the workspace and
    /// returns it; `None` if no touch was found near the witnesses.
    #[allow(clippy::too_many_arguments)]
    fn convex_events(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        w1: Vector,
        w2: Vector,
        s_g: f64,
        window: f64,
    ) -> Option<f64> {
        let ws = &mut self.ws;
        ws.events.clear();
        ws.pairs.clear();
        ws.visited.clear();
        ws.grow.clear();
        let tol = fr.tol;
        let r = Vector::splat((10.0 * window) as Real);
        let (mut near_f, mut near_m) = (
            std::mem::take(&mut ws.near_f),
            std::mem::take(&mut ws.near_m),
        );
        near_f.clear();
        near_f.extend(fixed.bvh().intersect_aabb(&Aabb::new(w1 - r, w1 + r)));
        near_m.clear();
        near_m.extend(moving.bvh().intersect_aabb(&Aabb::new(w2 - r, w2 + r)));
        let (lo, hi) = (s_g - window, s_g + window);
        let mut found = std::mem::take(&mut ws.near_touches);
        found.clear();
        for &tf in &near_f {
            for &tm in &near_m {
                ws.visited.insert(pair_key(tf, tm));
                if !boxes_meet(ws, fixed, moving, fr, tf, tm, lo, hi) {
                    continue;
                }
                let s = pair_events(ws, fixed, moving, fr, tf, tm, lo, hi);
                if s.is_finite() {
                    found.push((tf, tm, s));
                }
            }
        }
        ws.near_f = near_f;
        ws.near_m = near_m;
        let mut b = found.iter().map(|f| f.2).fold(f64::NEG_INFINITY, f64::max);
        if !b.is_finite() {
            return None;
        }
        ws.grow
            .extend(found.iter().filter(|f| f.2 >= b - tol).map(|f| (f.0, f.1)));
        ws.near_touches = found;
        while let Some((tf, tm)) = ws.grow.pop() {
            for k in 0..6 {
                let (mesh, v) = if k < 3 {
                    (fixed, fixed.indices()[tf as usize][k])
                } else {
                    (moving, moving.indices()[tm as usize][k - 3])
                };
                for &t in mesh.vertex_triangles(v) {
                    let (a, c) = if k < 3 { (t, tm) } else { (tf, t) };
                    if !ws.visited.insert(pair_key(a, c))
                        || !boxes_meet(ws, fixed, moving, fr, a, c, b - tol, b + tol)
                    {
                        continue;
                    }
                    let s = pair_events(ws, fixed, moving, fr, a, c, b - tol, b + tol);
                    if s >= b - tol {
                        b = b.max(s);
                        ws.grow.push((a, c));
                    }
                }
            }
        }
        ws.events.retain(|e| e.s >= b - tol);
        Some(b)
    }

    /// The largest touch `s` in `[s_min, s_max]` (`-inf` if none), with every event within the
    /// tolerance of it in `ws.events`. Branch and bound over both BVHs: a pair of boxes whose
    /// overlap along the ray ends below the best touch so far cannot hold the first touch.
    fn collect_first_touch(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_min: f64,
        s_max: f64,
    ) -> f64 {
        let ws = &mut self.ws;
        ws.pairs.clear();
        ws.events.clear();
        let pos12 = fr.pose12();
        let u = fr.u.as_vec3();
        let tol = fr.tol;
        let margin = fr.box_margin(fixed, moving);
        // Seed the bound with a touch that surely exists: each object's vertex deepest along
        // the motion, cast back along the trajectory. Less a margin that covers f32 rounding,
        // it is a lower bound of the first touch.
        let seed = seed_first_touch(fixed, moving, fr, s_min, s_max)
            .map_or(f64::NEG_INFINITY, |s| s - 10.0 * tol);
        let best = Cell::new(seed);
        let boxer = BoxTransform::new(&pos12, u, margin);
        let reach = |nf: &BvhNode, nm: &BvhNode| -> Option<f64> {
            let (lo, hi) = boxer.overlap_interval(nm, nf)?;
            let (lo, hi) = ((lo as f64).max(s_min), (hi as f64).min(s_max));
            (lo <= hi + tol).then_some(hi)
        };
        let check = |nf: &BvhNode, nm: &BvhNode| {
            reach(nf, nm).is_some_and(|hi| hi >= best.get() - 2.0 * tol)
        };
        let (fbvh, mbvh) = (fixed.bvh(), moving.bvh());
        for (tf, tm) in fbvh.leaf_pairs(mbvh, check) {
            let (Some(nf), Some(nm)) = (fbvh.leaf_node(tf), mbvh.leaf_node(tm)) else {
                continue;
            };
            if !check(nf, nm) {
                continue;
            }
            ws.pairs.push((tf, tm));
            let lo = s_min.max(best.get() - tol);
            // Exact bound from each triangle's plane: past it the other triangle has left the
            // plane, so no touch of this pair lies beyond (the boxes above are inflated by the
            // rotation).
            let pf = fixed_tri(fixed, tf);
            let pm = moving.indices()[tm as usize].map(|v| moving_pt(ws, moving, fr, v));
            if plane_bound(&pf, &pm, -fr.u).min(plane_bound(&pm, &pf, fr.u)) < lo - tol {
                continue;
            }
            let found = pair_events(ws, fixed, moving, fr, tf, tm, lo, s_max);
            if found > best.get() {
                best.set(found);
            }
        }
        let b = ws
            .events
            .iter()
            .map(|e| e.s)
            .fold(f64::NEG_INFINITY, f64::max);
        ws.events.retain(|e| e.s >= b - tol);
        b
    }

    /// Candidate pairs over `s ∈ [s_min, s_max]` and all three kinds of events in that range.
    fn collect_events(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_min: f64,
        s_max: f64,
    ) {
        let ws = &mut self.ws;
        ws.pairs.clear();
        ws.events.clear();
        let pos12 = fr.pose12();
        let u = fr.u.as_vec3();
        let margin = fr.box_margin(fixed, moving);
        let (a, b) = (-(s_min as Real) * u, -(s_max as Real) * u);
        let swept = |aabb: Aabb| -> Aabb {
            let m = aabb.transform_by(&pos12);
            Aabb::new(
                (m.mins + a).min(m.mins + b) - Vector::splat(margin),
                (m.maxs + a).max(m.maxs + b) + Vector::splat(margin),
            )
        };
        let fbvh = fixed.bvh();
        let mbvh = moving.bvh();
        for (tf, tm) in fbvh.leaf_pairs(mbvh, |nf, nm| swept(nm.aabb()).intersects(&nf.aabb())) {
            let (Some(nf), Some(nm)) = (fbvh.leaf_node(tf), mbvh.leaf_node(tm)) else {
                continue;
            };
            if swept(nm.aabb()).intersects(&nf.aabb()) {
                ws.pairs.push((tf, tm));
            }
        }
        if ws.pairs.is_empty() {
            return;
        }

        // Vertex (moving) against triangle (fixed): eq. (1)-(2).
        ws.pairs.sort_unstable();
        let mut i = 0;
        while i < ws.pairs.len() {
            let tf = ws.pairs[i].0;
            let st = ws.stamp();
            let tri = fixed_tri(fixed, tf);
            let n = tri_normal(&tri);
            while i < ws.pairs.len() && ws.pairs[i].0 == tf {
                let tm = ws.pairs[i].1;
                for &v in &moving.indices()[tm as usize] {
                    if ws.v_stamp_m[v as usize] != st {
                        ws.v_stamp_m[v as usize] = st;
                        let p = moving_pt(ws, moving, fr, v);
                        if let Some((s, bary)) = ray_triangle(p, -fr.u, &tri, s_min, s_max) {
                            ws.events.push(Event {
                                s,
                                point: p - s * fr.u,
                                normal: n,
                                fixed: tri_feature(fixed, tf, bary),
                                moving: Feature::Vertex(v),
                            });
                        }
                    }
                }
                i += 1;
            }
        }

        // Vertex (fixed) against triangle (moving): the special situation, eq. (3).
        ws.pairs.sort_unstable_by_key(|&(tf, tm)| (tm, tf));
        let qstamp = ws.stamp();
        let mut i = 0;
        while i < ws.pairs.len() {
            let tm = ws.pairs[i].1;
            let start = i;
            let st = ws.stamp();
            let idx = moving.indices()[tm as usize];
            let tri = idx.map(|v| moving_pt(ws, moving, fr, v));
            let n = tri_normal(&tri);
            while i < ws.pairs.len() && ws.pairs[i].1 == tm {
                let tf = ws.pairs[i].0;
                for &w in &fixed.indices()[tf as usize] {
                    if ws.v_stamp_f[w as usize] != st {
                        ws.v_stamp_f[w as usize] = st;
                        let q = fixed.vertices()[w as usize].as_dvec3();
                        if let Some((s, bary)) = ray_triangle(q, fr.u, &tri, s_min, s_max) {
                            ws.events.push(Event {
                                s,
                                point: q,
                                normal: n,
                                fixed: Feature::Vertex(w),
                                moving: tri_feature(moving, tm, bary),
                            });
                        }
                    }
                }
                i += 1;
            }
            ws.tm_range[tm as usize] = (start as u32, i as u32);
            ws.tm_range_stamp[tm as usize] = qstamp;
        }

        // Edge against edge: the 3D case the paper's 2D argument misses.
        for k in 0..ws.pairs.len() {
            let tm = ws.pairs[k].1;
            if k > 0 && ws.pairs[k - 1].1 == tm {
                continue;
            }
            for em in moving.triangle_edges(tm) {
                if ws.e_stamp_m[em as usize] == qstamp {
                    continue;
                }
                ws.e_stamp_m[em as usize] = qstamp;
                let st = ws.stamp();
                let [ma, mb] = moving.edges()[em as usize];
                let (p0, p1) = (moving_pt(ws, moving, fr, ma), moving_pt(ws, moving, fr, mb));
                let [t1, t2] = moving.edge_triangles(em);
                let mut tris = [tm, u32::MAX, u32::MAX];
                if t1 != tm {
                    tris[1] = t1;
                }
                if t2 != tm && t2 != t1 {
                    tris[2] = t2;
                }
                for t in tris {
                    if t == u32::MAX || ws.tm_range_stamp[t as usize] != qstamp {
                        continue;
                    }
                    let (r0, r1) = ws.tm_range[t as usize];
                    for r in r0..r1 {
                        let tf = ws.pairs[r as usize].0;
                        for ef in fixed.triangle_edges(tf) {
                            if ws.e_stamp_f[ef as usize] == st {
                                continue;
                            }
                            ws.e_stamp_f[ef as usize] = st;
                            let [fa, fb] = fixed.edges()[ef as usize];
                            let q0 = fixed.vertices()[fa as usize].as_dvec3();
                            let q1 = fixed.vertices()[fb as usize].as_dvec3();
                            if let Some((s, alpha, beta, n)) =
                                edge_edge(p0, p1, q0, q1, fr.u, s_min, s_max)
                            {
                                ws.events.push(Event {
                                    s,
                                    point: q0 + beta * (q1 - q0),
                                    normal: n,
                                    fixed: edge_feature([fa, fb], beta),
                                    moving: edge_feature([ma, mb], alpha),
                                });
                            }
                        }
                    }
                }
            }
        }
    }

    /// Do the objects interpenetrate with the moving one walked back by `s`? A transversal
    /// crossing of the surfaces, or one inside the other (the outer one closed).
    pub(super) fn penetrating_at(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s: f64,
    ) -> bool {
        let shift = -s * fr.u;
        // Two convex meshes: parry's GJK and EPA on the meshes' support maps decide in a few
        // support queries, where the triangle test below walks every pair of triangles within
        // the tolerance of each other (hundreds on a rounded shape resting on another; a bench
        // of the rotating path on rapier's rounded hulls spent 90 % of its time there).
        if fixed.is_convex() && moving.is_convex() {
            if let Some(p) = self.convex_penetrating(fixed, moving, fr, shift) {
                return p;
            }
        }
        // Quick sufficient test first: the vertex of each object deepest along the motion lies
        // inside the other (closed) one, farther than the tolerance from its surface.
        // (Containment needs only the container closed: an open mover, even a single
        // triangle, wholly inside a closed mesh penetrates it.)
        let inv = fr.rot.conjugate();
        if fixed.is_closed() {
            let v = support_vertex(moving, (inv * fr.u).as_vec3());
            let p = fr.moving_point(moving.vertices()[v as usize]) + shift;
            if deep_inside(fixed, p, fr.tol) {
                return true;
            }
        }
        if moving.is_closed() {
            let w = support_vertex(fixed, (-fr.u).as_vec3());
            let q = inv * (fixed.vertices()[w as usize].as_dvec3() - shift - fr.tra);
            if deep_inside(moving, q, fr.tol) {
                return true;
            }
        }
        let pos12 = Pose::from_parts((fr.tra + shift).as_vec3(), fr.rot.as_quat());
        let margin = fr.box_margin(fixed, moving);
        let overlap = |nf: &BvhNode, nm: &BvhNode| {
            nm.aabb()
                .transform_by(&pos12)
                .loosened(margin)
                .intersects(&nf.aabb())
        };
        let (fbvh, mbvh) = (fixed.bvh(), moving.bvh());
        for (tf, tm) in fbvh.leaf_pairs(mbvh, overlap) {
            let a = fixed_tri(fixed, tf);
            let b = moving.indices()[tm as usize]
                .map(|v| moving_pt(&mut self.ws, moving, fr, v) + shift);
            if triangles_cross(&a, &b, fr.tol) {
                return true;
            }
        }
        // A sample point of each surface inside the other one, when that one is closed.
        if fixed.is_closed()
            && sample_inside(moving, fixed, |p| fr.moving_point(p) + shift) == Some(true)
        {
            return true;
        }
        moving.is_closed()
            && sample_inside(fixed, moving, |p| inv * (p.as_dvec3() - shift - fr.tra)) == Some(true)
    }

    /// The pair as parry's GJK sees it, on coordinates divided by the pair's scale (see
    /// [`Reconstructor::convex_cast`]): the scale, the moving mesh's pose in the fixed one's
    /// frame with the moving mesh shifted by `shift`, and both meshes as support maps warm-started
    /// from the workspace (store their `warm` back after the query).
    fn scaled_pair<'a>(
        &self,
        fixed: &'a TouchMesh,
        moving: &'a TouchMesh,
        fr: &Frame,
        shift: DVec3,
    ) -> (f64, Pose, HillClimb<'a>, HillClimb<'a>) {
        let scale = fixed.scale().max(moving.scale()) as f64;
        let k = 1.0 / scale;
        let pos12 = Pose::from_parts((k * (fr.tra + shift)).as_vec3(), fr.rot.as_quat());
        let climb = |mesh, warm| HillClimb {
            mesh,
            warm: Cell::new(warm),
            k: k as Real,
        };
        (
            scale,
            pos12,
            climb(fixed, self.ws.warm[0]),
            climb(moving, self.ws.warm[1]),
        )
    }

    /// [`Reconstructor::penetrating_at`] for two convex meshes by GJK (and EPA when they
    /// intersect), on coordinates divided by the pair's scale like [`Reconstructor::convex_cast`]:
    /// overlapping deeper than the tolerance. `None` (the exact test decides) when the answer
    /// lies within 1e-3 of the scale of the decision or EPA does not converge.
    fn convex_penetrating(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        shift: DVec3,
    ) -> Option<bool> {
        let (scale, pos12, g1, g2) = self.scaled_pair(fixed, moving, fr, shift);
        let dir = pos12.translation.try_normalize().unwrap_or(Vector::X);
        let mut simplex = VoronoiSimplex::new();
        simplex.reset(gjk::CsoPoint::from_shapes(&pos12, &g1, &g2, dir));
        // GJK and EPA run in f32 and stop at their own tolerances (EPA depths off by 1.7e-4 of
        // the scale were seen): within `MARGIN` of the decision the exact test decides.
        const MARGIN: Real = 1.0e-3;
        let tol = (fr.tol / scale) as Real;
        let answer = match gjk::closest_points(&pos12, &g1, &g2, MARGIN, true, &mut simplex) {
            gjk::GJKResult::NoIntersection(_) => Some(false),
            gjk::GJKResult::Intersection => parry3d::query::epa::EPA::new()
                .closest_points(&pos12, &g1, &g2, &simplex)
                .and_then(|(p1, p2, n)| {
                    let depth = (p1 - p2).dot(n);
                    (depth > tol + MARGIN).then_some(true)
                }),
            _ => None,
        };
        self.ws.warm = [g1.warm.get(), g2.warm.get()];
        answer
    }

    /// Did the objects overlap somewhere strictly between the first touch and now?
    fn perforated_between(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        first: f64,
    ) -> bool {
        let mut ss: Vec<f64> = self
            .ws
            .events
            .iter()
            .map(|e| e.s)
            .filter(|&s| s > fr.tol && s <= first + fr.tol)
            .collect();
        ss.push(0.0);
        ss.sort_unstable_by(|a, b| b.total_cmp(a));
        ss.dedup_by(|a, b| (*a - *b).abs() <= fr.tol);
        let mids: Vec<f64> = ss.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        let n = mids.len();
        let budget = self.options.max_perforation_samples.max(1);
        let step = n.div_ceil(budget).max(1);
        (0..n)
            .step_by(step)
            .any(|k| self.penetrating_at(fixed, moving, fr, mids[k]))
    }
}

/// The vertex of `mesh` farthest along `dir` (mesh frame) reached by hill climbing over the
/// vertex graph from vertex 0: the support point on a convex mesh, a local maximum otherwise.
fn support_vertex(mesh: &TouchMesh, dir: Vector) -> u32 {
    mesh.hill_climb(0, dir)
}

/// What the convex path decided.
enum ConvexTouch {
    /// No touch at or behind the current pose.
    Apart,
    /// Penetrating now; the first touch is this far back (events in the workspace).
    Penetrating(f64),
    /// Touching now (events in the workspace).
    Touching,
}

/// A convex mesh scaled by `k` as a parry support map: support points by hill climbing
/// ([`TouchMesh::convex_support`]) from the previous answer.
struct HillClimb<'a> {
    mesh: &'a TouchMesh,
    warm: Cell<u32>,
    k: Real,
}

impl SupportMap for HillClimb<'_> {
    fn local_support_point(&self, dir: Vector) -> Vector {
        let v = self.mesh.convex_support(dir, self.warm.get()).unwrap_or(0);
        self.warm.set(v);
        self.mesh.vertices()[v as usize] * self.k
    }
}

fn pair_key(tf: u32, tm: u32) -> u64 {
    ((tf as u64) << 32) | tm as u64
}

/// Can triangles `tf` and `tm` (the latter walked back by some `s` in `[s0, s1]`) be within
/// the tolerance of each other? The fixed triangle's bounding box and the moving one's swept
/// over the range, loosened by two tolerances, overlap.
#[allow(clippy::too_many_arguments)]
fn boxes_meet(
    ws: &mut Workspace,
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
    tf: u32,
    tm: u32,
    s0: f64,
    s1: f64,
) -> bool {
    let a = fixed_tri(fixed, tf);
    let b = moving.indices()[tm as usize].map(|v| moving_pt(ws, moving, fr, v));
    let m = DVec3::splat(2.0 * fr.tol);
    let (a_lo, a_hi) = (a[0].min(a[1]).min(a[2]), a[0].max(a[1]).max(a[2]));
    let (b_lo, b_hi) = (b[0].min(b[1]).min(b[2]), b[0].max(b[1]).max(b[2]));
    let (d0, d1) = (-s0 * fr.u, -s1 * fr.u);
    let (b_lo, b_hi) = (b_lo + d0.min(d1), b_hi + d0.max(d1));
    (a_lo - m).cmple(b_hi).all() && (b_lo - m).cmple(a_hi).all()
}

/// A touch `s` in `[s_min, s_max]` found cheaply (or `None`): the moving object's deepest
/// vertex against the fixed mesh, and the fixed object's deepest vertex against the moving
/// mesh, each by one parry ray cast from the far end of the range.
fn seed_first_touch(
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
    s_min: f64,
    s_max: f64,
) -> Option<f64> {
    let span = s_max - s_min;
    if !(span.is_finite() && span >= 0.0) {
        return None;
    }
    let inv = fr.rot.conjugate();
    let mut best: Option<f64> = None;
    // Moving vertex p walked back by s sits at p - s u: from p - s_max u toward +u.
    let v = support_vertex(moving, (inv * fr.u).as_vec3());
    let p = fr.moving_point(moving.vertices()[v as usize]);
    let ray = Ray::new((p - s_max * fr.u).as_vec3(), fr.u.as_vec3());
    if let Some(t) = fixed.trimesh().cast_local_ray(&ray, span as Real, false) {
        best = Some(s_max - t as f64);
    }
    // Fixed vertex q against the moving mesh walked back by s: in the moving frame q sits at
    // q' + s u', from q' + s_max u' toward -u'.
    let w = support_vertex(fixed, (-fr.u).as_vec3());
    let q = inv * (fixed.vertices()[w as usize].as_dvec3() - fr.tra);
    let um = inv * fr.u;
    let ray = Ray::new((q + s_max * um).as_vec3(), (-um).as_vec3());
    if let Some(t) = moving.trimesh().cast_local_ray(&ray, span as Real, false) {
        let s = s_max - t as f64;
        best = Some(best.map_or(s, |b: f64| b.max(s)));
    }
    best
}

/// Largest `s` at which triangle `b`, moved by `s d` (unit `d`), can still meet the plane of
/// triangle `a`; `+inf` when `d` is parallel to the plane or `a` is degenerate.
fn plane_bound(a: &[DVec3; 3], b: &[DVec3; 3], d: DVec3) -> f64 {
    let n = (a[1] - a[0]).cross(a[2] - a[0]);
    let nd = n.dot(d);
    if nd.abs() <= 1e-12 * n.length() {
        return f64::INFINITY;
    }
    // Signed distances, oriented so that moving along d decreases them.
    let sign = if nd > 0.0 { -1.0 } else { 1.0 };
    let dist = b.map(|p| sign * n.dot(p - a[0]));
    // b meets the plane while min(dist) - s |nd| <= 0 <= max(dist) - s |nd|.
    dist[0].max(dist[1]).max(dist[2]) / nd.abs()
}

/// All touches of one triangle pair with `s` in `[lo, hi]`, pushed to `ws.events`; returns the
/// largest (or `-inf`).
#[allow(clippy::too_many_arguments)]
fn pair_events(
    ws: &mut Workspace,
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
    tf: u32,
    tm: u32,
    lo: f64,
    hi: f64,
) -> f64 {
    let fi = fixed.indices()[tf as usize];
    let mi = moving.indices()[tm as usize];
    let pf = fixed_tri(fixed, tf);
    let pm = mi.map(|v| moving_pt(ws, moving, fr, v));
    let mut best = f64::NEG_INFINITY;
    let mut push = |ws: &mut Workspace, e: Event| {
        best = best.max(e.s);
        ws.events.push(e);
    };
    for k in 0..3 {
        if let Some((s, bary)) = ray_triangle(pm[k], -fr.u, &pf, lo, hi) {
            let e = Event {
                s,
                point: pm[k] - s * fr.u,
                normal: tri_normal(&pf),
                fixed: tri_feature(fixed, tf, bary),
                moving: Feature::Vertex(mi[k]),
            };
            push(ws, e);
        }
        if let Some((s, bary)) = ray_triangle(pf[k], fr.u, &pm, lo, hi) {
            let e = Event {
                s,
                point: pf[k],
                normal: tri_normal(&pm),
                fixed: Feature::Vertex(fi[k]),
                moving: tri_feature(moving, tm, bary),
            };
            push(ws, e);
        }
    }
    for i in 0..3 {
        let (p0, p1) = (pm[i], pm[(i + 1) % 3]);
        for j in 0..3 {
            let (q0, q1) = (pf[j], pf[(j + 1) % 3]);
            if let Some((s, alpha, beta, n)) = edge_edge(p0, p1, q0, q1, fr.u, lo, hi) {
                let e = Event {
                    s,
                    point: q0 + beta * (q1 - q0),
                    normal: n,
                    fixed: edge_feature([fi[j], fi[(j + 1) % 3]], beta),
                    moving: edge_feature([mi[i], mi[(i + 1) % 3]], alpha),
                };
                push(ws, e);
            }
        }
    }
    best
}

/// Moves boxes of the moving tree into the fixed frame and intersects them with boxes of the
/// fixed tree along the ray, with the rotation matrices and `1/u` computed once per query.
struct BoxTransform {
    rot: glamx::Mat3,
    abs_rot: glamx::Mat3,
    tra: Vector,
    inv_u: Vector,
    u: Vector,
    margin: Real,
}

impl BoxTransform {
    fn new(pos12: &Pose, u: Vector, margin: Real) -> Self {
        let rot = glamx::Mat3::from_quat(pos12.rotation);
        let abs_rot = glamx::Mat3::from_cols(rot.x_axis.abs(), rot.y_axis.abs(), rot.z_axis.abs());
        Self {
            rot,
            abs_rot,
            tra: pos12.translation,
            inv_u: u.recip(),
            u,
            margin,
        }
    }

    /// The interval of `s` over which moving box `nm`, walked back by `s` along `-u`, overlaps
    /// fixed box `nf` (both loosened by the margin).
    #[inline]
    fn overlap_interval(&self, nm: &BvhNode, nf: &BvhNode) -> Option<(Real, Real)> {
        let (mmin, mmax) = (nm.mins(), nm.maxs());
        let c = self.rot * ((mmin + mmax) * 0.5) + self.tra;
        let h = self.abs_rot * ((mmax - mmin) * 0.5) + Vector::splat(2.0 * self.margin);
        let (fmin, fmax) = (nf.mins(), nf.maxs());
        // Need (c - h) - s u <= fmax and (c + h) - s u >= fmin, per axis.
        let a = (c - h - fmax) * self.inv_u;
        let b = (c + h - fmin) * self.inv_u;
        let (mut lo, mut hi) = (Real::NEG_INFINITY, Real::INFINITY);
        for k in 0..3 {
            if self.u[k].abs() < 1e-12 {
                if c[k] - h[k] > fmax[k] || c[k] + h[k] < fmin[k] {
                    return None;
                }
                continue;
            }
            let (l, r) = if self.u[k] > 0.0 {
                (a[k], b[k])
            } else {
                (b[k], a[k])
            };
            lo = lo.max(l);
            hi = hi.min(r);
        }
        (lo <= hi).then_some((lo, hi))
    }
}

/// The interval of `s` over which the moving mesh's box (walked back by `s`) overlaps the fixed
/// mesh's box.
fn aabb_overlap_range(fixed: &TouchMesh, moving: &TouchMesh, fr: &Frame) -> Option<(f64, f64)> {
    let f = fixed.local_aabb();
    let pos12 = fr.pose12();
    let m = moving.local_aabb().transform_by(&pos12);
    let pad = fr.tol * 4.0 + 1e-5 * (f.extents().length() as f64).max(1e-12);
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        let (fmn, fmx) = (f.mins[k] as f64 - pad, f.maxs[k] as f64 + pad);
        let (mmn, mmx) = (m.mins[k] as f64, m.maxs[k] as f64);
        let uk = fr.u[k];
        // Need mmn - s uk <= fmx and mmx - s uk >= fmn.
        if uk.abs() < 1e-15 {
            if mmn > fmx || mmx < fmn {
                return None;
            }
            continue;
        }
        let a = (mmn - fmx) / uk;
        let b = (mmx - fmn) / uk;
        let (l, h) = if uk > 0.0 { (a, b) } else { (b, a) };
        lo = lo.max(l);
        hi = hi.min(h);
    }
    (lo <= hi).then_some((lo, hi))
}

fn moving_pt(ws: &mut Workspace, moving: &TouchMesh, fr: &Frame, v: u32) -> DVec3 {
    let i = v as usize;
    if ws.m_pt_stamp[i] != fr.stamp {
        ws.m_pt_stamp[i] = fr.stamp;
        ws.m_pts[i] = fr.moving_point(moving.vertices()[i]);
    }
    ws.m_pts[i]
}

fn fixed_tri(fixed: &TouchMesh, t: u32) -> [DVec3; 3] {
    fixed.indices()[t as usize].map(|v| fixed.vertices()[v as usize].as_dvec3())
}

pub(crate) fn tri_normal(t: &[DVec3; 3]) -> DVec3 {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero()
}

/// Ray `o + s d` (unit `d`) against triangle `t`: `(s, [α, β, γ])` when it hits with `s` in
/// range. Parallel rays (no single crossing) return `None`.
pub(crate) fn ray_triangle(
    o: DVec3,
    d: DVec3,
    t: &[DVec3; 3],
    s_min: f64,
    s_max: f64,
) -> Option<(f64, [f64; 3])> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det.abs() <= 1e-10 * e1.length() * e2.length() {
        return None;
    }
    let inv = 1.0 / det;
    let sv = o - t[0];
    let b = inv * sv.dot(h);
    if !(-BARY_EPS..=1.0 + BARY_EPS).contains(&b) {
        return None;
    }
    let q = sv.cross(e1);
    let c = inv * d.dot(q);
    if c < -BARY_EPS || b + c > 1.0 + BARY_EPS {
        return None;
    }
    let s = inv * e2.dot(q);
    (s >= s_min && s <= s_max).then_some((s, [1.0 - b - c, b, c]))
}

/// Edges `p0 p1` (moving, walked back by `s` along `-u`) and `q0 q1` (fixed): the `s` at
/// which they cross, with the parameters along each edge and the unit normal `e × f`.
pub(crate) fn edge_edge(
    p0: DVec3,
    p1: DVec3,
    q0: DVec3,
    q1: DVec3,
    u: DVec3,
    s_min: f64,
    s_max: f64,
) -> Option<(f64, f64, f64, DVec3)> {
    let e = p1 - p0;
    let f = q1 - q0;
    let n = e.cross(f);
    let det = n.dot(u);
    // Parallel to the motion (or to each other): no single crossing. Also rejects n = 0.
    if det * det <= 1e-20 * e.length_squared() * f.length_squared() {
        return None;
    }
    let w = q0 - p0;
    let inv = 1.0 / det;
    // The range of s is the most selective test: first. (e · (f × w) = w · n.)
    let s = -w.dot(n) * inv;
    if !(s >= s_min && s <= s_max) {
        return None;
    }
    let alpha = w.dot(f.cross(u)) * inv;
    if !(-BARY_EPS..=1.0 + BARY_EPS).contains(&alpha) {
        return None;
    }
    let beta = -e.dot(w.cross(u)) * inv;
    if !(-BARY_EPS..=1.0 + BARY_EPS).contains(&beta) {
        return None;
    }
    Some((
        s,
        alpha.clamp(0.0, 1.0),
        beta.clamp(0.0, 1.0),
        n.normalize(),
    ))
}

/// Snaps a point given by barycentric coordinates on internal triangle `t` to the feature it
/// lies on.
pub(crate) fn tri_feature(mesh: &TouchMesh, t: u32, bary: [f64; 3]) -> Feature {
    const SNAP: f64 = 1.0e-7;
    let idx = mesh.indices()[t as usize];
    let mut on = [0usize; 3];
    let mut n = 0;
    for (k, &b) in bary.iter().enumerate() {
        if b > SNAP {
            on[n] = k;
            n += 1;
        }
    }
    match n {
        1 => Feature::Vertex(idx[on[0]]),
        2 => {
            let (x, y) = (idx[on[0]], idx[on[1]]);
            Feature::Edge([x.min(y), x.max(y)])
        }
        _ => Feature::Face(t),
    }
}

fn edge_feature(e: [u32; 2], t: f64) -> Feature {
    const SNAP: f64 = 1.0e-7;
    if t <= SNAP {
        Feature::Vertex(e[0])
    } else if t >= 1.0 - SNAP {
        Feature::Vertex(e[1])
    } else {
        Feature::Edge([e[0].min(e[1]), e[0].max(e[1])])
    }
}

/// Do two triangles cross transversally (deeper than `tol`)? Touching along a vertex, an edge
/// or a face is not a crossing.
fn triangles_cross(a: &[DVec3; 3], b: &[DVec3; 3], tol: f64) -> bool {
    edges_cross_triangle(a, b, tol) || edges_cross_triangle(b, a, tol)
}

/// Does an edge of `b` cross the interior of triangle `a`, with both ends farther than `tol`
/// from its plane?
fn edges_cross_triangle(a: &[DVec3; 3], b: &[DVec3; 3], tol: f64) -> bool {
    let n = (a[1] - a[0]).cross(a[2] - a[0]);
    let nl = n.length();
    if nl == 0.0 {
        return false;
    }
    let n = n / nl;
    let d = b.map(|p| n.dot(p - a[0]));
    if (d[0] > -tol && d[1] > -tol && d[2] > -tol) || (d[0] < tol && d[1] < tol && d[2] < tol) {
        return false;
    }
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        if (d[i] < -tol && d[j] > tol) || (d[i] > tol && d[j] < -tol) {
            let x = b[i] + (b[j] - b[i]) * (d[i] / (d[i] - d[j]));
            if point_strictly_in_triangle(x, a, n, tol) {
                return true;
            }
        }
    }
    false
}

/// Is `x` (on the plane of `t`) inside `t` by more than `tol` from every edge?
fn point_strictly_in_triangle(x: DVec3, t: &[DVec3; 3], n: DVec3, tol: f64) -> bool {
    for k in 0..3 {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        let edge = q - p;
        let len = edge.length();
        if len == 0.0 {
            return false;
        }
        // Signed distance from the edge, positive inside.
        if n.cross(edge).dot(x - p) / len <= tol {
            return false;
        }
    }
    true
}

/// Is a sample point of `sampled` (mapped by `to_other`) inside the closed mesh `other`?
/// Tries a few triangle centroids; `None` if every sample was ambiguous.
fn sample_inside(
    sampled: &TouchMesh,
    other: &TouchMesh,
    to_other: impl Fn(Vector) -> DVec3,
) -> Option<bool> {
    let n = sampled.num_triangles();
    for k in 0..n.min(4) {
        let t = (k * n / n.clamp(1, 4)) as u32;
        let [a, b, c] = sampled.indices()[t as usize].map(|v| sampled.vertices()[v as usize]);
        let centroid = (a + b + c) / 3.0;
        if let Some(inside) = point_in_closed_mesh(other, to_other(centroid)) {
            return Some(inside);
        }
    }
    None
}

/// Is `p` (mesh frame) inside the closed mesh and farther than `tol` from its surface?
fn deep_inside(mesh: &TouchMesh, p: DVec3, tol: f64) -> bool {
    point_in_closed_mesh(mesh, p) == Some(true)
        && mesh
            .trimesh()
            .project_local_point_with_max_dist(p.as_vec3(), false, tol as Real)
            .is_none_or(|q| q.point.as_dvec3().distance(p) > tol)
}

/// Parity test for a point in the local frame of a closed mesh. `None` if the ray grazes an
/// edge or the point is on the surface (ambiguous); the caller tries another point.
pub(crate) fn point_in_closed_mesh(mesh: &TouchMesh, p: DVec3) -> Option<bool> {
    const DIRS: [[f64; 3]; 3] = [
        [0.539_163, 0.617_213, 0.573_025],
        [-0.283_111, 0.911_711, -0.297_514],
        [0.712_345, -0.100_113, -0.694_610],
    ];
    let aabb = mesh.local_aabb();
    let pf = p.as_vec3();
    if !aabb.contains_local_point(pf) {
        return Some(false);
    }
    let reach = aabb.extents().length() as f64 * 2.0 + 1.0;
    let eps = 1e-9 * mesh.scale() as f64;
    'dirs: for d in DIRS {
        let d = DVec3::from(d).normalize();
        let ray = Ray::new(pf, d.as_vec3());
        let mut count = 0u32;
        let mut ambiguous = false;
        mesh.bvh().traverse(|node| {
            if ambiguous {
                return TraversalAction::EarlyExit;
            }
            let b = node.aabb().loosened(1e-4 * mesh.scale());
            if !b.intersects_local_ray(&ray, reach as Real) {
                return TraversalAction::Prune;
            }
            if let Some(t) = node.leaf_data() {
                let tri = fixed_tri(mesh, t);
                if let Some((s, bary)) = ray_triangle(p, d, &tri, -eps, reach) {
                    if s.abs() <= eps || bary.iter().any(|&x| x.abs() < 1e-7) {
                        ambiguous = true;
                    } else {
                        count += 1;
                    }
                }
            }
            TraversalAction::Continue
        });
        if ambiguous {
            continue 'dirs;
        }
        return Some(count % 2 == 1);
    }
    None
}
