//! The paper's global filter, eq. (8)-(10).
//!
//! Implicit Euler with the forces linearized at the start of the step (eq. 5-7) gives, per
//! coordinate and for the free (unpinned) vertices,
//!
//! ```text
//! S Δv = dt (Fⁿ + dt K vⁿ),      S = M - dt² K - dt C            (eq. 7)
//! Δv   = W M⁻¹ dt (Fⁿ + dt K vⁿ), W = (I - K dt²/m - C dt/m)⁻¹ = S⁻¹ M   (eq. 8)
//! ```
//!
//! where `K = -Lk` and `C = -Lc` are the stiffness and damping graph Laplacians of the edges
//! (each `N × N`, applied to the three coordinates alike, as the paper "compounds" its 1D
//! matrix). `S` is symmetric positive definite whenever every mass is positive, so it is
//! factored once (sparse Cholesky, faer; solved as `sparse_llt` says) and each step costs two
//! triangular solves with three right-hand sides; the dense `W` is never formed (except on
//! request, for analysis).
//!
//! The `dt K vⁿ` term is the part of the Taylor expansion `K Δx = K dt (vⁿ + Δv)` known at the
//! start of the step: the spring force change the current velocity will cause over the step.
//! The paper calls it artificial viscosity; it is what makes the update implicit in position and
//! not only in velocity. Without it a stiff surface keeps oscillating at `dt` far above the
//! explicit limit.
//!
//! **The immediate-neighbour filter** (the paper's simplification, eq. 10 restricted to the
//! 1-ring): with `D = diag(S)` and `B = I - D^{-1/2} S D^{-1/2}`,
//! `S⁻¹ = D^{-1/2} (I - B)⁻¹ D^{-1/2} ≈ D^{-1/2} (I + B + … + B^r) D^{-1/2}`. With `r = 1` this is
//! the paper's first-order Neumann polynomial `2D⁻¹ - D⁻¹ S D⁻¹`, with the sparsity of the mesh;
//! each further term widens it by one ring. `‖B‖ ≤ s/(1+s)` per vertex, with
//! `s = dt²Σk/m + dt Σc/m`, so the truncation error shrinks like `(s/(1+s))^(r+1)`: the filter is
//! close to `W` only while `s` is small.
//!
//! **Corrections to the paper:** the truncated series does not reproduce rigid motion (the rows
//! of its `W` do not sum to one), so a free surface's momentum drifts and the transient is off.
//! Two fixes, both free per step:
//! - on the rows of vertices with `s ≤ 1`, a diagonal term `δ_i = (1 - (P S 1)_i) / (S 1)_i`
//!   makes the filter exact on the constant vector. It cuts the neighbour filter's deviation
//!   from the exact one about 40-fold at `s ≈ 0.25` (the `plate_step_force` example: 0.08 %
//!   instead of 3 % RMS). Applied to every row it would make the filter unstable from
//!   `s ≈ 2` (it shifts the high-frequency modes), where the paper's plain series stays stable
//!   up to `s ≈ 25`, hence the limit;
//! - on a surface with no pinned vertex, the surface adds the mean velocity change that makes
//!   the momentum change equal the applied impulse (a rank-one correction of the rigid mode
//!   only; see [`super::MassSpringSurface::step`]), so momentum is conserved at any `s`.
//!   The constraint solve's impulses (holds and presses) reach the vertices through the same
//!   truncated columns and get the same correction after the solve: without it, a free
//!   surface under contact took up to 3.3 % more or less momentum than its holds and presses
//!   gave (one ring, a coarse grid; `tests/it/surface.rs`), with it single precision (two
//!   more passes over the vertices in a step with contacts).

mod neighbour;
mod sparse_llt;

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use glamx::DVec3;
pub(crate) use neighbour::neighbour_error_bound;
use neighbour::neumann;
use sparse_llt::{path_dot, SparseLlt, COLUMN_BATCH};

/// Why a filter could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FilterError {
    /// The system matrix is not positive definite (a zero or negative mass, or a negative
    /// stiffness or damping slipped through).
    #[error("the implicit system is not positive definite")]
    NotPositiveDefinite,
    /// faer failed (out of memory, index overflow).
    #[error("sparse factorization failed: {0}")]
    Faer(String),
}

