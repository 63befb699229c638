//! # rapier_touch
//!
//! Exact touch contacts and filtered soft surfaces for [rapier3d](https://rapier.rs).
//!
//! When two polyhedral objects interpenetrate, [`geometry::Reconstructor`] walks the moving one
//! back along its own trajectory (inverse trajectory mapping) to the configuration where it
//! first touched, returns the *reversing vector*, and says what touches: vertex, edge or face,
//! with the contact polygon and the mesh features on both sides.
//!
//! ## Quick start
//! ```
//! use rapier_touch::prelude::*;
//!
//! // A fixed floor slab and a cube that fell 0.5 m during the last step and now sinks 0.2 m.
//! let floor = TouchMesh::from_shape(&Cuboid::new(Vector::new(2.0, 0.5, 2.0))).unwrap();
//! let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.5))).unwrap();
//! let floor_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
//! let now = Pose::from_translation(Vector::new(0.3, 0.3, 0.0));
//! let before = Pose::from_translation(Vector::new(0.3, 0.8, 0.0));
//!
//! let mut rec = Reconstructor::default();
//! let contact = rec.reconstruct(&floor, &floor_pose, &cube, &now, &before).unwrap();
//! assert_eq!(contact.state, TouchState::Penetrating);
//! // Moving the cube by the reversing vector puts it exactly on the floor.
//! assert!((contact.reversing_vector - Vector::new(0.0, 0.2, 0.0)).length() < 1e-5);
//! let patch = &contact.patches[0];
//! assert_eq!(patch.kind, ContactKind::Face);
//! assert_eq!(patch.polygon.len(), 4); // the cube's bottom square
//! ```
//!
//! ## Layers
//! Lower layers never name a rapier handle or set:
//! - [`geometry`]: pure geometry, the paper's eq. (1)-(3) (no pipeline).
//! - [`surface`]: the soft-surface model, the paper's eq. (3)-(10) (no pipeline).
//! - [`coupling`]: soft surfaces on rapier bodies, pressed by rigid tools.
//! - [`hooks`]: the rapier integration: [`hooks::TouchPipeline`] steps a `PhysicsWorld` with
//!   [`hooks::TouchHooks`], a step guard against tunneling, tool proxies and contact reports.
//! - [`haptics`]: device-rate haptics (no pipeline): a device trait with a workspace mapping,
//!   a simulated hand for tests, the virtual coupling with its passive stiffness, CSV
//!   recordings of device trajectories, and the servo loop on its own thread that renders a
//!   local contact model the world publishes through wait-free links.
//! - `bevy_plugin` (feature `bevy`): the same in bevy_rapier3d 0.37's schedule: components
//!   for tracked colliders, soft surfaces and tools, the hooks through bevy_rapier's hook
//!   mechanism, the guard and the surfaces after its step.
//!
//! ## Caveats
//! - A body that also rotated over the step is walked back along its real path
//!   ([`geometry::RigidMotion`]: rotation about its centre of mass, as rapier integrates it); the
//!   result is then a touch pose ([`geometry::ContactConfiguration::touch_pose`]). If the step
//!   started penetrating, the reversal continues past the step's start to the nearest
//!   non-penetrating pose ([`geometry::ContactConfiguration::on_trajectory`] is `false`).
//! - With no translation (`D = 0`) a fallback direction is used
//!   ([`geometry::ReconstructionOptions::zero_motion_direction`]).
//! - "One object wholly inside the other" is detected only when the outer one is closed;
//!   open meshes (a floor of zero thickness) are shells.
#![warn(missing_docs)]
#![warn(missing_debug_implementations)]
#![cfg_attr(docsrs, feature(doc_cfg))]

pub use parry3d;
pub use rapier3d;

#[cfg(feature = "bevy")]
pub mod bevy_plugin;
pub mod coupling;
pub mod geometry;
pub mod haptics;
pub mod hooks;
pub mod math;
#[cfg(feature = "render")]
pub mod render;
#[cfg(feature = "fixtures")]
pub mod scenes;
pub mod surface;
mod touch_diff;

/// Everything a user needs, in one import.
///
/// It glob-imports next to `rapier3d::prelude::*` without ambiguity: the names both export
/// (`Real`, `Vector`, `Pose`, `Rotation`, `Cuboid`, `ConvexPolyhedron`, `TriMesh`) are the very
/// same items.
///
/// ```
/// # #![deny(ambiguous_glob_imports)]
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// // A unit cube on a collider and as a touch mesh, from the same `Cuboid`.
/// let shape = Cuboid::new(Vector::splat(0.5));
/// let collider = ColliderBuilder::new(SharedShape::new(shape)).build();
/// let mesh = TouchMesh::from_shape(collider.shape()).unwrap();
/// assert_eq!(mesh.num_triangles(), 12);
/// assert!((mesh.min_extent() - 1.0).abs() < 1e-6);
/// ```
pub mod prelude {
    pub use crate::coupling::{
        AttachOptions, AttachedSurface, CouplingError, Friction, SurfaceHandle, SurfaceSet,
        ToolReaction, ToolTouchEvent,
    };
    pub use crate::geometry::{
        safe_step_length, ContactConfiguration, ContactKind, ContactPatch, ContactPoint,
        DirectionSource, Feature, ReconstructionError, ReconstructionOptions, Reconstructor,
        RigidMotion, TouchMesh, TouchMeshError, TouchState,
    };
    pub use crate::hooks::{
        HookCounters, PairReport, PairTouchEvent, PhysicsSets, ToolFeedback, TouchHooks,
        TouchOptions, TouchPipeline,
    };
    pub use crate::math::{Pose, Real, Rotation, Vector};
    pub use crate::surface::{
        FilterKind, ForceProfile, Integrator, MassDistribution, MassSpringSurface,
        MassSpringSurfaceBuilder, PointPress, SpringModel, SurfaceError, Tangential,
    };
    // The shapes below are the very items `rapier3d::prelude` exports under the same names
    // (rapier's `Cuboid` is its own alias of parry's), so both preludes glob-import together.
    pub use parry3d::shape::{ConvexPolyhedron, TriMesh};
    pub use rapier3d::geometry::Cuboid;
}

/// The README's code blocks, compiled and run as doctests so the README stays true.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
#[derive(Debug)]
pub struct ReadmeDoctests;
