//! A simulated hand on a device: what tests and examples use instead of a user.

use super::{DeviceState, HapticDevice, HapticsError};
use crate::math::{Pose, Real, Vector};
use glamx::DVec3;

/// A hand holding a device's end effector: a point mass (hand and handle) pulled along a
/// scripted trajectory by a spring and damper (the arm), slowed by the device's own physical
/// damping, and pushed by the force the device renders (held over each servo tick). Each
/// [`SimulatedHand::step`] is one servo tick (semi-implicit Euler).
///
/// It keeps the books of energy: [`SimulatedHand::rendered_work`], the work the rendered
/// forces did on it, and [`SimulatedHand::damping_loss`], what the device's damping took.
///
/// # Example
/// ```
/// use rapier_touch::haptics::{HapticDevice, SimulatedHand};
/// use rapier_touch::prelude::{Pose, Vector};
///
/// // At 1 kHz, the arm holds the hand 1 cm below a wall at y = 0 that pushes back with
/// // 200 N/m: it settles where the arm (300 N/m) and the wall balance.
/// let mut hand = SimulatedHand::new(1000.0, |_t| Pose::from_translation(Vector::new(0.0, -0.01, 0.0))).unwrap();
/// for _ in 0..3000 {
///     let y = hand.state().pose.translation.y;
///     hand.set_force(Vector::new(0.0, (-y).max(0.0) * 200.0, 0.0));
///     hand.step();
/// }
/// let y = hand.state().pose.translation.y;
/// assert!((y + 0.01 * 300.0 / 500.0).abs() < 1e-5);
/// ```
pub struct SimulatedHand {
    /// Mass of hand and handle (kg). Default 0.1.
    pub mass: Real,
    /// The arm's spring toward the trajectory (N/m). Default 300.
    pub arm_stiffness: Real,
    /// The arm's damper (N·s/m). Default 5.
    pub arm_damping: Real,
    /// The device's physical damping (N·s/m). Default 2.
    pub device_damping: Real,
    trajectory: Box<dyn Fn(Real) -> Pose + Send>,
    dt: Real,
    t: f64,
    x: DVec3,
    v: DVec3,
    force: Vector,
    buttons: u32,
    rendered_work: f64,
    damping_loss: f64,
}

impl std::fmt::Debug for SimulatedHand {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimulatedHand")
            .field("t", &self.t)
            .field("position", &self.x)
            .field("velocity", &self.v)
            .field("force", &self.force)
            .finish_non_exhaustive()
    }
}

impl SimulatedHand {
    /// Integration steps of the hand per servo tick.
    pub const SUBSTEPS: u32 = 20;

    /// A hand served at `rate_hz`, its arm following `trajectory` (time in s to device pose),
    /// starting at rest where the trajectory starts.
    ///
    /// # Errors
    /// [`HapticsError::InvalidRate`] for a rate that is not finite and positive;
    /// [`HapticsError::InvalidTrajectory`] if the trajectory's start is not finite.
    pub fn new(
        rate_hz: Real,
        trajectory: impl Fn(Real) -> Pose + Send + 'static,
    ) -> Result<Self, HapticsError> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(HapticsError::InvalidRate(rate_hz as f64));
        }
        let start = trajectory(0.0);
        if !start.is_finite() {
            return Err(HapticsError::InvalidTrajectory);
        }
        Ok(SimulatedHand {
            mass: 0.1,
            arm_stiffness: 300.0,
            arm_damping: 5.0,
            device_damping: 2.0,
            trajectory: Box::new(trajectory),
            dt: 1.0 / rate_hz,
            t: 0.0,
            x: start.translation.as_dvec3(),
            v: DVec3::ZERO,
            force: Vector::ZERO,
            buttons: 0,
            rendered_work: 0.0,
            damping_loss: 0.0,
        })
    }

    /// One servo tick: the arm, the device's damping and the rendered force (held over the
    /// tick, as a device holds it) move the hand, integrated in [`Self::SUBSTEPS`] steps as
    /// the continuous hand it stands for (so a held force does the work it does on a real
    /// device). A non-finite trajectory point leaves the arm where it was.
    pub fn step(&mut self) {
        // In f64: a sub-micrometre step added to a position of centimetres in f32 rounds by a
        // percent, and the books drifted from the motion the device reports.
        let h = self.dt as f64 / Self::SUBSTEPS as f64;
        let mass = self.mass.max(1e-9) as f64;
        let force = self.force.as_dvec3();
        let target_at = |t: f64| (self.trajectory)(t as Real).translation.as_dvec3();
        let mut before = target_at(self.t);
        for _ in 0..Self::SUBSTEPS {
            let next = target_at(self.t + h);
            let (target, target_v) = if next.is_finite() && before.is_finite() {
                (next, (next - before) / h)
            } else {
                (self.x, DVec3::ZERO)
            };
            let arm = (target - self.x) * self.arm_stiffness as f64
                + (target_v - self.v) * self.arm_damping as f64;
            let damping = -self.v * self.device_damping as f64;
            self.v += (arm + damping + force) * (h / mass);
            let step = self.v * h;
            self.rendered_work += force.dot(step);
            self.damping_loss += self.device_damping as f64 * self.v.length_squared() * h;
            self.x += step;
            self.t += h;
            before = next;
        }
    }

    /// Time (s).
    pub fn time(&self) -> Real {
        self.t as Real
    }

    /// The hand's velocity (device frame).
    pub fn velocity(&self) -> Vector {
        self.v.as_vec3()
    }

    /// Presses buttons (a bit each) from now on.
    pub fn set_buttons(&mut self, buttons: u32) {
        self.buttons = buttons;
    }

    /// The work the rendered forces have done on the hand (J): positive when the rendering
    /// gave the hand energy.
    pub fn rendered_work(&self) -> f64 {
        self.rendered_work
    }

    /// The energy the device's own damping has taken from the hand (J).
    pub fn damping_loss(&self) -> f64 {
        self.damping_loss
    }
}

impl HapticDevice for SimulatedHand {
    fn state(&mut self) -> DeviceState {
        DeviceState {
            pose: Pose::from_parts(self.x.as_vec3(), (self.trajectory)(self.t as Real).rotation),
            buttons: self.buttons,
        }
    }

    fn set_force(&mut self, force: Vector) {
        self.force = if force.is_finite() {
            force
        } else {
            Vector::ZERO
        };
    }

    /// One [`SimulatedHand::step`]: the hand's time runs with the servo's ticks.
    fn end_tick(&mut self) {
        self.step();
    }
}
