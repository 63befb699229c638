//! Tests of the active-set solve and its factor.

use super::*;

/// `(row, of, scale, nudge)`: row `row` of `B` set to `scale ×` row `of` plus `nudge` in
/// one entry.
type Repeat = (usize, usize, f64, f64);

/// A symmetric positive semi-definite `m × m` matrix `B Bᵀ` (plus a small diagonal), with
/// rows `copies` made (near) repeats of earlier rows.
fn system(m: usize, seed: u64, copies: &[Repeat]) -> nalgebra::DMatrix<f64> {
    let mut r = seed;
    let mut rnd = move || {
        r = r
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (r >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut b = nalgebra::DMatrix::<f64>::from_fn(m, m + 3, |_, _| rnd());
    for &(row, of, scale, nudge) in copies {
        let copy = b.row(of) * scale;
        b.set_row(row, &copy);
        b[(row, row % (m + 3))] += nudge;
    }
    let mut a = &b * b.transpose();
    let diag = (0..m).map(|i| a[(i, i)]).fold(0.0, f64::max);
    for i in 0..m {
        a[(i, i)] += 1e-12 * diag;
    }
    a
}

#[test]
fn the_factor_reproduces_the_rows_kept_and_leaves_out_the_repeated_ones() {
    let cases: [(usize, &[Repeat], &[usize]); 5] = [
        (10, &[], &[]),
        (40, &[(17, 3, 1.0, 0.0)], &[3]),
        (
            75,
            &[(5, 2, -2.0, 0.0), (30, 29, 1.0, 1e-9), (60, 5, 0.5, 0.0)],
            &[2, 5, 29],
        ),
        (
            60,
            &[
                (20, 1, 1.0, 0.0),
                (21, 2, 1.0, 0.0),
                (22, 3, 1.0, 0.0),
                (23, 4, 1.0, 0.0),
                (24, 5, 1.0, 0.0),
            ],
            &[1, 2, 3, 4, 5],
        ),
        // A row that is not a repeat (nudged by 0.5): kept.
        (50, &[(40, 10, 1.0, 0.5)], &[]),
    ];
    for (seed, (m, copies, repeats)) in cases.into_iter().enumerate() {
        let a = system(m, seed as u64 + 1, copies);
        // A priority order that is not the index order: the later rows of each repeated
        // pair come first, so the earlier ones (`repeats`) are the rows left out.
        let rows: Vec<usize> = (0..m).rev().collect();
        let mut chol = Cholesky::new(m, Vec::new());
        let mut left = chol.factorize(&a, &rows);
        left.sort_unstable();
        assert_eq!(left, repeats, "m {m}: rows left out");
        let kept: Vec<usize> = rows.iter().copied().filter(|i| !left.contains(i)).collect();
        assert_eq!(chol.kept, kept, "m {m}: rows kept, in order");
        // L Lᵀ is A on the rows kept.
        let k = kept.len();
        for r in 0..k {
            for c in 0..=r {
                let llt: f64 = (0..=c).map(|j| chol.l[r * m + j] * chol.l[c * m + j]).sum();
                let want = a[(kept[r], kept[c])];
                assert!(
                    (llt - want).abs() <= 1e-9 * (1.0 + want.abs()),
                    "m {m}: (L Lᵀ)[{r}, {c}] {llt} against {want}"
                );
            }
        }
        // The factor solves the kept system.
        let b = nalgebra::DVector::from_fn(m, |i, _| (i as f64).sin());
        let x = chol.solve(&b);
        for (r, &i) in chol.kept.iter().enumerate() {
            let ax: f64 = chol.kept.iter().zip(&x).map(|(&j, v)| a[(i, j)] * v).sum();
            assert!(
                (ax - b[i]).abs() <= 1e-6 * (1.0 + b[i].abs()),
                "m {m}: row {r}"
            );
        }
    }
}

/// The push-only solve against every active set tried in turn (a linear complementarity
/// problem with a positive definite `A` has one solution): small random systems, some rows
/// bilateral, from every kind of starting guess.
#[test]
fn the_pushing_solve_finds_the_one_complementary_solution_from_any_start() {
    let m = 9;
    for seed in 0..40u64 {
        let mut a = system(m, 100 + seed, &[]);
        for i in 0..m {
            a[(i, i)] += 0.05;
        }
        let b =
            nalgebra::DVector::from_fn(m, |i, _| ((i as f64 + 1.3) * (seed as f64 + 0.7)).sin());
        let bilateral = |i: usize| (i + seed as usize).is_multiple_of(4);
        // Brute force: the set whose solution pushes on its push-only rows and leaves the
        // others satisfied.
        let mut want = None;
        for set in 0u32..1 << m {
            if (0..m).any(|i| bilateral(i) && set & (1 << i) == 0) {
                continue;
            }
            let rows: Vec<usize> = (0..m).filter(|&i| set & (1 << i) != 0).collect();
            let sub =
                nalgebra::DMatrix::from_fn(rows.len(), rows.len(), |r, c| a[(rows[r], rows[c])]);
            let rhs = nalgebra::DVector::from_fn(rows.len(), |r, _| b[rows[r]]);
            let Some(sol) = sub.cholesky().map(|c| c.solve(&rhs)) else {
                continue;
            };
            let mut x = nalgebra::DVector::zeros(m);
            for (r, &i) in rows.iter().enumerate() {
                x[i] = sol[r];
            }
            let ax = &a * &x;
            let ok = (0..m).all(|i| {
                if set & (1 << i) != 0 {
                    bilateral(i) || x[i] >= -1e-12
                } else {
                    b[i] - ax[i] <= 1e-12
                }
            });
            if ok {
                want = Some(x);
                break;
            }
        }
        let want = want.expect("a complementary solution");
        for start in 0..4u64 {
            let guess = |i: usize| match start {
                0 => false,
                1 => true,
                2 => b[i] > 0.0,
                _ => (i as u64 * 7 + seed).is_multiple_of(3),
            };
            let mut factor = Vec::new();
            let (x, active) = solve_pushing(
                &a,
                &b,
                (|i| !bilateral(i), guess),
                &[],
                1e-12,
                &mut factor,
                true,
            )
            .expect("a finite solution");
            for i in 0..m {
                assert!(
                    (x[i] - want[i]).abs() <= 1e-8 * (1.0 + want[i].abs()),
                    "seed {seed}, start {start}: x[{i}] {} against {}",
                    x[i],
                    want[i]
                );
                assert!(active[i] || x[i] == 0.0);
            }
        }
    }
}

#[test]
fn a_row_of_nan_is_left_out_and_the_rest_kept() {
    let m = 40;
    let mut a = system(m, 7, &[]);
    for j in 0..m {
        a[(12, j)] = f64::NAN;
        a[(j, 12)] = f64::NAN;
    }
    let rows: Vec<usize> = (0..m).collect();
    let mut chol = Cholesky::new(m, Vec::new());
    let left = chol.factorize(&a, &rows);
    assert_eq!(left, vec![12]);
    let rest: Vec<usize> = rows.iter().copied().filter(|&i| i != 12).collect();
    assert_eq!(chol.kept, rest);
    // The factor's rows (by position) are finite.
    for k in 0..chol.kept.len() {
        assert!(chol.l[k * m..k * m + k + 1].iter().all(|v| v.is_finite()));
    }
}

/// The weights of five points of one triangle on its three vertices (rank three).
const FIVE_POINTS: [[f64; 3]; 5] = [
    [0.6, 0.2, 0.2],
    [0.2, 0.6, 0.2],
    [0.2, 0.2, 0.6],
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
    [0.05, 0.05, 0.9],
];

/// Five points of one triangle (three unit masses, one normal) pressed at once, as a flat
/// face on a coarse surface presses it: their rows have rank three, so two repeat the rows
/// taken first. One of them wants more than the plane the first three give it (0.65 against
/// 0.55): the factor alone leaves it 0.1 short, and the relaxation meets every row, pushing
/// only, each push on a row that is met (within 1e-6).
#[test]
fn a_repeated_row_the_rows_kept_leave_violated_is_still_met() {
    let w = FIVE_POINTS;
    let plane = [1.0, 1.0, 0.5];
    let m = w.len();
    let a = nalgebra::DMatrix::from_fn(m, m, |i, j| (0..3).map(|k| w[i][k] * w[j][k]).sum());
    let b = nalgebra::DVector::from_fn(m, |i, _| {
        (0..3).map(|k| w[i][k] * plane[k]).sum::<f64>() + if i == 4 { 0.1 } else { 0.0 }
    });
    let worst = |x: &nalgebra::DVector<f64>| {
        let ax = &a * x;
        (0..m).map(|i| b[i] - ax[i]).fold(f64::MIN, f64::max)
    };
    let solve = |relax: bool| {
        let mut factor = Vec::new();
        solve_pushing(&a, &b, (|_| true, |_| true), &[], 1e-12, &mut factor, relax)
            .expect("a finite solution")
            .0
    };
    assert!(worst(&solve(false)) > 0.09);
    let x = solve(true);
    let ax = &a * &x;
    assert!(worst(&x) <= 1e-6, "violated by {}", worst(&x));
    for i in 0..m {
        assert!(x[i] >= 0.0);
        assert!(
            x[i] * (ax[i] - b[i]) <= 1e-6,
            "row {i}: {} pushing, {} past",
            x[i],
            ax[i] - b[i]
        );
    }
}

/// The relaxation beside bad input: the five rows of the triangle above (one repeated row
/// violated, so it runs) plus a row whose diagonal is NaN, which the factor leaves out. The
/// answer stays finite, the NaN row pushes nothing, and the five rows are met.
#[test]
fn the_relaxation_beside_a_nan_row_hands_back_no_nan() {
    let w = FIVE_POINTS;
    let m = w.len() + 1;
    let a = nalgebra::DMatrix::from_fn(m, m, |i, j| match (i, j) {
        (5, 5) => f64::NAN,
        (5, _) | (_, 5) => 0.0,
        _ => (0..3).map(|k| w[i][k] * w[j][k]).sum(),
    });
    let b = nalgebra::DVector::from_fn(m, |i, _| [0.9, 0.9, 0.7, 2.5 / 3.0, 0.65, 1.0][i]);
    let mut factor = Vec::new();
    let (x, active) = solve_pushing(&a, &b, (|_| true, |_| true), &[], 1e-12, &mut factor, true)
        .expect("a finite solution");
    assert!(x.iter().all(|v| v.is_finite()), "{x}");
    assert_eq!(x[5], 0.0);
    assert!(!active[5]);
    for i in 0..5 {
        let ax: f64 = (0..5).map(|j| a[(i, j)] * x[j]).sum();
        assert!(b[i] - ax <= 1e-6, "row {i} short by {}", b[i] - ax);
    }
}
