//! Haptics at device rate (issue 14): a servo loop on its own thread renders the contact forces
//! of a tool at 1-10 kHz while the world steps at its own rate.
//!
//! - The device layer: a [`HapticDevice`] trait (pose and buttons in, force out, a
//!   [`Workspace`] mapping device to world), a [`SimulatedHand`] that stands in for a user in
//!   tests and examples, and [`Recording`]s of device trajectories (CSV).
//! - The exchange: [`haptic_link`] gives a tool's two ends, a [`WorldLink`] for the world
//!   thread ([`crate::coupling::SurfaceSet::connect_haptic`]) and a [`ServoLink`] for the
//!   servo thread. They share wait-free triple buffers: neither side ever waits for the other,
//!   so a world step or a refactorization never blocks the device.
//! - The local model: after each world step the surface set publishes a [`ServoModel`] per
//!   linked tool (the full solution's force at the tool less its dampers' share, the
//!   contact's stiffness around it,
//!   the few vertices a smooth tool holds, the surface vertices near a tool that touches
//!   nothing). Its size depends on the
//!   contact, not on the mesh.
//! - The loop: [`Servo`] reads the device, rests a massless proxy between the
//!   [`VirtualCoupling`] and the model's force, renders the coupling's force (bounded; passive
//!   under [`VirtualCoupling::max_passive_stiffness`]) and sends the proxy back; the world
//!   moves the tool there. [`Servo::spawn`] runs it on its own thread.
//!
//! No pipeline is needed here; the world side lives in [`crate::coupling`]. In bevy (the
//! `bevy` feature), give the tool's entity a `bevy_plugin::HapticTool` holding the world end:
//! the plugin connects it, moves it to the proxy and publishes its models around each step.
//!
//! # Limits
//! - Translation only: the model renders the force on the tool, not a torque (a 3-DoF
//!   device); a 6-DoF device's rotation is passed to the tool but gets no torque back.
//! - The model is a linearisation around the last full solution, so it is only as good as
//!   the update is recent. The servo eases each update in ([`Servo::set_update_ramp`]): a
//!   world that steps slower than its `dt` in wall time (a 100,000-node surface under the
//!   exact filter steps in 24-27 ms on a 2-core machine, for a 1/60 s `dt`) is felt without
//!   knocks (largest jump 1.5-3.0 % of the peak on the 99,848-node sphere,
//!   `examples/haptic_thread.rs`), but its contact lags the hand: the world's simulated time
//!   runs slower than the wall, and a model is fully rendered one update interval after it
//!   arrives. A larger world `dt` is the other way to keep up with the wall clock; it was
//!   not re-measured with the ramp (before it, at 1/30 s the coupled contact bounced).
//! - On a heavily damped surface the next update depends on how the tool moved, not only on
//!   where it is: the dampers push against a moving press and let go when it stops. The
//!   model's force leaves out what the held vertices' dampers put on the last move, and its
//!   stiffness is what the next update meets a move with (dampers included, often far more
//!   than the static stiffness). Replayed synchronously (`tests/it/slow_world.rs`), a world
//!   that steps every 200-500 servo ticks over the damped 10,000-node sphere no longer shakes
//!   the hand (largest jump 1.7-3.2 % of the peak, against 3.0-51 % before); at 700 ticks,
//!   or 500 on the 100,000-node sphere, it still does.
//! - The model's stiffness is a symmetric, positive secant of the full solution between
//!   updates. A smooth tool (a ball, a capsule, a rounded shape) holding a few vertices (up
//!   to four: a coarse mesh) also gets them as [`HeldVertex`]es: each pushes along the tool's
//!   normal nearest its anchor, so its force turns as the tool slides past it, which no
//!   positive stiffness holds. On the six plates of `tests/it/haptic_servo.rs` the model
//!   predicts the next update within 5 % of the peak at 94-100 % of the updates; a capsule as
//!   wide as a mesh cell dragged over a stiff coarse plate went from 83 % (the secant alone,
//!   whose change of force came out at right angles to the true one) to 94 %, its misses
//!   left all updates where the full solution itself jumps by more than 5 % (a vertex
//!   captured or let go). Over 54 coarse stiff plates and tools nobody tuned, the full
//!   solution jumps so at about one update in five, and at the others the model is within
//!   5 % at 98.7 % of them (93.4 % with the secant alone). Scaling the secant by how well it predicted the last update
//!   raised the capsule to 87 % but gave a stiff press back 2.1 % more energy per cycle than
//!   the hand put in (0.8 % without): not kept. Adding a vertex the tool comes to cover
//!   between updates (as a first touch does) read better on that capsule (96 %) but worse
//!   over the 54 plates (97.8 % of the smooth updates): not kept.
//! - Passivity comes from the passivity controller ([`Servo::set_passivity`], on by
//!   default): the proxy moves toward where the model puts it only as far as keeps the
//!   energy its moves draw into the coupling spring over a contact at or below zero, so the
//!   hand gets at most the sampled spring's give-back, which its damping absorbs. A property
//!   test over scale (0.3 mm to 3 km), edge stiffness (10-2000 N/m), mass (10 g to 1 t),
//!   ball, cube and capsule tools, the update ramp on and off, in a world that steps slower
//!   than its clock and irregularly, finds the hand given at most half of what its damping
//!   took in contact, as the bound says (150 cases for each of ten seeds). Without the
//!   controller a cube on a 0.3 m, 883 N/m plate gave the hand 209 J against 48 J. Its price:
//!   a device that starts inside a surface, or a surface the world moves onto a device that
//!   holds still, renders nothing until the device presses on; where the model would push
//!   the proxy out with energy the device never put in, the proxy (and the tool) stays where
//!   it was and the device feels the coupling's stiffness.
//! - Between updates, a contact that starts is rendered from one surface vertex (the deepest
//!   the tool covers, with its own stiffness), not from the surface's coupled response: the
//!   first update after a touch corrects it.
//!
//! # Wiring a real device
//! Implement [`HapticDevice`] over the device's SDK (CHAI3D, OpenHaptics, libnifalcon...):
//! `state` reads its end effector (metres and radians in the device's frame) and buttons,
//! `set_force` sends a force (newtons, device frame). Give it the [`Workspace`] that maps its
//! reach onto the scene. If the SDK runs its own servo callback, call [`Servo::tick`] from it
//! instead of [`Servo::spawn`]. Nothing in the crate's tests needs hardware.

mod hand;
mod link;
mod recording;
mod servo;
mod servo_model;
mod virtual_coupling;

pub use hand::SimulatedHand;
pub use link::{haptic_link, DeviceSample, ServoLink, WorldLink};
pub use recording::{Recording, RecordingError};
pub use servo::{Servo, ServoReport, ServoThread, ServoTick, TickRecord};
pub(crate) use servo_model::{is_smooth, normal_at, outer, positive_part, MAX_PATCH};
pub use servo_model::{HeldVertex, PatchVertex, ServoModel};
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
    /// Called once at the end of every servo tick, after [`HapticDevice::set_force`]. A real
    /// device has nothing to do (its time runs by itself); a simulated one advances one tick.
    fn end_tick(&mut self) {}
}
