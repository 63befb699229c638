//! The bevy plugin (`--features bevy`): the crate inside bevy_rapier3d 0.37's schedule.
//!
//! bevy_rapier keeps rapier's sets in components of its context entity and steps them in
//! [`PhysicsSet::StepSimulation`]. [`RapierTouchPlugin`] runs the crate around that step, on
//! the same sets (lent as a `PhysicsWorld` through [`crate::hooks::PhysicsSets`], no copy):
//! - before it ([`TouchSystems::BeforeStep`], after bevy_rapier has created the handles of new
//!   entities): registers [`TouchTracked`] colliders, attaches [`SoftSurface`]s, registers
//!   [`SurfaceTool`]s and [`HapticTool`]s, records where the bodies and tools start the
//!   step, and moves each haptic tool to its servo loop's latest proxy;
//! - during it, the crate's hooks, through bevy_rapier's own hook mechanism:
//!   `RapierPhysicsPlugin::<TouchPhysicsHooks>`;
//! - after it ([`TouchSystems::AfterStep`], before bevy_rapier writes the transforms back):
//!   the step guard, then the surfaces' substeps; each tool's reaction is written into its
//!   [`SurfaceToolReaction`], each surface into its entity's [`Mesh3d`], if it has one, and
//!   each haptic tool's model goes to its servo loop ([`crate::haptics`]).
//!
//! The plugin uses bevy's headless parts only (the ECS, transforms and `Mesh` assets).
//!
//! # Time step
//! The guard walks back one rigid step and a surface's filter is factorized for one step
//! length, so the plugin sets bevy_rapier's [`TimestepMode`] to `Fixed` with one substep (the
//! `dt` of [`RapierTouchPlugin::with_dt`], 1/60 s by default). Another mode is reported once
//! with a `log` warning; the guard then reads the whole frame as one motion.
//!
//! # Limitations
//! - Your own [`BevyPhysicsHooks`] cannot be stacked under the crate's by the type system as
//!   [`crate::hooks::TouchHooks`] stacks rapier hooks: make `TouchPhysicsHooks` a field of your
//!   hooks' `SystemParam` and call its methods from yours.
//! - [`crate::coupling::SurfaceSet::add_tool`] takes a solver group off the tool's collider;
//!   a later change of that entity's `SolverGroups` component puts it back.
//! - A dynamic tool is moved by the surfaces in the same step, its mass in their solve (as
//!   without bevy: [`crate::coupling::SurfaceSet`]'s docs), after rapier's step and before
//!   bevy_rapier's writeback copies the bodies to their transforms.
//! - The default context only ([`DefaultRapierContext`]).
//!
//! # Example
//! A tracked floor, a fast box that must not go through it, and a ball tool pressing a soft
//! plate, stepped headless for a second:
//! ```
//! use bevy::prelude::*;
//! use bevy::time::TimeUpdateStrategy;
//! use bevy_rapier3d::prelude::*;
//! use rapier_touch::bevy_plugin::*;
//! use rapier_touch::prelude::{AttachOptions, MassSpringSurfaceBuilder};
//! use rapier_touch::surface::meshing::{plate, plate_rim};
//!
//! let mut app = App::new();
//! app.add_plugins((MinimalPlugins, TransformPlugin))
//!     .add_plugins(RapierPhysicsPlugin::<TouchPhysicsHooks>::default())
//!     .add_plugins(RapierTouchPlugin::default())
//!     .insert_resource(TimeUpdateStrategy::ManualDuration(
//!         std::time::Duration::from_secs_f32(1.0 / 60.0),
//!     ));
//!
//! // Both sides of a guarded pair opt in, as with `TouchPipeline::track_collider`.
//! app.world_mut().spawn((Collider::cuboid(5.0, 0.01, 5.0), TouchTracked));
//! let cube = app
//!     .world_mut()
//!     .spawn((
//!         RigidBody::Dynamic,
//!         Collider::cuboid(0.1, 0.1, 0.1),
//!         Velocity::linear(Vec3::new(0.0, -60.0, 0.0)),
//!         Transform::from_xyz(0.0, 1.0, 0.0),
//!         TouchTracked,
//!     ))
//!     .id();
//!
//! let soft = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 8, 8))
//!     .pinned(plate_rim(8, 8))
//!     .build()
//!     .unwrap();
//! let options = AttachOptions { substeps: 4, collider: true };
//! app.world_mut().spawn((
//!     RigidBody::Fixed,
//!     Transform::from_xyz(3.0, 1.0, 0.0),
//!     SoftSurface::new(soft, options),
//! ));
//! let ball = app
//!     .world_mut()
//!     .spawn((
//!         RigidBody::KinematicPositionBased,
//!         Collider::ball(0.05),
//!         SurfaceTool,
//!         Transform::from_xyz(3.0, 1.1, 0.0),
//!     ))
//!     .id();
//!
//! for frame in 1..=60 {
//!     let y = (1.1 - 0.005 * frame as f32).max(1.03);
//!     app.world_mut().get_mut::<Transform>(ball).unwrap().translation.y = y;
//!     app.update();
//! }
//! // A 60 m/s box on a 2 cm floor: resting on it, not through it.
//! let y = app.world().get::<Transform>(cube).unwrap().translation.y;
//! assert!((y - 0.11).abs() < 0.01, "{y}");
//! // The plate pushes the ball back up.
//! let reaction = app.world().get::<SurfaceToolReaction>(ball).unwrap();
//! assert!(reaction.0.force.y > 0.0);
//! ```

