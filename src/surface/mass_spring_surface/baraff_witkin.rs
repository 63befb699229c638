//! The Baraff-Witkin integrator: implicit Euler with the exact spring Jacobian, solved by
//! conjugate gradients with the held directions filtered out (Baraff and Witkin 1998, §5.3).

use super::{motion_watch, MassSpringSurface, SpringModel, NOT_FREE};
use glamx::{DMat3, DVec3};

/// The CG's work arrays, kept between steps.
///
/// The CG is hand-written: faer's matrix-free `conjugate_gradient` on the same operator (`P A P`
/// through a `LinOp`, the same warm start and tolerance) was slower in one `soft_step` run
/// (`cargo bench --bench soft_step -- baraff_witkin`, two interleaved rounds, hand / faer):
/// 100 nodes 12.0 / 15.9 µs, 784 128 / 150 µs, 3025 390-494 / 596-612 µs, 10k 1.82-2.02 /
/// 2.44-2.71 ms, 19881 4.06-4.40 / 5.74-6.27 ms. It is a block CG (a k × k Cholesky per
/// iteration for k right-hand sides) working on faer matrices, where this one works on
/// `DVec3`s in place.
#[derive(Clone, Debug, Default)]
pub(super) struct CgScratch {
    r: Vec<DVec3>,
    p: Vec<DVec3>,
    ap: Vec<DVec3>,
    blocks: Vec<DMat3>,
}

impl MassSpringSurface {
    /// Baraff-Witkin: `(M - dt² J - dt C) Δv = dt (Fⁿ + dt J vⁿ)` with the exact spring
    /// Jacobian `J` at `xⁿ`, by conjugate gradients.
    #[allow(clippy::needless_range_loop)] // CG updates several arrays by the same index
    pub(super) fn baraff_witkin_step(&mut self, max_iterations: u32, tolerance: f64) {
        let dt = self.dt;
        let nf = self.free.len();
        // Per-edge Jacobian blocks (PSD part kept for a definite system).
        let mut blocks = std::mem::take(&mut self.cg.blocks);
        blocks.clear();
        for (e, &[a, b]) in self.edges.iter().enumerate() {
            let jb = match self.model {
                SpringModel::Linear => DMat3::IDENTITY * self.k[e],
                SpringModel::Length => {
                    let d = self.pos[b as usize] - self.pos[a as usize];
                    let l = d.length();
                    if l > 0.0 {
                        let n = d / l;
                        let nn = DMat3::from_cols(n * n.x, n * n.y, n * n.z);
                        let t = (1.0 - self.rest[e] / l).max(0.0);
                        (nn + (DMat3::IDENTITY - nn) * t) * self.k[e]
                    } else {
                        DMat3::IDENTITY * self.k[e]
                    }
                }
            };
            blocks.push(jb);
        }
        // Right-hand side.
        let mut rhs = std::mem::take(&mut self.rhs);
        for (fi, &v) in self.free.iter().enumerate() {
            rhs[fi] = self.force[v as usize];
        }
        for (e, &[a, b]) in self.edges.iter().enumerate() {
            let jv = blocks[e] * (self.vel[b as usize] - self.vel[a as usize]) * dt;
            let (fa, fb) = (self.free_index[a as usize], self.free_index[b as usize]);
            if fa != NOT_FREE {
                rhs[fa as usize] += jv;
            }
            if fb != NOT_FREE {
                rhs[fb as usize] -= jv;
            }
        }
        for r in &mut rhs {
            *r *= dt;
        }
        let mut x = std::mem::take(&mut self.dv);
        let mut cg = std::mem::take(&mut self.cg);
        cg.r.resize(nf, DVec3::ZERO);
        cg.p.resize(nf, DVec3::ZERO);
        cg.ap.resize(nf, DVec3::ZERO);
        // Held vertices: Baraff and Witkin's filtered CG. The held directions are projected
        // out of the iterate, the residual and the search direction, so the solution has the
        // holder's velocity there and the rest responds to it as to a pin.
        self.project_held(&mut x);
        self.bw_apply(&blocks, &x, &mut cg.ap);
        for i in 0..nf {
            cg.r[i] = rhs[i] - cg.ap[i];
        }
        self.project_held(&mut cg.r);
        cg.p.copy_from_slice(&cg.r);
        let dot = |a: &[DVec3], b: &[DVec3]| a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum::<f64>();
        let bnorm = dot(&rhs, &rhs).sqrt().max(1e-300);
        let mut rr = dot(&cg.r, &cg.r);
        let mut it = 0;
        while it < max_iterations && rr.sqrt() > tolerance * bnorm {
            self.bw_apply(&blocks, &cg.p, &mut cg.ap);
            self.project_held(&mut cg.ap);
            let pap = dot(&cg.p, &cg.ap);
            if pap <= 0.0 || !pap.is_finite() {
                break;
            }
            let alpha = rr / pap;
            for i in 0..nf {
                x[i] += cg.p[i] * alpha;
                cg.r[i] -= cg.ap[i] * alpha;
            }
            let rr_new = dot(&cg.r, &cg.r);
            let beta = rr_new / rr;
            for i in 0..nf {
                cg.p[i] = cg.r[i] + cg.p[i] * beta;
            }
            rr = rr_new;
            it += 1;
        }
        self.last_cg_iterations = it;
        let mut probe = 0.0;
        for (fi, &v) in self.free.iter().enumerate() {
            let i = v as usize;
            let dv = self.unheld_part(i, x[fi]);
            self.vel[i] += dv;
            self.pos[i] += self.vel[i] * dt;
            probe += self.pos[i].element_sum();
            motion_watch::note(&mut self.watch, i, self.pos[i]);
        }
        self.check_probe(probe);
        // x stays as the next warm start.
        self.dv = x;
        self.rhs = rhs;
        cg.blocks = blocks;
        self.cg = cg;
    }

    /// `A x = M x + Σ_e (dt² J_e + dt c_e I)(x_a - x_b)` on a, opposite on b (free vertices).
    fn bw_apply(&self, blocks: &[DMat3], x: &[DVec3], out: &mut [DVec3]) {
        let dt = self.dt;
        for (fi, &v) in self.free.iter().enumerate() {
            out[fi] = x[fi] * self.mass[v as usize];
        }
        for (e, &[a, b]) in self.edges.iter().enumerate() {
            let (fa, fb) = (self.free_index[a as usize], self.free_index[b as usize]);
            let xa = if fa != NOT_FREE {
                x[fa as usize]
            } else {
                DVec3::ZERO
            };
            let xb = if fb != NOT_FREE {
                x[fb as usize]
            } else {
                DVec3::ZERO
            };
            let y = (blocks[e] * (dt * dt) + DMat3::IDENTITY * (dt * self.c[e])) * (xa - xb);
            if fa != NOT_FREE {
                out[fa as usize] += y;
            }
            if fb != NOT_FREE {
                out[fb as usize] -= y;
            }
        }
    }

    /// Removes the held directions of every free vertex's entry of `v`.
    fn project_held(&self, v: &mut [DVec3]) {
        if !self.held_list.is_empty() {
            for (fi, &i) in self.free.iter().enumerate() {
                v[fi] = self.unheld_part(i as usize, v[fi]);
            }
        }
    }
}