/// Which filter `W` the implicit integrator applies.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum FilterKind {
    /// The exact filter: `S` prefactored by sparse Cholesky, two triangular solves per step.
    Exact,
    /// The truncated Neumann series with `rings` terms beyond the identity: `rings = 1` is the
    /// paper's immediate-neighbour filter, each extra ring widens the stencil by one ring of
    /// neighbours and cuts the error by a factor of about `s/(1+s)`.
    Neighbour {
        /// Number of Neumann terms after the identity (1 = immediate neighbours). At least 1.
        rings: u32,
    },
}

/// A symmetric sparse matrix in compressed rows, read once per pass by a `Vec3` product.
#[derive(Clone, Debug, Default)]
pub(crate) struct Csr {
    pub n: usize,
    pub ptr: Vec<usize>,
    pub idx: Vec<u32>,
    pub val: Vec<f64>,
}

impl Csr {
    /// `y = A x` over `Vec3`s (one read of the matrix).
    ///
    /// Hand-written on purpose: faer's `sparse_dense_matmul` on the same matrix (built once with
    /// [`Csr::to_faer`], the three coordinates copied into and out of an `n × 3` `Mat` each
    /// step) made a whole neighbour-filter step slower in one `cargo bench --bench soft_step --
    /// neighbour` A/B on this crate's 2-core machine (2026-11-23): 784 nodes 22.3 → 31.4 µs,
    /// 3,025 nodes 94 → 150 µs, 10,000 nodes 351 → 612 µs, 19,881 nodes 806 → 1044 µs. faer
    /// builds, multiplies and factors the matrices everywhere else in this file.
    #[inline]
    pub fn mul_vec3(&self, x: &[DVec3], y: &mut [DVec3]) {
        for (yi, w) in y.iter_mut().zip(self.ptr.windows(2)) {
            let (idx, val) = (&self.idx[w[0]..w[1]], &self.val[w[0]..w[1]]);
            let mut acc = DVec3::ZERO;
            for (&j, &a) in idx.iter().zip(val) {
                acc += x[j as usize] * a;
            }
            *yi = acc;
        }
    }

    fn from_faer(m: &SparseColMat<u32, f64>) -> Self {
        // Symmetric: the columns are the rows.
        let n = m.ncols();
        let sym = m.symbolic();
        let mut ptr = Vec::with_capacity(n + 1);
        let mut idx = Vec::new();
        let mut val = Vec::new();
        ptr.push(0);
        for j in 0..n {
            let rows = sym.row_idx_of_col_raw(j);
            let vals = m.val_of_col(j);
            for (r, v) in rows.iter().zip(vals) {
                if *v != 0.0 {
                    idx.push(*r);
                    val.push(*v);
                }
            }
            ptr.push(idx.len());
        }
        Self { n, ptr, idx, val }
    }

    fn to_faer(&self) -> Result<SparseColMat<u32, f64>, FilterError> {
        let mut t = Vec::with_capacity(self.val.len());
        for i in 0..self.n {
            for k in self.ptr[i]..self.ptr[i + 1] {
                t.push(Triplet::new(self.idx[k], i as u32, self.val[k]));
            }
        }
        SparseColMat::try_new_from_triplets(self.n, self.n, &t)
            .map_err(|e| FilterError::Faer(format!("{e:?}")))
    }
}

/// The implicit system of the free vertices: `S = M + dt² Lk + dt Lc` (eq. 7), kept as its
/// graph so that `dt`, stiffness and damping can change without rebuilding the mesh.
#[derive(Clone, Debug)]
pub(crate) struct System {
    /// Mass of each free vertex.
    pub mass: Vec<f64>,
    /// Springs between two free vertices: (a, b, k, c), free indices.
    pub pairs: Vec<(u32, u32, f64, f64)>,
    /// Springs from a free vertex to a pinned one: (a, k, c).
    pub anchors: Vec<(u32, f64, f64)>,
}

impl System {
    /// `S` for time step `dt`, as a symmetric CSR matrix (diagonal included).
    pub fn matrix(&self, dt: f64) -> Csr {
        let n = self.mass.len();
        let mut diag: Vec<f64> = self.mass.clone();
        let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
        for &(a, b, k, c) in &self.pairs {
            let w = dt * dt * k + dt * c;
            diag[a as usize] += w;
            diag[b as usize] += w;
            rows[a as usize].push((b, -w));
            rows[b as usize].push((a, -w));
        }
        for &(a, k, c) in &self.anchors {
            diag[a as usize] += dt * dt * k + dt * c;
        }
        let mut ptr = Vec::with_capacity(n + 1);
        let mut idx = Vec::new();
        let mut val = Vec::new();
        ptr.push(0);
        for (i, mut r) in rows.into_iter().enumerate() {
            r.push((i as u32, diag[i]));
            r.sort_unstable_by_key(|e| e.0);
            // Parallel edges (duplicates) add up.
            let mut last = u32::MAX;
            for (j, v) in r {
                if j == last {
                    *val.last_mut().expect("pushed above") += v;
                } else {
                    idx.push(j);
                    val.push(v);
                    last = j;
                }
            }
            ptr.push(idx.len());
        }
        Csr { n, ptr, idx, val }
    }

