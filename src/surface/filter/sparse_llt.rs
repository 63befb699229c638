//! The exact filter's factor: `S = Pᵀ L Lᵀ P` as faer computes it (sparse Cholesky, AMD
//! ordering, always the simplicial factor), solved by hand where that is faster.
//!
//! Measured on this crate's 2-core machine (2026-11-26) on `S` of grid surfaces like the
//! shipped plates (3,025 to 99,856 free vertices), one process per size:
//! - **Simplicial, not supernodal.** faer picks a supernodal factor from about 20,000
//!   vertices. Its solves with three right-hand sides took 2.4 / 7.2 / 22 ms at 20,000 /
//!   40,000 / 100,000 vertices against the simplicial factor's 1.06 / 3.0 / 9.2 ms, and its
//!   batches of filter columns 0.46 / 2.8 ms per column (20,000 / 100,000) against the
//!   hand-written batches below (0.16-0.18 / 1.8 ms). The price is the factorization, once per
//!   `dt`, stiffness or pin change: 12 → 34 ms at 20,000 vertices, 92 → 284 ms at 100,000.
//! - **A vertex's three coordinates in one pass** ([`SparseLlt::solve3`]): one read of the
//!   factor updates the three coordinates of a row together, where faer's simplicial solve
//!   works on an `n × 3` column-major matrix. Faster while the factor fits the cache:
//!   94-107 µs against faer's 114-148 µs at 3,025 vertices (65,898 factor entries), 435-452
//!   µs against 495-503 µs at 10,000; slower past that (1.10 against 1.06 ms at 20,000, 15.3
//!   against 9.2 ms at 100,000), so larger factors go to faer's solve.
//! - **Batches of filter columns** ([`SparseLlt::columns`]): up to 16 unit right-hand sides
//!   interleaved per row, the forward pass started at the first nonzero row: 15 µs per column
//!   at 3,025 vertices against faer's 37 µs in batches of 32, 70 against 165-205 µs at
//!   10,000, 1.8 against 3.4 ms at 100,000.
//!
//! Both read faer's factor in place (its column pointers, row indices and values); only the
//! permutation and the inverses of the diagonal are kept beside it.

use super::FilterError;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::SparseColMat;
use faer::{Conj, MatMut, Par, Side};
use glamx::DVec3;

/// Columns of `S⁻¹` solved together by [`SparseLlt::columns`].
pub(crate) const COLUMN_BATCH: usize = 16;

/// Factors with more entries than this are solved by faer in [`SparseLlt::solve3`] (module
/// docs: the crossover on this machine lies between 300,000 and 620,000 entries).
const HAND_SOLVE_MAX_ENTRIES: usize = 400_000;

/// `S` factored; see the module docs.
pub(crate) struct SparseLlt {
    symbolic: SymbolicCholesky<u32>,
    values: Vec<f64>,
    simplicial: Option<Simplicial>,
    /// Largest factor [`Self::solve3`] solves by hand ([`HAND_SOLVE_MAX_ENTRIES`]).
    hand_solve_max: usize,
    /// The permuted right-hand sides of [`Self::solve3`].
    work: Vec<DVec3>,
}

/// What the interleaved solves add to faer's simplicial factor (whose columns they read in
/// place, through [`Columns`]).
struct Simplicial {
    /// Row `i` of the permuted system is row `perm[i]` of `S`.
    perm: Vec<u32>,
    /// Row `i` of `S` is row `inv[i]` of the permuted system.
    inv: Vec<u32>,
    /// `1 / L[j, j]`.
    inv_diag: Vec<f64>,
    /// Column `j`'s entries in faer's arrays start at `ptr[j]` (the diagonal, then the rows
    /// below it up to `ptr[j + 1]`).
    ptr: Vec<usize>,
}

/// faer's simplicial factor, read in place.
struct Columns<'a> {
    s: &'a Simplicial,
    rows: &'a [u32],
    vals: &'a [f64],
}

