//! Rigid holders: bodies whose mass enters the filtered step's constraint solve (implicit
//! coupling). A point pressed by a rigid holder ([`super::PointPress::holder`]) is held at the
//! holder's velocity *after* the step, which the surface's impulses change: the holder takes
//! `-Σ λ d` from its rows, so its velocity along row `a` at the point changes by
//! `-Σ_b (dₐ · M⁻¹ d_b + (rₐ × dₐ) · I⁻¹ (r_b × d_b)) λ_b`. Moved to the left of the solve's
//! `J P Jᵀ λ = b`, that is the holder's compliance added to `A` between its own rows (rank six
//! at most). A light body is then stopped by the surface's inertia and springs and a heavy one
//! carries on, in the same step, whatever the ratio of their masses: the surface and the body
//! meet as in an inelastic collision, which creates no energy (a force handed to the body a
//! step later does: a light body on a stiff surface overshoots and is flung).

use super::SurfaceError;
use crate::math::{Matrix, Real, Vector};
use glamx::{DMat3, DVec3};

/// A rigid body pressing points of the surface whose mass enters the filtered step's
/// constraint solve (see [`super::MassSpringSurface::set_holders`]). Everything is in the
/// surface's frame.
///
/// # Example
/// A 10 g needle falling at 1 m/s onto a plate of 30 g vertices presses the middle of a
/// triangle: in one step (1/60 s) they meet as in an inelastic collision, with the vertices
/// and the stiff springs behind them. The needle is all but stopped, and does not bounce.
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::surface::meshing::plate;
/// use rapier_touch::surface::RigidHolder;
///
/// let mesh = plate(1.0, 1.0, 4, 4);
/// let rim = |v: Vector| v.x.abs() > 0.49 || v.z.abs() > 0.49;
/// let edge: Vec<u32> = (0..mesh.vertices.len() as u32)
///     .filter(|&i| rim(mesh.vertices[i as usize]))
///     .collect();
/// let mut surface = MassSpringSurfaceBuilder::from_mesh(&mesh)
///     .mass(MassDistribution::PerVertex(0.03))
///     .pinned(edge)
///     .build()
///     .unwrap();
/// let [a, b, c] = *surface
///     .triangles()
///     .iter()
///     .find(|t| t.iter().all(|&v| !surface.is_pinned(v)))
///     .unwrap();
/// let down = Vector::new(0.0, -1.0, 0.0);
/// let needle = RigidHolder::point_mass(0.01, Vector::ZERO, down);
/// surface.set_holders(&[needle]).unwrap();
/// let third = 1.0 / 3.0;
/// let press = PointPress {
///     vertices: &[(a, third), (b, third), (c, third)],
///     normal: down,
///     depth: 0.0,
///     normal_velocity: 1.0,
///     tangential: Tangential::Free,
///     holder: Some((0, Vector::ZERO)),
/// };
/// surface.press_points(&[press]).unwrap();
/// surface.step();
/// let (impulse, _) = surface.holder_impulse(0).unwrap();
/// // The surface pushed the needle up: from 1 m/s down to a few cm/s, still down.
/// let velocity = -1.0 + impulse.y / 0.01;
/// assert!(velocity < 0.0 && velocity > -0.05, "{velocity}");
/// // The point moved down with it.
/// let point = (surface.velocity(a) + surface.velocity(b) + surface.velocity(c)) / 3.0;
/// assert!((point.y - velocity).abs() < 1e-3);
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RigidHolder {
    /// Its inverse mass (1/kg), as a matrix: `I / m` for a free body, zero along locked axes.
    pub inverse_mass: Matrix,
    /// Its inverse inertia about its centre of mass (1/(kg·m²)); zero for a body that does not
    /// turn.
    pub inverse_inertia: Matrix,
    /// Its centre of mass (m).
    pub centre: Vector,
    /// Its velocity before the surface's impulses of the step (m/s).
    pub velocity: Vector,
    /// Its angular velocity before them (rad/s).
    pub angular_velocity: Vector,
}

impl RigidHolder {
    /// A body of `mass` (kg) at `centre` moving at `velocity`, which does not turn.
    pub fn point_mass(mass: Real, centre: Vector, velocity: Vector) -> Self {
        RigidHolder {
            inverse_mass: Matrix::from_diagonal(Vector::splat(1.0 / mass)),
            inverse_inertia: Matrix::ZERO,
            centre,
            velocity,
            angular_velocity: Vector::ZERO,
        }
    }
}

/// A holder as the solve uses it, and what the last filtered step gave it.
#[derive(Copy, Clone, Debug)]
pub(super) struct HolderState {
    inverse_mass: DMat3,
    inverse_inertia: DMat3,
    pub(super) centre: DVec3,
    velocity: DVec3,
    angular_velocity: DVec3,
    /// The impulse the surface gave it in the last filtered step (N·s), and its moment about
    /// the centre (N·m·s).
    pub(super) impulse: DVec3,
    pub(super) angular_impulse: DVec3,
}