    /// The paper's `s` per free vertex: `(dt² Σk + dt Σc) / m`.
    pub fn s_values(&self, dt: f64) -> Vec<f64> {
        let mut s = vec![0.0; self.mass.len()];
        for &(a, b, k, c) in &self.pairs {
            let w = dt * dt * k + dt * c;
            s[a as usize] += w;
            s[b as usize] += w;
        }
        for &(a, k, c) in &self.anchors {
            s[a as usize] += dt * dt * k + dt * c;
        }
        for (si, m) in s.iter_mut().zip(&self.mass) {
            *si /= m;
        }
        s
    }
}

/// A precomputed filter: `apply` solves (or approximates) `S Δv = b` without allocating.
pub(crate) enum Filter {
    Exact {
        llt: Box<SparseLlt>,
        /// Right-hand sides of [`Filter::add_impulses`]' solve.
        rhs: Vec<DVec3>,
        /// Columns of `S⁻¹` solved so far (for held vertices), dense.
        columns: std::collections::HashMap<u32, Vec<f64>>,
        /// On large systems ([`PATHS_FROM`]), the elimination-tree paths of held vertices
        /// instead ([`SparseLlt::path`]).
        paths: std::collections::HashMap<u32, Vec<(u32, f64)>>,
        /// Scratch of [`SparseLlt::path`].
        path_work: Vec<f64>,
        /// Entries of `S⁻¹` made from paths, by `(smaller, larger)` index: a held set changes
        /// little from one substep to the next.
        entries: std::collections::HashMap<(u32, u32), f64>,
        /// Systems of this many vertices or more keep paths ([`PATHS_FROM`]).
        paths_from: usize,
    },
    Neighbour {
        p: Csr,
        rings: u32,
    },
}

impl Filter {
    pub fn precompute(system: &System, dt: f64, kind: FilterKind) -> Result<Self, FilterError> {
        let s = system.matrix(dt);
        match kind {
            FilterKind::Exact => {
                let llt = Box::new(SparseLlt::new(&s.to_faer()?)?);
                Ok(Filter::Exact {
                    llt,
                    rhs: vec![DVec3::ZERO; s.n],
                    columns: Default::default(),
                    paths: Default::default(),
                    path_work: Vec::new(),
                    entries: Default::default(),
                    paths_from: PATHS_FROM,
                })
            }
            FilterKind::Neighbour { rings } => Ok(Filter::Neighbour {
                p: neumann(&s, &system.mass, rings.max(1))?,
                rings: rings.max(1),
            }),
        }
    }

    pub fn kind(&self) -> FilterKind {
        match self {
            Filter::Exact { .. } => FilterKind::Exact,
            Filter::Neighbour { rings, .. } => FilterKind::Neighbour { rings: *rings },
        }
    }

    /// `out = S⁻¹ b` (exact) or its approximation.
    pub fn apply(&mut self, b: &[DVec3], out: &mut [DVec3]) {
        match self {
            Filter::Exact { llt, .. } => {
                for (o, v) in out.iter_mut().zip(b) {
                    *o = *v;
                }
                llt.solve3(out);
            }
            Filter::Neighbour { p, .. } => p.mul_vec3(b, out),
        }
    }

    /// `out += P b` for `b` zero but on the free indices `at` (`b[at[k]] = impulse[k]`): the
    /// velocity change impulses on a few vertices cause. The neighbour filter visits their
    /// sparse columns; the exact filter, past [`SOLVE_PAST_COLUMNS`] of them, solves once (a
    /// solve costs about as much as 16 of its dense columns on the 784-node plate, and six
    /// cubes on it hold about 120 vertices: 33 µs by columns).
    pub fn add_impulses(&mut self, at: &[u32], impulse: &[DVec3], out: &mut [DVec3]) {
        if let Filter::Exact {
            llt,
            rhs,
            paths_from,
            ..
        } = self
        {
            // A large system's columns are not kept (see `prepare_columns`).
            if at.len() > SOLVE_PAST_COLUMNS || llt.n() >= *paths_from {
                rhs.fill(DVec3::ZERO);
                for (&j, b) in at.iter().zip(impulse) {
                    if let Some(r) = rhs.get_mut(j as usize) {
                        *r = *b;
                    }
                }
                llt.solve3(rhs);
                for (o, r) in out.iter_mut().zip(rhs.iter()) {
                    *o += *r;
                }
                return;
            }
        }
        for (&j, &b) in at.iter().zip(impulse) {
            if b != DVec3::ZERO {
                self.for_column(j, |i, w| out[i as usize] += b * w);
            }
        }
    }

