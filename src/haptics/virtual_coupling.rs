//! The virtual coupling between a device and its tool proxy (Colgate, Stanley and Brown 1995).

use crate::math::{Real, Vector};

/// A spring and damper between the device and the tool proxy, with a force bound: what the
/// device renders is `k (proxy - device) + b (proxy velocity - device velocity)`, at most
/// `max_force` long.
///
/// Sampled at `f_s` with a force held between samples, a spring gives energy back (about
/// `k T / 2` of damping's worth, `T = 1 / f_s`); the coupled device stays passive while its
/// own physical damping `B` covers it, `k < 2 B f_s` (Colgate and Schenkel 1997, without the
/// coupling's damper): [`VirtualCoupling::max_passive_stiffness`]. A stiffer coupling can feel
/// stiffer and can buzz.
///
/// # Example
/// ```
/// use rapier_touch::haptics::VirtualCoupling;
/// use rapier_touch::prelude::Vector;
///
/// // A device with 2 N·s/m of its own damping, served at 5 kHz: up to 20 kN/m.
/// let k_max = VirtualCoupling::max_passive_stiffness(5000.0, 2.0);
/// assert!((k_max - 20_000.0).abs() < 1e-3);
/// let c = VirtualCoupling { stiffness: 0.5 * k_max, damping: 0.0, max_force: 8.0 };
/// // 1 mm from the proxy: 10 N, bounded to 8 N, toward the proxy.
/// let f = c.force(Vector::ZERO, Vector::ZERO, Vector::new(0.0, 1e-3, 0.0), Vector::ZERO);
/// assert!((f - Vector::new(0.0, 8.0, 0.0)).length() < 1e-4);
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct VirtualCoupling {
    /// Spring stiffness (N/m).
    pub stiffness: Real,
    /// Damper (N·s/m).
    pub damping: Real,
    /// The longest force rendered (N).
    pub max_force: Real,
}

impl VirtualCoupling {
    /// The stiffest spring a device of physical damping `device_damping` (N·s/m) renders
    /// passively when served at `rate_hz`: `2 B f_s` (zero for a bad input).
    pub fn max_passive_stiffness(rate_hz: Real, device_damping: Real) -> Real {
        if rate_hz.is_finite() && device_damping.is_finite() && rate_hz > 0.0 {
            (2.0 * device_damping * rate_hz).max(0.0)
        } else {
            0.0
        }
    }

    /// The force on the device (world units) for the device and proxy positions and
    /// velocities. Not finite inputs render no force.
    pub fn force(
        &self,
        device: Vector,
        device_velocity: Vector,
        proxy: Vector,
        proxy_velocity: Vector,
    ) -> Vector {
        let f =
            (proxy - device) * self.stiffness + (proxy_velocity - device_velocity) * self.damping;
        if !f.is_finite() {
            return Vector::ZERO;
        }
        f.clamp_length_max(self.max_force.max(0.0))
    }
}
