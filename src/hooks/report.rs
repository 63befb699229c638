//! What the crate reports after each step.

use crate::geometry::{ContactConfiguration, ContactKind, ContactPatch, TouchState};
use crate::math::{Pose, Real, Vector};
use rapier3d::geometry::ColliderHandle;

/// One reconstructed pair after a step: what the paper showed on screen.
#[derive(Clone, Debug, PartialEq)]
pub struct PairReport {
    /// The collider taken as fixed (the partner).
    pub fixed: ColliderHandle,
    /// The collider that was walked back (on the moving body).
    pub moving: ColliderHandle,
    /// Touching, penetrating or perforated, as found right after rapier's step (before the
    /// guard's correction).
    pub state: TouchState,
    /// The translation that brought (or would bring) the moving collider back to first touch.
    pub reversing_vector: Vector,
    /// `|reversing_vector|`.
    pub depth: Real,
    /// `true` when the first touch lies on the last step's path. `false` for a pair that
    /// already overlapped when the step began (a resting contact): it is then reported along
    /// rapier's contact normal.
    pub on_trajectory: bool,
    /// The contact regions at first touch, with kinds, points and features.
    pub patches: Vec<ContactPatch>,
}

impl PairReport {
    pub(crate) fn new(
        fixed: ColliderHandle,
        moving: ColliderHandle,
        c: &ContactConfiguration,
    ) -> Self {
        Self {
            fixed,
            moving,
            state: c.state,
            reversing_vector: c.reversing_vector,
            depth: c.depth,
            on_trajectory: c.on_trajectory,
            patches: c.patches.clone(),
        }
    }

    /// The contact kinds of the patches.
    pub fn kinds(&self) -> Vec<ContactKind> {
        self.patches.iter().map(|p| p.kind).collect()
    }
}

/// A tool's device pose, its proxy (the last pose that does not penetrate), and the offset
/// between them: `k * offset` is a spring feedback force toward the proxy for a haptic device.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ToolFeedback {
    /// Where the device put the tool.
    pub device: Pose,
    /// Where the crate let the tool be.
    pub proxy: Pose,
    /// `proxy.translation - device.translation`.
    pub offset: Vector,
}
