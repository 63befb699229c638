//! [`SurfaceSet`]: soft surfaces attached to rapier bodies, pressed by rigid tools.

use super::events::{ToolTouchEvent, TouchTracker};
use super::friction::{Friction, Sticks};
use super::haptic_links::LinkState;
use super::holding::{attached_with_pose, lerp_pose, surface_substep, ToolMotion};
use super::pressing::Pressed;
use super::tool_shape::ToolShape;
use crate::geometry::SurfaceContact;
use crate::math::{Pose, Real, Vector};
use crate::surface::{MassSpringSurface, SurfaceError};
use parry3d::bounding_volume::Aabb;
use parry3d::shape::{SharedShape, TriMeshFlags};
use rapier3d::dynamics::RigidBodyHandle;
use rapier3d::geometry::{ColliderBuilder, ColliderHandle, ColliderSet, Group, InteractionGroups};
use rapier3d::pipeline::PhysicsWorld;
use std::collections::HashMap;
use std::sync::Arc;

/// The solver group this crate reserves for surface colliders: tools registered with
/// [`SurfaceSet::add_tool`] drop it from their solver-group filter, so rapier does not also
/// treat the surface as rigid against them (the surface's own forces act instead).
pub const SURFACE_SOLVER_GROUP: Group = Group::GROUP_32;

/// Why a surface could not be attached.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CouplingError {
    /// The body handle is not in the world.
    #[error("the rigid body is not in the world")]
    NoSuchBody,
    /// Substeps must be at least 1.
    #[error("substeps must be at least 1")]
    InvalidSubsteps,
    /// The surface rejected its new time step.
    #[error(transparent)]
    Surface(#[from] SurfaceError),
    /// The tool's collider is not in the world.
    #[error("the tool's collider is not in the world")]
    NoSuchCollider,
    /// The tool's shape has no size (its bounding box has no extent), so it could hold nothing.
    #[error("the tool's shape has no size")]
    ZeroSizeTool,
    /// The surface handle is stale (the surface was removed).
    #[error("no such surface")]
    NoSuchSurface,
    /// A friction coefficient is negative or not finite, or the dynamic one is above the
    /// static one.
    #[error("invalid friction: static {static_coefficient}, dynamic {dynamic_coefficient}")]
    InvalidFriction {
        /// The static coefficient given.
        static_coefficient: f64,
        /// The dynamic coefficient given.
        dynamic_coefficient: f64,
    },
    /// parry rejected the surface's triangle mesh.
    #[error("the surface mesh cannot be a collider: {0}")]
    Collider(String),
    /// A haptic tool must be kinematic or have no body: a dynamic body's motion is rapier's,
    /// not the device's ([`SurfaceSet::connect_haptic`]).
    #[error("a haptic tool cannot be on a dynamic body")]
    DynamicHapticTool,
}

/// A handle to a surface in a [`SurfaceSet`].
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct SurfaceHandle {
    pub(super) index: u32,
    pub(super) generation: u32,
}

impl SurfaceHandle {
    /// The index and generation, for ordering.
    pub(super) fn raw(&self) -> (u32, u32) {
        (self.index, self.generation)
    }
}

/// How a surface is attached.
///
/// # Example
/// A 1020 Hz surface in a 60 Hz scene: its time step becomes the world's over 17.
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
/// use rapier_touch::surface::meshing::plate;
///
/// let mut world = PhysicsWorld::default(); // dt = 1/60 s
/// let body = world.insert_body(RigidBodyBuilder::fixed());
/// let surface = || MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 2, 2)).build().unwrap();
/// let mut set = SurfaceSet::new();
/// let options = AttachOptions { substeps: 17, collider: false };
/// let h = set.insert(surface(), body, &mut world, options).unwrap();
/// let attached = set.get(h).unwrap();
/// assert!((attached.surface.dt() - 1.0 / 60.0 / 17.0).abs() < 1e-9);
/// assert_eq!(attached.collider(), None);
/// // At least one surface step per rigid step.
/// let none = AttachOptions { substeps: 0, ..Default::default() };
/// assert_eq!(set.insert(surface(), body, &mut world, none), Err(CouplingError::InvalidSubsteps));
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct AttachOptions {
    /// Surface steps per rigid step (a 1 kHz surface in a 60 Hz scene: 17). The surface's time
    /// step becomes the world's `dt / substeps`. Default 1.
    pub substeps: u32,
    /// Give the body a TriMesh collider that follows the deformed surface (updated once per
    /// rigid step). It adds no mass to the body (the surface's masses are its own): give a
    /// dynamic body its mass through its other colliders or `additional_mass`. Default `true`.
    pub collider: bool,
}

