//! What a reconstruction returns: [`ContactConfiguration`] and its [`ContactPatch`]es.

use super::touch_mesh::Feature;
use crate::math::{Pose, Real, Vector};

/// The configuration of the pair at the current pose (the paper's Fig. 1).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum TouchState {
    /// The surfaces do not meet (and neither object is inside the other).
    Separated,
    /// The surfaces meet without interpenetrating (Fig. 1 b): nothing to correct.
    Touching,
    /// The objects interpenetrate (Fig. 1 a): apply the reversing vector.
    Penetrating,
    /// During the step the moving object passed into and out of the fixed one (Fig. 1 c): the
    /// current pose does not penetrate but the step went through. The reversing vector still
    /// leads back to the first touch; callers should split the step (see
    /// [`crate::geometry::safe_step_length`]) or stop there.
    Perforated,
}

/// How a contact region touches (the paper's vertex, line and polygon contacts).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum ContactKind {
    /// The region is a single point.
    Vertex,
    /// The region is a segment (a line contact).
    Edge,
    /// The region is a polygon (a face contact).
    Face,
}

/// Where the reconstruction's direction of travel came from.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum DirectionSource {
    /// The moving object's own translation over the step (`D`).
    Trajectory,
    /// The object did not translate (`D = 0`): the fallback direction was used (see
    /// [`crate::geometry::ReconstructionOptions::zero_motion_direction`]).
    ZeroMotionFallback,
}

/// One touching point at the first-touch configuration.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ContactPoint {
    /// World-space point, with the moving object at its first-touch pose (current pose plus
    /// the reversing vector).
    pub point: Vector,
    /// The feature of the fixed mesh that touches.
    pub fixed_feature: Feature,
    /// The feature of the moving mesh that touches.
    pub moving_feature: Feature,
}

/// A connected contact region at first touch.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactPatch {
    /// Vertex, edge (line) or face (polygon) contact.
    pub kind: ContactKind,
    /// World-space unit normal, pointing out of the fixed object toward the moving one.
    pub normal: Vector,
    /// The region's shape in world space at first touch: one point for a vertex contact, the
    /// two ends of the segment for an edge contact, the convex polygon (counter-clockwise about
    /// `normal`) for a face contact.
    pub polygon: Vec<Vector>,
    /// Every touching point of the region, with the features on both meshes.
    pub points: Vec<ContactPoint>,
    /// The fixed mesh's features involved (sorted, unique).
    pub fixed_features: Vec<Feature>,
    /// The moving mesh's features involved (sorted, unique).
    pub moving_features: Vec<Feature>,
}

impl ContactPatch {
    /// The centroid of the region's polygon.
    pub fn center(&self) -> Vector {
        self.polygon.iter().copied().sum::<Vector>() / self.polygon.len().max(1) as Real
    }
}

/// The reconstructed contact configuration of a fixed and a moving object.
///
/// Apply [`ContactConfiguration::reversing_vector`] to the moving object's translation to bring
/// it back, along its own trajectory, to the configuration where it first touched.
///
/// # Example
/// A unit cube, half over the edge of a slab whose top is at `y = 0`, fell from `y = 0.8` to
/// `y = 0.3` over the step and sinks 0.2 m into it: it first touched at 60 % of the step, centre
/// at `y = 0.5`, with the half of its bottom face that lies over the slab.
/// ```
/// use rapier_touch::prelude::*;
/// let slab = TouchMesh::from_shape(&Cuboid::new(Vector::new(1.0, 0.5, 1.0))).unwrap();
/// let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.5))).unwrap();
/// let slab_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
/// let now = Pose::from_translation(Vector::new(1.0, 0.3, 0.0));
/// let before = Pose::from_translation(Vector::new(1.0, 0.8, 0.0));
/// let c = Reconstructor::default()
///     .reconstruct(&slab, &slab_pose, &cube, &now, &before)
///     .unwrap();
/// assert_eq!(c.state, TouchState::Penetrating);
/// assert_eq!(c.direction_source, DirectionSource::Trajectory);
/// assert!((c.direction - Vector::NEG_Y).length() < 1e-6);
/// assert!(c.on_trajectory);
/// assert!((c.time_of_impact.unwrap() - 0.6).abs() < 1e-4);
/// assert!((c.depth - 0.2).abs() < 1e-5);
/// assert!((c.touch_pose.translation - Vector::new(1.0, 0.5, 0.0)).length() < 1e-5);
/// // The touching region: the half of the cube's bottom that lies over the slab.
/// let patch = &c.patches[0];
/// assert_eq!(patch.kind, ContactKind::Face);
/// assert!((patch.center() - Vector::new(0.75, 0.0, 0.0)).length() < 1e-4);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ContactConfiguration {
    /// The configuration at the current pose.
    pub state: TouchState,
    /// World-space translation that takes the moving object from its current pose back to first
    /// touch. Parallel to `-D` (zero when separated or touching). When the object also turned
    /// over the step, it is the translation part of the way back to
    /// [`ContactConfiguration::touch_pose`], which also restores the orientation.
    pub reversing_vector: Vector,
    /// `|reversing_vector|`: the penetration depth measured along the trajectory (the paper's
    /// maximum `d_ij`). When the object also turned, the largest distance a touching point of
    /// the moving object travelled from first touch to its current place.
    pub depth: Real,
    /// World-space unit direction of travel `D_u` the reconstruction used.
    pub direction: Vector,
    /// Whether `direction` is the object's own motion or the zero-motion fallback.
    pub direction_source: DirectionSource,
    /// `true` when the first touch lies on this step's trajectory. `false` when the object
    /// already penetrated at the start of the step (or only its rotation caused the
    /// penetration): the reversing vector then goes back past the start of the step, to the
    /// nearest non-penetrating pose along `-D`.
    pub on_trajectory: bool,
    /// Fraction of the step at which the first touch happened (0 = previous pose, 1 = current
    /// pose); `None` when it is not on this step's trajectory or the state is `Separated`.
    pub time_of_impact: Option<Real>,
    /// The moving object's world pose at first touch. For a translation (the paper's case) it
    /// is the current pose moved by [`ContactConfiguration::reversing_vector`]; when the object
    /// also turned over the step it is the pose on its path
    /// ([`crate::geometry::RigidMotion`]) where it first touched, orientation included: set
    /// the object there to undo the penetration. The current pose when nothing is to undo.
    pub touch_pose: Pose,
    /// The contact regions at first touch (several for non-convex objects touching in several
    /// places). Empty when separated.
    pub patches: Vec<ContactPatch>,
    /// Number of candidate triangle pairs the BVHs let through (a measure of the work done).
    pub candidate_pairs: usize,
}

impl ContactConfiguration {
    /// A configuration with nothing found yet: separated, nothing to undo, the moving object
    /// at `pose`.
    pub(crate) fn separated(
        direction: Vector,
        direction_source: DirectionSource,
        on_trajectory: bool,
        pose: Pose,
    ) -> Self {
        Self {
            state: TouchState::Separated,
            reversing_vector: Vector::ZERO,
            depth: 0.0,
            direction,
            direction_source,
            on_trajectory,
            time_of_impact: None,
            touch_pose: pose,
            patches: Vec::new(),
            candidate_pairs: 0,
        }
    }

    /// `true` if the state is [`TouchState::Penetrating`] or [`TouchState::Perforated`]: the
    /// current pose must be corrected.
    pub fn needs_correction(&self) -> bool {
        matches!(self.state, TouchState::Penetrating | TouchState::Perforated)
    }
}