    /// Entries `rows` (sorted free indices) of column `j` into `out` (see
    /// [`Filter::for_column`]).
    pub fn gather(&mut self, j: u32, rows: &[u32], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        match self {
            Filter::Neighbour { .. } => {
                self.for_column(j, |i, w| {
                    if let Ok(k) = rows.binary_search(&i) {
                        out[k] = w;
                    }
                });
            }
            Filter::Exact { .. } => {
                let col = self.exact_column(j);
                for (o, &r) in out.iter_mut().zip(rows) {
                    *o = col[r as usize];
                }
            }
        }
    }

    /// The block of the filter at `list` (sorted free indices) into `out` (`h × h`, column
    /// major, `h = list.len()`): [`Filter::prepare_columns`] then [`Filter::gather`] of each
    /// column, or, where the exact filter keeps paths ([`Filter::prepare_paths`]), each entry
    /// above the diagonal from two
    /// paths, mirrored (the block is symmetric; 321 held vertices on a 200,000-vertex system
    /// took 150 ms to gather column by column) and kept for the next substeps (in the 100,000-
    /// vertex plate of `benches/haptic_servo.rs`, held still, the entries made anew at every
    /// step cost more than the dense columns they replaced, which were kept).
    pub fn gather_block(&mut self, list: &[u32], out: &mut [f64]) {
        let h = list.len();
        if out.len() != h * h {
            return;
        }
        if self.prepare_paths(list) {
            let Filter::Exact { paths, entries, .. } = self else {
                return;
            };
            let found: Option<Vec<&Vec<(u32, f64)>>> = list.iter().map(|j| paths.get(j)).collect();
            if let Some(found) = found {
                if entries.len() > ENTRY_CACHE {
                    entries.clear();
                }
                for b in 0..h {
                    for a in 0..=b {
                        let key = (list[a].min(list[b]), list[a].max(list[b]));
                        let v = *entries
                            .entry(key)
                            .or_insert_with(|| path_dot(found[a], found[b]));
                        out[b * h + a] = v;
                        out[a * h + b] = v;
                    }
                }
                return;
            }
        }
        self.prepare_columns(list);
        for (b, &j) in list.iter().enumerate() {
            self.gather(j, list, &mut out[b * h..(b + 1) * h]);
        }
    }

    /// On an exact filter of [`PATHS_FROM`] vertices or more, makes sure it holds the path in
    /// the elimination tree ([`SparseLlt::path`]) of every vertex of `js` below its order, for
    /// [`Filter::gather_block`] to make entries from; `false` (nothing done) elsewhere, or
    /// where the factor is not the hand-read simplicial one. A dense column there is a pass
    /// over the whole factor (14 ms at 200,000 vertices), so a press that met a few hundred
    /// new vertices at once stalled the world for most of a second (293 columns in 740 ms),
    /// and the column cache, holding 20 such columns, solved 4-6 of them again at every step.
    fn prepare_paths(&mut self, js: &[u32]) -> bool {
        let Filter::Exact {
            llt,
            paths,
            path_work,
            paths_from,
            ..
        } = self
        else {
            return false;
        };
        let n = llt.n();
        if n < *paths_from {
            return false;
        }
        if paths.len() + js.len() > PATH_CACHE {
            let mut keep: Vec<u32> = js.to_vec();
            keep.sort_unstable();
            paths.retain(|j, _| keep.binary_search(j).is_ok());
        }
        for &j in js {
            if (j as usize) < n && !paths.contains_key(&j) {
                match llt.path(j, path_work) {
                    Some(p) => {
                        paths.insert(j, p);
                    }
                    None => return false,
                }
            }
        }
        true
    }