impl std::fmt::Debug for SparseLlt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLlt")
            .field("n", &self.symbolic.nrows())
            .field("entries", &self.values.len())
            .field("simplicial", &self.simplicial.is_some())
            .finish()
    }
}

impl SparseLlt {
    /// Factors the symmetric positive definite `a` (its lower triangle is read).
    pub fn new(a: &SparseColMat<u32, f64>) -> Result<Self, FilterError> {
        Self::with_threshold(a, SupernodalThreshold::FORCE_SIMPLICIAL)
    }

    /// [`Self::new`] with faer's choice between a simplicial and a supernodal factor.
    fn with_threshold(
        a: &SparseColMat<u32, f64>,
        supernodal: SupernodalThreshold,
    ) -> Result<Self, FilterError> {
        let faer_err = |e: faer::sparse::FaerError| FilterError::Faer(format!("{e:?}"));
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: supernodal,
            ..Default::default()
        };
        let symbolic =
            factorize_symbolic_cholesky(a.symbolic(), Side::Lower, SymmetricOrdering::Amd, params)
                .map_err(faer_err)?;
        let mut values = vec![0.0; symbolic.len_val()];
        let scratch = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        let mut buffer =
            MemBuffer::try_new(scratch).map_err(|_| FilterError::Faer("out of memory".into()))?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a.as_ref(),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .map_err(|_| FilterError::NotPositiveDefinite)?;
        let simplicial = Simplicial::new(&symbolic, &values);
        Ok(Self {
            work: vec![DVec3::ZERO; symbolic.nrows()],
            symbolic,
            values,
            simplicial,
            hand_solve_max: HAND_SOLVE_MAX_ENTRIES,
        })
    }

    /// The order of `S`.
    pub fn n(&self) -> usize {
        self.symbolic.nrows()
    }

    /// `x ← S⁻¹ x`, the three coordinates alike.
    pub fn solve3(&mut self, x: &mut [DVec3]) {
        let n = self.n();
        if x.len() != n {
            return;
        }
        if self.values.len() <= self.hand_solve_max {
            let Self {
                symbolic,
                values,
                simplicial,
                work,
                ..
            } = self;
            if let Some(c) = Columns::of(symbolic, values, simplicial.as_ref()) {
                for (w, &p) in work.iter_mut().zip(&c.s.perm) {
                    *w = x[p as usize];
                }
                c.forward(work, 0);
                c.backward(work);
                for (w, &p) in work.iter().zip(&c.s.perm) {
                    x[p as usize] = *w;
                }
                return;
            }
        }
        let mut m = faer::Mat::<f64>::from_fn(n, 3, |i, c| x[i][c]);
        self.faer_solve(m.as_mut());
        for (i, xi) in x.iter_mut().enumerate() {
            *xi = DVec3::new(m[(i, 0)], m[(i, 1)], m[(i, 2)]);
        }
    }

    /// Columns `js` of `S⁻¹` (at most [`COLUMN_BATCH`], each below [`Self::n`]), handed to
    /// `out(k, column)` for `js[k]`.
    pub fn columns(&self, js: &[u32], mut out: impl FnMut(usize, Vec<f64>)) {
        let n = self.n();
        let js = &js[..js.len().min(COLUMN_BATCH)];
        match Columns::of(&self.symbolic, &self.values, self.simplicial.as_ref()) {
            Some(c) => match js.len() {
                0 => {}
                1..=4 => c.columns::<4>(js, &mut out),
                5..=8 => c.columns::<8>(js, &mut out),
                _ => c.columns::<COLUMN_BATCH>(js, &mut out),
            },
            None => {
                let mut e = faer::Mat::<f64>::zeros(n, js.len());
                for (k, &j) in js.iter().enumerate() {
                    e[(j as usize, k)] = 1.0;
                }
                self.faer_solve(e.as_mut());
                for k in 0..js.len() {
                    out(k, e.col(k).iter().copied().collect());
                }
            }
        }
    }

    /// `y = L⁻¹ P e_j` for column `j` of `S` (below [`Self::n`]), as `(permuted row, value)` in
    /// increasing rows; `None` without the hand-read simplicial factor. Its only nonzeros lie on
    /// the path from `j`'s permuted row to the root of the elimination tree (a column's pattern
    /// holds only ancestors of it, the first row below its diagonal being its parent), so it
    /// costs the factor's columns along that path, not the whole factor; and `S⁻¹[r, j] =
    /// yᵣ · yⱼ` ([`path_dot`]). `work` is scratch of length [`Self::n`], left zero.
    pub fn path(&self, j: u32, work: &mut Vec<f64>) -> Option<Vec<(u32, f64)>> {
        let c = Columns::of(&self.symbolic, &self.values, self.simplicial.as_ref())?;
        let n = self.n();
        let start = *c.s.inv.get(j as usize)? as usize;
        work.resize(n, 0.0);
        work[start] = 1.0;
        let mut path = Vec::new();
        let mut k = start;
        loop {
            let xk = work[k] * c.s.inv_diag[k];
            work[k] = 0.0;
            path.push((k as u32, xk));
            let mut parent = usize::MAX;
            for (&i, &l) in c.below(k) {
                work[i as usize] -= l * xk;
                parent = parent.min(i as usize);
            }
            if parent >= n {
                break;
            }
            k = parent;
        }
        Some(path)
    }

    /// faer's own solve.
    fn faer_solve(&self, rhs: MatMut<'_, f64>) {
        let k = rhs.ncols();
        let Ok(mut buffer) =
            MemBuffer::try_new(self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq))
        else {
            return;
        };
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut buffer),
        );
    }
}

