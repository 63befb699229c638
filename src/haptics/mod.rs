//! The device layer for haptics (issue 14, first part): a [`HapticDevice`] trait (pose and
//! buttons in, force out, a [`Workspace`] mapping device to world), a [`SimulatedHand`] that
//! stands in for a user on a device in tests and examples, the [`VirtualCoupling`] that
//! renders a tool proxy's position as a bounded, passive force, and [`Recording`]s of device
//! trajectories (CSV).
//!
//! No pipeline is needed: the crate's tool proxies ([`crate::hooks::TouchPipeline::tool_feedback`])
//! or a surface's [`crate::coupling::SurfaceSet::haptic_step`] give the proxy; a device loop
//! reads the device, moves the proxy's target, and writes the coupling's force back.
//!
//! # Wiring a real device
//! Implement [`HapticDevice`] over the device's SDK (CHAI3D, OpenHaptics, libnifalcon...):
//! `state` reads its end effector (metres and radians in the device's frame) and buttons,
//! `set_force` sends a force (newtons, device frame). Give it the [`Workspace`] that maps its
//! reach onto the scene. Nothing in the crate's tests needs hardware.
//!
//! Not yet here (issue 14 stays open): the servo thread with its lock-free exchange and the
//! local contact model at device rate.

mod hand;
mod recording;
mod virtual_coupling;

pub use hand::SimulatedHand;
pub use recording::{Recording, RecordingError};
pub use virtual_coupling::VirtualCoupling;

use crate::math::{Pose, Real, Vector};

/// Why a haptics object could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HapticsError {
    /// A servo rate must be finite and positive (Hz).
    #[error("invalid servo rate {0} Hz")]
    InvalidRate(f64),
    /// A trajectory must start at a finite pose.
    #[error("the trajectory does not start at a finite pose")]
    InvalidTrajectory,
}

/// What a device reports at one instant.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct DeviceState {
    /// The end effector's pose (device frame, metres).
    pub pose: Pose,
    /// Its buttons, one bit each.
    pub buttons: u32,
}

/// How a device's frame maps onto the world: a device position `p` is at
/// `offset · (scale p)` in the world, its rotation turned by `offset`'s. Forces map back so
/// that power is kept: a world force `f` is `scale · offset⁻¹ f` on the device (moving the
/// device by `d` moves the world point by `scale d`).
///
/// # Example
/// ```
/// use rapier_touch::haptics::Workspace;
/// use rapier_touch::prelude::{Pose, Vector};
///
/// // A desk device's ±10 cm onto a ±1 m scene, 1 m up.
/// let w = Workspace { scale: 10.0, offset: Pose::from_translation(Vector::Y) };
/// let world = w.to_world(&Pose::from_translation(Vector::new(0.05, 0.0, 0.0)));
/// assert!((world.translation - Vector::new(0.5, 1.0, 0.0)).length() < 1e-6);
/// // 1 N in the world is 10 N at the device: the same work over the mapped motion.
/// assert!((w.force_to_device(Vector::X) - Vector::X * 10.0).length() < 1e-6);
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Workspace {
    /// World metres per device metre.
    pub scale: Real,
    /// Where the device's origin and axes are in the world.
    pub offset: Pose,
}

impl Default for Workspace {
    /// The device's frame is the world's.
    fn default() -> Self {
        Workspace {
            scale: 1.0,
            offset: Pose::IDENTITY,
        }
    }
}

impl Workspace {
    /// The world pose of a device pose.
    pub fn to_world(&self, device: &Pose) -> Pose {
        self.offset * Pose::from_parts(device.translation * self.scale, device.rotation)
    }

    /// The device force that does the same work as the world force `f`.
    pub fn force_to_device(&self, f: Vector) -> Vector {
        self.offset.rotation.inverse() * f * self.scale
    }
}

/// A haptic device: reads its end effector and buttons, renders a force.
pub trait HapticDevice: Send {
    /// The end effector now.
    fn state(&mut self) -> DeviceState;
    /// Renders `force` (N, device frame) until the next call.
    fn set_force(&mut self, force: Vector);
    /// How the device maps onto the world.
    fn workspace(&self) -> Workspace {
        Workspace::default()
    }
}
