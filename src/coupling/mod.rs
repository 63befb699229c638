//! Soft surfaces in a rapier pipeline: [`SurfaceSet`] attaches [`crate::surface::MassSpringSurface`]s
//! to rigid bodies, gives them colliders that follow the deformation, lets any number of rigid
//! tools press into them, and returns each tool's reaction force (two-way for dynamic tools).

mod dynamic_tools;
mod events;
mod friction;
mod haptic_links;
mod holding;
mod pressing;
mod search;
mod surface_set;
mod tool_shape;
mod vertex_holds;

pub use events::ToolTouchEvent;
pub use friction::Friction;

pub use surface_set::{
    AttachOptions, AttachedSurface, CouplingError, SurfaceHandle, SurfaceSet, ToolReaction,
    SURFACE_SOLVER_GROUP,
};