impl Default for AttachOptions {
    fn default() -> Self {
        Self {
            substeps: 1,
            collider: true,
        }
    }
}

/// What a surface pushes back on one tool with, after the last step.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct ToolReaction {
    /// Net force on the tool at the end of the last surface substep (N, world frame): the sum
    /// of the spring and damper forces of the vertices it holds. What a haptic device renders.
    pub force: Vector,
    /// Torque of those forces about the tool body's centre of mass (N·m, world frame).
    pub torque: Vector,
    /// The force averaged over the rigid step's substeps (N): what a dynamic tool receives.
    pub mean_force: Vector,
    /// Number of surface vertices the tool holds.
    pub held_vertices: usize,
    /// How many of those stick to it (with friction, [`SurfaceSet::set_tool_friction`]); the
    /// others slide.
    pub sticking_vertices: usize,
    /// Number of surface points a polyhedral tool's vertices and edges pressed between the
    /// surface's vertices (inside triangles, on edges) during the last substep.
    pub pressed_points: usize,
}

/// A surface attached to a rigid body.
pub struct AttachedSurface {
    /// The deformable model (its positions live in the body's frame).
    pub surface: MassSpringSurface,
    pub(super) body: RigidBodyHandle,
    collider: Option<ColliderHandle>,
    substeps: u32,
    pub(super) scratch: Vec<Vector>,
    pub(super) before: Vec<Vector>,
    pub(super) was_held: Vec<bool>,
    /// Points the tools pressed in the current and the last substep.
    pub(super) pressed: Vec<Pressed>,
    pub(super) last_pressed: Vec<Pressed>,
    pub(super) candidates: Vec<u32>,
    /// Every triangle's bounds over the substep (sharp tools' candidates).
    pub(super) triangle_bounds: Vec<Aabb>,
    pub(super) contacts: Vec<SurfaceContact>,
    /// Vertices stuck to a tool (friction).
    pub(super) sticks: Sticks,
    /// Friction of given tools on this surface, in place of the tool's own.
    pub(super) pair_friction: HashMap<ColliderHandle, Friction>,
}

impl std::fmt::Debug for AttachedSurface {
    /// The surface, its attachment and how many of its vertices the tools hold; the scratch
    /// buffers are left out.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let held = (0..self.surface.num_vertices() as u32)
            .filter(|&i| self.surface.is_held(i))
            .count();
        f.debug_struct("AttachedSurface")
            .field("surface", &self.surface)
            .field("body", &self.body)
            .field("collider", &self.collider)
            .field("substeps", &self.substeps)
            .field("held_vertices", &held)
            .finish_non_exhaustive()
    }
}

impl AttachedSurface {
    /// The body carrying the surface.
    pub fn body(&self) -> RigidBodyHandle {
        self.body
    }
    /// The collider following the deformed surface, if any.
    pub fn collider(&self) -> Option<ColliderHandle> {
        self.collider
    }
    /// Surface steps per rigid step.
    pub fn substeps(&self) -> u32 {
        self.substeps
    }
}

#[derive(Clone, Debug)]
pub(super) struct ToolState {
    prev: Option<Pose>,
    pub(super) reaction: ToolReaction,
    /// The force and torque this set currently adds to the tool's body.
    applied: (Vector, Vector),
    /// The device pose of the last haptic step.
    haptic_prev: Option<Pose>,
    /// Whether the tool's solver-group filter held [`SURFACE_SOLVER_GROUP`] before
    /// [`SurfaceSet::add_tool`] dropped it (restored by [`SurfaceSet::remove_tool`]).
    had_surface_group: bool,
    /// The tool's shape as the coupling uses it.
    shape: Arc<ToolShape>,
    /// Its friction on the surfaces (unless a surface has its own for it).
    friction: Friction,
    /// Whether it grasps what it touches.
    pub(super) grasp: bool,
}

