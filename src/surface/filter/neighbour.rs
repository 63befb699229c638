//! The immediate-neighbour filter (eq. 10 restricted to rings of the mesh; the module docs of
//! [`super`] derive it): the truncated Neumann series of `S⁻¹` with the consistency correction,
//! and its truncation-error bound.

use super::{Csr, FilterError};
use faer::sparse::linalg::matmul::sparse_sparse_matmul;
use faer::Par;
use glamx::DVec3;

/// Largest `s` at which a row of the neighbour filter gets the consistency correction.
const CORRECTION_MAX_S: f64 = 1.0;

/// `D^{-1/2} (I + B + … + B^r) D^{-1/2}`, the truncated Neumann series, with the consistency
/// correction on the rows where it is stable (module docs).
pub(super) fn neumann(s: &Csr, mass: &[f64], rings: u32) -> Result<Csr, FilterError> {
    let n = s.n;
    let mut dinv_sqrt = vec![0.0; n];
    for (i, d) in dinv_sqrt.iter_mut().enumerate() {
        let diag = (s.ptr[i]..s.ptr[i + 1])
            .find(|&k| s.idx[k] as usize == i)
            .map(|k| s.val[k])
            .unwrap_or(0.0);
        if diag <= 0.0 || !diag.is_finite() {
            return Err(FilterError::NotPositiveDefinite);
        }
        *d = 1.0 / diag.sqrt();
    }
    // B = I - D^{-1/2} S D^{-1/2}: the off-diagonal part, negated and scaled.
    let mut b = Csr {
        n,
        ptr: vec![0],
        idx: Vec::new(),
        val: Vec::new(),
    };
    for i in 0..n {
        for k in s.ptr[i]..s.ptr[i + 1] {
            let j = s.idx[k] as usize;
            if j != i {
                b.idx.push(j as u32);
                b.val.push(-s.val[k] * dinv_sqrt[i] * dinv_sqrt[j]);
            }
        }
        b.ptr.push(b.idx.len());
    }
    let bf = b.to_faer()?;
    // Sum of powers by Horner: T = I + B (I + B (…)).
    let mut total = identity(n);
    let mut power = identity(n).to_faer()?;
    for _ in 0..rings {
        power = sparse_sparse_matmul(bf.as_ref(), power.as_ref(), 1.0, Par::Seq)
            .map_err(|e| FilterError::Faer(format!("{e:?}")))?;
        total = add(&total, &Csr::from_faer(&power));
    }
    // Scale by D^{-1/2} on both sides.
    for i in 0..n {
        for k in total.ptr[i]..total.ptr[i + 1] {
            let j = total.idx[k] as usize;
            total.val[k] *= dinv_sqrt[i] * dinv_sqrt[j];
        }
    }
    // Consistency correction where it is stable: make P (S 1) = 1 on the rows of vertices
    // with s <= 1 (module docs).
    let ones = vec![DVec3::ONE; n];
    let mut s1 = vec![DVec3::ZERO; n];
    s.mul_vec3(&ones, &mut s1);
    let mut ps1 = vec![DVec3::ZERO; n];
    total.mul_vec3(&s1, &mut ps1);
    for i in 0..n {
        let diag = 1.0 / (dinv_sqrt[i] * dinv_sqrt[i]);
        let s_i = (diag - mass[i]) / mass[i];
        if s_i > CORRECTION_MAX_S {
            continue;
        }
        let delta = (1.0 - ps1[i].x) / s1[i].x;
        if let Some(k) = (total.ptr[i]..total.ptr[i + 1]).find(|&k| total.idx[k] as usize == i) {
            total.val[k] += delta;
        }
    }
    Ok(total)
}

fn identity(n: usize) -> Csr {
    Csr {
        n,
        ptr: (0..=n).collect(),
        idx: (0..n as u32).collect(),
        val: vec![1.0; n],
    }
}

/// Sum of two CSR matrices of the same size (rows merged).
fn add(a: &Csr, b: &Csr) -> Csr {
    let mut out = Csr {
        n: a.n,
        ptr: vec![0],
        idx: Vec::with_capacity(a.idx.len() + b.idx.len()),
        val: Vec::with_capacity(a.idx.len() + b.idx.len()),
    };
    let mut row: Vec<(u32, f64)> = Vec::new();
    for i in 0..a.n {
        row.clear();
        row.extend((a.ptr[i]..a.ptr[i + 1]).map(|k| (a.idx[k], a.val[k])));
        row.extend((b.ptr[i]..b.ptr[i + 1]).map(|k| (b.idx[k], b.val[k])));
        row.sort_unstable_by_key(|e| e.0);
        let mut last = u32::MAX;
        for &(j, v) in &row {
            if j == last {
                *out.val.last_mut().expect("pushed") += v;
            } else {
                out.idx.push(j);
                out.val.push(v);
                last = j;
            }
        }
        out.ptr.push(out.idx.len());
    }
    out
}

/// Largest truncation-error bound `(s/(1+s))^(rings+1)` over the vertices.
pub(crate) fn neighbour_error_bound(s_values: &[f64], rings: u32) -> f64 {
    s_values
        .iter()
        .map(|s| (s / (1.0 + s)).powi(rings as i32 + 1))
        .fold(0.0, f64::max)
}