/// `a · b` for two of [`SparseLlt::path`]'s vectors: an entry of `S⁻¹`. The rows two paths
/// share are their common ancestors, the tail from where they meet to the root, so the sum
/// runs back from the root while the rows agree: it costs the shared tail, not both paths.
pub(crate) fn path_dot(a: &[(u32, f64)], b: &[(u32, f64)]) -> f64 {
    a.iter()
        .rev()
        .zip(b.iter().rev())
        .take_while(|(x, y)| x.0 == y.0)
        .map(|(x, y)| x.1 * y.1)
        .sum()
}

/// A row of right-hand sides solved together: a vertex's three coordinates, or a batch of
/// columns.
trait Lanes: Copy {
    fn scale(&mut self, a: f64);
    /// `self -= a · other`.
    fn sub_scaled(&mut self, a: f64, other: &Self);
}

impl Lanes for DVec3 {
    #[inline(always)]
    fn scale(&mut self, a: f64) {
        *self *= a;
    }
    #[inline(always)]
    fn sub_scaled(&mut self, a: f64, other: &Self) {
        *self -= *other * a;
    }
}

impl<const W: usize> Lanes for [f64; W] {
    #[inline(always)]
    fn scale(&mut self, a: f64) {
        self.iter_mut().for_each(|c| *c *= a);
    }
    #[inline(always)]
    fn sub_scaled(&mut self, a: f64, other: &Self) {
        for (c, o) in self.iter_mut().zip(other) {
            *c -= a * o;
        }
    }
}

