//! The servo loop's passivity controller (on by default, [`Servo::set_passivity`]): the
//! observer books what the device's moves did beyond the coupling spring's own exchange, and
//! the proxy moves toward where the model puts it only as far as keeps the energy its moves
//! draw into the spring over a contact at or below zero.

use super::{LastTick, Servo};
use crate::haptics::HapticDevice;
use crate::math::{Real, Vector};

impl<D: HapticDevice> Servo<D> {
    /// The coupling spring's energy (J) with the device at `x` and the proxy at `p`.
    pub(super) fn spring_energy(&self, x: Vector, p: Vector) -> f64 {
        0.5 * self.coupling.stiffness.max(0.0) as f64 * (p - x).length_squared() as f64
    }

    /// The passivity observer's hand phase: the device moved from the last tick's position to
    /// `x` under the last tick's force, its proxy held. For the coupling's spring alone that
    /// force's work is exactly what the spring's energy lost plus the sampled spring's
    /// give-back `k Δx² / 2` (which the device's damping absorbs under
    /// [`crate::haptics::VirtualCoupling::max_passive_stiffness`]); what the damper or the
    /// force bound did beyond that is booked.
    pub(super) fn observe_hand_move(&mut self, last: LastTick, x: Vector) {
        let moved = x - last.device;
        let work = last.force.dot(moved) as f64;
        let residual = work + self.spring_energy(x, last.proxy)
            - self.spring_energy(last.device, last.proxy)
            - self.spring_energy(moved, Vector::ZERO);
        self.drawn += residual;
        if !self.drawn.is_finite() {
            self.drawn = 0.0;
        }
    }

    /// The passivity controller's proxy phase: the proxy goes from where it was toward the
    /// `candidate` (where the model puts it, with the surfaces' force `surface_force`) only
    /// as far as keeps the energy the proxy's moves have drawn into the coupling spring
    /// since the contact began at or below zero. Returns the proxy and the surfaces' force
    /// there. Out of contact (the candidate is the device `x`) nothing is drawn and the
    /// account restarts.
    ///
    /// Why it bounds the whole rendering: split a tick into the device's move (proxy held)
    /// and the proxy's move (device held). In the first the spring's work on the device is
    /// what its energy lost plus the sampled give-back; in the second it does no work on the
    /// device. Over a contact, then, the device gets the give-back plus what the proxy's
    /// moves drew in, which this keeps at or below zero. Under a fixed elastic model a proxy
    /// resting where the model puts it draws in minus what the surface stores, never above
    /// zero, so the bound acts only on what a model that changes under the tool (a world
    /// update, an eased-in offset, a damper's late force) would give. It is exact, not a
    /// prediction of the device's next move.
    pub(super) fn bound_proxy(
        &mut self,
        x: Vector,
        candidate: Vector,
        surface_force: Vector,
    ) -> (Vector, Vector) {
        if !(x.is_finite() && candidate.is_finite()) {
            return (candidate, surface_force);
        }
        if candidate == x {
            // Out of contact (the proxy is the device): the spring holds nothing, and the
            // account restarts.
            self.drawn = 0.0;
            return (candidate, surface_force);
        }
        // After a tick that read no device position (a dropped frame) the spring held
        // nothing: the proxy starts again from the device, with what the contact banked.
        let held = self.last.map_or(x, |l| l.proxy);
        let before = self.spring_energy(x, held);
        let after = self.spring_energy(x, candidate);
        let cap = (before - self.drawn).max(0.0);
        if after <= cap {
            self.drawn += after - before;
            return (candidate, surface_force);
        }
        // As far from the held proxy toward the candidate as the bound allows: the tool stays
        // where the world has it rather than being pulled onto the device (where, held on the
        // device with nothing banked, it would render nothing until the contact ended). When
        // even the held proxy is over the bound (a damper's work booked), toward the device.
        let k = self.coupling.stiffness.max(0.0) as f64;
        let bounded = match toward_within(held - x, candidate - held, 2.0 * cap / k) {
            Some(s) => held + (candidate - held) * s,
            None => x + (candidate - x) * (cap / after).sqrt() as Real,
        };
        let bounded = if bounded.is_finite() { bounded } else { x };
        self.drawn += self.spring_energy(x, bounded) - before;
        (bounded, self.model_at(bounded).0)
    }
}

/// The largest `s` in `[0, 1]` with `|d + s e|² <= r2` (`d`: from the device to the held
/// proxy, `e`: from the held proxy to the candidate), or `None` when `s = 0` is already over.
fn toward_within(d: Vector, e: Vector, r2: f64) -> Option<Real> {
    let (d, e) = (d.as_dvec3(), e.as_dvec3());
    let c = d.length_squared() - r2;
    if c.is_nan() || c > 0.0 {
        return None;
    }
    let (a, b) = (e.length_squared(), d.dot(e));
    if a <= 0.0 {
        return Some(0.0);
    }
    let s = (-b + (b * b - a * c).max(0.0).sqrt()) / a;
    Some(s.clamp(0.0, 1.0) as Real)
}

#[cfg(test)]
mod tests {
    use super::toward_within;
    use crate::math::Vector;

    #[test]
    fn the_step_toward_the_candidate_ends_on_the_bound() {
        // Held 1 cm from the device, the candidate 3 cm out along another axis, the bound at
        // 2 cm: the step stops where the stretch is 2 cm, and a held proxy already past the
        // bound gives none.
        let (d, e) = (Vector::new(0.01, 0.0, 0.0), Vector::new(0.0, 0.03, 0.0));
        let s = toward_within(d, e, 0.02f64 * 0.02).unwrap();
        let stretch = (d + e * s).length();
        assert!((stretch - 0.02).abs() < 1e-6, "stretch {stretch}");
        assert!(s > 0.0 && s < 1.0);
        assert_eq!(toward_within(d, e, 0.005f64 * 0.005), None);
        // Within the bound all the way: the whole step.
        assert_eq!(toward_within(d, e, 1.0), Some(1.0));
    }
}
