//! The active-set solve shared by the presses' position projection and the filtered step's
//! constraint impulses: `A x = b` with push-only rows, over a Cholesky factor that is updated
//! (rows appended, rows downdated out) as the active set changes.

/// Solves `A x = b` for contact rows that push (an active set, by block principal pivoting): a row
/// with `push_only(i)` must end with `xᵢ ≥ 0`, the others may have any sign; a row left out has
/// `xᵢ = 0` and must end satisfied, `bᵢ - (A x)ᵢ ≤ tol` (the other rows' pushes did its work).
/// The push-only rows start in where `starts_in` says. Each pass moves the rows on the wrong
/// side (block principal pivoting, below); at most `4m + 8` passes. Returns `x`
/// (zero on the rows left out) and which rows are in, or `None` when a solve fails or is not
/// finite.
///
/// Rows that (nearly) repeat rows already in are left out for good: with targets that differ
/// a little, a near-singular system answers with huge opposite impulses (a cube corner next to
/// a triangle edge gave a vertex press and an edge press on almost the same weights: 775 N on
/// a 3 N contact, then the plate tangled). The first factorization takes the rows in priority
/// order (the rows that are not push-only, then the push-only ones by decreasing `b`); a row
/// that comes back later is appended after the rows kept. A row whose pivot is below
/// [`REDUNDANT`] of its diagonal is the one left out.
///
/// `reference` gives each row the length that test measures against, in place of its diagonal
/// (empty: the diagonal). A rigid holder's mass in the filtered step's solve
/// ([`super::rigid_holder`]) adds a term of rank six at most to the rows it holds: for a light
/// body it dwarfs the surface's own compliance, and every row past the sixth would look like
/// a repeat of the others against its diagonal. Measured against the surface's part of the
/// diagonal, a row repeats the others only where the surface alone says so (the holder's
/// term, positive semi-definite, only raises the pivots).
///
/// `factor` is the storage of the Cholesky factor, kept by the caller from one solve to the
/// next. `relax`: rows left out as repeats that the answer leaves violated are met by
/// relaxing them and the rows coupled to them ([`relax_repeats`]). The callers leave it off
/// where a rigid holder's rows are in the system: there the sweeps, slow on the holder's
/// rank-six term, still left residuals of 1e-6 to 1e-4 after 50 of them, and a heavy U at
/// rest on a soft plate at one substep was kicked about at 1.1-1.5 cm/s by their changing
/// answers (under 1 cm/s without).
pub(super) fn solve_pushing(
    a: &nalgebra::DMatrix<f64>,
    b: &nalgebra::DVector<f64>,
    (push_only, starts_in): (impl Fn(usize) -> bool, impl Fn(usize) -> bool),
    reference: &[f64],
    tol: f64,
    factor: &mut Vec<f64>,
    relax: bool,
) -> Option<(nalgebra::DVector<f64>, Vec<bool>)> {
    let mut chol = Cholesky::new(b.len(), std::mem::take(factor));
    chol.reference.clear();
    chol.reference.extend_from_slice(reference);
    let solved = solve_on(&mut chol, a, b, push_only, starts_in, tol, relax);
    *factor = chol.l;
    solved
}

/// The rows of the symmetric `a` that nearly repeat rows before them in `order` (a
/// factorization in that order leaves them out, as [`solve_pushing`] does), over the factor's
/// storage `factor`.
pub(super) fn repeated_rows(
    a: &nalgebra::DMatrix<f64>,
    order: &[usize],
    factor: &mut Vec<f64>,
) -> Vec<usize> {
    let mut chol = Cholesky::new(a.nrows(), std::mem::take(factor));
    let left_out = chol.factorize(a, order);
    *factor = chol.l;
    left_out
}

