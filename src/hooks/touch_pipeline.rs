//! [`TouchPipeline`]: one call that steps a rapier `PhysicsWorld` with the touch hooks, the
//! step guard, the tools' proxies and the contact report.

use super::events::{self, PairTouchEvent, PairTracker};
use super::pair_filter::{rapier_solves_pair, user_removes_contact};
use super::pose_history::PoseHistory;
use super::report::{PairReport, ToolFeedback};
use super::step_motion::{
    body_motion, collider_reach, previous_collider_pose, relative_motion, shape_reach,
};
use super::touch_hooks::{
    meshed_exactly, pair_configuration, shape_key, CachedMesh, ShapeKey, TouchHooks,
};
use crate::coupling::SurfaceSet;
use crate::geometry::{
    ReconstructionOptions, Reconstructor, TouchMesh, TouchMeshError, TouchState,
};
use crate::math::{Pose, Real, Vector};
use parry3d::bounding_volume::BoundingVolume;
use parry3d::utils::hashmap::HashMap;
use parry3d::utils::hashset::HashSet;
use rapier3d::dynamics::{IntegrationParameters, RigidBodyHandle, RigidBodySet};
use rapier3d::geometry::{ColliderHandle, ColliderSet};
use rapier3d::pipeline::{ActiveHooks, EventHandler, PhysicsHooks, PhysicsWorld, QueryFilter};
use std::sync::Arc;

mod articulations;
mod correction;
mod guard;
mod hook_flags;
mod impacts;
mod left_alone;
mod meshes;
mod misread;
mod movers;
mod options;
mod pair_view;
pub(crate) mod pose_sync;
mod rapier_contacts;
mod swept;
mod swept_calm;

pub use options::TouchOptions;
use pair_view::PairStates;

/// A user-driven tool (god-object / proxy): where the device puts it, and where the crate lets
/// it be.
#[derive(Copy, Clone, Debug)]
struct Tool {
    device: Pose,
    proxy: Pose,
}

/// Steps a rapier [`PhysicsWorld`] with exact touch contacts.
///
/// Colliders take part when they have `ActiveHooks::MODIFY_SOLVER_CONTACTS` (hooks, guard and
/// reports) or were given to [`TouchPipeline::track_collider`] (guard and reports, no rapier
/// hooks), and have a shape with a triangle-mesh form ([`TouchMesh::from_shape`]). Each [`TouchPipeline::step`]:
/// 1. records every body's pose (the history the reconstruction walks back along);
/// 2. runs rapier's step with [`TouchHooks`] (which forward to your hooks);
/// 3. **step guard:** for every moving dynamic body, reconstructs it against each opted-in
///    collider its swept box touches; a body that penetrates deeper than the slop, or that went
///    through a thin object (perforation), is moved back along its own trajectory to first touch
///    and loses its velocity into the surface. This *clamps the motion to first touch*, so fast
///    objects do not tunnel even with rapier's CCD off, and moving TriMesh bodies (which
///    rapier's CCD never sweeps) are guarded too. Only pairs rapier itself would solve are
///    corrected: a body passes sensors, colliders its collision or solver groups exclude,
///    disabled colliders, pairs its `ActiveCollisionTypes` leave out, bodies joined by a joint
///    with contacts disabled, pairs your `filter_contact_pair` refuses and contacts your
///    `modify_solver_contacts` removes (a one-way platform: the guard asks it on the first-touch
///    contact before correcting), exactly as in vanilla rapier (tools ignore the collision
///    types only). The colliders of moved bodies and their broad-phase boxes are synced at
///    once, so collider poses and the query pipeline see the corrected poses after the step.
///    Articulated bodies are rapier's where its joint solver holds them: a body held by
///    impulse joints is corrected only where it may have passed through its partner, never
///    against a body of its own articulation; a multibody's links are never moved (rapier
///    computes their poses from the multibody's joint coordinates), so they are guarded by
///    rapier alone (its CCD), a limitation;
/// 4. **tools:** a kinematic body registered with [`TouchPipeline::set_tool_target`] is put at
///    the last pose that does not penetrate (its proxy), and
///    [`TouchPipeline::tool_feedback`] gives the device-to-proxy offset for a feedback force;
/// 5. fills the [`PairReport`]s of the step ([`TouchPipeline::reports`]).
///
/// # Example
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// let mut world = PhysicsWorld::default();
/// world.integration_parameters.contact_clustering = false;
/// world.insert_collider(
///     ColliderBuilder::cuboid(5.0, 0.05, 5.0).active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS),
///     None,
/// );
/// let body = world.insert_body(
///     RigidBodyBuilder::dynamic()
///         .translation(Vector::new(0.0, 2.0, 0.0))
///         .linvel(Vector::new(0.0, -100.0, 0.0)),
/// );
/// world.insert_collider(
///     ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS),
///     Some(body),
/// );
/// let mut touch = TouchPipeline::default();
/// for _ in 0..60 {
///     touch.step(&mut world);
/// }
/// // A 100 m/s box does not go through a 10 cm slab (rapier's CCD is on by default, but the
/// // guard does not need it).
/// assert!(world.bodies[body].translation().y > 0.0);
/// ```
pub struct TouchPipeline<H: PhysicsHooks = ()> {
    /// The hooks handed to rapier's step (they forward to your hooks).
    pub hooks: TouchHooks<H>,
    /// Tuning.
    pub options: TouchOptions,
    reconstructor: Reconstructor,
    reports: Vec<PairReport>,
    tools: HashMap<RigidBodyHandle, Tool>,
    corrections: usize,
    tracked: HashSet<ColliderHandle>,
    /// Colliders opted in with the hook flag while the pipeline manages it
    /// ([`TouchOptions::hook_flags_on_demand`]).
    hooked: HashSet<ColliderHandle>,
    pair_states: PairStates,
    /// How many pair states there were when those of removed colliders were last dropped.
    pair_states_pruned_at: usize,
    /// Opted-in colliders whose shape has no touch mesh: the shape's address and why.
    refused: HashMap<ColliderHandle, (usize, TouchMeshError)>,
    /// Touch started / ended per pair ([`TouchPipeline::drain_touch_events`]).
    touch: PairTracker,
    /// Each mover's pose when the guard last read its pairs: one still over the step that moved
    /// less than a tenth of the slop since then is skipped against fixed partners
    /// (`Screen::restless_pairs`).
    pairs_read_at: HashMap<ColliderHandle, Pose>,
    /// The last step's pose history, kept to be refilled (a map of every body collected anew
    /// each step grew and rehashed every time: a tenth of the pyramid scene's touch step).
    spare_poses: PoseHistory,
}

