//! What holds a surface from outside during a filtered step: vertex holds (a tool holding a
//! vertex, fully or along a normal) and point holds (a tool's vertex or edge pressing a point
//! inside a triangle or on an edge, which loads the vertices around it by barycentric
//! weights). Both are solved together through the filter's columns, so the rest of the
//! surface responds to them as to moving pins.

use super::active_set::{give_back, solve_pushing, zeroed, Scratch};
use super::blocks::independent_blocks;
use super::{motion_watch, MassSpringSurface, SurfaceError, NOT_FREE};
use crate::math::{Real, Vector};
use crate::surface::filter::{Filter, FilterKind};
use glamx::DVec3;
use parry3d::utils::hashset::HashSet;

/// A point of the surface, `Σ wⱼ xⱼ` over up to three vertices, pressed along a normal by
/// something outside it (see [`MassSpringSurface::press_point`]).
#[derive(Copy, Clone, Debug)]
pub(crate) struct PointHold {
    vertices: [u32; 3],
    weights: [f64; 3],
    count: usize,
    /// Unit direction the holder pushes the point in.
    normal: DVec3,
    /// The impulse (N·s, along `normal`) the holder gave: the press's velocity change, plus the
    /// constraint impulse of the step after it.
    impulse: f64,
    /// The least velocity along `normal` the point may have after the step: the holder's for
    /// a point in contact; less by `gap / dt` for a point `gap` short of its holder (it may
    /// close the gap, not pass the holder).
    min_velocity: f64,
}

impl PointHold {
    /// The hold's key across steps: the surface vertices it loads, sorted.
    fn key(&self) -> [u32; 3] {
        let mut v = self.vertices;
        v[self.count.min(3)..]
            .iter_mut()
            .for_each(|x| *x = u32::MAX);
        v.sort_unstable();
        v
    }

    fn entries(&self) -> impl Iterator<Item = (u32, f64)> + '_ {
        self.vertices[..self.count]
            .iter()
            .copied()
            .zip(self.weights[..self.count].iter().copied())
    }
}

/// Which push-only rows of the filtered step's constraint solve pushed at its end, by key
/// ([`PointHold::key`]): the next step's solve starts from them, so a contact that persists
/// costs fewer active-set passes (six cubes on a plate, about 110 rows of which 40 push: from
/// 5-10 passes to mostly 2-5; `cargo bench --bench coupled_step` 0.70 → 0.44 ms). A row not
/// seen last time starts in if it asks for a push.
#[derive(Clone, Debug, Default)]
pub(crate) struct ActiveMemory {
    seen: HashSet<[u32; 3]>,
    pushing: HashSet<[u32; 3]>,
    /// The solves' dense storage, reused.
    scratch: Scratch,
}

impl ActiveMemory {
    fn starts_in(&self, key: [u32; 3], b: f64) -> bool {
        if self.seen.contains(&key) {
            self.pushing.contains(&key)
        } else {
            b > 0.0
        }
    }
}

/// The least weight a pressed point must have on vertices that can move.
const MIN_MOVABLE_WEIGHT: f64 = 0.25;

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
}