impl Simplicial {
    /// The additions for faer's factor, if it is simplicial with each column's diagonal first
    /// and positive.
    fn new(symbolic: &SymbolicCholesky<u32>, values: &[f64]) -> Option<Self> {
        let SymbolicCholeskyRaw::Simplicial(s) = symbolic.raw() else {
            return None;
        };
        let n = symbolic.nrows();
        let (col_ptr, row_idx) = (s.col_ptr(), s.row_idx());
        let (perm, inv) = match symbolic.perm() {
            Some(p) => (p.arrays().0.to_vec(), p.arrays().1.to_vec()),
            None => ((0..n as u32).collect(), (0..n as u32).collect()),
        };
        let ptr: Vec<usize> = col_ptr.iter().map(|&p| p as usize).collect();
        if ptr.len() != n + 1 || ptr[n] > values.len().min(row_idx.len()) {
            return None;
        }
        let mut inv_diag = Vec::with_capacity(n);
        for j in 0..n {
            let a = ptr[j];
            if a >= ptr[j + 1] || row_idx[a] as usize != j || values[a] <= 0.0 {
                return None;
            }
            inv_diag.push(1.0 / values[a]);
        }
        Some(Self {
            perm,
            inv,
            inv_diag,
            ptr,
        })
    }
}

impl<'a> Columns<'a> {
    /// faer's factor in `symbolic` and `values`, when `simplicial` was made for it.
    fn of(
        symbolic: &'a SymbolicCholesky<u32>,
        values: &'a [f64],
        simplicial: Option<&'a Simplicial>,
    ) -> Option<Self> {
        let SymbolicCholeskyRaw::Simplicial(f) = symbolic.raw() else {
            return None;
        };
        Some(Self {
            s: simplicial?,
            rows: f.row_idx(),
            vals: values,
        })
    }

    /// Column `j`'s rows below the diagonal and their values.
    #[inline]
    fn below(&self, j: usize) -> impl Iterator<Item = (&u32, &f64)> {
        let r = self.s.ptr[j] + 1..self.s.ptr[j + 1];
        self.rows[r.clone()].iter().zip(&self.vals[r])
    }

    /// Columns `js` (at most `W`) of `S⁻¹`, solved together, to `out`.
    fn columns<const W: usize>(&self, js: &[u32], out: &mut impl FnMut(usize, Vec<f64>)) {
        let n = self.s.perm.len();
        let mut x = vec![[0.0; W]; n];
        let mut start = n;
        for (k, &j) in js.iter().enumerate().take(W) {
            if let Some(&row) = self.s.inv.get(j as usize) {
                x[row as usize][k] = 1.0;
                start = start.min(row as usize);
            }
        }
        // Rows above the first unit stay zero through the forward pass.
        self.forward(&mut x, start);
        self.backward(&mut x);
        for k in 0..js.len().min(W) {
            let mut col = vec![0.0; n];
            for (c, &p) in x.iter().zip(&self.s.perm) {
                col[p as usize] = c[k];
            }
            out(k, col);
        }
    }

    /// `x ← L⁻¹ x`, for `x` zero above row `start`.
    #[inline]
    fn forward<T: Lanes>(&self, x: &mut [T], start: usize) {
        for j in start..x.len() {
            let mut xj = x[j];
            xj.scale(self.s.inv_diag[j]);
            x[j] = xj;
            for (&i, &l) in self.below(j) {
                x[i as usize].sub_scaled(l, &xj);
            }
        }
    }

    /// `x ← L⁻ᵀ x`.
    #[inline]
    fn backward<T: Lanes>(&self, x: &mut [T]) {
        for j in (0..x.len()).rev() {
            let mut a = x[j];
            for (&i, &l) in self.below(j) {
                a.sub_scaled(l, &x[i as usize]);
            }
            a.scale(self.s.inv_diag[j]);
            x[j] = a;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::System;
    use super::*;

    /// A `w × w` grid of free vertices with diagonals, masses, stiffnesses and dampings spread
    /// over two decades, its rim anchored, at a `dt` that makes `s` reach the hundreds.
    fn grid_system(w: u32) -> System {
        let mut seed = 0x2545_f491_u64;
        let mut rand = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 10_000) as f64 / 10_000.0
        };
        let id = |i: u32, j: u32| i * w + j;
        let mut pairs = Vec::new();
        let mut anchors = Vec::new();
        for i in 0..w {
            for j in 0..w {
                for (di, dj) in [(0, 1), (1, 0), (1, 1)] {
                    if i + di < w && j + dj < w {
                        let k = 10.0 * (1.0 + 99.0 * rand());
                        pairs.push((id(i, j), id(i + di, j + dj), k, 0.05 * rand()));
                    }
                }
                if i == 0 || j == 0 || i == w - 1 || j == w - 1 {
                    anchors.push((id(i, j), 30.0, 0.05));
                }
            }
        }
        let mass = (0..w * w).map(|_| 1e-4 * (1.0 + 99.0 * rand())).collect();
        System {
            mass,
            pairs,
            anchors,
        }
    }

