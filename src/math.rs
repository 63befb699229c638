//! The math types at the crate's boundary: rapier's own (glam via glamx).

pub use rapier3d::math::{Matrix, Pose, Real, Rotation, Vector};