/// Soft surfaces on rapier bodies and the rigid tools that press into them.
///
/// # Stepping
/// [`SurfaceSet::step`] runs rapier's step, then each surface's substeps. In every substep the
/// tools' poses are interpolated between the start and the end of the rigid step, expressed in
/// the surface body's frame, and every surface vertex a tool contains is moved out along the
/// tool's own motion over the substep (the vertex form of the inverse trajectory mapping, eq.
/// 1-2), or to the nearest tool surface point when the tool did not move. By default the
/// contact is frictionless: the vertex takes the tool's normal velocity and is held along the
/// tool's normal only ([`MassSpringSurface::hold_sliding`]), so it slides over the tool under
/// the tangential part of its forces. With Coulomb friction ([`SurfaceSet::set_tool_friction`],
/// [`super::Friction`]) a vertex sticks to the tool's material point (held on all axes, carried
/// by the tool) while its tangential force is within the static limit, and slips against
/// kinetic friction beyond it; the tool receives the tangential force too. A held vertex stays
/// in contact when the tool slows down or turns back (it is snapped back onto the tool) until
/// its springs pull it away from the tool. The filter then spreads that deformation over the
/// next substep. The reaction on a tool is the sum of the spring and damper forces of the
/// vertices it holds: their normal parts, and the tangential parts of those that stick or
/// kinetic friction for those that slip.
/// Dynamic tools carry the substep-averaged reaction as a rapier force through the next rigid
/// step (one step of lag), and surface colliders are updated once per rigid step
/// (`TriMesh::set_vertices`, a BVH refit).
///
/// # Limitations
/// - Curved tools load the surface's vertices only (mesh it finer than a ball). Polyhedral
///   tools also press their vertices and edges between the surface's vertices, except next to
///   a vertex they hold (left to that vertex's holder): a flat face holding a vertex sinks its
///   corners into the triangles around it, up to about a millimetre at first contact.
/// - Tools are tested with parry's point queries: convex shapes. Balls, cuboids, capsules and
///   cylinders give steady forces, and so does a box-shaped convex polyhedron. A rounded
///   convex polyhedron (the hull of an icosphere) holds vertices but its force fluctuates from
///   step to step, up to ten times the ball's (not yet understood; parry's point queries on a
///   hull with merged faces also disagree with its face planes by up to a millimetre on a 3 cm
///   hull).
///   A TriMesh tool is not solid for parry and holds no vertex.
/// - An upright flat face dragged sideways ploughs the vertices ahead of it (frictionless
///   contact with linear springs gives them no reason to slide under); tilt it like a sled.
/// - The surface is rigidly attached to its body's frame; the body's acceleration does not
///   load it.
///
/// # Example
/// A plate 0.4 m square (vertices 0.1 m apart) clamped at its rim, pressed at its centre by a
/// kinematic ball lowered until its lowest point is 2 cm below the plate:
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
/// use rapier_touch::surface::meshing::{plate, plate_rim};
///
/// let mut world = PhysicsWorld { gravity: Vector::ZERO, ..Default::default() };
/// let fixed = world.insert_body(RigidBodyBuilder::fixed());
/// let surface = MassSpringSurfaceBuilder::from_mesh(&plate(0.4, 0.4, 4, 4))
///     .stiffness(100.0)
///     .mass(MassDistribution::Total(0.1))
///     .pinned(plate_rim(4, 4))
///     .build()
///     .unwrap();
/// let options = AttachOptions { substeps: 4, collider: true };
/// let mut set = SurfaceSet::new();
/// let plate = set.insert(surface, fixed, &mut world, options).unwrap();
///
/// let start = Vector::new(0.0, 0.1, 0.0);
/// let ball = world.insert_body(RigidBodyBuilder::kinematic_position_based().translation(start));
/// let tool = world.insert_collider(ColliderBuilder::ball(0.05), Some(ball));
/// set.add_tool(tool, &mut world).unwrap();
/// for step in 1..=60 {
///     // Down 7 cm in 20 steps, then held: the ball's lowest point ends at y = -0.02.
///     let y = (0.1 - 0.0035 * step as f32).max(0.03);
///     world.bodies[ball].set_next_kinematic_translation(Vector::new(0.0, y, 0.0));
///     set.step(&mut world);
/// }
///
/// // The centre vertex (12) is the only one inside the ball: it is held on the ball's surface.
/// let surface = &set.get(plate).unwrap().surface;
/// assert!(surface.is_held(12));
/// assert!((surface.displacement(12) - Vector::new(0.0, -0.02, 0.0)).length() < 1e-3);
/// // The plate pushes the ball back up with its centre vertex's spring force.
/// let reaction = set.tool_reaction(tool).unwrap();
/// assert_eq!(reaction.held_vertices, 1);
/// assert!(reaction.force.y > 0.0);
/// assert!((reaction.force - surface.internal_force(12)).length() < 0.05 * reaction.force.y);
/// ```
pub struct SurfaceSet {
    pub(super) entries: Vec<(u32, Option<AttachedSurface>)>,
    pub(super) tools: HashMap<ColliderHandle, ToolState>,
    touch: TouchTracker,
    /// Tools driven by servo loops ([`SurfaceSet::connect_haptic`]).
    pub(super) links: HashMap<ColliderHandle, LinkState>,
}

