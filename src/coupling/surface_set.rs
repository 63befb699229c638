//! [`SurfaceSet`]: soft surfaces attached to rapier bodies, pressed by rigid tools.

use super::dynamic_tools::{press_ahead, DynamicTool, Fed, MotionChange};
use super::events::{ToolTouchEvent, TouchTracker};
use super::friction::{Friction, Sticks};
use super::haptic_links::LinkState;
use super::holding::{attached_with_pose, lerp_pose, surface_substep, HeldContacts, ToolMotion};
use super::pressing::{GraspedPoint, Pressed};
use super::search::ContactSearch;
use super::tool_shape::ToolShape;
use crate::geometry::SurfaceContact;
use crate::math::{Pose, Real, Vector};
use crate::surface::{MassSpringSurface, SurfaceError};
use parry3d::shape::{SharedShape, TriMeshFlags};
use parry3d::utils::hashmap::HashMap;
use parry3d::utils::hashset::HashSet;
use rapier3d::dynamics::RigidBodyHandle;
use rapier3d::geometry::{ColliderBuilder, ColliderHandle, ColliderSet, Group, InteractionGroups};
use rapier3d::pipeline::PhysicsWorld;
use std::sync::Arc;

mod auto_tools;
mod stepping;
mod tools;

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
    /// The surface has no collider ([`AttachOptions::collider`]), which
    /// [`SurfaceSet::set_auto_tools`] needs.
    #[error("the surface has no collider")]
    NoCollider,
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
    /// step becomes the world's `dt / substeps`, and follows the world's `dt` when it changes
    /// (the filter refactored once per change; a world's `dt` of zero steps no surface).
    /// Default 1.
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
    /// The impulse the surfaces gave the tool over the rigid step, over the step's length
    /// (N, world frame): the reverse of the momentum the tool gave them. For a dynamic tool,
    /// what moved it; for a kinematic one, what its vertex holds gave (the velocities they
    /// set, the part of the held vertices' forces they took, the constraint impulses that
    /// kept them on the tool) and its points' presses and impulses, in the substep each
    /// happened. On a free surface it balances the surface's momentum change exactly
    /// (`tests/it/momentum_books.rs`); `force`, the springs at the end of the step, does not
    /// (a tool striking a surface in one 60 Hz step reads several times the momentum it
    /// gave).
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
    /// Which vertices were held through the substep's step (`true` only at `held_list`, and
    /// only while the tools look; all `false` between substeps).
    pub(super) was_held: Vec<bool>,
    /// The vertices the tools held at the end of the last substep.
    pub(super) held_list: Vec<u32>,
    /// Which tool holds each of those: the impulses of its holds through the next step are
    /// its.
    pub(super) held_by: Vec<(u32, ColliderHandle)>,
    /// Points the tools pressed in the current and the last substep.
    pub(super) pressed: Vec<Pressed>,
    pub(super) last_pressed: Vec<Pressed>,
    /// Where the tools may touch the surface.
    pub(super) search: ContactSearch,
    pub(super) contacts: Vec<SurfaceContact>,
    /// Vertices stuck to a tool (friction).
    pub(super) sticks: Sticks,
    /// Points grasping tools hold.
    pub(super) grasped: Vec<GraspedPoint>,
    /// Friction of given tools on this surface, in place of the tool's own.
    pub(super) pair_friction: HashMap<ColliderHandle, Friction>,
    /// Whether any dynamic body about to touch it becomes a tool ([`SurfaceSet::set_auto_tools`]).
    pub(super) auto_tools: bool,
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
    /// Its parent body's pose times its pose on the body at the end of the last step (`None`
    /// for a collider without a body), to tell at the next step which of the two the user
    /// moved in between ([`SurfaceSet::begin_step`]).
    seen_on_body: Option<Pose>,
    pub(super) reaction: ToolReaction,
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
    /// The vertices it held at the end of the last step: each one's position and force on
    /// the tool (world), for the haptic model.
    pub(super) held: HeldContacts,
    /// A dynamic tool's support by the surfaces: their impulse and its moment about the
    /// centre of mass over its last rigid step, over the step's length (world; zero when they
    /// did not touch it), handed to rapier's next step as a force ([`super::dynamic_tools::Fed`]).
    pub(super) feed: (Vector, Vector),
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
/// kinetic friction for those that slip; plus the impulses of the points it presses between
/// vertices (normal, and with friction tangential: [`crate::surface::Tangential`]). A
/// grasping tool also holds those points, in every direction, until it lets go.
/// Dynamic tools are coupled implicitly ([`crate::surface::RigidHolder`]): rapier moves them
/// first (gravity, your forces, their other contacts, and the surfaces' support of the last
/// step as a force, so that bodies resting on a tool rest on a held body); then each surface
/// replays the rigid step from their poses and velocities at its start, what rapier's step
/// changed of those added a substep at a time, the body's mass entering every substep's
/// constraint solve, and the body takes the pose and velocity the surfaces leave it (with its
/// colliders, so ray casts see it there). A dynamic tool presses the surface vertices inside
/// it or within its reach over the next substep, the points of the triangles nearest it or deepest in it
/// (parry's contact query) and, for a polyhedral tool, its own vertices and edges; a point
/// short of it is a speculative contact, which may close its gap, not pass it, and one that
/// overlaps it by less than a thousandth of its size is held where it is, not pushed out.
/// Surface colliders are updated once per rigid step (`TriMesh::set_vertices`, a BVH refit).
///
/// # Limitations
/// - A dynamic tool touching two surfaces in one step gets the sum of what each changed of its
///   motion, each surface solving as if the other were not there. Its friction, like a
///   kinematic tool's, is [`SurfaceSet::set_tool_friction`]'s, not its collider's. rapier
///   decides when it sleeps; a sleeping one is woken when the surfaces move it faster than
///   its sleep thresholds (a box at rest on a plate still turns back and forth slightly, and
///   does not fall asleep).
///   The haptic path ([`SurfaceSet::haptic_step`]) holds dynamic tools where they are.
/// - Curved tools load the surface's vertices only (mesh it finer than a ball). Polyhedral
///   tools also press their vertices and edges between the surface's vertices, next to a
///   vertex they hold too, except points with less than a quarter of their weight off the
///   held vertex (left to that vertex's holder): a corner there can end tens of micrometres
///   inside a triangle.
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
    /// The tools [`SurfaceSet::set_auto_tools`] registered (not the user's).
    pub(super) auto: HashSet<ColliderHandle>,
    /// The supports added to dynamic tools' bodies for the rigid step under way.
    pub(super) fed: Vec<Fed>,
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
            tools: HashMap::default(),
            touch: TouchTracker::default(),
            links: HashMap::default(),
            auto: HashSet::default(),
            fed: Vec::new(),
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
            held_list: Vec::new(),
            held_by: Vec::new(),
            pressed: Vec::new(),
            last_pressed: Vec::new(),
            search: ContactSearch::default(),
            sticks: Sticks::default(),
            grasped: Vec::new(),
            pair_friction: HashMap::default(),
            auto_tools: false,
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
}