/// [`solve_pushing`] on the factor's workspace `chol`.
fn solve_on(
    chol: &mut Cholesky,
    a: &nalgebra::DMatrix<f64>,
    b: &nalgebra::DVector<f64>,
    push_only: impl Fn(usize) -> bool,
    starts_in: impl Fn(usize) -> bool,
    tol: f64,
    relax: bool,
) -> Option<(nalgebra::DVector<f64>, Vec<bool>)> {
    let m = b.len();
    // A push-only row starts out unless `starts_in` says (the caller's guess: it asks for a
    // push, or it pushed at the last solve); a row out comes in if the others' pushes violate
    // it, a row in that pulls goes out.
    let mut active: Vec<bool> = (0..m).map(|i| !push_only(i) || starts_in(i)).collect();
    let mut redundant = vec![false; m];
    let mut x = nalgebra::DVector::<f64>::zeros(m);
    // The rows in, in priority order (ties by index).
    let mut first: Vec<(bool, f64, usize)> = (0..m)
        .filter(|&i| active[i])
        .map(|i| (push_only(i), b[i], i))
        .collect();
    first.sort_unstable_by(|p, q| p.0.cmp(&q.0).then(q.1.total_cmp(&p.1)).then(p.2.cmp(&q.2)));
    let first: Vec<usize> = first.into_iter().map(|(_, _, i)| i).collect();
    for i in chol.factorize(a, &first) {
        redundant[i] = true;
        active[i] = false;
    }
    // Block principal pivoting (Júdice and Pires 1994): every row on the wrong side (in and
    // pulling, or out and violated) changes side at once while that lowers how many are
    // wrong, or within `BACKUP` tries of the best; after that one row at a time, the highest
    // index first (Murty's rule, which ends on a positive definite system). The earlier
    // loop, which only dropped rows in one pass and only took rows back in another, could
    // cycle: started from another guess (the last friction pass's solution) it ran out of
    // passes on six cubes and returned impulses of 10⁸ N.
    let (mut best, mut backup) = (usize::MAX, BACKUP);
    let mut settled = false;
    // Solves on the rows kept and spreads the answer over `x` (zero on the rows left out);
    // `None` when it is not finite.
    let solve_into = |chol: &mut Cholesky, x: &mut nalgebra::DVector<f64>| {
        let sol = chol.solve(b);
        if !sol.iter().all(|v| v.is_finite()) {
            return None;
        }
        x.fill(0.0);
        for (&i, v) in chol.kept.iter().zip(&sol) {
            x[i] = *v;
        }
        Some(sol)
    };
    for _ in 0..4 * m + 8 {
        let sol = solve_into(chol, &mut x)?;
        let floor = -1e-9 * x.amax();
        let pulling: Vec<usize> = chol
            .kept
            .iter()
            .copied()
            .filter(|&i| push_only(i) && x[i] < floor)
            .collect();
        // (A x)ᵢ over the rows kept (x is zero elsewhere), down column i (A is symmetric:
        // contiguous in nalgebra's column-major storage, where row i is strided).
        let violated: Vec<usize> = (0..m)
            .filter(|&i| {
                if active[i] || redundant[i] {
                    return false;
                }
                let column = a.column(i);
                let ax: f64 = chol
                    .kept
                    .iter()
                    .zip(&sol)
                    .map(|(&c, v)| column[c] * v)
                    .sum();
                b[i] - ax > tol
            })
            .collect();
        let wrong = pulling.len() + violated.len();
        if wrong == 0 {
            settled = true;
            break;
        }
        let (pulling, violated) = if wrong < best {
            (best, backup) = (wrong, BACKUP);
            (pulling, violated)
        } else if backup > 0 {
            backup -= 1;
            (pulling, violated)
        } else {
            let last = pulling.iter().chain(&violated).copied().max();
            (
                pulling.into_iter().filter(|&i| Some(i) == last).collect(),
                violated.into_iter().filter(|&i| Some(i) == last).collect(),
            )
        };
        // By updating the factor: a row out is a downdate, a row back is appended (a full
        // factorization per pass cost 1.5 ms a step for six cubes).
        for &i in &pulling {
            active[i] = false;
        }
        for i in chol.remove_all(a, &pulling) {
            redundant[i] = true;
            active[i] = false;
        }
        for i in violated {
            if chol.push(a, i) {
                active[i] = true;
            } else {
                redundant[i] = true;
            }
        }
    }
    if !settled {
        // What the last pass changed is solved for.
        solve_into(chol, &mut x)?;
    }
    if relax {
        relax_repeats(a, b, &push_only, &redundant, tol, &mut x, &mut active);
    }
    Some((x, active))
}

