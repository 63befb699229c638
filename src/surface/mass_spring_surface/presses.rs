//! Pressing points of a surface from outside: a tool's vertex inside a triangle (the
//! paper's eq. 3 situation) or its edge across a surface edge, moved onto the holder and held
//! there along the contact normal (and, with friction, along the tangent plane) through the
//! next filtered step's constraint solve ([`super::constraints`]).

use super::active_set::{give_back, solve_pushing, zeroed};
use super::point_hold::PointHold;
use super::rigid_holder::HolderState;
use super::{motion_watch, MassSpringSurface, SurfaceError};
use crate::math::{Real, Vector};
use glamx::DVec3;

/// The least weight a pressed point must have on vertices that can move.
const MIN_MOVABLE_WEIGHT: f64 = 0.25;
/// Below [`MIN_MOVABLE_WEIGHT`], a point is still pressed while the way its free vertices must
/// go (its depth over their weight) is at most this share of its vertices' span, and their
/// weight at least [`LEAST_MOVABLE_WEIGHT`].
const MAX_LEVERED_SHARE: f64 = 0.05;
/// The weight on movable vertices below which a point is always left to its other vertices.
const LEAST_MOVABLE_WEIGHT: f64 = 0.02;

/// Makes a rigid holder's press's targets relative to the holder's velocity at the point (the
/// step reads it from `holders`); a press naming no such holder loses its holder.
fn relative_to_holder(holders: &[HolderState], hold: &mut PointHold) {
    let Some((index, point)) = hold.holder else {
        return;
    };
    let Some(state) = holders.get(index) else {
        hold.holder = None;
        return;
    };
    let arm = point - state.centre;
    let own = state.velocity_at(arm);
    hold.holder = Some((index, arm));
    hold.min_velocity -= own.dot(hold.normal);
    hold.carried = hold.carried.map(|v| v - own);
}

/// One point to press (see [`MassSpringSurface::press_points`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PointPress<'a> {
    /// Up to three `(vertex, weight)` pairs, weights ≥ 0 (normalised to sum to one): the
    /// surface point `Σ wⱼ xⱼ`.
    pub vertices: &'a [(u32, Real)],
    /// The direction the holder pushes the point in (normalised).
    pub normal: Vector,
    /// How far to move the point along `normal` now (m).
    pub depth: Real,
    /// The point's velocity along `normal` from now on (m/s): the holder's.
    pub normal_velocity: Real,
    /// What the holder does along the point's tangent plane (friction).
    pub tangential: Tangential,
    /// The rigid holder pressing it, as an index into [`MassSpringSurface::set_holders`]'s
    /// list and the holder's point that presses (its lever arm for the holder's turning), or
    /// `None` for a holder whose motion nothing changes (kinematic). With a holder,
    /// `normal_velocity` and the tangential velocity are the holder's at the point when
    /// pressed: through the step the point follows the holder's velocity as the holders list
    /// gives it then, changed by the impulses the surface gives the holder in the same solve
    /// (implicit coupling), and the press gives the point no velocity change of its own (the
    /// step's solve does, with the holder's mass).
    pub holder: Option<(usize, Vector)>,
}

