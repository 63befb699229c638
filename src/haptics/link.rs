//! The lock-free exchange between a world step and a servo loop: a pair of wait-free triple
//! buffers per tool (the `triple_buffer` crate), one carrying the world's [`ServoModel`] to the
//! servo loop, one carrying the device's latest [`DeviceSample`] back.

use super::ServoModel;
use crate::math::{Pose, Vector};
use triple_buffer::{triple_buffer, Input, Output};

/// What the servo loop last computed for its tool: the device's pose (world), the proxy pose
/// the tool should move to (the device's rotation, the proxy's position), the force rendered.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct DeviceSample {
    /// Servo ticks so far (0: the servo loop has not run yet).
    pub tick: u64,
    /// The device's pose, mapped into the world.
    pub device: Pose,
    /// Where the tool should be: the proxy.
    pub proxy: Pose,
    /// The device's buttons.
    pub buttons: u32,
    /// The force rendered at this tick (world, N).
    pub force: Vector,
    /// The [`ServoModel::sequence`] this tick read.
    pub model_sequence: u64,
}

impl Default for DeviceSample {
    fn default() -> Self {
        DeviceSample {
            tick: 0,
            device: Pose::IDENTITY,
            proxy: Pose::IDENTITY,
            buttons: 0,
            force: Vector::ZERO,
            model_sequence: 0,
        }
    }
}

/// The world's end of a haptic link: publishes models, reads the device. Give it to
/// [`crate::coupling::SurfaceSet::connect_haptic`]. Dropping it tells the servo loop to render
/// nothing.
#[derive(Debug)]
pub struct WorldLink {
    model: Input<ServoModel>,
    device: Output<DeviceSample>,
    sequence: u64,
}

/// The servo loop's end of a haptic link: reads the latest model, publishes device samples.
/// Neither call waits for the world (wait-free), allocates, or takes a lock.
#[derive(Debug)]
pub struct ServoLink {
    model: Output<ServoModel>,
    device: Input<DeviceSample>,
}

/// A new haptic link for one tool: its world end and its servo end (each `Send`, to live on
/// different threads).
///
/// # Example
/// ```
/// use rapier_touch::haptics::{haptic_link, DeviceSample, ServoModel};
/// use rapier_touch::prelude::Vector;
///
/// let (mut world_end, mut servo_end) = haptic_link();
/// world_end.publish(ServoModel { force: Vector::Y, ..ServoModel::default() });
/// assert_eq!(servo_end.model().sequence, 1);
/// servo_end.send(DeviceSample { tick: 7, ..DeviceSample::default() });
/// assert_eq!(world_end.device().tick, 7);
/// ```
pub fn haptic_link() -> (WorldLink, ServoLink) {
    let (model_in, model_out) = triple_buffer(&ServoModel::default());
    let (device_in, device_out) = triple_buffer(&DeviceSample::default());
    (
        WorldLink {
            model: model_in,
            device: device_out,
            sequence: 0,
        },
        ServoLink {
            model: model_out,
            device: device_in,
        },
    )
}

impl WorldLink {
    /// Publishes `model` (its `sequence` is set to the next number) for the servo loop.
    pub fn publish(&mut self, mut model: ServoModel) {
        self.sequence += 1;
        model.sequence = self.sequence;
        self.model.write(model);
    }

    /// The servo loop's latest sample.
    pub fn device(&mut self) -> DeviceSample {
        *self.device.read()
    }

    /// How many models were published.
    pub fn sequence(&self) -> u64 {
        self.sequence
    }
}

impl Drop for WorldLink {
    fn drop(&mut self) {
        self.publish(ServoModel {
            attached: false,
            ..ServoModel::default()
        });
    }
}

impl ServoLink {
    /// The world's latest model.
    pub fn model(&mut self) -> &ServoModel {
        self.model.read()
    }

    /// Publishes the servo loop's latest sample.
    pub fn send(&mut self, sample: DeviceSample) {
        self.device.write(sample);
    }
}