/// Most projected Gauss-Seidel sweeps [`relax_repeats`] makes.
const RELAX_SWEEPS: usize = 50;

/// Rows whose coupling with a violated repeated row (`A_ij² / (A_ii A_jj)`) reaches this
/// are relaxed with it ([`relax_repeats`]): a cosine of 0.1 in `A`'s metric.
const COUPLED: f64 = 1e-2;

/// A row left out as a near repeat of the rows kept is still a contact. Where the rows kept
/// leave it violated (its target differs from what their combination gives it: a flat face
/// on a few triangles, pressed at more points than the triangles have vertices, with normals
/// a little apart), the factor's answer lets it through. A jaw resting flat on a coarse plate
/// (`tests/it/tool_shapes/tilted.rs`) had a corner row left out that way at a substep, its point
/// rising 0.12 mm into the jaw; pressed back at the next, it pushed the triangle down under
/// the other corners, which lost their rows: the face see-sawed at rest, its force swinging
/// 9.7-11.0 N about the pins' 10.4 N. Such rows, with the rows coupled to them
/// ([`COUPLED`]), are relaxed by projected Gauss-Seidel from the factor's answer until none
/// of them is wrong by more than `tol` or [`RELAX_SWEEPS`] sweeps are done. That converges on
/// the near-singular system without the opposite impulses an exact solve of it gives (a
/// sweep only moves one row at a time to its own target). Relaxing every row instead cost
/// the six cubes of `coupled_step` (whose faces leave repeated rows violated at most
/// solves) 1.7× their step. An answer that is not finite is not taken: the factor's stands.
fn relax_repeats(
    a: &nalgebra::DMatrix<f64>,
    b: &nalgebra::DVector<f64>,
    push_only: &impl Fn(usize) -> bool,
    redundant: &[bool],
    tol: f64,
    x: &mut nalgebra::DVector<f64>,
    active: &mut [bool],
) {
    let m = b.len();
    let violated: Vec<usize> = (0..m)
        .filter(|&i| redundant[i] && b[i] - a.column(i).dot(x) > tol)
        .collect();
    if violated.is_empty() {
        return;
    }
    let set: Vec<usize> = (0..m)
        .filter(|&j| {
            violated.iter().any(|&i| {
                let aij = a[(i, j)];
                i == j || aij * aij >= COUPLED * a[(i, i)] * a[(j, j)]
            })
        })
        .collect();
    // Each row's residual, kept as its rows move (the rows outside stay where they are).
    let mut r: Vec<f64> = set.iter().map(|&j| b[j] - a.column(j).dot(x)).collect();
    let mut relaxed: Vec<f64> = set.iter().map(|&j| x[j]).collect();
    for _ in 0..RELAX_SWEEPS {
        let mut worst: f64 = 0.0;
        for (p, &j) in set.iter().enumerate() {
            let d = a[(j, j)];
            if d.is_nan() || d <= 0.0 {
                continue;
            }
            let mut next = relaxed[p] + r[p] / d;
            if push_only(j) {
                next = next.max(0.0);
            }
            // How wrong the row was: violated, or (in) off its target.
            let wrong = if push_only(j) && relaxed[p] <= 0.0 {
                r[p]
            } else {
                r[p].abs()
            };
            worst = worst.max(wrong);
            let delta = next - relaxed[p];
            if delta != 0.0 {
                relaxed[p] = next;
                for (q, &k) in set.iter().enumerate() {
                    r[q] -= delta * a[(k, j)];
                }
            }
        }
        if worst <= tol {
            break;
        }
    }
    if relaxed.iter().all(|v| v.is_finite()) {
        for (p, &j) in set.iter().enumerate() {
            x[j] = relaxed[p];
            active[j] = !push_only(j) || x[j] > 0.0;
        }
    }
}

