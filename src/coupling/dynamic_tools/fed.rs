//! The surfaces' support of a dynamic tool, handed to rapier as a force for one rigid step.

use crate::math::{Real, Vector};
use rapier3d::dynamics::{IntegrationParameters, RigidBodyHandle, RigidBodySet};

/// The surfaces' support of a dynamic tool, handed to rapier as a force on its body for one
/// rigid step (added before it, taken off after it).
///
/// The surfaces replay a rigid step's motion of a tool they touch from its pose and
/// velocities at the step's start. Without the support, rapier moved the tool as if nothing
/// held it: a box resting on a surface fell freely in rapier's step, and a box stacked on it
/// was pushed back by only its share of their contact (half, between equal boxes), the other
/// half going into the lower box's fall, which the surfaces' replay then undid. The upper box
/// sank into the lower one at a steady 0.3 m/s until the two were one (three 12 cm boxes
/// stacked on a soft plate ended at the same height). With the surfaces' support of the last
/// step as a force (the share of their impulse that held the tool:
/// [`super::DynamicTool::support`]), rapier's step holds the lower box as the surfaces will,
/// and the contact above it is solved against a supported body. The replay takes the support
/// back out of rapier's velocity ([`super::DynamicTool::new`]): what the body itself does is
/// still decided by the surfaces, in the same substep (implicitly), so a lone body moves as
/// without it.
///
/// Every awake dynamic tool's body gets a record, support or none: its velocities before
/// rapier's step, from which the replay starts ([`super::DynamicTool::new`]).
#[derive(Copy, Clone, Debug)]
pub(crate) struct Fed {
    pub body: RigidBodyHandle,
    pub(super) force: Vector,
    pub(super) torque: Vector,
    /// The body's user force and torque before: restored as they were.
    user_force: Vector,
    user_torque: Vector,
    /// The body's velocities before rapier's step.
    linvel: Vector,
    angvel: Vector,
}

impl Fed {
    /// Records an awake dynamic `body` before the coming rigid step and adds `(force, torque)`
    /// (torque about the centre of mass, world) to it for that step (none if not finite).
    pub fn add(
        bodies: &mut RigidBodySet,
        body: RigidBodyHandle,
        (force, torque): (Vector, Vector),
    ) -> Option<Self> {
        let b = bodies.get_mut(body)?;
        if !b.is_dynamic() || b.is_sleeping() {
            return None;
        }
        let (force, torque) = if force.is_finite() && torque.is_finite() {
            (force, torque)
        } else {
            (Vector::ZERO, Vector::ZERO)
        };
        let fed = Fed {
            body,
            force,
            torque,
            user_force: b.user_force(),
            user_torque: b.user_torque(),
            linvel: b.linvel(),
            angvel: b.angvel(),
        };
        if force == Vector::ZERO && torque == Vector::ZERO {
            return Some(fed);
        }
        b.add_force(force, false);
        b.add_torque(torque, false);
        Some(fed)
    }

    /// Takes the support off the body after rapier's step: the user's own force and torque
    /// exactly as they were, or, if something changed them since, less the support.
    pub fn remove(&self, bodies: &mut RigidBodySet) {
        let Some(b) = bodies.get_mut(self.body) else {
            return;
        };
        if self.force == Vector::ZERO && self.torque == Vector::ZERO {
            return;
        }
        if b.user_force() == self.user_force + self.force
            && b.user_torque() == self.user_torque + self.torque
        {
            b.reset_forces(false);
            b.reset_torques(false);
            b.add_force(self.user_force, false);
            b.add_torque(self.user_torque, false);
        } else {
            b.add_force(-self.force, false);
            b.add_torque(-self.torque, false);
        }
    }

    /// The velocities recorded before rapier's step, capped as rapier's step caps them (at
    /// `max_linear_velocity`, and at a quarter turn per step unless the body turns faster after
    /// the step: fast rotation allowed): a cap is an instant change, started from, not spread over
    /// the substeps (a ball thrown at 10³⁰ m/s crossed the plate in the first substep).
    pub(super) fn start_velocities(
        &self,
        params: &IntegrationParameters,
        angvel_after: Vector,
    ) -> (Vector, Vector) {
        let cap = |v: Vector, max: Real| {
            if max > 0.0 {
                v.clamp_length_max(max)
            } else {
                v
            }
        };
        let max_turn = std::f32::consts::FRAC_PI_4 * params.inv_dt();
        let turn = if angvel_after.length() > max_turn * 1.001 {
            self.angvel
        } else {
            cap(self.angvel, max_turn)
        };
        (cap(self.linvel, params.max_linear_velocity()), turn)
    }
}
