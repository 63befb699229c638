//! The soft-surface model (paper section 3), no rapier pipeline: a surface triangle mesh with
//! lumped masses on its vertices and a spring and a damper on every edge, integrated by
//! explicit Euler (eq. 4), the paper's global filter (eq. 8-10, in [`filter`]) or Baraff-Witkin
//! implicit Euler.
//!
//! - [`MassSpringSurface`] / [`MassSpringSurfaceBuilder`]: the model (eq. 3-4).
//! - [`filter`]: the global filter `W`, exact (sparse Cholesky) or immediate-neighbour.

pub mod filter;
mod gltf_mesh;
mod mass_spring_surface;
pub mod meshing;

pub use filter::{FilterError, FilterKind};
pub use mass_spring_surface::{
    Escaped, ForceProfile, Integrator, MassDistribution, MassSpringSurface,
    MassSpringSurfaceBuilder, PointPress, RigidHolder, SpringModel, SurfaceError, Tangential,
    DEFAULT_AREA_DENSITY,
};
