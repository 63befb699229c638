//! [`PhysicsSets`]: rapier's individual sets, as a classic `PhysicsPipeline::step` loop keeps
//! them, for everything in this crate that takes a `PhysicsWorld`.

use crate::math::Vector;
use rapier3d::dynamics::{
    CCDSolver, ImpulseJointSet, IntegrationParameters, IslandManager, MultibodyJointSet,
    RigidBodySet, SoftBodySet,
};
use rapier3d::geometry::{BroadPhaseBvh, ColliderSet, NarrowPhase};
use rapier3d::pipeline::{PhysicsPipeline, PhysicsWorld};

/// rapier's sets, borrowed from a classic loop (the arguments of `PhysicsPipeline::step`),
/// so that [`crate::hooks::TouchPipeline`], [`crate::coupling::SurfaceSet`] and the rest of
/// the crate run on them exactly as on a `PhysicsWorld`.
///
/// [`PhysicsSets::with_world`] moves the sets into a `PhysicsWorld` for the call and back out
/// after it: no copy of their contents, the same results as the `PhysicsWorld` front
/// (`tests/it/classic_loop.rs` checks it pose for pose).
///
/// # Example
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// let (mut bodies, mut colliders) = (RigidBodySet::new(), ColliderSet::new());
/// let (mut islands, mut broad_phase, mut narrow_phase) =
///     (IslandManager::new(), DefaultBroadPhase::default(), NarrowPhase::new());
/// let (mut impulse_joints, mut multibody_joints) = (ImpulseJointSet::new(), MultibodyJointSet::new());
/// let (mut soft_bodies, mut ccd_solver) = (SoftBodySet::default(), CCDSolver::new());
/// let mut pipeline = PhysicsPipeline::new();
/// let mut params = IntegrationParameters::default();
/// TouchPipeline::configure(&mut params);
///
/// let floor = colliders.insert(ColliderBuilder::cuboid(5.0, 0.01, 5.0));
/// let body = bodies.insert(
///     RigidBodyBuilder::dynamic()
///         .translation(Vector::new(0.0, 2.0, 0.0))
///         .linvel(Vector::new(0.0, -50.0, 0.0)),
/// );
/// colliders.insert_with_parent(ColliderBuilder::cuboid(0.2, 0.2, 0.2), body, &mut bodies);
///
/// let mut touch = TouchPipeline::default();
/// touch.track_collider(floor);
/// for _ in 0..60 {
///     let mut sets = PhysicsSets {
///         gravity: Vector::new(0.0, -9.81, 0.0),
///         integration_parameters: &mut params,
///         physics_pipeline: &mut pipeline,
///         islands: &mut islands,
///         broad_phase: &mut broad_phase,
///         narrow_phase: &mut narrow_phase,
///         bodies: &mut bodies,
///         colliders: &mut colliders,
///         impulse_joints: &mut impulse_joints,
///         multibody_joints: &mut multibody_joints,
///         soft_bodies: &mut soft_bodies,
///         ccd_solver: &mut ccd_solver,
///     };
///     sets.with_world(|world| touch.step(world));
/// }
/// // A 50 m/s box on a 2 cm floor: stopped on it.
/// assert!((bodies[body].translation().y - 0.21).abs() < 1e-3);
/// ```
pub struct PhysicsSets<'a> {
    /// Gravity.
    pub gravity: Vector,
    /// The integration parameters (the crate reads them; [`crate::hooks::TouchPipeline`]'s
    /// `configure` sets them).
    pub integration_parameters: &'a mut IntegrationParameters,
    /// rapier's pipeline.
    pub physics_pipeline: &'a mut PhysicsPipeline,
    /// The island manager.
    pub islands: &'a mut IslandManager,
    /// The broad phase.
    pub broad_phase: &'a mut BroadPhaseBvh,
    /// The narrow phase.
    pub narrow_phase: &'a mut NarrowPhase,
    /// The rigid bodies.
    pub bodies: &'a mut RigidBodySet,
    /// The colliders.
    pub colliders: &'a mut ColliderSet,
    /// The impulse joints.
    pub impulse_joints: &'a mut ImpulseJointSet,
    /// The multibody joints.
    pub multibody_joints: &'a mut MultibodyJointSet,
    /// rapier's own soft bodies.
    pub soft_bodies: &'a mut SoftBodySet,
    /// The CCD solver.
    pub ccd_solver: &'a mut CCDSolver,
}

impl std::fmt::Debug for PhysicsSets<'_> {
    /// The gravity and the sizes of the sets (rapier's workspaces have no `Debug`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhysicsSets")
            .field("gravity", &self.gravity)
            .field("bodies", &self.bodies.len())
            .field("colliders", &self.colliders.len())
            .finish_non_exhaustive()
    }
}

impl PhysicsSets<'_> {
    /// Runs `f` on a `PhysicsWorld` holding these sets (moved in, and back out when `f`
    /// returns): call any of the crate's `PhysicsWorld` functions on a classic loop's sets.
    pub fn with_world<R>(&mut self, f: impl FnOnce(&mut PhysicsWorld) -> R) -> R {
        use std::mem::take;
        let mut world = PhysicsWorld {
            gravity: self.gravity,
            integration_parameters: *self.integration_parameters,
            physics_pipeline: take(self.physics_pipeline),
            islands: take(self.islands),
            broad_phase: take(self.broad_phase),
            narrow_phase: take(self.narrow_phase),
            bodies: take(self.bodies),
            colliders: take(self.colliders),
            impulse_joints: take(self.impulse_joints),
            multibody_joints: take(self.multibody_joints),
            soft_bodies: take(self.soft_bodies),
            ccd_solver: take(self.ccd_solver),
            ..PhysicsWorld::default()
        };
        let out = f(&mut world);
        self.gravity = world.gravity;
        *self.integration_parameters = world.integration_parameters;
        *self.physics_pipeline = world.physics_pipeline;
        *self.islands = world.islands;
        *self.broad_phase = world.broad_phase;
        *self.narrow_phase = world.narrow_phase;
        *self.bodies = world.bodies;
        *self.colliders = world.colliders;
        *self.impulse_joints = world.impulse_joints;
        *self.multibody_joints = world.multibody_joints;
        *self.soft_bodies = world.soft_bodies;
        *self.ccd_solver = world.ccd_solver;
        out
    }
}
