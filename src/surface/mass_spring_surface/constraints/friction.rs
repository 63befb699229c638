//! How the points with friction hold to their holders through the filtered step's friction
//! passes ([`super::constrain`]).

use glamx::DVec3;

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

impl Grip {
    /// Coulomb's law on a pass's impulses: a point with no normal `load` is let go (no
    /// friction), one let go is stuck again, a stuck one whose `carrying` impulse (in its
    /// tangent rows' basis) passes the static limit slides at kinetic friction, and a sliding
    /// one that its fixed impulse would drive past its holder (its rows' `residual` against
    /// its direction) sticks.
    pub(super) fn next(
        self,
        load: f64,
        carrying: (f64, f64),
        residual: impl FnOnce() -> (f64, f64),
        (mu_s, mu_d): (f64, f64),
    ) -> Grip {
        match self {
            _ if load == 0.0 => Grip::Off,
            Grip::Off => Grip::Stuck,
            Grip::Stuck => match unit(carrying) {
                Some(direction) if carrying.0.hypot(carrying.1) > mu_s * load => Grip::Sliding {
                    direction,
                    impulse: mu_d * load,
                },
                _ => Grip::Stuck,
            },
            Grip::Sliding { direction, .. } => {
                let r = residual();
                if r.0 * direction.0 + r.1 * direction.1 < 0.0 {
                    Grip::Stuck
                } else {
                    Grip::Sliding {
                        direction,
                        impulse: mu_d * load,
                    }
                }
            }
        }
    }

    /// Whether going to `next` changes the point's hold enough for another pass.
    pub(super) fn changed_to(self, next: Grip) -> bool {
        match (self, next) {
            (Grip::Sliding { impulse: a, .. }, Grip::Sliding { impulse: b, .. }) => {
                (a - b).abs() > FRICTION_TOLERANCE * b
            }
            (a, b) => std::mem::discriminant(&a) != std::mem::discriminant(&b),
        }
    }
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

/// Most solves of a block with a rigid holder's rows ([`HolderCuts`]: a 16 g box under a
/// column of three on a stiff plate, with two, took 0.03 N·s sideways on a 0.003 N·s weight
/// and later blew up).
pub(super) const HOLDER_FRICTION_PASSES: usize = 4;

/// How much of a rigid holder's normal load (as a force, and as a torque over its longest
/// lever arm) cutting its stuck points to their static limit after the last pass may take off
/// it before the block is solved again without friction on those points.
pub(super) const UNBALANCED: f64 = 0.1;

/// What cutting rigid holders' stuck points to their static limit after a pass would take off
/// each holder.
///
/// A holder's stuck points are coupled through its motion and can take impulses far past
/// their static limit in a solve, the normal rows' pushes balancing them. Cut to the limit
/// after the last pass, they left those pushes unbalanced: a box struck by another took a
/// point's 0.06 N·s of carrying with no normal load behind it and spun at 260 rad/s. The
/// passes help (a holder gets [`HOLDER_FRICTION_PASSES`]); where they end with points whose
/// cuts would take more than [`UNBALANCED`] of their holder's load off it (as a force, or as
/// a torque over its longest lever arm), the block is solved once more with no friction on
/// those points for that substep: a consistent answer, which creates no energy. Smaller cuts
/// are made as before: a column at rest on a plate has its stuck points squeeze the plate's
/// vertices against each other past their limits (a median of 2.5 times it after the last
/// pass), and the cuts cancel; solved without their friction instead, the boxes above the
/// lowest rocked at 1-3 cm/s for good.
pub(super) struct HolderCuts {
    /// Per holder: the force and torque the cuts take off it, its longest lever arm and its
    /// points' normal load.
    net: Vec<(DVec3, DVec3, f64, f64)>,
    /// The points past their limit, with their holder.
    over: Vec<(usize, usize)>,
}

impl HolderCuts {
    /// No cuts yet, for `holders` holders.
    pub(super) fn new(holders: usize) -> Self {
        HolderCuts {
            net: vec![(DVec3::ZERO, DVec3::ZERO, 0.0, 0.0); holders],
            over: Vec::new(),
        }
    }

    /// Stuck point `pi` on holder `(j, arm)` (its point from the holder's centre), carrying
    /// `carrying` along its tangent rows' `directions`, against its static `limit` and normal
    /// `load`.
    pub(super) fn add(
        &mut self,
        pi: usize,
        (j, arm): (usize, DVec3),
        (directions, carrying): ((DVec3, DVec3), (f64, f64)),
        limit: f64,
        load: f64,
    ) {
        let Some(n) = self.net.get_mut(j) else {
            return;
        };
        n.3 += load;
        n.2 = n.2.max(arm.length());
        let t = carrying.0.hypot(carrying.1);
        if t > limit * (1.0 + FRICTION_TOLERANCE) && t > 0.0 {
            let cut = (directions.0 * carrying.0 + directions.1 * carrying.1) * (1.0 - limit / t);
            n.0 += cut;
            n.1 += arm.cross(cut);
            self.over.push((pi, j));
        }
    }

    /// The points past their limit on holders their cuts would unbalance.
    pub(super) fn unbalancing(&self) -> Vec<usize> {
        let unbalanced = |j: usize| {
            let (f, t, arm, load) = self.net[j];
            f.length() + t.length() / arm.max(f64::MIN_POSITIVE) > UNBALANCED * load
        };
        self.over
            .iter()
            .filter(|&&(_, j)| unbalanced(j))
            .map(|&(pi, _)| pi)
            .collect()
    }
}

/// The unit direction of `(a, b)`, or `None` for a zero vector.
pub(super) fn unit((a, b): (f64, f64)) -> Option<(f64, f64)> {
    let l = a.hypot(b);
    (l > 0.0).then(|| (a / l, b / l))
}