impl<H: PhysicsHooks> std::fmt::Debug for TouchPipeline<H> {
    /// The hooks, the options and the sizes of the pipeline's per-collider state (not its
    /// contents).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TouchPipeline")
            .field("hooks", &self.hooks)
            .field("options", &self.options)
            .field("reports", &self.reports.len())
            .field("tools", &self.tools.len())
            .field("corrections", &self.corrections)
            .field("tracked", &self.tracked.len())
            .field("hooked", &self.hooked.len())
            .field("refused", &self.refused.len())
            .finish_non_exhaustive()
    }
}

impl Default for TouchPipeline<()> {
    /// A pipeline with no hooks of yours, managing the hook flags
    /// ([`TouchOptions::hook_flags_on_demand`]).
    fn default() -> Self {
        let mut pipeline = Self::new(());
        pipeline.options.hook_flags_on_demand = true;
        pipeline
    }
}

impl TouchPipeline<()> {
    /// Sets the integration parameters this crate expects: no contact clustering (mesh
    /// manifolds keep their triangles).
    pub fn configure(params: &mut IntegrationParameters) {
        params.contact_clustering = false;
    }
}

impl<H: PhysicsHooks> TouchPipeline<H> {
    /// A pipeline whose hooks forward to `inner`.
    pub fn new(inner: H) -> Self {
        Self {
            hooks: TouchHooks::new(inner),
            options: TouchOptions::default(),
            reconstructor: Reconstructor::default(),
            reports: Vec::new(),
            tools: HashMap::default(),
            corrections: 0,
            tracked: HashSet::default(),
            hooked: HashSet::default(),
            pair_states: HashMap::default(),
            pair_states_pruned_at: 0,
            refused: HashMap::default(),
            touch: PairTracker::default(),
            spare_poses: PoseHistory::default(),
            pairs_read_at: HashMap::default(),
        }
    }

    /// The reports of the last step: one per reconstructed pair that touched, penetrated or
    /// perforated.
    pub fn reports(&self) -> &[PairReport] {
        &self.reports
    }