impl std::fmt::Debug for SurfaceSet {
    /// The attached surfaces (handle order) and the registered tools (collider-handle order)
    /// with their last reactions.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let surfaces: Vec<&AttachedSurface> = self
            .entries
            .iter()
            .filter_map(|(_, e)| e.as_ref())
            .collect();
        let mut tools: Vec<(ColliderHandle, ToolReaction)> =
            self.tools.iter().map(|(&h, t)| (h, t.reaction)).collect();
        tools.sort_by_key(|(h, _)| h.into_raw_parts());
        f.debug_struct("SurfaceSet")
            .field("surfaces", &surfaces)
            .field("tools", &tools)
            .finish()
    }
}

impl Default for SurfaceSet {
    fn default() -> Self {
        Self::new()
    }
}

impl SurfaceSet {
    /// An empty set.
    pub fn new() -> Self {
        Self {
            entries: Vec::new(),
            tools: HashMap::new(),
            touch: TouchTracker::default(),
            links: HashMap::new(),
        }
    }

    /// Attaches `surface` (positions in `body`'s frame) to `body`.
    ///
    /// # Errors
    /// See [`CouplingError`].
    pub fn insert(
        &mut self,
        mut surface: MassSpringSurface,
        body: RigidBodyHandle,
        world: &mut PhysicsWorld,
        options: AttachOptions,
    ) -> Result<SurfaceHandle, CouplingError> {
        if !world.bodies.contains(body) {
            return Err(CouplingError::NoSuchBody);
        }
        if options.substeps == 0 {
            return Err(CouplingError::InvalidSubsteps);
        }
        surface.set_dt(world.integration_parameters.dt / options.substeps as Real)?;
        let mut verts = Vec::new();
        surface.positions_into(&mut verts);
        let collider = if options.collider {
            let shape = SharedShape::trimesh_with_flags(
                verts.clone(),
                surface.triangles().to_vec(),
                TriMeshFlags::DEFORMABLE,
            )
            .map_err(|e| CouplingError::Collider(format!("{e:?}")))?;
            let c = ColliderBuilder::new(shape)
                .solver_groups(InteractionGroups::new(
                    SURFACE_SOLVER_GROUP,
                    Group::ALL,
                    Default::default(),
                ))
                // The surface's inertia is its own lumped masses: the collider adds none to
                // the body, and rapier does not integrate the deformed mesh's volume again
                // after every update.
                .mass_properties(parry3d::mass_properties::MassProperties::default())
                .build();
            Some(world.insert_collider(c, Some(body)))
        } else {
            None
        };
        let attached = AttachedSurface {
            surface,
            body,
            collider,
            substeps: options.substeps,
            before: verts.clone(),
            was_held: Vec::new(),
            pressed: Vec::new(),
            last_pressed: Vec::new(),
            candidates: Vec::new(),
            triangle_bounds: Vec::new(),
            sticks: Sticks::default(),
            pair_friction: HashMap::default(),
            contacts: Vec::new(),
            scratch: verts,
        };
        if let Some(i) = self.entries.iter().position(|e| e.1.is_none()) {
            let generation = self.entries[i].0 + 1;
            self.entries[i] = (generation, Some(attached));
            return Ok(SurfaceHandle {
                index: i as u32,
                generation,
            });
        }
        self.entries.push((0, Some(attached)));
        Ok(SurfaceHandle {
            index: self.entries.len() as u32 - 1,
            generation: 0,
        })
    }

    /// Detaches a surface (and removes its collider from the world).
    pub fn remove(
        &mut self,
        h: SurfaceHandle,
        world: &mut PhysicsWorld,
    ) -> Option<AttachedSurface> {
        let entry = self.entries.get_mut(h.index as usize)?;
        if entry.0 != h.generation {
            return None;
        }
        let s = entry.1.take()?;
        if let Some(c) = s.collider {
            world.remove_collider(c);
        }
        Some(s)
    }

    /// The surface behind a handle.
    pub fn get(&self, h: SurfaceHandle) -> Option<&AttachedSurface> {
        let e = self.entries.get(h.index as usize)?;
        (e.0 == h.generation).then_some(())?;
        e.1.as_ref()
    }

    /// The surface behind a handle, mutably (forces, pins, integrator).
    pub fn get_mut(&mut self, h: SurfaceHandle) -> Option<&mut AttachedSurface> {
        let e = self.entries.get_mut(h.index as usize)?;
        (e.0 == h.generation).then_some(())?;
        e.1.as_mut()
    }