/// Storage the constraint solves reuse from one call to the next: their dense matrices (the
/// system, the filter's block, the factor) are 100-150 KB each for six cubes on a plate, which
/// the allocator would map and zero afresh at every substep.
#[derive(Clone, Debug, Default)]
pub(super) struct Scratch {
    /// The Cholesky factor's storage.
    pub(super) factor: Vec<f64>,
    /// A system matrix's.
    pub(super) system: Vec<f64>,
    /// The filter block's.
    pub(super) block: Vec<f64>,
}

/// A zeroed `rows × cols` matrix on `storage` (taken; give it back with [`give_back`]).
pub(super) fn zeroed(storage: &mut Vec<f64>, rows: usize, cols: usize) -> nalgebra::DMatrix<f64> {
    let mut v = std::mem::take(storage);
    v.clear();
    v.resize(rows * cols, 0.0);
    nalgebra::DMatrix::from_vec(rows, cols, v)
}

/// Returns a matrix's storage to `storage`.
pub(super) fn give_back(storage: &mut Vec<f64>, m: nalgebra::DMatrix<f64>) {
    *storage = m.data.into();
}

/// How many passes of block principal pivoting may fail to lower the number of rows on the
/// wrong side before rows change side one at a time ([`solve_pushing`]).
const BACKUP: usize = 3;

/// A row whose part independent of the rows factorized before it is below this fraction of
/// its diagonal (its independent part under a tenth of its length in `A`'s metric, an angle of
/// about 6°) repeats them. At 1e-4 (0.6°) a point press's normal row next to a stuck point's
/// three rows on nearly the same weights was kept, and the two targets' small difference came
/// back as opposite impulses hundreds of times the contact's: the six cubes with friction
/// (`coupled_step`) had tool forces of 0.6-1.9 N in a 0.25 N press, and up to 10⁸ N once the
/// friction passes were warm-started. Now their largest force is 0.47 N.
const REDUNDANT: f64 = 1e-2;

/// Fewest rows [`Cholesky::factorize`] hands to faer's blocked factorization. Measured on
/// this machine, a system gathered and factorized by faer against appended row by row: 8 rows
/// 0.25 µs against 0.15, 12 rows 0.38 against 0.41, 16 rows 0.49 against 0.79, 30 rows 1.9
/// against 5.3.
const BLOCKED_FROM: usize = 16;

/// The Cholesky factor `L` of `A` on the rows kept, in their order (the workspace is reused).
///
/// Kept by hand around faer's factorization: it leaves out, in priority order, the rows that
/// nearly repeat those kept before them, which a plain factorization cannot (the first
/// factorization is faer's, cut at such a row: [`Cholesky::factorize`]), and
/// `solve_pushing` changes its active set by updating the factor (a row appended, a row
/// removed by Givens rotations) rather than refactorizing each pass. With that and four-way
/// dot products, six cubes pressing a 784-node plate (`cargo bench --bench coupled_step`:
/// about 109 rows and 5-10 passes per solve) went from 1.5 ms per step to the figure in the
/// README.
struct Cholesky {
    kept: Vec<usize>,
    /// `L`, row-major with rows of `stride` (the system's size).
    l: Vec<f64>,
    stride: usize,
    y: Vec<f64>,
    /// Each row's length for the repeat test (empty: `A`'s diagonal; see [`solve_pushing`]).
    reference: Vec<f64>,
}

/// `Σ a_j b_j` in four independent sums (a single running sum waits on each addition).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

impl Cholesky {
    /// A workspace for systems of `m` rows, in `storage` (reused: a fresh 130 × 130 factor is
    /// 135 KB that the allocator maps and zeroes anew each time).
    fn new(m: usize, mut storage: Vec<f64>) -> Self {
        storage.clear();
        storage.resize(m * m, 0.0);
        Cholesky {
            kept: Vec::with_capacity(m),
            l: storage,
            stride: m,
            y: Vec::with_capacity(m),
            reference: Vec::new(),
        }
    }

    /// Row `i`'s length for the repeat test ([`REDUNDANT`]).
    fn length(&self, a: &nalgebra::DMatrix<f64>, i: usize) -> f64 {
        self.reference.get(i).copied().unwrap_or(a[(i, i)])
    }