/// What a press's holder does along the pressed point's tangent plane in the next filtered
/// step (see [`MassSpringSurface::press_points`]). The tangential impulse it gives is
/// [`MassSpringSurface::point_tangent_impulse`].
///
/// # Example
/// A needle tip pressing 1 cm into the middle of a triangle and moving sideways at 1 cm/s:
/// with enough friction the point goes along, without it the point stays.
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::surface::meshing::plate;
///
/// let moved = |tangential: Tangential| {
///     let mesh = plate(1.0, 1.0, 4, 4);
///     let rim = |v: Vector| v.x.abs() > 0.49 || v.z.abs() > 0.49;
///     let edge: Vec<u32> = (0..mesh.vertices.len() as u32)
///         .filter(|&i| rim(mesh.vertices[i as usize]))
///         .collect();
///     let mut surface = MassSpringSurfaceBuilder::from_mesh(&mesh).pinned(edge).build().unwrap();
///     let [a, b, c] = *surface
///         .triangles()
///         .iter()
///         .find(|t| t.iter().all(|&v| !surface.is_pinned(v)))
///         .unwrap();
///     let point = |s: &MassSpringSurface| (s.position(a) + s.position(b) + s.position(c)) / 3.0;
///     let start = point(&surface);
///     let third = 1.0 / 3.0;
///     let press = PointPress {
///         vertices: &[(a, third), (b, third), (c, third)],
///         normal: Vector::new(0.0, -1.0, 0.0),
///         depth: 0.01,
///         normal_velocity: 0.0,
///         tangential,
///         holder: None,
///     };
///     surface.press_points(&[press]).unwrap();
///     surface.step();
///     (point(&surface) - start).x / surface.dt()
/// };
/// let sideways = Vector::new(0.01, 0.0, 0.0);
/// let grip = Tangential::Coulomb {
///     velocity: sideways,
///     static_coefficient: 1.0,
///     dynamic_coefficient: 1.0,
/// };
/// assert!((moved(grip) - 0.01).abs() < 1e-4);
/// assert!(moved(Tangential::Free).abs() < 1e-4);
/// ```
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub enum Tangential {
    /// Nothing: the point slides along the holder freely (frictionless).
    #[default]
    Free,
    /// Coulomb friction with a holder whose material point at the press moves with `velocity`
    /// (m/s). Solved with the step's other constraints: the point sticks to the holder (its
    /// velocity along the tangent plane held at `velocity`'s) while the impulse that takes is
    /// at most `static_coefficient` times the press's normal impulse; beyond, it slides, and
    /// the holder's tangential impulse is `dynamic_coefficient` times the normal one, along
    /// the impulse that would have held it (against its slip). Coefficients ≥ 0, dynamic ≤
    /// static.
    Coulomb {
        /// The holder's velocity at the point (m/s).
        velocity: Vector,
        /// `μs`.
        static_coefficient: Real,
        /// `μd`.
        dynamic_coefficient: Real,
    },
    /// The holder grasps the point: the press moves it onto the holder (by `depth`, which
    /// may be negative: pulled) and through the step carries it with this velocity (m/s)
    /// whatever that takes, pushing or pulling (the press is bilateral).
    Grasped(Vector),
}

impl MassSpringSurface {
    /// Presses one surface point, frictionless: [`MassSpringSurface::press_points`] with one
    /// press.
    ///
    /// # Errors
    /// As [`MassSpringSurface::press_points`].
    ///
    /// # Example
    /// A needle tip pressing 1 cm into the middle of a triangle of a plate, held there:
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::surface::meshing::plate;
    ///
    /// let mesh = plate(1.0, 1.0, 4, 4);
    /// let rim = |v: Vector| v.x.abs() > 0.49 || v.z.abs() > 0.49;
    /// let edge: Vec<u32> = (0..mesh.vertices.len() as u32)
    ///     .filter(|&i| rim(mesh.vertices[i as usize]))
    ///     .collect();
    /// let mut surface = MassSpringSurfaceBuilder::from_mesh(&mesh).pinned(edge).build().unwrap();
    /// // A triangle with no pinned vertex.
    /// let [a, b, c] = *surface
    ///     .triangles()
    ///     .iter()
    ///     .find(|t| t.iter().all(|&v| !surface.is_pinned(v)))
    ///     .unwrap();
    /// let point = |s: &MassSpringSurface| (s.position(a) + s.position(b) + s.position(c)) / 3.0;
    /// let third = 1.0 / 3.0;
    /// let down = Vector::new(0.0, -1.0, 0.0);
    /// let id = surface.press_point(&[(a, third), (b, third), (c, third)], down, 0.01, 0.0);
    /// let id = id.unwrap().unwrap();
    /// assert!((point(&surface).y + 0.01).abs() < 1e-6);
    /// surface.step();
    /// // Held along the normal: the springs did not pull the point back up.
    /// assert!((point(&surface).y + 0.01).abs() < 1e-6);
    /// assert!(surface.point_impulse(id).unwrap() > 0.0);
    /// ```
    pub fn press_point(
        &mut self,
        vertices: &[(u32, Real)],
        normal: Vector,
        depth: Real,
        normal_velocity: Real,
    ) -> Result<Option<usize>, SurfaceError> {
        let press = PointPress {
            vertices,
            normal,
            depth,
            normal_velocity,
            tangential: Tangential::Free,
            holder: None,
        };
        Ok(self.press_points(&[press])?.pop().flatten())
    }