    /// Registers collider `tool` as a tool pressing into every surface of the set.
    ///
    /// Two things change on the tool, both undone by [`SurfaceSet::remove_tool`]:
    /// - its solver-group filter loses [`SURFACE_SOLVER_GROUP`] (the group of the surfaces'
    ///   colliders), so rapier's rigid contact with a surface's collider does not fight the
    ///   surface's own response (rapier still reports the pair; it only stops solving it);
    /// - from the next [`SurfaceSet::step`] on, the surfaces' reaction is added to its body's
    ///   user force and torque (a dynamic body).
    ///
    /// Adding a tool twice changes nothing more.
    ///
    /// # Errors
    /// [`CouplingError::NoSuchCollider`] when `tool` is not in the world;
    /// [`CouplingError::ZeroSizeTool`] for a shape of no size (a ball of radius zero, a cuboid
    /// of zero half-extents: its bounding box has no extent, or a non-finite one), which could
    /// hold nothing. Nothing changes then.
    pub fn add_tool(
        &mut self,
        tool: ColliderHandle,
        world: &mut PhysicsWorld,
    ) -> Result<(), CouplingError> {
        if self.tools.contains_key(&tool) {
            return Ok(());
        }
        let c = world
            .colliders
            .get_mut(tool)
            .ok_or(CouplingError::NoSuchCollider)?;
        let extent = c.shape().compute_local_aabb().extents().max_element();
        if !(extent > 0.0 && extent.is_finite()) {
            return Err(CouplingError::ZeroSizeTool);
        }
        let shape = Arc::new(ToolShape::of(c.shape()));
        let g = c.solver_groups();
        let had_surface_group = g.filter.contains(SURFACE_SOLVER_GROUP);
        c.set_solver_groups(InteractionGroups::new(
            g.memberships,
            g.filter & !SURFACE_SOLVER_GROUP,
            g.test_mode,
        ));
        self.tools.insert(
            tool,
            ToolState {
                prev: None,
                reaction: ToolReaction::default(),
                applied: (Vector::ZERO, Vector::ZERO),
                haptic_prev: None,
                had_surface_group,
                shape,
                friction: Friction::NONE,
                grasp: false,
            },
        );
        Ok(())
    }

    /// Stops treating `tool` as a tool: the vertices it held are released, the force and
    /// torque the set added to its body are taken back, and its solver-group filter gets
    /// [`SURFACE_SOLVER_GROUP`] back if it had it before [`SurfaceSet::add_tool`] (so rapier
    /// solves its contacts with the surfaces' colliders again). A tool whose collider left the
    /// world is simply forgotten.
    pub fn remove_tool(&mut self, tool: ColliderHandle, world: &mut PhysicsWorld) {
        let Some(state) = self.tools.remove(&tool) else {
            return;
        };
        self.links.remove(&tool);
        for s in self.entries.iter_mut().filter_map(|e| e.1.as_mut()) {
            s.sticks.retain(|_, st| st.0 != tool);
            s.pair_friction.remove(&tool);
        }
        let Some(c) = world.colliders.get_mut(tool) else {
            return;
        };
        if state.had_surface_group {
            let g = c.solver_groups();
            c.set_solver_groups(InteractionGroups::new(
                g.memberships,
                g.filter | SURFACE_SOLVER_GROUP,
                g.test_mode,
            ));
        }
        let parent = c.parent();
        if let Some(b) = parent.and_then(|p| world.bodies.get_mut(p)) {
            if b.is_dynamic() && state.applied != (Vector::ZERO, Vector::ZERO) {
                b.add_force(-state.applied.0, true);
                b.add_torque(-state.applied.1, true);
            }
        }
    }