    /// Factorizes `A` on `rows`, in order, leaving out the rows that nearly repeat those kept
    /// before them (returned): with faer's dense factorization up to the first such row
    /// ([`Cholesky::factorize_blocked`]), the rows after it appended one by one
    /// ([`Cholesky::push`]). Factorizing the rest with faer again after each repeated row (up
    /// to three times, as before) cost more than it saved where rows repeat (the six cubes
    /// with friction in a 60 Hz step, about 1.6 of 46 rows: 30 µs a factorization).
    fn factorize(&mut self, a: &nalgebra::DMatrix<f64>, rows: &[usize]) -> Vec<usize> {
        self.kept.clear();
        let mut left_out = Vec::new();
        let start = match self.factorize_blocked(a, rows) {
            Some(taken) if taken == rows.len() => return left_out,
            Some(taken) => {
                left_out.push(rows[taken]);
                taken + 1
            }
            None => {
                self.kept.clear();
                0
            }
        };
        left_out.extend(rows[start..].iter().copied().filter(|&i| !self.push(a, i)));
        left_out
    }

    /// Factorizes `A` on `rows` with faer's dense Cholesky (blocked and vectorised) and keeps
    /// its leading rows up to the first that nearly repeats those before it (the rows a
    /// factorization in order would keep, in the same order: a Cholesky factor's leading rows
    /// depend only on the leading rows of `A`); returns how many it kept, or `None` (nothing
    /// kept) for a system too small to gain or one faer could not factorize (a pivot at or
    /// below zero: the rows are then appended one by one, which leaves such a row out).
    /// Measured on this machine: 70 rows in 10 µs against [`Cholesky::push`]'s 39 µs, 120
    /// rows in 20 µs against 153 µs.
    fn factorize_blocked(&mut self, a: &nalgebra::DMatrix<f64>, rows: &[usize]) -> Option<usize> {
        let (k, n) = (rows.len(), self.stride);
        if k < BLOCKED_FROM || k > n {
            return None;
        }
        // Its lower triangle (all faer reads), down A's columns (contiguous in nalgebra's
        // column-major storage), factorized in place.
        let mut l = faer::Mat::<f64>::zeros(k, k);
        for (c, &j) in rows.iter().enumerate() {
            let column = a.column(j);
            for (r, &i) in rows.iter().enumerate().skip(c) {
                l[(r, c)] = column[i];
            }
        }
        use faer::linalg::cholesky::llt::factor;
        let mut mem = faer::dyn_stack::MemBuffer::new(factor::cholesky_in_place_scratch::<f64>(
            k,
            faer::Par::Seq,
            Default::default(),
        ));
        factor::cholesky_in_place(
            l.as_mut(),
            Default::default(),
            faer::Par::Seq,
            faer::dyn_stack::MemStack::new(&mut mem),
            Default::default(),
        )
        .ok()?;
        for (r, &i) in rows.iter().enumerate() {
            let pivot = l[(r, r)];
            // As in `push`: a pivot (squared) at or below `REDUNDANT` of its diagonal, or not
            // a number, ends what is taken.
            let squared = pivot * pivot;
            if squared.is_nan() || squared <= REDUNDANT * self.length(a, i) || !pivot.is_finite() {
                return Some(r);
            }
            for c in 0..=r {
                self.l[r * n + c] = l[(r, c)];
            }
            self.kept.push(i);
        }
        Some(k)
    }

    /// Appends row `i` of `A` to the factor; `false` (and nothing appended) when it nearly
    /// repeats the rows kept.
    fn push(&mut self, a: &nalgebra::DMatrix<f64>, i: usize) -> bool {
        let (n, k) = (self.stride, self.kept.len());
        if k >= n {
            return false;
        }
        // Row k of L: L[k, c] = (a[kept c, i] - Σ L[k, <c] L[c, <c]) / L[c, c].
        for c in 0..k {
            let d = dot(&self.l[k * n..k * n + c], &self.l[c * n..c * n + c]);
            self.l[k * n + c] = (a[(self.kept[c], i)] - d) / self.l[c * n + c];
        }
        let row = &self.l[k * n..k * n + k];
        let pivot = a[(i, i)] - dot(row, row);
        // Also a NaN pivot: such a row is left out.
        if pivot.is_nan() || pivot <= REDUNDANT * self.length(a, i) {
            return false;
        }
        self.l[k * n + k] = pivot.sqrt();
        self.kept.push(i);
        true
    }

