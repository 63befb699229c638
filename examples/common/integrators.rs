//! The integrators run side by side by `plate_step_force` and `constrained_790`
//! (`scenes::COMPARED_INTEGRATORS`, in lockstep), what each one did and the table they print.
//! Included with `#[path = "common/integrators.rs"] mod integrators;`.
#![allow(dead_code)]

use rapier_touch::prelude::*;
use rapier_touch::scenes::{diverged, COMPARED_INTEGRATORS as INTEGRATORS};
use std::time::{Duration, Instant};

/// Index of explicit Euler in `COMPARED_INTEGRATORS`.
pub const EULER: usize = 0;
/// Index of the exact filter in `COMPARED_INTEGRATORS`: the reference of the RMS differences.
pub const EXACT: usize = 1;
/// Index of the paper's neighbour filter in `COMPARED_INTEGRATORS`.
pub const NEIGHBOUR: usize = 2;
/// Index of Baraff-Witkin in `COMPARED_INTEGRATORS`.
pub const BARAFF_WITKIN: usize = 3;

/// What one integrator did over the run.
pub struct Run {
    /// (max displacement, RMS difference from exact, energy) at each sample, `None` once
    /// diverged.
    pub samples: Vec<Option<(Real, Real, f64)>>,
    /// The largest RMS difference from the exact run (m).
    pub max_rms: Real,
    /// The largest displacement (m).
    pub max_displacement: Real,
    /// First time at which the state was no longer finite, if it diverged.
    pub diverged_at: Option<Real>,
    /// Wall-clock time of its steps.
    pub time: Duration,
}

/// Steps `surfaces` (one per integrator of `COMPARED_INTEGRATORS`) `steps` times in lockstep.
/// Before every step and after the last, `check(step, surfaces)` runs, then each surface is
/// measured against the exact filter's (at t = `step` × `dt`), with a sample kept every
/// `sample_every` steps. Returns what each did.
pub fn run_side_by_side(
    surfaces: &mut [MassSpringSurface],
    steps: usize,
    dt: Real,
    sample_every: usize,
    mut check: impl FnMut(usize, &[MassSpringSurface]),
) -> Vec<Run> {
    let mut runs: Vec<Run> = surfaces
        .iter()
        .map(|_| Run {
            samples: Vec::with_capacity(steps / sample_every + 1),
            max_rms: 0.0,
            max_displacement: 0.0,
            diverged_at: None,
            time: Duration::ZERO,
        })
        .collect();
    for step in 0..=steps {
        check(step, surfaces);
        for (s, run) in surfaces.iter().zip(runs.iter_mut()) {
            if run.diverged_at.is_none() && diverged(s) {
                run.diverged_at = Some(step as Real * dt);
            }
            let state = run.diverged_at.is_none().then(|| {
                (
                    s.max_displacement(),
                    s.rms_difference(&surfaces[EXACT]),
                    s.total_energy(),
                )
            });
            if let Some((d, rms, _)) = state {
                run.max_rms = run.max_rms.max(rms);
                run.max_displacement = run.max_displacement.max(d);
            }
            if step % sample_every == 0 {
                run.samples.push(state);
            }
        }
        if step < steps {
            for (s, run) in surfaces.iter_mut().zip(runs.iter_mut()) {
                let t0 = Instant::now();
                s.step();
                run.time += t0.elapsed();
            }
        }
    }
    runs
}

/// Prints the runs of [`run_side_by_side`] (`steps` steps of `dt`, a sample every
/// `sample_every`): per integrator and sample, the largest displacement, the RMS difference
/// from the exact run and the energy, or "diverged"; then per integrator when it diverged or
/// its largest RMS difference relative to the exact run's largest displacement, and its
/// wall-clock time per step.
pub fn print_runs(runs: &[Run], steps: usize, dt: Real, sample_every: usize) {
    println!(
        "{:<17} {:>5} {:>16} {:>18} {:>14}",
        "integrator", "t s", "max disp mm", "RMS vs exact mm", "energy J"
    );
    for ((name, _), run) in INTEGRATORS.iter().zip(runs) {
        for (k, sample) in run.samples.iter().enumerate() {
            let t = (k * sample_every) as Real * dt;
            match sample {
                Some((d, rms, e)) => println!(
                    "{name:<17} {t:>5.1} {:>16.4} {:>18.3e} {e:>14.4e}",
                    d * 1000.0,
                    rms * 1000.0
                ),
                None => println!(
                    "{name:<17} {t:>5.1} {:>16} {:>18} {:>14}",
                    "diverged", "-", "-"
                ),
            }
        }
    }
    for ((name, _), run) in INTEGRATORS.iter().zip(runs) {
        let us = run.time.as_secs_f64() * 1e6 / steps as f64;
        match run.diverged_at {
            Some(t) => println!("{name:<17} diverged at t = {t:.3} s; {us:.0} us/step"),
            None => println!(
                "{name:<17} max RMS vs exact over the run {:.3e} mm = {:.3} % of the exact run's \
                 max displacement; {us:.0} us/step",
                run.max_rms * 1000.0,
                100.0 * run.max_rms / runs[EXACT].max_displacement,
            ),
        }
    }
}