    /// Makes sure the exact filter holds columns `js` (sorted or not) of `S⁻¹`: the missing ones
    /// are solved together, up to [`COLUMN_BATCH`] right-hand sides per pass over the factor
    /// (a batch costs far less than as many single solves; see `sparse_llt`). The cache keeps
    /// up to [`COLUMN_CACHE_BYTES`] of columns, and never fewer than `js`: when full, columns
    /// outside `js` are dropped first, so a held set larger than the budget is not re-solved
    /// every step (it was, at 100,000 nodes with a few hundred held vertices: seconds per step).
    /// No-op for the neighbour filter.
    pub fn prepare_columns(&mut self, js: &[u32]) {
        let Filter::Exact { llt, columns, .. } = self else {
            return;
        };
        let n = llt.n();
        let mut missing: Vec<u32> = js
            .iter()
            .copied()
            .filter(|j| (*j as usize) < n && !columns.contains_key(j))
            .collect();
        missing.sort_unstable();
        missing.dedup();
        if missing.is_empty() {
            return;
        }
        let cap = (COLUMN_CACHE_BYTES / (8 * n.max(1))).max(js.len());
        if columns.len() + missing.len() > cap {
            let mut keep: Vec<u32> = js.to_vec();
            keep.sort_unstable();
            columns.retain(|j, _| keep.binary_search(j).is_ok());
        }
        for chunk in missing.chunks(COLUMN_BATCH) {
            llt.columns(chunk, |c, col| {
                columns.insert(chunk[c], col);
            });
        }
    }

    fn exact_column(&mut self, j: u32) -> &[f64] {
        self.prepare_columns(&[j]);
        match self {
            Filter::Exact { columns, .. } => columns.get(&j).map_or(&[], Vec::as_slice),
            Filter::Neighbour { .. } => &[],
        }
    }

    /// Visits column `j` of the filter (the velocity change a unit impulse on free vertex `j`
    /// causes, per coordinate) as `(row, value)`: the neighbour filter's own sparse row (the
    /// filter is symmetric), or, for the exact filter, a solve, cached
    /// ([`Filter::prepare_columns`]) until the filter is rebuilt.
    pub fn for_column(&mut self, j: u32, mut visit: impl FnMut(u32, f64)) {
        match self {
            Filter::Neighbour { p, .. } => {
                let (a, b) = (p.ptr[j as usize], p.ptr[j as usize + 1]);
                for (&i, &v) in p.idx[a..b].iter().zip(&p.val[a..b]) {
                    visit(i, v);
                }
            }
            Filter::Exact { .. } => {
                for (i, &v) in self.exact_column(j).iter().enumerate() {
                    visit(i as u32, v);
                }
            }
        }
    }
}

/// The exact filter's column cache budget (bytes); see [`Filter::prepare_columns`].
const COLUMN_CACHE_BYTES: usize = 32 << 20;

/// Systems of this many vertices or more keep elimination-tree paths rather than dense columns
/// of `S⁻¹` ([`Filter::prepare_paths`]).
const PATHS_FROM: usize = 50_000;

/// Most paths kept ([`Filter::prepare_paths`]; each is a few thousand entries of 16 bytes
/// on a system of 100,000 vertices or more: some 50 MB in all at most, and never fewer than a
/// solve asks for).
const PATH_CACHE: usize = 1024;

/// Most entries of `S⁻¹` kept from paths ([`Filter::gather_block`]): about 32 MB.
const ENTRY_CACHE: usize = 1 << 20;

/// Impulses on more vertices than this are applied by a solve of the exact filter rather than
/// by its cached columns (see [`Filter::add_impulses`]).
const SOLVE_PAST_COLUMNS: usize = 16;

/// The dense exact filter `W = S⁻¹ M` (row `i`: weights of every vertex's force on vertex
/// `i`), for analysis on small meshes (Table II). `O(N²)` memory.
pub(crate) fn dense_weights(system: &System, dt: f64) -> Result<Vec<Vec<f64>>, FilterError> {
    let s = system.matrix(dt).to_faer()?;
    let llt = s
        .sp_cholesky(Side::Lower)
        .map_err(|_| FilterError::NotPositiveDefinite)?;
    let n = system.mass.len();
    // Columns of S⁻¹ M: solve S x = M e_j.
    let mut rhs = Mat::<f64>::zeros(n, n);
    for j in 0..n {
        rhs[(j, j)] = system.mass[j];
    }
    llt.solve_in_place(rhs.as_mut());
    Ok((0..n)
        .map(|i| (0..n).map(|j| rhs[(i, j)]).collect())
        .collect())
}