    /// Opted-in colliders the crate cannot guard, with the reason: their shape has no finite
    /// triangle surface ([`TouchMesh::from_shape`]: a half-space, a segment, a polyline). rapier
    /// handles their contacts alone. Filled by each step (a changed shape is tried again).
    ///
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    /// let mut world = PhysicsWorld::default();
    /// // A segment is a curve: it has no surface to touch.
    /// let ground = world.insert_collider(ColliderBuilder::segment(Vector::ZERO, Vector::X), None);
    /// let mut touch = TouchPipeline::default();
    /// touch.track_collider(ground);
    /// touch.step(&mut world);
    /// let (h, why) = touch.refused_colliders().next().unwrap();
    /// assert_eq!(h, ground);
    /// assert!(matches!(why, TouchMeshError::UnsupportedShape { .. }));
    /// ```
    pub fn refused_colliders(&self) -> impl Iterator<Item = (ColliderHandle, &TouchMeshError)> {
        self.refused.iter().map(|(h, (_, e))| (*h, e))
    }

    /// How many body poses the step guard corrected during the last step.
    pub fn corrections(&self) -> usize {
        self.corrections
    }

    /// Guards and reports `collider` without rapier hooks. Colliders with
    /// `ActiveHooks::MODIFY_SOLVER_CONTACTS` are guarded anyway and also get their manifolds
    /// rewritten; rapier never recycles the contacts of a pair with active hooks (1.4-1.7x its
    /// step time with 100 boxes on a TriMesh floor, see the README), which
    /// [`TouchOptions::hook_flags_on_demand`] avoids by raising the flag only on fast bodies.
    /// Tracking needs no flag at all.
    pub fn track_collider(&mut self, collider: ColliderHandle) {
        self.tracked.insert(collider);
    }

    /// Builds now the touch meshes of every collider guarded (tracked, or with
    /// `ActiveHooks::MODIFY_SOLVER_CONTACTS`), instead of in the first step that sees them.
    /// Optional: call it once a scene is loaded, as rapier builds a convex hull's shape when
    /// its collider is built. A rounded convex hull's mesh takes a few milliseconds to build
    /// (rapier's convex-hull stress scene: five of them, 13-14 ms in all here), a hitch in the
    /// first frame otherwise. Colliders sharing a shape share one mesh; the ones whose shape
    /// has no mesh are listed by [`TouchPipeline::refused_colliders`].
    ///
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    ///
    /// let mut world = PhysicsWorld::default();
    /// let points = [
    ///     Vector::new(0.0, 0.0, 0.0), Vector::new(1.0, 0.0, 0.0),
    ///     Vector::new(0.0, 1.0, 0.0), Vector::new(0.0, 0.0, 1.0),
    /// ];
    /// let body = world.insert_body(RigidBodyBuilder::dynamic());
    /// let hull = ColliderBuilder::round_convex_hull(&points, 0.05).unwrap();
    /// let collider = world.insert_collider(hull, Some(body));
    /// let mut touch = TouchPipeline::default();
    /// touch.track_collider(collider);
    /// touch.prepare_meshes(&world.colliders);
    /// assert_eq!(touch.refused_colliders().count(), 0);
    /// touch.step(&mut world);
    /// ```
    pub fn prepare_meshes(&mut self, colliders: &ColliderSet) {
        self.refresh_meshes(colliders);
    }

    /// Stops tracking `collider` (see [`TouchPipeline::track_collider`]).
    pub fn untrack_collider(&mut self, collider: ColliderHandle) {
        self.tracked.remove(&collider);
        self.hooked.remove(&collider);
    }

    /// Drives kinematic body `body` as a tool toward `device` (a mouse or haptic device pose).
    /// At each step the body moves toward the device pose but stops at first touch; see
    /// [`TouchPipeline::tool_feedback`].
    pub fn set_tool_target(&mut self, body: RigidBodyHandle, device: Pose) {
        let e = self.tools.entry(body).or_insert(Tool {
            device,
            proxy: device,
        });
        e.device = device;
    }

    /// Stops treating `body` as a tool.
    pub fn remove_tool(&mut self, body: RigidBodyHandle) {
        self.tools.remove(&body);
    }

