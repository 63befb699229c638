//! What the crate reports after each step.

use crate::geometry::{ContactConfiguration, ContactKind, ContactPatch, TouchState};
use crate::math::{Pose, Real, Vector};
use rapier3d::geometry::ColliderHandle;

/// One reconstructed pair after a step: what the paper showed on screen.
///
/// # Example
/// A box falling at 60 m/s (1 m per step) goes through a 10 cm slab during its second step
/// (rapier's CCD off). The report of that step says it went through, how far back its first
/// touch lies and which faces touch; the guard has already put the box back on the slab:
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// let mut world = PhysicsWorld::default();
/// TouchPipeline::configure(&mut world.integration_parameters);
/// world.integration_parameters.max_ccd_substeps = 0;
/// let hooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;
/// let slab = ColliderBuilder::cuboid(2.0, 0.05, 2.0).active_hooks(hooks);
/// let slab = world.insert_collider(slab, None);
/// let body = world.insert_body(
///     RigidBodyBuilder::dynamic()
///         .translation(Vector::new(0.0, 1.5, 0.0))
///         .linvel(Vector::new(0.0, -60.0, 0.0)),
/// );
/// let cube = ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(hooks);
/// let cube = world.insert_collider(cube, Some(body));
/// let mut touch = TouchPipeline::default();
/// touch.step(&mut world); // y = 0.5: still above the slab
/// assert!(touch.reports().is_empty());
/// touch.step(&mut world); // y ≈ -0.5: through the slab
///
/// let report = touch.reports().iter().find(|r| r.moving == cube).unwrap();
/// assert_eq!(report.fixed, slab);
/// assert_eq!(report.state, TouchState::Perforated);
/// assert!(report.on_trajectory);
/// // First touch was on the way down, with the cube's centre at y = 0.3: straight up, ~0.8 m.
/// assert!(report.reversing_vector.x.abs() < 1e-4 && report.reversing_vector.z.abs() < 1e-4);
/// assert!((report.depth - 0.8).abs() < 0.02);
/// // Face on face: the cube's bottom square on the slab's top, normal up.
/// assert_eq!(report.kinds(), [ContactKind::Face]);
/// assert!((report.patches[0].normal - Vector::Y).length() < 1e-4);
/// assert_eq!(report.patches[0].polygon.len(), 4);
/// assert!(report.patches[0].polygon.iter().all(|p| (p.y - 0.05).abs() < 1e-4));
/// // The guard has moved the cube back along its path: it stands on the slab.
/// assert!((world.bodies[body].translation().y - 0.3).abs() < 1e-3);
/// ```
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
///
/// # Example
/// A kinematic cube tool (10 cm half side) driven 50 cm into a fixed slab stops on it; the
/// feedback offset is how deep the device went:
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// let mut world = PhysicsWorld::default();
/// TouchPipeline::configure(&mut world.integration_parameters);
/// let hooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;
/// let slab = ColliderBuilder::cuboid(2.0, 0.5, 2.0).translation(Vector::new(0.0, -0.5, 0.0));
/// world.insert_collider(slab.active_hooks(hooks), None);
/// let start = Vector::new(0.0, 0.5, 0.0);
/// let tool = world.insert_body(RigidBodyBuilder::kinematic_position_based().translation(start));
/// let cube = ColliderBuilder::cuboid(0.1, 0.1, 0.1).active_hooks(hooks);
/// world.insert_collider(cube, Some(tool));
/// let mut touch = TouchPipeline::default();
/// let mut device = Pose::from_translation(start);
/// for _ in 0..20 {
///     device.translation.y -= 0.05; // the device goes down to y = -0.5
///     touch.set_tool_target(tool, device);
///     touch.step(&mut world);
/// }
///
/// let feedback = touch.tool_feedback(tool).unwrap();
/// assert_eq!(feedback.device, device);
/// // The proxy stands on the slab (its bottom face at y = 0), and so does the tool's body.
/// assert!((feedback.proxy.translation.y - 0.1).abs() < 1e-3);
/// assert!((world.bodies[tool].translation().y - 0.1).abs() < 1e-3);
/// // A spring of 200 N/m pulls the device back up toward the proxy: 120 N.
/// let force = 200.0 * feedback.offset;
/// assert!((force - Vector::new(0.0, 120.0, 0.0)).length() < 0.5);
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ToolFeedback {
    /// Where the device put the tool.
    pub device: Pose,
    /// Where the crate let the tool be.
    pub proxy: Pose,
    /// `proxy.translation - device.translation`.
    pub offset: Vector,
}