    /// Presses surface points — a tool's vertex inside a triangle (the paper's eq. 3 situation),
    /// a tool's edge across a surface edge — each by its `depth` along its `normal`, gives each
    /// its `normal_velocity`, and holds them there along their normals for the next step, until
    /// [`MassSpringSurface::release_all`].
    ///
    /// The position and velocity changes are the least mass-weighted ones that give every point
    /// its depth and velocity together (a small dense solve over the points: presses sharing a
    /// vertex do not undo each other). Pinned and held vertices do not move (a vertex on a
    /// sliding hold may slide along its holder's face: below). In the next
    /// filtered step each point keeps its normal velocity: its impulse is solved with the vertex
    /// holds' through the filter's columns at its vertices, and a point whose impulse would pull
    /// is let go. Along its tangent plane it does what its [`Tangential`] says: slides freely,
    /// sticks to its holder or slides against kinetic friction (Coulomb's law on the step's
    /// impulses, solved with the rest: two more rows), or is grasped (held in every direction,
    /// pulled as well as pushed). A press with a negative `depth` (its
    /// holder is that far above it), or one the others' pushes already satisfy (pushing one
    /// point of a triangle moves its neighbours), is not moved and is held as a speculative
    /// contact: over the next step it may close its gap to the holder, not pass it. A press on
    /// a triangle with a held vertex moves the triangle's other vertices (a flat face holding a
    /// vertex presses the triangles round it: its corners stay out of them). Returns each
    /// press's index for [`MassSpringSurface::point_impulse`], or `None` for a press with less
    /// than a quarter of its weight on vertices that can move (its pinned or held vertices
    /// carry it: moving it would fling its free vertex by depth / weight), unless its depth is
    /// a small share of its triangle's span (below a twentieth of it times that weight, or,
    /// where a sliding hold keeps most of its weight on a tool's face, times that weight plus
    /// the held vertices' weight across their holds' normals: those then slide along the
    /// face with the press). A rigid holder's
    /// press on a triangle with a pinned vertex is not moved first either, nor pushed out: it
    /// is held in the step's solve with the holder's mass so that it comes no deeper (the
    /// pinned vertices are fixed ground for the holder). The explicit and
    /// Baraff-Witkin integrators apply the position and velocity changes but do not hold the
    /// points during the step.
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`]; [`SurfaceError::InvalidPointHold`] for a press with
    /// no vertex or more than three, a negative or non-finite weight, weights summing to zero, a
    /// zero or non-finite normal, a non-finite depth, velocity or [`Tangential`], or a holder
    /// index past [`MassSpringSurface::set_holders`]'s list. Nothing is pressed then.
    pub fn press_points(
        &mut self,
        presses: &[PointPress<'_>],
    ) -> Result<Vec<Option<usize>>, SurfaceError> {
        let mut holds = Vec::with_capacity(presses.len());
        for p in presses {
            holds.push(self.point_hold(p)?);
        }
        // The movable share of each vertex: 1/m, zero for pinned and held vertices (a held
        // vertex stays where its holder keeps it; a press beside it moves the others).
        let inv_mass = |s: &Self, v: u32| {
            let v = v as usize;
            if s.pinned[v] || s.held[v] {
                0.0
            } else {
                1.0 / s.mass[v]
            }
        };
        // A vertex on a sliding hold moves along its holder's plane: the hold's normal (none
        // for a free, pinned or fully held vertex).
        let slide = |s: &Self, v: u32| {
            let v = v as usize;
            let m = s.held_normal[v];
            (s.held[v] && !s.pinned[v] && m != DVec3::ZERO).then_some(m)
        };
        let across = |m: DVec3, n: DVec3| n - m * m.dot(n);
        let mut out = Vec::with_capacity(presses.len());
        let mut kept: Vec<(PointHold, f64, f64)> = Vec::new();
        // Whether each kept press also slides its vertices on sliding holds (below).
        let mut slides: Vec<bool> = Vec::new();
        // The rigid holders' points on pinned vertices (below): their place in `out`, their
        // hold.
        let mut on_pins: Vec<(usize, PointHold)> = Vec::new();
        for (hold, p) in holds.into_iter().zip(presses) {
            // The weight on vertices that can move: a point mostly on pinned or held vertices
            // is carried by them where moving it would fling its free vertices (by depth /
            // weight). A tool's corner beside a vertex its face holds has most of its weight
            // there, and left alone it sank under the triangle's free side (66 µm, a jaw's
            // corner with 0.83 of its weight on the held vertex): pressed while that way is
            // short. (Not for a rigid holder's points, whose solve meets its mass: pressed so,
            // dynamic bodies on soft plates lost their balance and their rolling.)
            let movable: f64 = hold
                .entries()
                .filter(|&(v, _)| inv_mass(self, v) > 0.0)
                .map(|(_, w)| w)
                .sum();
            // (The vertices' span only for the few points that get this far.)
            let span = || {
                hold.entries()
                    .flat_map(|(a, _)| hold.entries().map(move |(b, _)| (a as usize, b as usize)))
                    .map(|(a, b)| (self.pos[a] - self.pos[b]).length())
                    .fold(0.0, f64::max)
            };
            let levered = || {
                if hold.holder.is_some() || movable < LEAST_MOVABLE_WEIGHT {
                    return false;
                }
                f64::from(p.depth).max(0.0) <= MAX_LEVERED_SHARE * span() * movable
            };
            // A rigid holder's point on a triangle with a pinned vertex: the pinned vertices
            // are fixed ground, and the holder's own motion must keep off them as off a rigid
            // body. Not moved first (moving the free vertices alone flings them by depth /
            // weight) and not pushed out (work the holder never paid for): held in the step's
            // solve, with the holder's mass, so that it comes no deeper. Moved, a box tipping
            // over a plate's pinned rim flung the rim's free vertices by centimetres and the
            // plate's energy went from 0.2 J to tens of joules.
            let on_pin = hold.entries().any(|(v, _)| self.pinned[v as usize]);
            if hold.holder.is_some() && on_pin {
                let mut hold = hold;
                hold.min_velocity += f64::from(p.depth).min(0.0) / self.dt;
                on_pins.push((out.len(), hold));
                out.push(None);
                continue;
            }
            // A point with too little weight on free vertices (but some), most of it on
            // vertices a sliding hold keeps on a tool's face, is pressed by sliding those along
            // the face too (their share across the hold's normal), while the way they must go
            // stays within the levered share of the span: a tilted U's corner beside a vertex
            // its bottom face held (99 % of the weight there) sank 26 um to 0.11 mm under the
            // triangle, the vertex kept 1.3 mm from the corner. (The step's solve holds such a
            // point only where its normal is more than about 6° from the hold's: nearer, its row
            // nearly repeats the hold's and is only relaxed toward its target, `solve_pushing`,
            // so the springs draw the vertex part of the way back until the next press.)
            let slid = || {
                let sliding: f64 = hold
                    .entries()
                    .filter_map(|(v, w)| {
                        slide(self, v).map(|m| w * across(m, hold.normal).length())
                    })
                    .sum();
                if hold.holder.is_some()
                    || movable <= 0.0
                    || sliding <= 0.0
                    || movable + sliding < LEAST_MOVABLE_WEIGHT
                {
                    return false;
                }
                f64::from(p.depth).max(0.0) <= MAX_LEVERED_SHARE * span() * (movable + sliding)
            };
            let plain = movable >= MIN_MOVABLE_WEIGHT || levered();
            if plain || slid() {
                slides.push(!plain);
                let velocity: f64 = hold
                    .entries()
                    .map(|(v, w)| w * self.vel[v as usize].dot(hold.normal))
                    .sum();
                out.push(Some(self.point_holds.len() + kept.len()));
                // A rigid holder's press changes no velocity: the step's solve meets the point
                // and the holder with its mass.
                let change = if hold.holder.is_some() {
                    0.0
                } else {
                    p.normal_velocity as f64 - velocity
                };
                kept.push((hold, p.depth as f64, change));
            } else {
                out.push(None);
            }
        }
        let m = kept.len();
        // The points on pins go after the others, relative to their holder's velocity.
        let first_on_pins = self.point_holds.len() + m;
        for (k, (slot, hold)) in on_pins.iter_mut().enumerate() {
            out[*slot] = Some(first_on_pins + k);
            relative_to_holder(&self.holders, hold);
        }
        let on_pins: Vec<PointHold> = on_pins.into_iter().map(|(_, h)| h).collect();
        if m == 0 {
            self.point_holds.extend(on_pins);
            return Ok(out);
        }
        // A = J M⁻¹ Jᵀ over the kept presses; δx = M⁻¹ Jᵀ μ with A μ = depth (likewise for the
        // velocities).
        let mut scratch = std::mem::take(&mut self.pushing.scratch);
        let mut a = zeroed(&mut scratch.system, m, m);
        // Two presses meet only on the vertices they share: the (vertex, press, weight)
        // entries sorted by vertex give the nonzero pairs (not all m² of them).
        let mut on_vertex: Vec<(u32, usize, f64)> = kept
            .iter()
            .enumerate()
            .flat_map(|(i, (h, _, _))| h.entries().map(move |(v, w)| (v, i, w)))
            .collect();
        on_vertex.sort_unstable_by_key(|e| (e.0, e.1));
        for run in on_vertex.chunk_by(|x, y| x.0 == y.0) {
            let im = inv_mass(self, run[0].0);
            // (A vertex on a sliding hold is held: `inv_mass` gives it none.)
            let sliding = slide(self, run[0].0);
            for &(_, i, wi) in run {
                for &(_, j, wj) in run {
                    let (ni, nj) = (kept[i].0.normal, kept[j].0.normal);
                    a[(i, j)] += match sliding {
                        Some(m) if slides[i] && slides[j] => {
                            across(m, ni).dot(across(m, nj)) * wi * wj
                                / self.mass[run[0].0 as usize]
                        }
                        _ => ni.dot(nj) * wi * wj * im,
                    };
                }
            }
        }
        let scale = (0..m).map(|i| a[(i, i)]).fold(0.0, f64::max);
        for i in 0..m {
            a[(i, i)] += 1e-12 * scale;
        }
        let solved = solve_presses(&a, &kept, &mut scratch.factor);
        if let Some(PressImpulses {
            mu,
            active,
            rows,
            nu,
        }) = &solved
        {
            for (r, &i) in rows.iter().enumerate() {
                let hold = &mut kept[i].0;
                // The impulse the press gave: the start of what the hold reports.
                hold.impulse = nu[r];
                let mut momentum = DVec3::ZERO;
                for (v, w) in hold.entries() {
                    let im = inv_mass(self, v);
                    // The way the press moves the vertex per unit impulse: along its normal,
                    // or across a sliding hold's normal for a press that slides it.
                    let way = match slide(self, v) {
                        Some(m) if slides[i] => {
                            across(m, hold.normal) * (w / self.mass[v as usize])
                        }
                        _ => hold.normal * (w * im),
                    };
                    self.pos[v as usize] += way * mu[i];
                    motion_watch::note(&mut self.watch, v as usize, self.pos[v as usize]);
                    self.vel[v as usize] += way * nu[r];
                    momentum += way * (self.mass[v as usize] * nu[r]);
                }
                hold.momentum = momentum;
            }
            // A press left out is `gap` short of its holder (its own negative depth, or where
            // the others' pushes put it): it is held as a speculative contact that may close
            // the gap over the next step, not more.
            for (i, k) in kept.iter_mut().enumerate() {
                if active[i] {
                    continue;
                }
                // Row i of the symmetric `a`, read down its column (contiguous, and no
                // transposed copy of `mu` per press).
                let gap = (a.column(i).dot(mu) - k.1).max(0.0);
                k.0.min_velocity -= gap / self.dt;
            }
            // A rigid holder's targets become relative to its velocity at the point, which
            // the step reads from the holders list.
            for (hold, _, _) in kept.iter_mut() {
                relative_to_holder(&self.holders, hold);
            }
        }
        give_back(&mut scratch.system, a);
        self.pushing.scratch = scratch;
        if solved.is_none() {
            return Ok(out.iter().map(|_| None).collect());
        }
        self.point_holds.extend(kept.into_iter().map(|(h, _, _)| h));
        self.point_holds.extend(on_pins);
        Ok(out)
    }

    /// Whether [`MassSpringSurface::press_points`] takes `press` (the checks its errors
    /// list), for a caller that drops a bad press rather than the whole call.
    pub(crate) fn press_is_valid(&self, press: &PointPress<'_>) -> bool {
        self.point_hold(press).is_ok()
    }

    /// A press checked and normalised.
    fn point_hold(&self, p: &PointPress<'_>) -> Result<PointHold, SurfaceError> {
        let vertices = p.vertices;
        if vertices.is_empty() || vertices.len() > 3 {
            return Err(SurfaceError::InvalidPointHold);
        }
        for &(v, w) in vertices {
            self.check_vertex(v)?;
            if !(w.is_finite() && w >= 0.0) {
                return Err(SurfaceError::InvalidPointHold);
            }
        }
        let total: f64 = vertices.iter().map(|&(_, w)| w as f64).sum();
        let n = p.normal.as_dvec3().try_normalize();
        let (carried, cone, tangential_ok) = match p.tangential {
            Tangential::Free => (None, None, true),
            Tangential::Grasped(v) => (Some(v.as_dvec3()), None, v.is_finite()),
            Tangential::Coulomb {
                velocity,
                static_coefficient: s,
                dynamic_coefficient: d,
            } => (
                Some(velocity.as_dvec3()),
                Some((s as f64, d as f64)),
                velocity.is_finite() && s.is_finite() && d >= 0.0 && d <= s,
            ),
        };
        let holder_ok = p
            .holder
            .is_none_or(|(k, point)| k < self.holders.len() && point.is_finite());
        let (Some(n), true, true) = (
            n,
            total > 0.0 && total.is_finite(),
            p.depth.is_finite() && p.normal_velocity.is_finite() && tangential_ok && holder_ok,
        ) else {
            return Err(SurfaceError::InvalidPointHold);
        };
        let mut hold = PointHold {
            vertices: [0; 3],
            weights: [0.0; 3],
            count: vertices.len(),
            normal: n,
            impulse: 0.0,
            min_velocity: p.normal_velocity as f64,
            carried,
            cone,
            tangent_impulse: DVec3::ZERO,
            momentum: DVec3::ZERO,
            held_share: 0.0,
            held_across: DVec3::ZERO,
            holder: p.holder.map(|(k, point)| (k, point.as_dvec3())),
        };
        for (k, &(v, w)) in vertices.iter().enumerate() {
            hold.vertices[k] = v;
            hold.weights[k] = w as f64 / total;
            if self.held[v as usize] {
                hold.held_share += hold.weights[k];
            }
        }
        Ok(hold)
    }

    /// How many points are held (see [`MassSpringSurface::press_point`]).
    pub fn num_point_holds(&self) -> usize {
        self.point_holds.len()
    }
}

/// What the presses' solves give (see [`solve_presses`]).
struct PressImpulses {
    /// Position impulse per press (zero on those left out).
    mu: nalgebra::DVector<f64>,
    /// Which presses push.
    active: Vec<bool>,
    /// The pushing presses, and their velocity impulses in that order.
    rows: Vec<usize>,
    nu: nalgebra::DVector<f64>,
}

/// The presses' solves over `a = J M⁻¹ Jᵀ` (`kept`: each press with its depth and the normal
/// velocity its holder asks for): position impulses, push-only, then, for the presses that
/// push, velocity impulses that bring them to their holders' normal velocity, again push-only
/// (a point already leaving its holder faster keeps its velocity). `None` when a solve fails.
fn solve_presses(
    a: &nalgebra::DMatrix<f64>,
    kept: &[(PointHold, f64, f64)],
    factor: &mut Vec<f64>,
) -> Option<PressImpulses> {
    let m = kept.len();
    // Positions: presses only push; one with a negative depth (a speculative contact short
    // of its holder) or that the others' pushes satisfy is left out. A grasped point is moved
    // onto its holder either way.
    let grasped = |i: usize| kept[i].0.grasped();
    let depth = nalgebra::DVector::from_fn(m, |i, _| kept[i].1);
    let tol = 1e-9 * depth.amax();
    // Repeated rows met by relaxation (`solve_pushing`), except where a rigid holder presses:
    // relaxed there too, the heavy U of `tests/it/dynamic_drops.rs` (one substep) was kicked
    // about at rest at 1.5 cm/s.
    let relax = kept.iter().all(|k| k.0.holder.is_none());
    let (mu, active) = solve_pushing(
        a,
        &depth,
        (|i| !grasped(i), |i| depth[i] > 0.0 || grasped(i)),
        &[],
        tol,
        factor,
        relax,
    )?;
    let rows: Vec<usize> = (0..m).filter(|&i| active[i]).collect();
    let sub = nalgebra::DMatrix::from_fn(rows.len(), rows.len(), |r, c| a[(rows[r], rows[c])]);
    let dv = nalgebra::DVector::from_fn(rows.len(), |r, _| kept[rows[r]].2);
    let vtol = 1e-9 * (1.0 + dv.amax());
    let (nu, _) = solve_pushing(
        &sub,
        &dv,
        (|r| !grasped(rows[r]), |r| dv[r] > 0.0 || grasped(rows[r])),
        &[],
        vtol,
        factor,
        relax,
    )?;
    Some(PressImpulses {
        mu,
        active,
        rows,
        nu,
    })
}