    /// The device pose, the proxy pose and their offset for tool `body`, after the last step.
    pub fn tool_feedback(&self, body: RigidBodyHandle) -> Option<ToolFeedback> {
        self.tools.get(&body).map(|t| ToolFeedback {
            device: t.device,
            proxy: t.proxy,
            offset: t.proxy.translation - t.device.translation,
        })
    }

    /// Steps `world` once: see the type's documentation.
    pub fn step(&mut self, world: &mut PhysicsWorld) {
        self.step_with_events(world, &());
    }

    /// The crate's main loop in one call: steps `world` through this pipeline (rapier's step,
    /// the hooks and the step guard), then every surface of `surfaces` (their substeps, the
    /// tools' reactions, the two-way coupling and the surface colliders' refit), in that order.
    /// The same as `surfaces.step_with(world, |w| touch.step(w))`.
    ///
    /// A surface's collider and its tools may be opted in: the guard obeys the solver group
    /// [`crate::coupling::SurfaceSet::add_tool`] takes off a tool, so a tool is not stopped at
    /// the surface's collider (the surface answers it instead).
    ///
    /// # Example
    /// A rigid box dropped on a guarded floor and a ball tool pressing a soft plate, one loop:
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    /// use rapier_touch::surface::meshing::{plate, plate_rim};
    ///
    /// let mut world = PhysicsWorld::default();
    /// TouchPipeline::configure(&mut world.integration_parameters);
    /// let hooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;
    /// world.insert_collider(ColliderBuilder::cuboid(5.0, 0.05, 5.0).active_hooks(hooks), None);
    /// let body = world.insert_body(
    ///     RigidBodyBuilder::dynamic()
    ///         .translation(Vector::new(3.0, 2.0, 0.0))
    ///         .linvel(Vector::new(0.0, -30.0, 0.0)),
    /// );
    /// world.insert_collider(ColliderBuilder::cuboid(0.2, 0.2, 0.2).active_hooks(hooks), Some(body));
    ///
    /// let mut surfaces = SurfaceSet::new();
    /// let ground = world.insert_body(RigidBodyBuilder::fixed().translation(Vector::new(0.0, 1.0, 0.0)));
    /// let mesh = plate(1.0, 1.0, 8, 8);
    /// let soft = MassSpringSurfaceBuilder::from_mesh(&mesh).pinned(plate_rim(8, 8)).build().unwrap();
    /// let options = AttachOptions { substeps: 8, collider: true };
    /// surfaces.insert(soft, ground, &mut world, options).unwrap();
    /// let tool_body = world.insert_body(
    ///     RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.0, 1.1, 0.0)),
    /// );
    /// let tool = world.insert_collider(ColliderBuilder::ball(0.05), Some(tool_body));
    /// surfaces.add_tool(tool, &mut world).unwrap();
    ///
    /// let mut touch = TouchPipeline::default();
    /// for step in 1..=60 {
    ///     let y = (1.1 - 0.005 * step as f32).max(1.03);
    ///     world.bodies[tool_body].set_next_kinematic_translation(Vector::new(0.0, y, 0.0));
    ///     touch.step_with_surfaces(&mut world, &mut surfaces);
    /// }
    /// assert!(world.bodies[body].translation().y > 0.2); // on the floor, not through it
    /// assert!(surfaces.tool_reaction(tool).unwrap().force.y > 0.0); // the plate pushes back
    /// ```
    pub fn step_with_surfaces(&mut self, world: &mut PhysicsWorld, surfaces: &mut SurfaceSet) {
        // The surfaces' coming tools are taken as rapier pairs them, the user's hooks asked.
        let joints = (&world.impulse_joints, &world.multibody_joints);
        let dt = world.integration_parameters.dt;
        surfaces.take_coming_tools(
            &world.bodies,
            &mut world.colliders,
            joints,
            &self.hooks.inner,
            dt,
        );
        surfaces.step_taken(world, |w| self.step(w));
    }

    /// Like [`TouchPipeline::step`], with rapier's event handler.
    pub fn step_with_events(&mut self, world: &mut PhysicsWorld, events: &dyn EventHandler) {
        let unit = world.integration_parameters.length_unit;
        let prev = self.begin_step(&mut world.bodies, &world.colliders, unit);
        world.step_with_events(&self.hooks, events);
        self.end_step(world, prev);
    }

