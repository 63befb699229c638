//! Pure geometry: contact reconstruction by inverse trajectory mapping (paper section 2,
//! eq. 1-3). No rapier pipeline here: plain poses, meshes and slices.
//!
//! - [`TouchMesh`]: a parry `TriMesh` plus adjacency, built once per mesh (from any collider
//!   shape with a surface: [`TouchMesh::from_shape`]).
//! - [`Reconstructor`]: walks the moving object back along its trajectory to first touch.
//! - [`ContactConfiguration`]: state, reversing vector and the classified contact patches.
//! - [`tool_surface_contacts`]: a rigid tool's vertices and edges pressing a deformable
//!   surface between its vertices (the same eq. 1-3 tests, for the soft coupling).

mod classify;
mod contact;
pub mod generators;
mod hull;
mod mesh_separation;
mod motion;
mod reconstruction;
mod shape_cast;
mod shapes;
pub(crate) mod solid_contacts;
mod surface_bvh;
mod surface_contact;
pub(crate) mod tool_boundary;
mod touch_mesh;

pub use contact::{
    ContactConfiguration, ContactKind, ContactPatch, ContactPoint, DirectionSource, TouchState,
};
pub(crate) use mesh_separation::apart_from_mesh;
pub use motion::RigidMotion;
pub(crate) use motion::GRAZING;
pub use reconstruction::{ReconstructionError, ReconstructionOptions, Reconstructor};
pub(crate) use shape_cast::contact_near;
pub(crate) use shapes::shape_reach;
pub use surface_bvh::{NearCache, SurfaceBvh};
pub use surface_contact::{
    tool_surface_contacts, tool_surface_contacts_with_rings, triangles_in, SurfaceContact,
    SurfaceSnapshot, TrianglesRound,
};
pub use touch_mesh::{safe_step_length, Feature, TouchMesh, TouchMeshError};