    fn vec3s(n: usize) -> Vec<DVec3> {
        (0..n)
            .map(|i| {
                let t = i as f64;
                DVec3::new((0.37 * t).sin(), (1.3 * t).cos() - 0.2, (t * 0.011).sqrt())
            })
            .collect()
    }

    /// `‖S x - b‖∞ / ‖b‖∞`, with `S` applied by its own rows (not the factor).
    fn residual(s: &super::super::Csr, x: &[DVec3], b: &[DVec3]) -> f64 {
        let mut sx = vec![DVec3::ZERO; b.len()];
        s.mul_vec3(x, &mut sx);
        let scale = b.iter().map(|v| v.abs().max_element()).fold(0.0, f64::max);
        sx.iter()
            .zip(b)
            .map(|(a, b)| (*a - *b).abs().max_element())
            .fold(0.0, f64::max)
            / scale
    }

    #[test]
    fn both_factors_solve_three_coordinates_and_give_columns_of_the_inverse() {
        for w in [1, 2, 7, 30] {
            let system = grid_system(w);
            let s = system.matrix(1.0 / 60.0);
            let a = s.to_faer().unwrap();
            let n = s.n;
            for (threshold, by_hand) in [
                (SupernodalThreshold::AUTO, true),
                (SupernodalThreshold::FORCE_SIMPLICIAL, true),
                (SupernodalThreshold::FORCE_SIMPLICIAL, false),
                (SupernodalThreshold::FORCE_SUPERNODAL, true),
            ] {
                let mut llt = SparseLlt::with_threshold(&a, threshold).unwrap();
                if !by_hand {
                    // faer's solve of the simplicial factor, as for large factors.
                    llt.hand_solve_max = 0;
                }
                assert_eq!(llt.n(), n);
                // The hand-written solves run on every simplicial factor.
                if threshold == SupernodalThreshold::FORCE_SIMPLICIAL {
                    assert!(llt.simplicial.is_some());
                } else if threshold == SupernodalThreshold::FORCE_SUPERNODAL && w > 2 {
                    // (faer factors the smallest matrices simplicially whatever the threshold)
                    assert!(llt.simplicial.is_none());
                }
                let b = vec3s(n);
                let mut x = b.clone();
                llt.solve3(&mut x);
                let r = residual(&s, &x, &b);
                assert!(r < 1e-10, "w {w}, {threshold:?}: residual {r:e}");
                // A wrong length is left alone.
                let mut short = b[..n - 1].to_vec();
                llt.solve3(&mut short);
                assert_eq!(short, b[..n - 1]);
                // Batches of every width: S · column j = e_j.
                for count in [1, 3, 4, 5, 8, 9, COLUMN_BATCH, COLUMN_BATCH + 3] {
                    let js: Vec<u32> = (0..count as u32).map(|k| (k * 7 + 3) % n as u32).collect();
                    let mut seen = 0;
                    llt.columns(&js, |k, col| {
                        seen += 1;
                        let x: Vec<DVec3> = col.iter().map(|&v| DVec3::splat(v)).collect();
                        let mut e = vec![DVec3::ZERO; n];
                        e[js[k] as usize] = DVec3::ONE;
                        let mut sx = vec![DVec3::ZERO; n];
                        s.mul_vec3(&x, &mut sx);
                        let err = sx
                            .iter()
                            .zip(&e)
                            .map(|(a, b)| (*a - *b).abs().max_element())
                            .fold(0.0, f64::max);
                        assert!(
                            err < 1e-10,
                            "w {w}, {threshold:?}, column {}: {err:e}",
                            js[k]
                        );
                    });
                    assert_eq!(seen, count.min(COLUMN_BATCH), "w {w}, {count} columns");
                }
                // Entries of the inverse from two elimination-tree paths, against its columns.
                if llt.simplicial.is_some() {
                    let mut work = Vec::new();
                    let js: Vec<u32> = (0..n as u32).step_by((n / 7).max(1)).collect();
                    let paths: Vec<_> = js
                        .iter()
                        .map(|&j| llt.path(j, &mut work).unwrap())
                        .collect();
                    assert!(work.iter().all(|&v| v == 0.0));
                    llt.columns(&js, |k, col| {
                        for (r, &j) in js.iter().enumerate() {
                            let e = path_dot(&paths[k], &paths[r]);
                            let want = col[j as usize];
                            assert!(
                                (e - want).abs() <= 1e-12 * want.abs().max(1.0),
                                "w {w}: S⁻¹[{}, {}] {e} against {want}",
                                j,
                                js[k]
                            );
                        }
                    });
                }
            }
        }
    }