    /// The part of a step before rapier's: refreshes the touch meshes, aims the tools, and
    /// returns where every body starts the step (hand it to [`TouchPipeline::end_step`]).
    /// rapier's step between the two must run with [`TouchPipeline::hooks`]. For engines
    /// that own the step (the bevy plugin); [`TouchPipeline::step`] is both halves.
    pub(crate) fn begin_step(
        &mut self,
        bodies: &mut RigidBodySet,
        colliders: &ColliderSet,
        length_unit: Real,
    ) -> PoseHistory {
        self.refresh_meshes(colliders);
        self.hooks.options = self.options.reconstruction;
        self.hooks.slop = self.options.in_length_unit(length_unit).penetration_slop;
        self.reconstructor.options = self.options.reconstruction;

        // Tools: aim the kinematic bodies at their device pose.
        self.tools.retain(|h, _| bodies.contains(*h));
        for (h, tool) in &self.tools {
            if let Some(b) = bodies.get_mut(*h) {
                if b.is_kinematic() {
                    b.set_next_kinematic_position(tool.device);
                }
            }
        }

        // Pose history: where every body starts this step.
        let mut prev = std::mem::take(&mut self.spare_poses);
        prev.record(bodies);
        self.hooks.begin_step();
        prev
    }

    /// The part of a step after rapier's: the step guard, the tool proxies and the touch
    /// events; `prev` is what [`TouchPipeline::begin_step`] returned.
    pub(crate) fn end_step(&mut self, world: &mut PhysicsWorld, prev: PoseHistory) {
        self.spare_poses = std::mem::replace(&mut self.hooks.prev_poses, prev);

        self.reports.clear();
        self.corrections = 0;
        // The guard runs on the slops in rapier's length unit.
        let options = self.options;
        self.options = options.in_length_unit(world.integration_parameters.length_unit);
        self.guard(world);
        self.options = options;
        let proxies: Vec<(RigidBodyHandle, Pose)> = self
            .tools
            .keys()
            .filter_map(|h| Some((*h, *world.bodies.get(*h)?.position())))
            .collect();
        for (h, p) in proxies {
            if let Some(t) = self.tools.get_mut(&h) {
                t.proxy = p;
            }
        }
        self.record_touches(world);
    }

    /// The pairs that started or stopped touching, step by step, since the last drain (oldest
    /// first); see [`PairTouchEvent`].
    ///
    /// # Example
    /// A box dropped on an opted-in slab starts touching it and, lifted off, stops:
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    ///
    /// let mut world = PhysicsWorld::default();
    /// let slab = world.insert_collider(ColliderBuilder::cuboid(5.0, 0.05, 5.0), None);
    /// let body = world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 0.5, 0.0)));
    /// let cube = world.insert_collider(ColliderBuilder::cuboid(0.2, 0.2, 0.2), Some(body));
    /// let mut touch = TouchPipeline::default();
    /// touch.track_collider(slab);
    /// for _ in 0..60 {
    ///     touch.step(&mut world);
    /// }
    /// let events: Vec<PairTouchEvent> = touch.drain_touch_events().collect();
    /// assert_eq!(events, [PairTouchEvent::Started { collider1: slab, collider2: cube }]);
    /// world.bodies[body].set_translation(Vector::new(0.0, 3.0, 0.0), true);
    /// touch.step(&mut world);
    /// touch.step(&mut world);
    /// assert!(touch.drain_touch_events().any(|e| !e.started() && e.pair() == (slab, cube)));
    /// ```
    pub fn drain_touch_events(&mut self) -> impl Iterator<Item = PairTouchEvent> + '_ {
        self.touch.drain()
    }

    /// The pairs touching after the step (rapier's active contacts with an opted-in collider,
    /// and the pairs reported), compared with the last step's.
    fn record_touches(&mut self, world: &PhysicsWorld) {
        let meshes = &self.hooks.meshes;
        let mut now = self.touch.take_spare_list();
        now.extend(
            world
                .narrow_phase
                .contact_pairs()
                .filter(|p| p.has_any_active_contact())
                .filter(|p| meshes.contains_key(&p.collider1) || meshes.contains_key(&p.collider2))
                .map(|p| events::ordered(p.collider1, p.collider2)),
        );
        now.extend(
            self.reports
                .iter()
                .map(|r| events::ordered(r.fixed, r.moving)),
        );
        events::update(&mut self.touch, now);
    }
}