use crate::coupling::{AttachOptions, CouplingError, SurfaceHandle, SurfaceSet, ToolReaction};
use crate::haptics::WorldLink;
use crate::hooks::{PhysicsSets, TouchPipeline};
use crate::math::Real;
use crate::surface::MassSpringSurface;
use bevy::asset::{Assets, RenderAssetUsages};
use bevy::ecs::intern::Interned;
use bevy::ecs::schedule::ScheduleLabel;
use bevy::ecs::system::SystemParam;
use bevy::mesh::{Indices, Mesh, Mesh3d, PrimitiveTopology};
use bevy::prelude::*;
use bevy_rapier3d::pipeline::{
    BevyPhysicsHooks, ContactModificationContextView, PairFilterContextView,
};
use bevy_rapier3d::plugin::context::{
    DefaultRapierContext, RapierContextColliders, RapierContextJoints, RapierContextSimulation,
    RapierRigidBodySet,
};
use bevy_rapier3d::plugin::{PhysicsSet, RapierConfiguration, TimestepMode};
use bevy_rapier3d::prelude::{RapierColliderHandle, RapierRigidBodyHandle};
use parry3d::utils::hashmap::HashMap;
use rapier3d::geometry::{ColliderHandle, SolverFlags};
use rapier3d::pipeline::{PhysicsHooks, PhysicsWorld};

/// The crate's state in a bevy app: the [`TouchPipeline`] (hooks and step guard) and the
/// [`SurfaceSet`], on bevy_rapier's default context. Read it for reports, tool feedback and
/// events; configure [`TouchPipeline::options`] on it.
#[derive(Resource, Debug, Default)]
pub struct TouchWorld {
    /// The hooks, the step guard and the reports.
    pub pipeline: TouchPipeline,
    /// The soft surfaces and their tools.
    pub surfaces: SurfaceSet,
    /// Where the bodies start the step being run (between the two halves of a step).
    prev: Option<crate::hooks::PoseHistory>,
    tracked: HashMap<Entity, ColliderHandle>,
    warned_timestep: bool,
}

/// Marks a collider whose contacts the crate reconstructs and guards (see
/// [`TouchPipeline::track_collider`]): a pair is guarded when both its colliders are tracked
/// (or carry bevy_rapier's `ActiveHooks::MODIFY_SOLVER_CONTACTS`). Removing the component
/// untracks the collider.
#[derive(Component, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct TouchTracked;

/// A soft surface on this entity's rigid body (give the entity a `RigidBody`, usually
/// `Fixed`). The plugin attaches it once bevy_rapier has created the body.
///
/// The surface's positions live in the body's frame, which is the entity's: a [`Mesh3d`] on
/// the same entity shows the deformed surface (the plugin rewrites its positions and normals
/// every frame; [`surface_mesh`] builds the first one).
#[derive(Component, Debug)]
pub struct SoftSurface {
    pending: Option<(MassSpringSurface, AttachOptions)>,
    handle: Option<SurfaceHandle>,
    error: Option<CouplingError>,
}

impl SoftSurface {
    /// A surface to attach with `options`.
    pub fn new(surface: MassSpringSurface, options: AttachOptions) -> Self {
        Self {
            pending: Some((surface, options)),
            handle: None,
            error: None,
        }
    }

    /// The surface's handle in [`TouchWorld::surfaces`], once attached.
    pub fn handle(&self) -> Option<SurfaceHandle> {
        self.handle
    }

    /// Why the surface could not be attached, if it could not (also logged).
    pub fn error(&self) -> Option<&CouplingError> {
        self.error.as_ref()
    }
}