    /// The filter's block at a few vertices and the impulses' velocity change, from paths (as
    /// on systems of [`super::super::PATHS_FROM`] vertices or more) and from dense columns.
    #[test]
    fn paths_give_the_filter_block_and_impulses_as_columns_do() {
        use super::super::{Filter, FilterKind};
        let system = grid_system(40);
        let dt = 1.0 / 60.0;
        let dense = || Filter::precompute(&system, dt, FilterKind::Exact).unwrap();
        let mut by_paths = dense();
        if let Filter::Exact { paths_from, .. } = &mut by_paths {
            *paths_from = 0;
        }
        let mut by_columns = dense();
        let list: Vec<u32> = vec![0, 3, 41, 42, 43, 90, 777, 1200, 1599];
        let h = list.len();
        let (mut a, mut b) = (vec![0.0; h * h], vec![0.0; h * h]);
        by_paths.gather_block(&list, &mut a);
        by_columns.gather_block(&list, &mut b);
        if let Filter::Exact { paths, columns, .. } = &by_paths {
            assert_eq!(paths.len(), h);
            assert!(columns.is_empty());
        }
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (x - y).abs() <= 1e-12 * y.abs().max(1e-3),
                "{x} against {y}"
            );
        }
        // Again, from the kept entries, over a list that lost a vertex and gained one.
        let list2: Vec<u32> = vec![0, 3, 41, 43, 90, 500, 777, 1200, 1599];
        let (mut a2, mut b2) = (vec![0.0; h * h], vec![0.0; h * h]);
        by_paths.gather_block(&list2, &mut a2);
        by_columns.gather_block(&list2, &mut b2);
        for (x, y) in a2.iter().zip(&b2) {
            assert!(
                (x - y).abs() <= 1e-12 * y.abs().max(1e-3),
                "{x} against {y}"
            );
        }
        // A few impulses: a solve on one side, cached columns on the other.
        let impulse: Vec<DVec3> = vec3s(3);
        let n = system.mass.len();
        let (mut va, mut vb) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        by_paths.add_impulses(&list[..3], &impulse, &mut va);
        by_columns.add_impulses(&list[..3], &impulse, &mut vb);
        for (x, y) in va.iter().zip(&vb) {
            assert!((*x - *y).abs().max_element() <= 1e-12, "{x} against {y}");
        }
    }

    #[test]
    fn an_indefinite_matrix_is_an_error() {
        let mut system = grid_system(4);
        system.mass[5] = -1.0;
        let a = system.matrix(1e-3).to_faer().unwrap();
        assert_eq!(
            SparseLlt::new(&a).err(),
            Some(FilterError::NotPositiveDefinite)
        );
    }
}