impl HolderState {
    /// A holder checked: finite, and inverse mass and inertia with no negative diagonal.
    pub(super) fn new(h: &RigidHolder) -> Result<Self, SurfaceError> {
        let m = h.inverse_mass.as_dmat3();
        let i = h.inverse_inertia.as_dmat3();
        let finite = m.is_finite()
            && i.is_finite()
            && h.centre.is_finite()
            && h.velocity.is_finite()
            && h.angular_velocity.is_finite();
        let diagonal_ok = |m: &DMat3| (0..3).all(|k| m.col(k)[k] >= 0.0);
        if !(finite && diagonal_ok(&m) && diagonal_ok(&i)) {
            return Err(SurfaceError::InvalidHolder);
        }
        Ok(HolderState {
            inverse_mass: m,
            inverse_inertia: i,
            centre: h.centre.as_dvec3(),
            velocity: h.velocity.as_dvec3(),
            angular_velocity: h.angular_velocity.as_dvec3(),
            impulse: DVec3::ZERO,
            angular_impulse: DVec3::ZERO,
        })
    }

    /// The velocity of its material point `arm` from its centre.
    pub(super) fn velocity_at(&self, arm: DVec3) -> DVec3 {
        self.velocity + self.angular_velocity.cross(arm)
    }
}

/// A constraint row on a holder: the holder, the row's linear and angular directions (`d`,
/// `r × d`) and the holder's compliance applied to them (`M⁻¹ d`, `I⁻¹ (r × d)`).
#[derive(Copy, Clone, Debug)]
pub(super) struct HolderRow {
    holder: usize,
    linear: DVec3,
    angular: DVec3,
    linear_response: DVec3,
    angular_response: DVec3,
}

/// Per holder, `Σ λ (M⁻¹ d, I⁻¹ (r × d))` over some impulses: minus its velocity change.
pub(super) type HolderMotion = Vec<(DVec3, DVec3)>;

impl HolderRow {
    /// Row along `d` at the holder's material point `arm` from its centre.
    pub(super) fn new(holder: usize, state: &HolderState, d: DVec3, arm: DVec3) -> Self {
        let angular = arm.cross(d);
        HolderRow {
            holder,
            linear: d,
            angular,
            linear_response: state.inverse_mass * d,
            angular_response: state.inverse_inertia * angular,
        }
    }

    /// The holder's compliance between two rows: zero for rows on different holders.
    pub(super) fn coupling(&self, other: &HolderRow) -> f64 {
        if self.holder != other.holder {
            return 0.0;
        }
        self.linear.dot(other.linear_response) + self.angular.dot(other.angular_response)
    }

    /// How much the holders' `motion` ([`motion`]) takes off its velocity along this row.
    pub(super) fn along(&self, motion: &[(DVec3, DVec3)]) -> f64 {
        motion
            .get(self.holder)
            .map_or(0.0, |(l, a)| self.linear.dot(*l) + self.angular.dot(*a))
    }
}

/// [`HolderMotion`] of `impulses` (row, λ) over `holders` holders.
pub(super) fn motion(
    rows: &[Option<HolderRow>],
    holders: usize,
    impulses: impl Iterator<Item = (usize, f64)>,
) -> HolderMotion {
    let mut out = vec![(DVec3::ZERO, DVec3::ZERO); holders];
    for (c, l) in impulses {
        if let Some(r) = rows.get(c).copied().flatten() {
            if let Some(o) = out.get_mut(r.holder) {
                o.0 += r.linear_response * l;
                o.1 += r.angular_response * l;
            }
        }
    }
    out
}

/// Adds each row's impulse `λ` to its holder's: the holder takes `-λ d` and its moment.
pub(super) fn give_impulses(
    rows: &[Option<HolderRow>],
    lambda: &[f64],
    holders: &mut [HolderState],
) {
    for (r, &l) in rows.iter().zip(lambda) {
        if let Some(h) = r.and_then(|r| holders.get_mut(r.holder).map(|h| (r, h))) {
            h.1.impulse -= h.0.linear * l;
            h.1.angular_impulse -= h.0.angular * l;
        }
    }
}

/// Merges the independent blocks of the solve that hold rows of the same holder (its
/// compliance joins them); blocks keep their rows in increasing order.
pub(super) fn merge_blocks(blocks: Vec<Vec<usize>>, rows: &[Option<HolderRow>]) -> Vec<Vec<usize>> {
    let mut owner: Vec<Option<usize>> = Vec::new();
    let mut merged: Vec<Vec<usize>> = Vec::with_capacity(blocks.len());
    for block in blocks {
        let into = block.iter().find_map(|&c| {
            let h = rows.get(c).copied().flatten()?.holder;
            owner.get(h).copied().flatten()
        });
        let target = match into {
            Some(t) => {
                merged[t].extend_from_slice(&block);
                t
            }
            None => {
                merged.push(block);
                merged.len() - 1
            }
        };
        // Blocks met later join this one through any of its holders; a block that held two
        // holders already merged elsewhere is joined here too.
        let holders: Vec<usize> = merged[target]
            .iter()
            .filter_map(|&c| rows.get(c).copied().flatten().map(|r| r.holder))
            .collect();
        for h in holders {
            if owner.len() <= h {
                owner.resize(h + 1, None);
            }
            match owner[h] {
                Some(o) if o != target => {
                    let moved = std::mem::take(&mut merged[o]);
                    merged[target].extend(moved);
                    for x in owner.iter_mut().filter(|x| **x == Some(o)) {
                        *x = Some(target);
                    }
                }
                _ => owner[h] = Some(target),
            }
        }
    }
    merged.retain(|b| !b.is_empty());
    for b in &mut merged {
        b.sort_unstable();
    }
    merged
}