impl MassSpringSurface {
    /// Presses one surface point: [`MassSpringSurface::press_points`] with one press.
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
    /// vertex do not undo each other). Pinned and held vertices do not move. In the next
    /// filtered step each point keeps its normal velocity: its impulse is solved with the vertex
    /// holds' through the filter's columns at its vertices; it is free along its tangent plane
    /// (frictionless), and a point whose impulse would pull is let go. A press with a negative
    /// `depth` (its holder is that far above it), or one the others' pushes already satisfy
    /// (pushing one point of a triangle moves its neighbours), is not moved and is held as a
    /// speculative contact: over the next step it may close its gap to the holder, not pass it. Returns each press's index
    /// for [`MassSpringSurface::point_impulse`], or `None` for a press on a held vertex (its
    /// holder carries the contact there) or with less than a quarter of its weight on free
    /// vertices (its pinned vertices carry it). The explicit and Baraff-Witkin integrators apply
    /// the position and velocity changes but do not hold the points during the step.
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`]; [`SurfaceError::InvalidPointHold`] for a press with
    /// no vertex or more than three, a negative or non-finite weight, weights summing to zero, a
    /// zero or non-finite normal, a non-finite depth or velocity. Nothing is pressed then.
    pub fn press_points(
        &mut self,
        presses: &[PointPress<'_>],
    ) -> Result<Vec<Option<usize>>, SurfaceError> {
        let mut holds = Vec::with_capacity(presses.len());
        for p in presses {
            holds.push(self.point_hold(p)?);
        }
        // The movable share of each vertex: 1/m, zero for pinned vertices (presses on held
        // vertices are not kept, below).
        let inv_mass = |s: &Self, v: u32| {
            let v = v as usize;
            if s.pinned[v] {
                0.0
            } else {
                1.0 / s.mass[v]
            }
        };
        let mut out = Vec::with_capacity(presses.len());
        let mut kept: Vec<(PointHold, f64, f64)> = Vec::new();
        for (hold, p) in holds.into_iter().zip(presses) {
            // The weight on vertices that can move: a point mostly on pinned vertices is
            // carried by them (moving it would fling its free vertex by depth / weight).
            let movable: f64 = hold
                .entries()
                .filter(|&(v, _)| inv_mass(self, v) > 0.0)
                .map(|(_, w)| w)
                .sum();
            // A point on a held vertex is left to that vertex's holder, which already
            // carries the contact there.
            let on_held = hold
                .entries()
                .any(|(v, w)| w > 0.0 && self.held[v as usize]);
            if movable >= MIN_MOVABLE_WEIGHT && !on_held {
                let velocity: f64 = hold
                    .entries()
                    .map(|(v, w)| w * self.vel[v as usize].dot(hold.normal))
                    .sum();
                out.push(Some(self.point_holds.len() + kept.len()));
                kept.push((hold, p.depth as f64, p.normal_velocity as f64 - velocity));
            } else {
                out.push(None);
            }
        }
        let m = kept.len();
        if m == 0 {
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
            for &(_, i, wi) in run {
                for &(_, j, wj) in run {
                    let nn = kept[i].0.normal.dot(kept[j].0.normal);
                    a[(i, j)] += nn * wi * wj * im;
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
                for (v, w) in hold.entries() {
                    let share = w * inv_mass(self, v);
                    self.pos[v as usize] += hold.normal * (share * mu[i]);
                    motion_watch::note(&mut self.watch, v as usize, self.pos[v as usize]);
                    self.vel[v as usize] += hold.normal * (share * nu[r]);
                }
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
                let velocity: f64 =
                    k.0.entries()
                        .map(|(v, w)| w * self.vel[v as usize].dot(k.0.normal))
                        .sum();
                // The holder's velocity, as given, is the current point velocity plus `k.2`.
                k.0.min_velocity = velocity + k.2 - gap / self.dt;
            }
        }
        give_back(&mut scratch.system, a);
        self.pushing.scratch = scratch;
        if solved.is_none() {
            return Ok(out.iter().map(|_| None).collect());
        }
        self.point_holds.extend(kept.into_iter().map(|(h, _, _)| h));
        Ok(out)
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
        let (Some(n), true, true) = (
            n,
            total > 0.0 && total.is_finite(),
            p.depth.is_finite() && p.normal_velocity.is_finite(),
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
        };
        for (k, &(v, w)) in vertices.iter().enumerate() {
            hold.vertices[k] = v;
            hold.weights[k] = w as f64 / total;
        }
        Ok(hold)
    }

    /// The impulse (N·s, along its normal; positive when pushing) hold `id` of
    /// [`MassSpringSurface::press_points`] has given the surface: the press's own velocity
    /// change, plus the constraint impulse of the filtered step after it (all the momentum the
    /// holder gave the surface from the press to the end of that step). `None` for no such
    /// hold.
    pub fn point_impulse(&self, id: usize) -> Option<Real> {
        self.point_holds.get(id).map(|h| h.impulse as Real)
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
    // of its holder) or that the others' pushes satisfy is left out.
    let depth = nalgebra::DVector::from_fn(m, |i, _| kept[i].1);
    let tol = 1e-9 * depth.amax();
    let (mu, active) = solve_pushing(a, &depth, |_| true, |i| depth[i] > 0.0, tol, factor)?;
    let rows: Vec<usize> = (0..m).filter(|&i| active[i]).collect();
    let sub = nalgebra::DMatrix::from_fn(rows.len(), rows.len(), |r, c| a[(rows[r], rows[c])]);
    let dv = nalgebra::DVector::from_fn(rows.len(), |r, _| kept[rows[r]].2);
    let vtol = 1e-9 * (1.0 + dv.amax());
    let (nu, _) = solve_pushing(&sub, &dv, |_| true, |i| dv[i] > 0.0, vtol, factor)?;
    Some(PressImpulses {
        mu,
        active,
        rows,
        nu,
    })
}

/// The holders' impulses in the filtered step. Each constraint is a direction `d` applied to a
/// weighted set of vertices: a sliding vertex hold (its normal, weight 1), a full vertex hold
/// (the three axes), a point hold (its normal, its barycentric weights). With `J` the
/// constraints' rows and `P = S⁻¹ = W M⁻¹` the filter as applied to impulses (exact or
/// neighbour), it finds the impulses `λ` with `J (Δv + P Jᵀ λ) = 0` — a small dense system
/// `J P Jᵀ λ = -J Δv`, the capacitance matrix of the held set — and adds `P Jᵀ λ` to `Δv`. The
/// rest of the surface then responds to the holds as to pins moving where the holders put them,
/// and a point hold whose impulse would pull is let go (contact only pushes),
/// at any `s`, without refactoring the filter: `P`'s columns for the held vertices are the
/// filter's own rows (neighbour) or one cached solve each (exact).
#[allow(clippy::too_many_arguments)]
pub(super) fn constrain(
    filter: &mut Filter,
    free: &[u32],
    free_index: &[u32],
    held: &[bool],
    held_normal: &[DVec3],
    points: &mut [PointHold],
    vel: &[DVec3],
    dv: &mut [DVec3],
    memory: &mut ActiveMemory,
) {
    // The free slots involved, sorted (the neighbour filter's gather searches them).
    let mut list: Vec<u32> = free
        .iter()
        .enumerate()
        .filter(|(_, &v)| held[v as usize])
        .map(|(fi, _)| fi as u32)
        .collect();
    for p in points.iter() {
        for (v, _) in p.entries() {
            let fi = free_index[v as usize];
            if fi != NOT_FREE {
                list.push(fi);
            }
        }
    }
    list.sort_unstable();
    list.dedup();
    let h = list.len();
    if h == 0 {
        return;
    }
    let slot = |fi: u32| list.binary_search(&fi).ok();
    // Constraints: direction, (slot, weight) entries, and which point hold (if any).
    type Con = (DVec3, [(usize, f64); 3], usize, Option<usize>);
    let mut cons: Vec<Con> = Vec::with_capacity(h);
    for (k, &fi) in list.iter().enumerate() {
        let v = free[fi as usize] as usize;
        if !held[v] {
            continue;
        }
        let entry = [(k, 1.0), (0, 0.0), (0, 0.0)];
        let n = held_normal[v];
        if n == DVec3::ZERO {
            cons.extend([DVec3::X, DVec3::Y, DVec3::Z].map(|d| (d, entry, 1, None)));
        } else {
            cons.push((n, entry, 1, None));
        }
    }
    for (pi, p) in points.iter().enumerate() {
        let mut entry = [(0, 0.0); 3];
        let mut count = 0;
        for (v, w) in p.entries() {
            if let Some(k) = slot(free_index[v as usize]) {
                entry[count] = (k, w);
                count += 1;
            }
        }
        if count > 0 {
            cons.push((p.normal, entry, count, Some(pi)));
        }
    }
    // P restricted to the involved vertices (h × h), one column read each.
    let mut p_hh = zeroed(&mut memory.scratch.block, h, h);
    filter.prepare_columns(&list);
    for (b, &fj) in list.iter().enumerate() {
        filter.gather(fj, &list, p_hh.column_mut(b).as_mut_slice());
    }
    let m = cons.len();
    // P's column k (column-major storage): P[(j, k)] = p_col[k * h + j] = P[(k, j)].
    let p_col = p_hh.as_slice();
    // Entry (a, b) of A = J P Jᵀ.
    let a_entry = |(da, ea, na, _): &Con, (db, eb, nb, _): &Con| {
        let mut s = 0.0;
        for &(ka, wa) in &ea[..*na] {
            let column = &p_col[ka * h..ka * h + h];
            for &(kb, wb) in &eb[..*nb] {
                s += wa * wb * column[kb];
            }
        }
        da.dot(*db) * s
    };
    // Vertex holds: no change of the held velocity. Point holds: at least their least
    // velocity.
    let rhs: Vec<f64> = cons
        .iter()
        .map(|(da, ea, na, point)| match point {
            None => -ea[..*na]
                .iter()
                .map(|&(k, w)| w * da.dot(dv[list[k] as usize]))
                .sum::<f64>(),
            Some(pi) => {
                points[*pi].min_velocity
                    - ea[..*na]
                        .iter()
                        .map(|&(k, w)| {
                            let fi = list[k] as usize;
                            w * da.dot(vel[free[fi] as usize] + dv[fi])
                        })
                        .sum::<f64>()
            }
        })
        .collect();
    // A point hold on a held vertex, or two on the same points, repeat a constraint: a tiny
    // diagonal term keeps the system definite (the least-norm impulses).
    let scale = cons.iter().map(|c| a_entry(c, c)).fold(0.0, f64::max);
    // Point holds only push (one that would pull is let go) and a point left out must not pass
    // its holder; vertex holds are bilateral.
    let tol = 1e-9 * (1.0 + rhs.iter().fold(0.0, |a: f64, r| a.max(r.abs())));
    let keys: Vec<Option<[u32; 3]>> = cons
        .iter()
        .map(|c| c.3.map(|pi| points[pi].key()))
        .collect();
    let starts_in: Vec<bool> = (0..m)
        .map(|c| keys[c].is_none_or(|k| memory.starts_in(k, rhs[c])))
        .collect();
    // The neighbour filter reaches a few rings of vertices: tools pressing apart give
    // independent blocks of A, each solved on its own (six cubes on the 784-node plate: six
    // solves of about 18 rows instead of one of about 110). The exact filter connects every
    // pair: one block.
    let local = matches!(filter.kind(), FilterKind::Neighbour { .. });
    let blocks = independent_blocks(
        h,
        local.then_some(p_col),
        cons.iter()
            .map(|(_, e, n, _)| e[..*n].iter().map(|&(k, _)| k)),
    );
    let mut lambda = vec![0.0; m];
    let mut active = vec![false; m];
    let mut factor = std::mem::take(&mut memory.scratch.factor);
    for block in &blocks {
        let mb = block.len();
        // A is symmetric (P is): the upper triangle is computed and mirrored.
        let mut a_mat = zeroed(&mut memory.scratch.system, mb, mb);
        for (i, &ca) in block.iter().enumerate() {
            for (j, &cb) in block.iter().enumerate().skip(i) {
                let v = a_entry(&cons[ca], &cons[cb]);
                a_mat[(i, j)] = v;
                a_mat[(j, i)] = v;
            }
            a_mat[(i, i)] += 1e-12 * scale;
        }
        let b = nalgebra::DVector::from_fn(mb, |i, _| rhs[block[i]]);
        let solved = solve_pushing(
            &a_mat,
            &b,
            |i| cons[block[i]].3.is_some(),
            |i| starts_in[block[i]],
            tol,
            &mut factor,
        );
        give_back(&mut memory.scratch.system, a_mat);
        // A block whose solve fails (not finite) gives no impulses; the others stand.
        if let Some((x, act)) = solved {
            for (i, &c) in block.iter().enumerate() {
                lambda[c] = x[i];
                active[c] = act[i];
            }
        }
    }
    memory.scratch.factor = factor;
    give_back(&mut memory.scratch.block, p_hh);
    memory.seen.clear();
    memory.pushing.clear();
    for (c, key) in keys.iter().enumerate() {
        if let Some(k) = key {
            memory.seen.insert(*k);
            if active[c] && lambda[c] > 0.0 {
                memory.pushing.insert(*k);
            }
        }
    }
    let mut impulse = vec![DVec3::ZERO; h];
    for (c, (d, e, n, point)) in cons.iter().enumerate() {
        for &(k, w) in &e[..*n] {
            impulse[k] += *d * (w * lambda[c]);
        }
        if let Some(pi) = point {
            points[*pi].impulse += lambda[c];
        }
    }
    filter.add_impulses(&list, &impulse, dv);
}
