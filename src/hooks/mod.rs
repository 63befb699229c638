//! The rapier integration: hooks, the step guard, tools and reports.
//!
//! Lower layers ([`crate::geometry`]) know nothing of rapier's sets and handles; this one wires
//! them into a rapier 0.36 pipeline.
//!
//! # Activating
//! Give colliders `ActiveHooks::MODIFY_SOLVER_CONTACTS` and step the world through
//! [`TouchPipeline::step`] (or hand [`TouchPipeline::hooks`] to your own `step` calls and
//! call the guard yourself, see the pipeline's docs).
//!
//! # Caveats
//! - rapier runs hooks at the start of `step`, on the previous step's poses, with read-only
//!   sets: hooks can move at most rapier's ≤ 4 solver contacts per manifold and cannot move
//!   bodies, so exact positions come from the step guard, between steps.
//! - Set `IntegrationParameters::contact_clustering = false` ([`TouchPipeline::configure`]).
//! - Sleeping bodies are not guarded (they do not move); a collider whose shape has no
//!   triangle-mesh form (half-spaces, segments, polylines, custom shapes) is left to rapier
//!   ([`TouchPipeline::refused_colliders`]).
//! - Curved shapes (balls, capsules, cylinders, cones, rounded shapes) are guarded on the
//!   shapes themselves ([`crate::geometry::Reconstructor::reconstruct_shapes`]: conservative
//!   advancement on parry's GJK), not on their tessellated touch meshes; the hooks never
//!   rewrite their contacts (rapier's are exact).
//! - Two dynamic bodies that cannot have passed through each other over a step (relative
//!   travel under their safe step length) keep rapier's soft contact, in the guard and in the
//!   hooks alike.

mod events;
pub(crate) mod pair_filter;
mod pose_history;
mod report;
mod sets;
mod step_motion;
mod touch_hooks;
mod touch_pipeline;
pub(crate) use touch_pipeline::pose_sync::sync_moved_colliders;

pub use events::PairTouchEvent;
#[cfg(feature = "bevy")]
pub(crate) use pose_history::PoseHistory;
pub use report::{PairReport, ToolFeedback};
pub use sets::PhysicsSets;
pub use touch_hooks::{HookCounters, TouchHooks};
pub use touch_pipeline::{TouchOptions, TouchPipeline};