    /// The tools that started or stopped touching a surface, step by step, since the last
    /// drain (oldest first): a tool touches a surface while it holds at least one of its
    /// vertices at the end of a [`SurfaceSet::step`]. [`SurfaceSet::haptic_step`] does not
    /// record events; a removed tool or surface gets its `Stopped` at the next step.
    ///
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    /// use rapier_touch::surface::meshing::{plate, plate_rim};
    ///
    /// let mut world = PhysicsWorld { gravity: Vector::ZERO, ..Default::default() };
    /// let fixed = world.insert_body(RigidBodyBuilder::fixed());
    /// let surface = MassSpringSurfaceBuilder::from_mesh(&plate(0.4, 0.4, 4, 4))
    ///     .pinned(plate_rim(4, 4))
    ///     .build()
    ///     .unwrap();
    /// let mut set = SurfaceSet::new();
    /// let plate = set.insert(surface, fixed, &mut world, AttachOptions::default()).unwrap();
    /// let ball = world.insert_body(
    ///     RigidBodyBuilder::kinematic_velocity_based().translation(Vector::new(0.0, 0.1, 0.0)),
    /// );
    /// let tool = world.insert_collider(ColliderBuilder::ball(0.05), Some(ball));
    /// set.add_tool(tool, &mut world).unwrap();
    /// // Down through the plate's plane for half a second, then back up.
    /// world.bodies[ball].set_linvel(Vector::new(0.0, -0.15, 0.0), true);
    /// for _ in 0..30 {
    ///     set.step(&mut world);
    /// }
    /// world.bodies[ball].set_linvel(Vector::new(0.0, 0.3, 0.0), true);
    /// for _ in 0..30 {
    ///     set.step(&mut world);
    /// }
    /// let events: Vec<ToolTouchEvent> = set.drain_touch_events().collect();
    /// assert_eq!(
    ///     events,
    ///     [
    ///         ToolTouchEvent::Started { tool, surface: plate },
    ///         ToolTouchEvent::Stopped { tool, surface: plate },
    ///     ]
    /// );
    /// assert_eq!(set.drain_touch_events().count(), 0);
    /// ```
    pub fn drain_touch_events(&mut self) -> impl Iterator<Item = ToolTouchEvent> + '_ {
        self.touch.drain()
    }

    /// Sets the Coulomb friction of registered tool `tool` on every surface (that has no
    /// friction of its own for it, [`SurfaceSet::set_pair_friction`]). Tools start
    /// frictionless. Friction acts where the tool holds surface vertices (see
    /// [`super::Friction`]); the points a polyhedral tool presses between vertices stay
    /// frictionless.
    ///
    /// # Errors
    /// [`CouplingError::NoSuchCollider`] when `tool` is not a registered tool,
    /// [`CouplingError::InvalidFriction`] for bad coefficients; nothing changes then.
    pub fn set_tool_friction(
        &mut self,
        tool: ColliderHandle,
        friction: Friction,
    ) -> Result<(), CouplingError> {
        friction.check()?;
        let t = self
            .tools
            .get_mut(&tool)
            .ok_or(CouplingError::NoSuchCollider)?;
        t.friction = friction;
        Ok(())
    }

    /// Sets the friction of registered tool `tool` on surface `surface` only, in place of the
    /// tool's own ([`SurfaceSet::set_tool_friction`]).
    ///
    /// # Errors
    /// [`CouplingError::NoSuchSurface`] for a removed surface, [`CouplingError::NoSuchCollider`]
    /// when `tool` is not a registered tool, [`CouplingError::InvalidFriction`].
    pub fn set_pair_friction(
        &mut self,
        surface: SurfaceHandle,
        tool: ColliderHandle,
        friction: Friction,
    ) -> Result<(), CouplingError> {
        friction.check()?;
        if !self.tools.contains_key(&tool) {
            return Err(CouplingError::NoSuchCollider);
        }
        let s = self.get_mut(surface).ok_or(CouplingError::NoSuchSurface)?;
        s.pair_friction.insert(tool, friction);
        Ok(())
    }

    /// Makes registered tool `tool` grasp (`true`) or let go (`false`). While it grasps, every
    /// surface vertex it holds, or comes to hold, sticks to its material point whether the
    /// surface pushes or pulls it (a bilateral contact): lifting the tool lifts a fold of the
    /// surface, and the tool's reaction includes the springs' pull. Let go, the vertices the
    /// springs pull off the tool are released at the next substep. A kinematic tool (or one with
    /// no body) carries what it grasps; a dynamic tool is not chased by the vertices.
    ///
    /// # Example
    /// A ball pressed 1 cm into a clamped plate, made to grasp, and lifted 3 cm: it pulls the
    /// plate's centre up with it and feels the springs pull it down.
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    /// use rapier_touch::surface::meshing::{plate, plate_rim};
    ///
    /// let mut world = PhysicsWorld { gravity: Vector::ZERO, ..Default::default() };
    /// let fixed = world.insert_body(RigidBodyBuilder::fixed());
    /// let surface = MassSpringSurfaceBuilder::from_mesh(&plate(0.4, 0.4, 4, 4))
    ///     .pinned(plate_rim(4, 4))
    ///     .build()
    ///     .unwrap();
    /// let mut set = SurfaceSet::new();
    /// let options = AttachOptions { substeps: 4, collider: true };
    /// let plate = set.insert(surface, fixed, &mut world, options).unwrap();
    /// let ball = world.insert_body(
    ///     RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.0, 0.05, 0.0)),
    /// );
    /// let tool = world.insert_collider(ColliderBuilder::ball(0.02), Some(ball));
    /// set.add_tool(tool, &mut world).unwrap();
    /// let mut go = |world: &mut PhysicsWorld, set: &mut SurfaceSet, y: f32| {
    ///     for _ in 0..30 {
    ///         world.bodies[ball].set_next_kinematic_translation(Vector::new(0.0, y, 0.0));
    ///         set.step(world);
    ///     }
    /// };
    /// go(&mut world, &mut set, 0.01); // its bottom 1 cm into the plate
    /// set.set_grasp(tool, true).unwrap();
    /// go(&mut world, &mut set, 0.05); // lifted: its bottom 3 cm above the plate
    /// assert!(set.get(plate).unwrap().surface.displacement(12).y > 0.029);
    /// assert!(set.tool_reaction(tool).unwrap().force.y < 0.0); // pulled down
    /// set.set_grasp(tool, false).unwrap();
    /// go(&mut world, &mut set, 0.05);
    /// assert_eq!(set.tool_reaction(tool).unwrap().held_vertices, 0); // let go
    /// ```
    ///
    /// # Errors
    /// [`CouplingError::NoSuchCollider`] when `tool` is not a registered tool.
    pub fn set_grasp(&mut self, tool: ColliderHandle, grasp: bool) -> Result<(), CouplingError> {
        let t = self
            .tools
            .get_mut(&tool)
            .ok_or(CouplingError::NoSuchCollider)?;
        t.grasp = grasp;
        Ok(())
    }

    /// Whether `tool` grasps ([`SurfaceSet::set_grasp`]).
    pub fn is_grasping(&self, tool: ColliderHandle) -> bool {
        self.tools.get(&tool).is_some_and(|t| t.grasp)
    }

    /// The friction of `tool` on `surface`: the pair's own, else the tool's
    /// ([`Friction::NONE`] for an unknown tool).
    pub fn friction(&self, surface: SurfaceHandle, tool: ColliderHandle) -> Friction {
        self.get(surface)
            .and_then(|s| s.pair_friction.get(&tool).copied())
            .or_else(|| self.tools.get(&tool).map(|t| t.friction))
            .unwrap_or(Friction::NONE)
    }

    /// The reaction on `tool` after the last step.
    pub fn tool_reaction(&self, tool: ColliderHandle) -> Option<ToolReaction> {
        self.tools.get(&tool).map(|t| t.reaction)
    }

    /// The haptic path: puts `tool` at the device pose `device` (world), steps every surface
    /// once at its own time step with that tool moving from its last haptic pose (the other
    /// tools stay where they are), and returns the tool's reaction. No rigid step and no
    /// collider update: call it at the device's rate (1 kHz and more) between
    /// [`SurfaceSet::step`]s, which keep the rest of the scene going.
    pub fn haptic_step(
        &mut self,
        world: &PhysicsWorld,
        tool: ColliderHandle,
        device: Pose,
    ) -> Option<ToolReaction> {
        if !device.is_finite() || !world.colliders.contains(tool) {
            return None;
        }
        let state = self.tools.get_mut(&tool)?;
        let start = state.haptic_prev.unwrap_or(device);
        state.haptic_prev = Some(device);
        let (shape, friction, grasp) = (state.shape.clone(), state.friction, state.grasp);
        let others: Vec<ToolMotion> = self
            .tools
            .iter()
            .filter(|(h, _)| **h != tool)
            .filter_map(|(h, t)| {
                let p = *world.colliders.get(*h)?.position();
                Some(ToolMotion {
                    handle: *h,
                    start: p,
                    end: p,
                    shape: t.shape.clone(),
                    friction: t.friction,
                    grasp: t.grasp,
                })
            })
            .chain(std::iter::once(ToolMotion {
                handle: tool,
                start,
                end: device,
                shape,
                friction,
                grasp,
            }))
            .collect();
        let mut total = ToolReaction::default();
        for (_, s, body_pose) in attached_with_pose(&mut self.entries, world) {
            let h = s.surface.dt();
            for (th, r) in surface_substep(s, world, &body_pose, &others, h) {
                if th == tool {
                    total.force += r.force;
                    total.torque += r.torque;
                    total.mean_force += r.force;
                    total.held_vertices += r.held_vertices;
                    total.sticking_vertices += r.sticking_vertices;
                    total.pressed_points += r.pressed_points;
                }
            }
        }
        if let Some(state) = self.tools.get_mut(&tool) {
            state.reaction = total;
        }
        Some(total)
    }

    /// Steps rapier, then every surface (see the type's docs).
    pub fn step(&mut self, world: &mut PhysicsWorld) {
        self.step_with(world, |w| w.step());
    }

    /// Like [`SurfaceSet::step`] with your own rigid step (e.g. a
    /// [`crate::hooks::TouchPipeline`]).
    pub fn step_with(
        &mut self,
        world: &mut PhysicsWorld,
        rigid_step: impl FnOnce(&mut PhysicsWorld),
    ) {
        self.begin_step(&world.colliders);
        self.drive_haptic_tools(&mut world.bodies, &mut world.colliders);
        rigid_step(world);
        self.step_surfaces(world);
        self.publish_haptic_models(world);
    }

    /// Records the tools' poses at the start of a rigid step (the first half of
    /// [`SurfaceSet::step_with`], for engines that own the step).
    pub(crate) fn begin_step(&mut self, colliders: &ColliderSet) {
        self.tools.retain(|h, _| colliders.contains(*h));
        for (h, t) in self.tools.iter_mut() {
            t.prev = colliders.get(*h).map(|c| *c.position());
        }
    }

    /// The surface part of a step: substeps with the tools' poses interpolated from the
    /// recorded start poses to their current ones, reactions, impulses on dynamic tools, and
    /// collider updates.
    pub(crate) fn step_surfaces(&mut self, world: &mut PhysicsWorld) {
        let dt = world.integration_parameters.dt;
        for t in self.tools.values_mut() {
            t.reaction = ToolReaction::default();
        }
        let tool_list: Vec<ToolMotion> = self
            .tools
            .iter()
            .filter_map(|(h, t)| {
                let c = world.colliders.get(*h)?;
                let now = *c.position();
                Some(ToolMotion {
                    handle: *h,
                    start: t.prev.unwrap_or(now),
                    end: now,
                    shape: t.shape.clone(),
                    friction: t.friction,
                    grasp: t.grasp,
                })
            })
            .collect();
        let mut mean: HashMap<ColliderHandle, (Vector, Vector)> = HashMap::new();
        let mut touching = parry3d::utils::hashset::HashSet::default();
        for (handle, s, body_pose) in attached_with_pose(&mut self.entries, world) {
            let n = s.substeps.max(1);
            let h = dt / n as Real;
            for k in 1..=n {
                let a = k as Real / n as Real;
                let a_prev = (k - 1) as Real / n as Real;
                let poses: Vec<ToolMotion> = tool_list
                    .iter()
                    .map(|t| ToolMotion {
                        handle: t.handle,
                        start: lerp_pose(&t.start, &t.end, a_prev),
                        end: lerp_pose(&t.start, &t.end, a),
                        shape: t.shape.clone(),
                        friction: t.friction,
                        grasp: t.grasp,
                    })
                    .collect();
                for (th, r) in surface_substep(s, world, &body_pose, &poses, h) {
                    let m = mean.entry(th).or_insert((Vector::ZERO, Vector::ZERO));
                    m.0 += r.force / n as Real;
                    m.1 += r.torque / n as Real;
                    if k == n {
                        if r.held_vertices > 0 || r.pressed_points > 0 {
                            touching.insert((th, handle));
                        }
                        if let Some(t) = self.tools.get_mut(&th) {
                            t.reaction.force += r.force;
                            t.reaction.torque += r.torque;
                            t.reaction.held_vertices += r.held_vertices;
                            t.reaction.sticking_vertices += r.sticking_vertices;
                            t.reaction.pressed_points += r.pressed_points;
                        }
                    }
                }
            }
        }
        super::events::update(&mut self.touch, touching);
        // The colliders follow the deformed surfaces (a BVH refit each, once per rigid step).
        for (_, entry) in self.entries.iter_mut() {
            let Some(s) = entry.as_mut() else {
                continue;
            };
            if let Some(ch) = s.collider {
                s.surface.positions_into(&mut s.scratch);
                if let Some(c) = world.colliders.get_mut(ch) {
                    if let Some(m) = c.shape_mut().as_trimesh_mut() {
                        m.set_vertices(&s.scratch);
                    }
                }
            }
        }
        // Two-way coupling: dynamic tools carry the averaged reaction as a rapier force during
        // the next rigid step (one step of lag). The crate's previous contribution is replaced,
        // the user's own forces on the body are left alone.
        for (th, t) in self.tools.iter_mut() {
            let (f, tq) = mean
                .get(th)
                .copied()
                .unwrap_or((Vector::ZERO, Vector::ZERO));
            t.reaction.mean_force = f;
            let (f, tq) = if f.is_finite() && tq.is_finite() {
                (f, tq)
            } else {
                (Vector::ZERO, Vector::ZERO)
            };
            let Some(parent) = world.colliders.get(*th).and_then(|c| c.parent()) else {
                continue;
            };
            if let Some(b) = world.bodies.get_mut(parent) {
                if b.is_dynamic() {
                    b.add_force(f - t.applied.0, true);
                    b.add_torque(tq - t.applied.1, true);
                    t.applied = (f, tq);
                }
            }
        }
    }
}