/// Marks a collider as a tool pressing into every soft surface
/// ([`SurfaceSet::add_tool`]). Once registered the entity gets a [`SurfaceToolReaction`];
/// a refused tool gets a [`SurfaceToolRefused`] instead (and a `log` warning).
#[derive(Component, Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct SurfaceTool;

/// What the surfaces push a [`SurfaceTool`] back with after the last step (world frame).
#[derive(Component, Debug, Default, Clone, Copy, PartialEq)]
pub struct SurfaceToolReaction(pub ToolReaction);

/// A tool driven by a haptic device through a servo loop on its own thread
/// ([`crate::haptics::Servo`]): give the entity a `KinematicPositionBased` body and a
/// collider, and this component with the world end of a [`crate::haptics::haptic_link`].
/// The plugin connects it ([`SurfaceSet::connect_haptic`]: it becomes a tool of every
/// surface and gets a [`SurfaceToolReaction`]), moves it to the servo's proxy before each
/// step (its `Transform` is then written back by bevy_rapier; do not set it yourself) and
/// publishes its model after each step. A refused link gets a [`SurfaceToolRefused`].
#[derive(Component, Debug)]
pub struct HapticTool {
    link: Option<WorldLink>,
}

impl HapticTool {
    /// A tool to connect to the servo loop holding the other end of `link`.
    pub fn new(link: WorldLink) -> Self {
        Self { link: Some(link) }
    }
}

/// Why a [`SurfaceTool`] or a [`HapticTool`] was refused.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct SurfaceToolRefused(pub CouplingError);

/// The plugin's system sets, around bevy_rapier's [`PhysicsSet::StepSimulation`].
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TouchSystems {
    /// Registration of new components and the start-of-step records.
    BeforeStep,
    /// The step guard, the surfaces, reactions and meshes.
    AfterStep,
}

/// The crate's hooks as bevy_rapier hooks: add bevy_rapier's plugin as
/// `RapierPhysicsPlugin::<TouchPhysicsHooks>::default()`.
#[derive(SystemParam)]
pub struct TouchPhysicsHooks<'w> {
    touch: Res<'w, TouchWorld>,
}

impl std::fmt::Debug for TouchPhysicsHooks<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TouchPhysicsHooks")
            .field("hooks", &self.touch.pipeline.hooks)
            .finish()
    }
}

impl BevyPhysicsHooks for TouchPhysicsHooks<'_> {
    fn filter_contact_pair(&self, context: PairFilterContextView) -> Option<SolverFlags> {
        self.touch.pipeline.hooks.filter_contact_pair(context.raw)
    }

    fn filter_intersection_pair(&self, context: PairFilterContextView) -> bool {
        self.touch
            .pipeline
            .hooks
            .filter_intersection_pair(context.raw)
    }

    fn modify_solver_contacts(&self, context: ContactModificationContextView) {
        self.touch
            .pipeline
            .hooks
            .modify_solver_contacts(context.raw)
    }
}

/// Adds the crate to a bevy app that has bevy_rapier's `RapierPhysicsPlugin::<TouchPhysicsHooks>`
/// (see the [module](self)).
#[derive(Debug, Clone)]
pub struct RapierTouchPlugin {
    schedule: Interned<dyn ScheduleLabel>,
    dt: Real,
}

impl Default for RapierTouchPlugin {
    /// In `PostUpdate` (bevy_rapier's default schedule), at 60 Hz.
    fn default() -> Self {
        Self {
            schedule: PostUpdate.intern(),
            dt: 1.0 / 60.0,
        }
    }
}

impl RapierTouchPlugin {
    /// Runs the plugin's systems in `schedule`: the one bevy_rapier's plugin runs in.
    pub fn in_schedule(mut self, schedule: impl ScheduleLabel) -> Self {
        self.schedule = schedule.intern();
        self
    }

    /// The rigid step length (s) of the fixed time step the plugin sets.
    pub fn with_dt(mut self, dt: Real) -> Self {
        self.dt = dt;
        self
    }
}

impl Plugin for RapierTouchPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<TouchWorld>()
            .insert_resource(TimestepMode::Fixed {
                dt: self.dt,
                substeps: 1,
            })
            .configure_sets(
                self.schedule,
                (
                    TouchSystems::BeforeStep
                        .after(PhysicsSet::SyncBackend)
                        .before(PhysicsSet::StepSimulation),
                    TouchSystems::AfterStep
                        .after(PhysicsSet::StepSimulation)
                        .before(PhysicsSet::Writeback),
                ),
            )
            .add_systems(
                self.schedule,
                (register, before_step)
                    .chain()
                    .in_set(TouchSystems::BeforeStep),
            )
            .add_systems(
                self.schedule,
                (after_step, write_reactions, write_meshes)
                    .chain()
                    .in_set(TouchSystems::AfterStep),
            );
    }
}

