//! The surface's dynamics: spring and damper forces (eq. 3-4), energies and momentum, and one
//! time step with each integrator.

use super::*;

impl MassSpringSurface {
    // ----- Forces and energies -----

    /// Spring and damper force of edge `e` on its first vertex (the second gets the opposite).
    #[inline]
    pub(super) fn edge_force(&self, e: usize) -> DVec3 {
        let [a, b] = self.edges[e];
        let (a, b) = (a as usize, b as usize);
        let spring = match self.model {
            SpringModel::Linear => {
                self.k[e] * ((self.pos[b] - self.home[b]) - (self.pos[a] - self.home[a]))
            }
            SpringModel::Length => {
                let d = self.pos[b] - self.pos[a];
                let l = d.length();
                if l > 0.0 {
                    d * (self.k[e] * (l - self.rest[e]) / l)
                } else {
                    DVec3::ZERO
                }
            }
        };
        spring + self.c[e] * (self.vel[b] - self.vel[a])
    }

    /// The spring and damper force on vertex `i` (what it pushes back with when held).
    /// `O(degree)`.
    pub fn internal_force(&self, i: u32) -> Vector {
        let mut f = DVec3::ZERO;
        let i = i as usize;
        if i + 1 >= self.vertex_edge_ptr.len() {
            return Vector::ZERO;
        }
        for &e in &self.vertex_edges[self.vertex_edge_ptr[i]..self.vertex_edge_ptr[i + 1]] {
            let e = e as usize;
            if self.edges[e][0] as usize == i {
                f += self.edge_force(e);
            } else {
                f -= self.edge_force(e);
            }
        }
        f.as_vec3()
    }

    pub(super) fn compute_forces(&mut self) {
        self.accumulate_forces(0.0);
    }

    /// `force = ext + m g + schedules + springs + dampers + kv_dt K v` in one pass over the
    /// edges (`kv_dt = dt` adds the filter's `dt K vⁿ` term, with the paper's constant `K`).
    pub(super) fn accumulate_forces(&mut self, kv_dt: f64) {
        let t = self.time;
        for ((f, e), m) in self.force.iter_mut().zip(&self.ext).zip(&self.mass) {
            *f = *e + self.gravity * *m;
        }
        for (verts, profile) in &self.schedules {
            let f = profile.at(t);
            for &v in verts {
                self.force[v as usize] += f;
            }
        }
        let edges = self.edges.iter().zip(self.k.iter().zip(&self.c));
        match self.model {
            SpringModel::Linear => {
                // Displacement and velocity side by side once per vertex, then one read per
                // edge end.
                self.disp.clear();
                self.disp.extend(
                    self.pos
                        .iter()
                        .zip(&self.home)
                        .zip(&self.vel)
                        .map(|((p, h), v)| [*p - *h, *v]),
                );
                let state = &self.disp;
                let force = &mut self.force;
                for (&[a, b], (&k, &c)) in edges {
                    let (a, b) = (a as usize, b as usize);
                    let [ua, va] = state[a];
                    let [ub, vb] = state[b];
                    let f = (ub - ua) * k + (vb - va) * (c + kv_dt * k);
                    force[a] += f;
                    force[b] -= f;
                }
            }
            SpringModel::Length => {
                for ((&[a, b], (&k, &c)), &rest) in edges.zip(&self.rest) {
                    let (a, b) = (a as usize, b as usize);
                    let d = self.pos[b] - self.pos[a];
                    let l = d.length();
                    let spring = if l > 0.0 {
                        d * (k * (l - rest) / l)
                    } else {
                        DVec3::ZERO
                    };
                    let f = spring + (self.vel[b] - self.vel[a]) * (c + kv_dt * k);
                    self.force[a] += f;
                    self.force[b] -= f;
                }
            }
        }
        for &(i, f) in &self.held_forces {
            self.force[i as usize] += f;
        }
        // A holder takes what it holds of a held vertex's force: that part, over the step, is
        // the first part of the hold's impulse on it (the constraint solve adds the rest).
        // (`held_forces` are in the force already, along the tangent plane only.) Only the
        // held vertices are visited.
        for &i in &self.hold_impulse_at {
            self.hold_impulse[i as usize] = DVec3::ZERO;
        }
        self.hold_impulse_at.clear();
        let dt = self.dt;
        for &v in &self.held_list {
            let i = v as usize;
            let kept = self.unheld_part(i, self.force[i]);
            self.hold_impulse[i] = (kept - self.force[i]) * dt;
            self.force[i] = kept;
            self.hold_impulse_at.push(v);
        }
        // A holder's own pull on a vertex (kinetic friction) is its impulse too.
        for &(i, f) in &self.held_forces {
            if self.held[i as usize] {
                self.hold_impulse[i as usize] += f * dt;
            }
        }
    }

