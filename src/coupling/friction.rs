//! Coulomb friction between a tool and a surface at the vertices the tool holds: a held vertex
//! sticks to the tool's material point while the tangential part of its spring and damper
//! force is within the static limit, and slips, pulled back by kinetic friction, beyond it.
//! At the points a tool presses between vertices, the same law is solved by the surface with
//! the step's constraints ([`crate::surface::Tangential::Coulomb`], `super::pressing`).

use super::surface_set::CouplingError;
use crate::math::{Real, Vector};
use parry3d::utils::hashmap::HashMap;
use rapier3d::geometry::ColliderHandle;

/// Coulomb friction coefficients of a tool on a surface
/// (see [`super::SurfaceSet::set_tool_friction`]).
///
/// # Example
/// ```
/// use rapier_touch::coupling::Friction;
///
/// let rubber = Friction::new(0.9, 0.7).unwrap();
/// assert_eq!(rubber.dynamic_coefficient, 0.7);
/// assert!(Friction::new(0.5, 0.6).is_err()); // kinetic above static
/// assert!(Friction::new(-0.1, 0.0).is_err());
/// assert_eq!(Friction::default(), Friction::NONE); // frictionless, as without friction
/// ```
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Friction {
    /// The static coefficient `μs`: a held vertex sticks while its tangential force is at most
    /// `μs` times its normal force.
    pub static_coefficient: Real,
    /// The dynamic (kinetic) coefficient `μd ≤ μs`: a slipping vertex is pulled against its
    /// slip by `μd` times its normal force, and the tool receives the opposite.
    pub dynamic_coefficient: Real,
}

impl Friction {
    /// No friction: held vertices slide freely (the default).
    pub const NONE: Friction = Friction {
        static_coefficient: 0.0,
        dynamic_coefficient: 0.0,
    };

    /// Static and dynamic coefficients.
    ///
    /// # Errors
    /// [`CouplingError::InvalidFriction`] for a negative or non-finite coefficient, or a
    /// dynamic coefficient above the static one.
    pub fn new(static_coefficient: Real, dynamic_coefficient: Real) -> Result<Self, CouplingError> {
        let f = Friction {
            static_coefficient,
            dynamic_coefficient,
        };
        f.check()?;
        Ok(f)
    }

    pub(super) fn check(&self) -> Result<(), CouplingError> {
        let (s, d) = (self.static_coefficient, self.dynamic_coefficient);
        if s.is_finite() && d.is_finite() && s >= 0.0 && d >= 0.0 && d <= s {
            Ok(())
        } else {
            Err(CouplingError::InvalidFriction {
                static_coefficient: s as f64,
                dynamic_coefficient: d as f64,
            })
        }
    }

    /// Whether held vertices slide freely (`μs = 0`).
    pub fn is_frictionless(&self) -> bool {
        self.static_coefficient <= 0.0
    }
}

/// How a held vertex touched its tool in the last substep (only with friction).
#[derive(Copy, Clone, Debug)]
pub(super) enum Contact {
    /// Stuck to this point of the tool (the tool's frame).
    Stuck(Vector),
    /// Slipping over the tool in this direction (unit, surface frame).
    Slipping(Vector),
}

/// The friction contacts of a surface's held vertices: the tool, and the contact.
pub(super) type Sticks = HashMap<u32, (ColliderHandle, Contact)>;

/// What a held vertex does next.
pub(super) enum Settled {
    /// It sticks to the tool's material point.
    Stick,
    /// It slides in direction `dir` (zero without friction) relative to the tool, with the
    /// kinetic friction force `on_vertex` on it.
    Slip { on_vertex: Vector, dir: Vector },
}

/// Coulomb's law for a held vertex pushing the tool with its spring and damper force `f`
/// (`f · n < 0`) at a contact of outward normal `n`, which last `was` stuck or slipping (or is
/// new), and moves over the tool with tangential velocity `slip` (`slip_eps`: a speed below
/// which it is at rest on the tool). Returns the force the tool receives, and what the vertex
/// does next:
/// - a stuck vertex stays stuck while its tangential force is within `μs` times its normal
///   force, and slips along that force beyond it;
/// - a slipping (or new) vertex that stopped or turned back over the tool, with its tangential
///   force within the static limit, sticks; otherwise it slips along its motion over the tool
///   (along its force when at rest), against kinetic friction `μd` times its normal force.
pub(super) fn settle(
    friction: Friction,
    f: Vector,
    n: Vector,
    was: Option<Contact>,
    slip: Vector,
    slip_eps: Real,
) -> (Vector, Settled) {
    let load = -f.dot(n);
    let normal = -n * load;
    if friction.is_frictionless() {
        let none = Settled::Slip {
            on_vertex: Vector::ZERO,
            dir: Vector::ZERO,
        };
        return (normal, none);
    }
    let tangential = f - normal;
    let within = tangential.length() <= friction.static_coefficient * load;
    let at_rest = match was {
        Some(Contact::Stuck(_)) => true,
        Some(Contact::Slipping(dir)) => slip.dot(dir) <= slip_eps,
        None => slip.length() <= slip_eps,
    };
    if at_rest && within {
        return (f, Settled::Stick);
    }
    let dir = match was {
        Some(Contact::Slipping(_)) | None if slip.length() > slip_eps => slip.normalize(),
        _ => tangential.normalize_or_zero(),
    };
    let kinetic = dir * (friction.dynamic_coefficient * load);
    let settled = Settled::Slip {
        on_vertex: -kinetic,
        dir,
    };
    (normal + kinetic, settled)
}