    /// Takes `rows` out of the factor, by downdates or by refactorizing the kept rows from
    /// the first one that goes, whichever costs less; returns the rows a refactorization
    /// found redundant (left out).
    fn remove_all(&mut self, a: &nalgebra::DMatrix<f64>, rows: &[usize]) -> Vec<usize> {
        let k = self.kept.len();
        let positions: Vec<usize> = rows
            .iter()
            .filter_map(|i| self.kept.iter().position(|r| r == i))
            .collect();
        let Some(&first) = positions.iter().min() else {
            return Vec::new();
        };
        // Downdates cost (k - p)² rotations per row, a refactorization (k - first)³ / 6
        // multiply-adds; measured on the six cubes' solve (`coupled_step`), downdating up to
        // (k - first)³ was the faster side of the line (47 µs per constraint solve against
        // 49 µs with a third of it, 62 µs with a thirty-sixth).
        let downdates: usize = positions.iter().map(|&p| (k - p) * (k - p)).sum();
        if downdates <= (k - first).pow(3) {
            rows.iter().for_each(|&i| self.remove(i));
            return Vec::new();
        }
        let rest: Vec<usize> = self.kept[first..]
            .iter()
            .copied()
            .filter(|i| !rows.contains(i))
            .collect();
        self.kept.truncate(first);
        rest.into_iter().filter(|&i| !self.push(a, i)).collect()
    }

    /// Takes row `i` out of the factor: its row of `L` is deleted and the rows below it are
    /// brought back to lower-triangular form by Givens rotations of neighbouring columns
    /// (`O(k²)` against a refactorization's `O(k³)`).
    fn remove(&mut self, i: usize) {
        let Some(p) = self.kept.iter().position(|&r| r == i) else {
            return;
        };
        let (n, k) = (self.stride, self.kept.len());
        // Shift the rows below p up by one: row r (new) has entries up to column r + 1.
        for r in p..k - 1 {
            let (src, dst) = ((r + 1) * n, r * n);
            self.l.copy_within(src..src + r + 2, dst);
        }
        for j in p..k - 1 {
            let (x, y) = (self.l[j * n + j], self.l[j * n + j + 1]);
            let h = (x * x + y * y).sqrt();
            if h == 0.0 {
                continue;
            }
            let (c, s) = (x / h, y / h);
            for r in j..k - 1 {
                let (u, v) = (self.l[r * n + j], self.l[r * n + j + 1]);
                self.l[r * n + j] = c * u + s * v;
                self.l[r * n + j + 1] = -s * u + c * v;
            }
            self.l[j * n + j + 1] = 0.0;
        }
        self.kept.remove(p);
    }

    /// Solves `A x = b` on the kept rows (in `kept`'s order).
    fn solve(&mut self, b: &nalgebra::DVector<f64>) -> Vec<f64> {
        let (k, n) = (self.kept.len(), self.stride);
        self.y.clear();
        for r in 0..k {
            let s = b[self.kept[r]] - dot(&self.l[r * n..r * n + r], &self.y);
            self.y.push(s / self.l[r * n + r]);
        }
        // Back substitution by rows of L (Lᵀ's columns): each x[r] found is taken out of the
        // entries above it along L's row r, contiguous in the row-major storage.
        let mut x = std::mem::take(&mut self.y);
        for r in (0..k).rev() {
            let xr = x[r] / self.l[r * n + r];
            x[r] = xr;
            for (xc, l) in x[..r].iter_mut().zip(&self.l[r * n..r * n + r]) {
                *xc -= l * xr;
            }
        }
        x
    }
}

#[cfg(test)]
mod tests;