    /// Kinetic energy (J).
    pub fn kinetic_energy(&self) -> f64 {
        self.vel
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| 0.5 * m * v.length_squared())
            .sum()
    }
    /// Elastic energy of the springs (J).
    pub fn elastic_energy(&self) -> f64 {
        self.edges
            .iter()
            .enumerate()
            .map(|(e, &[a, b])| {
                let (a, b) = (a as usize, b as usize);
                match self.model {
                    SpringModel::Linear => {
                        let d = (self.pos[b] - self.home[b]) - (self.pos[a] - self.home[a]);
                        0.5 * self.k[e] * d.length_squared()
                    }
                    SpringModel::Length => {
                        let l = (self.pos[b] - self.pos[a]).length();
                        0.5 * self.k[e] * (l - self.rest[e]).powi(2)
                    }
                }
            })
            .sum()
    }
    /// Kinetic + elastic + gravitational energy (relative to home) (J).
    pub fn total_energy(&self) -> f64 {
        let grav: f64 = (0..self.home.len())
            .map(|i| -self.mass[i] * self.gravity.dot(self.pos[i] - self.home[i]))
            .sum();
        self.kinetic_energy() + self.elastic_energy() + grav
    }
    /// Total momentum `Σ m v`.
    pub fn momentum(&self) -> Vector {
        self.vel
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| *v * *m)
            .sum::<DVec3>()
            .as_vec3()
    }
    /// Largest displacement from home over the vertices (m).
    pub fn max_displacement(&self) -> Real {
        self.pos
            .iter()
            .zip(&self.home)
            .map(|(p, h)| (*p - *h).length())
            .fold(0.0, f64::max) as Real
    }
    /// Root-mean-square distance between this surface's positions and `other`'s (m).
    pub fn rms_difference(&self, other: &MassSpringSurface) -> Real {
        let n = self.pos.len().min(other.pos.len()).max(1);
        (self
            .pos
            .iter()
            .zip(&other.pos)
            .map(|(a, b)| (*a - *b).length_squared())
            .sum::<f64>()
            / n as f64)
            .sqrt() as Real
    }
    /// `true` once a step produced a non-finite state (the surface then stops stepping).
    pub fn diverged(&self) -> bool {
        self.diverged
    }
    /// `true` if every position and velocity is finite.
    pub fn is_finite(&self) -> bool {
        self.pos.iter().all(|p| p.is_finite()) && self.vel.iter().all(|v| v.is_finite())
    }

    // ----- Stepping -----

    /// Advances the surface by one time step with its integrator.
    ///
    /// A state that stops being finite (explicit Euler beyond its stability limit) is not
    /// advanced further: check [`MassSpringSurface::is_finite`] or
    /// [`MassSpringSurface::diverged`].
    pub fn step(&mut self) {
        if self.diverged {
            return;
        }
        match self.integrator {
            Integrator::ExplicitEuler => {
                self.compute_forces();
                let dt = self.dt;
                let mut probe = 0.0;
                for &v in &self.free {
                    let i = v as usize;
                    self.vel[i] += self.force[i] * (dt / self.mass[i]);
                    self.pos[i] += self.vel[i] * dt;
                    probe += self.pos[i].element_sum();
                    motion_watch::note(&mut self.watch, i, self.pos[i]);
                }
                self.check_probe(probe);
            }
            Integrator::Filtered(_) => {
                if self.filter.is_none() && self.ensure_filter().is_err() {
                    return;
                }
                self.filtered_step();
            }
            Integrator::BaraffWitkin {
                max_iterations,
                tolerance,
            } => {
                self.compute_forces();
                self.baraff_witkin_step(max_iterations, tolerance as f64)
            }
        }
        self.time += self.dt;
    }

    /// NaN and infinity propagate into a sum of the new positions (every velocity went into
    /// them): one check per step instead of a scan.
    pub(super) fn check_probe(&mut self, probe: f64) {
        if !probe.is_finite() {
            self.diverged = true;
        }
    }

    /// Eq. (8): `Δv = W M⁻¹ dt (Fⁿ + dt K vⁿ)`, i.e. `S Δv = dt (Fⁿ + dt K vⁿ)`.
    pub(super) fn filtered_step(&mut self) {
        let dt = self.dt;
        self.accumulate_forces(dt);
        for (r, &v) in self.rhs.iter_mut().zip(&self.free) {
            *r = self.force[v as usize] * dt;
        }
        let Some(filter) = self.filter.as_mut() else {
            return;
        };
        filter.apply(&self.rhs, &mut self.dv);
        // The truncated filter drifts the rigid mode of a free surface: the mean velocity
        // change that makes the momentum change equal the applied impulse is added (module
        // docs of `filter`), for the step's forces and again for the constraint solve's
        // impulses, which reach the vertices through the same truncated columns.
        let rigid = self.free.len() == self.home.len()
            && matches!(filter.kind(), FilterKind::Neighbour { .. });
        if rigid {
            let impulse = self.rhs.iter().sum::<DVec3>();
            add_rigid_mode(&mut self.dv, &self.free, &self.mass, impulse, DVec3::ZERO);
        }
        for h in &mut self.holders {
            h.impulse = DVec3::ZERO;
            h.angular_impulse = DVec3::ZERO;
        }
        if !self.held_list.is_empty() || !self.point_holds.is_empty() {
            let before = if rigid {
                dv_momentum(&self.dv, &self.free, &self.mass)
            } else {
                DVec3::ZERO
            };
            let applied = constrain(
                filter,
                &mut self.holders,
                &self.free,
                &self.free_index,
                (&self.held, &self.held_normal, &mut self.hold_impulse),
                &mut self.point_holds,
                &self.vel,
                &mut self.dv,
                &mut self.pushing,
            );
            if rigid {
                add_rigid_mode(&mut self.dv, &self.free, &self.mass, applied, before);
            }
        }
        let mut probe = 0.0;
        for (fi, &v) in self.free.iter().enumerate() {
            let i = v as usize;
            // A held vertex keeps the holder's normal velocity (what the solve left of a
            // velocity change along it is the hold's too).
            let dv = self.unheld_part(i, self.dv[fi]);
            if self.held[i] {
                self.hold_impulse[i] -= (self.dv[fi] - dv) * self.mass[i];
            }
            self.vel[i] += dv;
            self.pos[i] += self.vel[i] * dt;
            probe += self.pos[i].element_sum();
            motion_watch::note(&mut self.watch, i, self.pos[i]);
        }
        self.check_probe(probe);
    }
}

/// `Σ m Δv` over the free vertices (`dv` by free slot).
fn dv_momentum(dv: &[DVec3], free: &[u32], mass: &[f64]) -> DVec3 {
    dv.iter()
        .zip(free)
        .map(|(dv, &v)| *dv * mass[v as usize])
        .sum()
}

/// Adds to every free vertex's `dv` the mean velocity change that makes the momentum `dv`
/// gained since it was `before` equal `impulse` (a rank-one correction of the rigid mode).
fn add_rigid_mode(dv: &mut [DVec3], free: &[u32], mass: &[f64], impulse: DVec3, before: DVec3) {
    let total: f64 = free.iter().map(|&v| mass[v as usize]).sum();
    if total > 0.0 {
        let gamma = (impulse - (dv_momentum(dv, free, mass) - before)) / total;
        dv.iter_mut().for_each(|dv| *dv += gamma);
    }
}