/// A bevy `Mesh` of `surface`'s current shape (its body's frame): positions, smooth normals
/// and its triangles, for a [`Mesh3d`] beside its [`SoftSurface`].
pub fn surface_mesh(surface: &MassSpringSurface) -> Mesh {
    let mut positions = Vec::new();
    surface.positions_into(&mut positions);
    let positions: Vec<[f32; 3]> = positions.iter().map(|p| p.to_array()).collect();
    let indices: Vec<u32> = surface.triangles().iter().flatten().copied().collect();
    let mut mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    );
    mesh.insert_attribute(Mesh::ATTRIBUTE_POSITION, positions);
    mesh.insert_indices(Indices::U32(indices));
    mesh.compute_smooth_normals();
    mesh
}

type ContextQuery<'w, 's> = Query<
    'w,
    's,
    (
        &'static mut RapierContextSimulation,
        &'static mut RapierContextColliders,
        &'static mut RapierContextJoints,
        &'static mut RapierRigidBodySet,
        &'static RapierConfiguration,
    ),
    With<DefaultRapierContext>,
>;

/// The tools not registered (nor refused) yet.
type NewTools<'w, 's> = Query<
    'w,
    's,
    (Entity, &'static RapierColliderHandle),
    (
        With<SurfaceTool>,
        Without<SurfaceToolReaction>,
        Without<SurfaceToolRefused>,
    ),
>;

/// Runs `f` on the default context's sets as a `PhysicsWorld` (moved in and back out).
fn with_context<R>(
    context: &mut ContextQuery,
    f: impl FnOnce(&mut PhysicsWorld) -> R,
) -> Option<R> {
    let (mut sim, mut colliders, mut joints, mut bodies, config) = context.single_mut().ok()?;
    let sim = &mut *sim;
    let joints = &mut *joints;
    let bodies = &mut *bodies;
    let mut sets = PhysicsSets {
        gravity: config.gravity,
        integration_parameters: &mut sim.integration_parameters,
        physics_pipeline: &mut sim.pipeline,
        islands: &mut sim.islands,
        broad_phase: &mut sim.broad_phase,
        narrow_phase: &mut sim.narrow_phase,
        bodies: &mut bodies.bodies,
        colliders: &mut colliders.colliders,
        impulse_joints: &mut joints.impulse_joints,
        multibody_joints: &mut joints.multibody_joints,
        soft_bodies: &mut bodies.soft_bodies,
        ccd_solver: &mut sim.ccd_solver,
    };
    Some(sets.with_world(f))
}

/// Registers new tracked colliders, surfaces and tools (their handles exist by now).
#[allow(clippy::too_many_arguments)]
fn register(
    mut commands: Commands,
    mut touch: ResMut<TouchWorld>,
    mut context: ContextQuery,
    mode: Res<TimestepMode>,
    tracked: Query<(Entity, &RapierColliderHandle), With<TouchTracked>>,
    mut untracked: RemovedComponents<TouchTracked>,
    mut surfaces: Query<(Entity, &mut SoftSurface, &RapierRigidBodyHandle)>,
    tools: NewTools,
    mut haptic: Query<(Entity, &RapierColliderHandle, &mut HapticTool)>,
) {
    let touch = &mut *touch;
    let dt = match *mode {
        TimestepMode::Fixed { dt, substeps: 1 } => Some(dt),
        other => {
            if !touch.warned_timestep {
                log::warn!(
                    "rapier_touch: TimestepMode is {other:?}; the guard and the surfaces expect \
                     TimestepMode::Fixed with one substep"
                );
                touch.warned_timestep = true;
            }
            None
        }
    };
    for e in untracked.read() {
        if let Some(h) = touch.tracked.remove(&e) {
            touch.pipeline.untrack_collider(h);
        }
    }
    for (e, h) in &tracked {
        if touch.tracked.insert(e, h.0) != Some(h.0) {
            touch.pipeline.track_collider(h.0);
        }
    }
    let pending: Vec<Entity> = surfaces
        .iter()
        .filter(|(_, s, _)| s.pending.is_some())
        .map(|(e, _, _)| e)
        .collect();
    let new_tools: Vec<(Entity, ColliderHandle)> = tools.iter().map(|(e, h)| (e, h.0)).collect();
    let links: Vec<(Entity, ColliderHandle, WorldLink)> = haptic
        .iter_mut()
        .filter_map(|(e, h, mut t)| t.link.take().map(|l| (e, h.0, l)))
        .collect();
    if pending.is_empty() && new_tools.is_empty() && links.is_empty() {
        return;
    }
    with_context(&mut context, |world| {
        TouchPipeline::configure(&mut world.integration_parameters);
        if let Some(dt) = dt {
            world.integration_parameters.dt = dt;
        }
        for e in pending {
            let Ok((_, mut soft, body)) = surfaces.get_mut(e) else {
                continue;
            };
            let Some((surface, options)) = soft.pending.take() else {
                continue;
            };
            match touch.surfaces.insert(surface, body.0, world, options) {
                Ok(h) => {
                    // bevy_rapier maps colliders to entities through their user data: the
                    // surface's collider belongs to the surface's entity.
                    let collider = touch.surfaces.get(h).and_then(|s| s.collider());
                    if let Some(c) = collider.and_then(|c| world.colliders.get_mut(c)) {
                        c.user_data = e.to_bits() as u128;
                    }
                    soft.handle = Some(h);
                }
                Err(err) => {
                    log::warn!("rapier_touch: soft surface of {e} not attached: {err}");
                    soft.error = Some(err);
                }
            }
        }
        for (e, h, link) in links {
            match touch.surfaces.connect_haptic(h, link, world) {
                Ok(()) => {
                    commands.entity(e).insert(SurfaceToolReaction::default());
                }
                Err(err) => {
                    log::warn!("rapier_touch: haptic tool {e} refused: {err}");
                    commands.entity(e).insert(SurfaceToolRefused(err));
                }
            }
        }
        for (e, h) in new_tools {
            match touch.surfaces.add_tool(h, world) {
                Ok(()) => {
                    commands.entity(e).insert(SurfaceToolReaction::default());
                }
                Err(err) => {
                    log::warn!("rapier_touch: surface tool {e} refused: {err}");
                    commands.entity(e).insert(SurfaceToolRefused(err));
                }
            }
        }
    });
}

/// The start-of-step records (body and tool poses), then the haptic tools to their proxies.
fn before_step(mut touch: ResMut<TouchWorld>, mut context: ContextQuery) {
    let Ok((sim, mut colliders, joints, mut bodies, _)) = context.single_mut() else {
        return;
    };
    let touch = &mut *touch;
    // bevy_rapier's user hooks are a system parameter this system does not see.
    touch.surfaces.take_coming_tools(
        &bodies.bodies,
        &mut colliders.colliders,
        (&joints.impulse_joints, &joints.multibody_joints),
        &touch.pipeline.hooks.inner,
        sim.integration_parameters.dt,
    );
    touch.prev = Some(touch.pipeline.begin_step(
        &mut bodies.bodies,
        &colliders.colliders,
        sim.integration_parameters.length_unit,
    ));
    touch
        .surfaces
        .begin_step(&mut bodies.bodies, &colliders.colliders);
    touch
        .surfaces
        .drive_haptic_tools(&mut bodies.bodies, &mut colliders.colliders);
}

/// The step guard, then the surfaces.
fn after_step(mut touch: ResMut<TouchWorld>, mut context: ContextQuery) {
    let touch = &mut *touch;
    let Some(prev) = touch.prev.take() else {
        return;
    };
    with_context(&mut context, |world| {
        touch.pipeline.end_step(world, prev);
        touch.surfaces.step_surfaces(world);
        touch.surfaces.publish_haptic_models(world);
    });
}

/// Each registered tool's reaction into its component.
fn write_reactions(
    touch: Res<TouchWorld>,
    mut tools: Query<(&RapierColliderHandle, &mut SurfaceToolReaction)>,
) {
    for (h, mut reaction) in &mut tools {
        let r = touch.surfaces.tool_reaction(h.0).unwrap_or_default();
        if reaction.0 != r {
            reaction.0 = r;
        }
    }
}

/// Each attached surface's deformed shape into its entity's mesh.
fn write_meshes(
    touch: Res<TouchWorld>,
    meshes: Option<ResMut<Assets<Mesh>>>,
    surfaces: Query<(&SoftSurface, &Mesh3d)>,
    mut scratch: Local<Vec<crate::math::Vector>>,
) {
    let Some(mut meshes) = meshes else {
        return;
    };
    for (soft, mesh3d) in &surfaces {
        let Some(attached) = soft.handle.and_then(|h| touch.surfaces.get(h)) else {
            continue;
        };
        let Some(mut mesh) = meshes.get_mut(&mesh3d.0) else {
            continue;
        };
        attached.surface.positions_into(&mut scratch);
        let positions: Vec<[f32; 3]> = scratch.iter().map(|p| p.to_array()).collect();
        mesh.insert_attribute(Mesh::ATTRIBUTE_POSITION, positions);
        mesh.compute_smooth_normals();
    }
}
