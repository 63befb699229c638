//! How the points with friction hold to their holders through the filtered step's friction
//! passes ([`super::constrain`]).

/// How a point with friction holds to its holder in a pass of the filtered step's solve.
#[derive(Copy, Clone, Debug)]
pub(super) enum Grip {
    /// Not pushing: no friction.
    Off,
    /// Carried by its holder (its tangent rows in the solve).
    Stuck,
    /// Sliding: its tangential impulse fixed at `impulse` (kinetic friction of its normal
    /// impulse) along the unit `direction` in its tangent rows' basis.
    Sliding { direction: (f64, f64), impulse: f64 },
}

/// A sliding point in a pass: its tangent rows, the unit direction of its impulse in their
/// basis, and the impulse.
pub(super) type SlidingPoint = ((usize, usize), (f64, f64), f64);

/// How closely a sliding point's impulse must follow kinetic friction of its normal impulse
/// before the passes stop (relative).
pub(super) const FRICTION_TOLERANCE: f64 = 1e-3;

/// Most solves of a block with friction (each pass fixes the sliding points' impulses at
/// kinetic friction of the last pass's normal impulses, and finds which points stick and
/// which slide).
pub(super) const FRICTION_PASSES: usize = 2;
