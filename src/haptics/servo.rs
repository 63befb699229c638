//! The servo loop: one device, one tool's [`ServoLink`], a [`VirtualCoupling`]; a tick reads the
//! device, finds the proxy in the world's latest [`super::ServoModel`] and renders the
//! coupling's force. [`Servo::spawn`] runs it on its own thread at a fixed rate.

use super::servo_model::{rest_proxy_from, MAX_PATCH};
use super::{DeviceSample, HapticDevice, HapticsError, ServoLink, ServoModel, VirtualCoupling};
use crate::math::{Matrix, Pose, Real, Vector};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

mod passivity;

/// A servo loop for one device and one tool.
///
/// Each [`Servo::tick`]: the device's pose (mapped into the world by its
/// [`super::Workspace`]), the proxy where a massless tool rests between the coupling spring
/// and the surfaces' force of the latest model ([`super::ServoModel::proxy`]), the
/// coupling's force (spring, damper, bound) sent to the device, and the sample (device, proxy,
/// force) sent back to the world, which moves the tool to the proxy at its next step.
/// The rendered stiffness is the coupling's and the contact's in series, never above the
/// coupling's: keep it under [`VirtualCoupling::max_passive_stiffness`] for the servo rate.
///
/// A new model does not replace the last one at once: at the first tick under a new model,
/// the difference between the surfaces' force the last tick rendered and the new model's
/// force at the same proxy becomes an offset, added to the new model's force and faded out
/// linearly over one world update interval (measured, as a running mean of the ticks between
/// updates, at most [`Servo::MAX_BLEND`]). A world update is felt as a ramp, not a step, even
/// when updates come irregularly (the ramp restarts from whatever was rendered). A world that
/// steps slower than its `dt` in wall time (a 100,000-node surface) hands over forces that
/// differ by a large share from one update to the next; the ramp keeps them from reaching the
/// hand as knocks. The price is latency: a model is fully rendered one update interval after
/// it arrives.
///
/// The ramp is held to an energy budget. A world's force is not always elastic: a damped
/// surface struck fast pushes back hardest while the tool moves in, and the world reports
/// that a step late. Eased in, such a force kept pushing a hand that had turned back, and a
/// hand pressing on bounced for good (the 100,000-node plate of the servo bench). So the loop
/// books the work of its rendered force on the device (held over a tick, it does the force
/// times the device's displacement); the energy the hand put in since the contact began is
/// the budget, and an offset whose work pushing the proxy out of the surfaces exceeds it
/// fades out faster (to 1 % in 90 ticks). Pressing in, the hand does the work: an offset
/// that eases a press in is not booked.
///
/// A passivity controller ([`Servo::set_passivity`], on by default) bounds the whole
/// rendering, not only the ramp: after the device's move the proxy goes toward where the model
/// puts it only as far as keeps the energy the proxy's moves have drawn into the coupling
/// spring since the contact began at or below zero. Over a contact the hand then gets at most
/// the sampled spring's give-back (`k Δx² / 2` per tick), which the device's damping absorbs
/// under [`VirtualCoupling::max_passive_stiffness`]. The bound is exact, not a prediction of
/// the device's next move.
pub struct Servo<D: HapticDevice> {
    device: D,
    link: ServoLink,
    coupling: VirtualCoupling,
    period: Real,
    ticks: u64,
    /// The last tick, when its device position and proxy were finite.
    last: Option<LastTick>,
    /// The latest model read.
    current: ServoModel,
    /// The force offset at the first tick under `current` (faded out over `interval`).
    offset: Vector,
    /// Ticks since `current` arrived, and the running mean of ticks between arrivals (0: not
    /// measured yet, no blending).
    since_update: u32,
    interval: Real,
    /// Whether updates are ramped in ([`Servo::set_update_ramp`]).
    ramp: bool,
    /// The energy the hand has put into the loop (J: the work of the rendered force on the
    /// device, negated), and the work the current offset has done on the proxy (J).
    reserve: f64,
    offset_work: f64,
    /// Whether the passivity controller is on ([`Servo::set_passivity`]), and the energy the
    /// proxy's moves have drawn into the coupling spring since the contact began (J, held at
    /// or below zero; the passivity observer, [`Servo::bound_proxy`]).
    passivity: bool,
    drawn: f64,
}

impl<D: HapticDevice> std::fmt::Debug for Servo<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Servo")
            .field("coupling", &self.coupling)
            .field("period", &self.period)
            .field("ticks", &self.ticks)
            .finish_non_exhaustive()
    }
}

/// What one servo tick did (world frame).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ServoTick {
    /// The device's pose in the world.
    pub device: Pose,
    /// The proxy's position.
    pub proxy: Vector,
    /// The force rendered (world; the device got it through its workspace).
    pub force: Vector,
    /// The surfaces' force on the proxy in the model.
    pub surface_force: Vector,
    /// The model's [`super::ServoModel::sequence`].
    pub model_sequence: u64,
    /// The model's force at the world step's tool pose ([`super::ServoModel::force`]).
    pub model_force: Vector,
}

impl<D: HapticDevice> Servo<D> {
    /// A servo loop ticking at `rate_hz` (the rate sets the velocities the coupling's damper
    /// sees; [`Servo::spawn`] keeps it).
    ///
    /// # Errors
    /// [`HapticsError::InvalidRate`] for a rate that is not finite and positive.
    pub fn new(
        device: D,
        link: ServoLink,
        coupling: VirtualCoupling,
        rate_hz: Real,
    ) -> Result<Self, HapticsError> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(HapticsError::InvalidRate(rate_hz as f64));
        }
        let model = || ServoModel {
            patch: Vec::with_capacity(MAX_PATCH),
            held: Vec::with_capacity(MAX_PATCH),
            ..ServoModel::default()
        };
        Ok(Servo {
            device,
            link,
            coupling,
            period: 1.0 / rate_hz,
            ticks: 0,
            last: None,
            current: model(),
            offset: Vector::ZERO,
            since_update: 0,
            interval: 0.0,
            ramp: true,
            reserve: 0.0,
            offset_work: 0.0,
            passivity: true,
            drawn: 0.0,
        })
    }

    /// Switches the ramp from one model to the next on or off (on by default; see the type's
    /// docs). Off, each model replaces the last at once: the rendered force is exactly the
    /// latest model's, with a step at each update.
    pub fn set_update_ramp(&mut self, on: bool) {
        self.ramp = on;
        if !on {
            self.offset = Vector::ZERO;
        }
    }

    /// Whether updates are ramped in.
    pub fn update_ramp(&self) -> bool {
        self.ramp
    }

    /// The longest blend between two models (s): a world that stalls (a refactorization)
    /// does not slow the next blends beyond this.
    pub const MAX_BLEND: Real = 0.1;

    /// Reads the link's latest model; a new one becomes `current` and starts a blend.
    fn read_model(&mut self) {
        let model = self.link.model();
        if model.sequence == self.current.sequence {
            self.since_update = self.since_update.saturating_add(1);
            return;
        }
        if self.current.sequence > 0 {
            let gap = (self.since_update as Real + 1.0).min(Self::MAX_BLEND / self.period);
            self.interval = if self.interval > 0.0 {
                0.8 * self.interval + 0.2 * gap
            } else {
                gap
            };
        }
        self.current.copy_from(model);
        self.since_update = 0;
        self.offset_work = 0.0;
        self.offset = match self.last {
            Some(last) if self.ramp && self.interval > 1.0 => {
                let o = last.surface_force - self.current.force_at(last.proxy);
                if o.is_finite() {
                    o
                } else {
                    Vector::ZERO
                }
            }
            _ => Vector::ZERO,
        };
    }

    /// Switches the passivity controller on or off (on by default; the type's docs). On, the
    /// loop never gives the hand more than the sampled coupling spring's give-back over a
    /// contact, whatever the world's forces do (a model that changes under the tool, an
    /// eased-in offset, a damper's late force). Its price: a device that starts inside a
    /// surface, or a surface the world moves onto a device that holds still (pushed by
    /// another tool, animated), renders nothing until the device presses on, since it has put
    /// no energy in; and where the model would push the proxy out with energy the device never
    /// put in, the proxy (and the tool, which the world moves to it) stays where it was and
    /// the device feels the coupling's stiffness there. Off, the rendering is the model's, and
    /// a property test finds worlds that pump energy into the hand
    /// (`tests/it/haptic_energy.rs`: 209 J given against 48 J damped).
    pub fn set_passivity(&mut self, on: bool) {
        self.passivity = on;
    }

    /// Whether the passivity controller is on.
    pub fn passivity(&self) -> bool {
        self.passivity
    }

    /// The surfaces' force and stiffness at `x`: the current model's, plus the fading offset
    /// (see the type's docs).
    fn model_at(&self, x: Vector) -> (Vector, Matrix) {
        let (f, k) = self.current.force_and_stiffness_at(x);
        (f + self.offset * self.fade(), k)
    }

    /// The share of the offset still applied.
    fn fade(&self) -> Real {
        if self.interval > 1.0 {
            1.0 - (self.since_update as Real / (FADE_SHARE * self.interval)).min(1.0)
        } else {
            0.0
        }
    }

    /// One tick (see the type's docs). Costs the model's contacts, not the mesh: a few
    /// microseconds in contact, one point query per patch vertex out of contact.
    pub fn tick(&mut self) -> ServoTick {
        let state = self.device.state();
        let workspace = self.device.workspace();
        let device = workspace.to_world(&state.pose);
        self.read_model();
        let (model_sequence, model_force) = (self.current.sequence, self.current.force);
        let x = device.translation;
        let (mut proxy, mut surface_force) = if x.is_finite() {
            let last = self.last.map(|l| l.proxy);
            rest_proxy_from(last, x, self.coupling.stiffness, |x| self.model_at(x))
        } else {
            (x, Vector::ZERO)
        };
        if let Some(LastTick { proxy: p, .. }) = self.last {
            // The ramp's energy budget: the offset may push the proxy out of the surfaces
            // with no more work than the hand has put in; past that, it fades out faster.
            // Only the push out is booked: pressing in, the hand does the work, and an
            // offset that eases the press in is paid back from the reserve on the way out.
            let offset = self.offset * self.fade();
            let step = proxy - p;
            if offset != Vector::ZERO && step.dot(surface_force) > 0.0 {
                self.offset_work += offset.dot(step).max(0.0) as f64;
                if self.offset_work > self.reserve.max(0.0) || !self.offset_work.is_finite() {
                    self.offset *= OVER_BUDGET_DECAY;
                    (proxy, surface_force) =
                        rest_proxy_from(Some(p), x, self.coupling.stiffness, |x| self.model_at(x));
                }
            }
        }
        if let Some(l) = self.last {
            let work = l.force.dot(x - l.device) as f64;
            self.reserve -= work;
            if self.passivity && x.is_finite() {
                self.observe_hand_move(l, x);
            }
        }
        if self.passivity {
            (proxy, surface_force) = self.bound_proxy(x, proxy, surface_force);
        }
        let (dv, pv) = match self.last {
            Some(l) => (
                (x - l.device) / self.period,
                (proxy - l.proxy) / self.period,
            ),
            None => (Vector::ZERO, Vector::ZERO),
        };
        let force = if proxy.is_finite() && x.is_finite() {
            self.coupling.force(x, dv, proxy, pv)
        } else {
            Vector::ZERO
        };
        if surface_force == Vector::ZERO || !self.reserve.is_finite() {
            // Out of contact the surfaces hold nothing for the hand.
            self.reserve = 0.0;
            self.offset_work = 0.0;
        }
        self.device.set_force(workspace.force_to_device(force));
        self.device.end_tick();
        self.last = Some(LastTick {
            device: x,
            proxy,
            force,
            surface_force,
        })
        .filter(|l| l.device.is_finite() && l.proxy.is_finite());
        self.ticks += 1;
        self.link.send(DeviceSample {
            tick: self.ticks,
            device,
            proxy: Pose::from_parts(proxy, device.rotation),
            buttons: state.buttons,
            force,
            model_sequence,
        });
        ServoTick {
            device,
            proxy,
            force,
            surface_force,
            model_sequence,
            model_force,
        }
    }

    /// The device.
    pub fn device(&self) -> &D {
        &self.device
    }

    /// The device, mutably.
    pub fn device_mut(&mut self) -> &mut D {
        &mut self.device
    }

    /// Ticks so far.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// The tick period (s).
    pub fn period(&self) -> Real {
        self.period
    }
}

impl<D: HapticDevice + 'static> Servo<D> {
    /// Runs the loop on its own thread, one tick per period (sleeping, then spinning the
    /// last 150 µs to the deadline, since a sleep overshoots by tens of microseconds), until
    /// [`ServoThread::stop`]. A loop that fell behind (descheduled by the OS) runs its late
    /// ticks back to back to keep the rate (and a simulated hand's clock in step with the
    /// wall); more than 50 periods behind, it restarts its schedule instead (counted in
    /// [`ServoReport::overruns`]); [`ServoReport::longest_gap`] tells how long the device
    /// went without a force. The first `record` ticks are recorded for [`ServoReport`]
    /// (allocated here, not while running).
    pub fn spawn(self, record: usize) -> ServoThread<D> {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let handle = std::thread::spawn(move || run(self, &flag, record));
        ServoThread {
            stop,
            handle: Some(handle),
        }
    }
}

/// One recorded tick.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TickRecord {
    /// Seconds since the loop started.
    pub time: f64,
    /// How long the tick took (s): reading the device and the model, the proxy, the force.
    pub latency: f64,
    /// The force rendered (world).
    pub force: Vector,
    /// The model it read.
    pub model_sequence: u64,
}

/// What a servo thread did.
#[derive(Clone, Debug, Default)]
pub struct ServoReport {
    /// Ticks run.
    pub ticks: u64,
    /// Wall time from the first tick to the stop (s).
    pub elapsed: f64,
    /// Times the loop was more than 50 periods behind and restarted its schedule.
    pub overruns: u64,
    /// The first ticks.
    pub records: Vec<TickRecord>,
}

impl ServoReport {
    /// Ticks per second achieved.
    pub fn rate_hz(&self) -> f64 {
        if self.elapsed > 0.0 {
            self.ticks as f64 / self.elapsed
        } else {
            0.0
        }
    }

    /// The `q`-quantile (0 to 1) of the recorded tick latencies (s), 0 with no record.
    pub fn latency_quantile(&self, q: f64) -> f64 {
        quantile(self.records.iter().map(|r| r.latency), q)
    }

    /// The `q`-quantile of the recorded force magnitudes (N).
    pub fn force_quantile(&self, q: f64) -> f64 {
        quantile(self.records.iter().map(|r| r.force.length() as f64), q)
    }

    /// The longest time between two recorded ticks (s): how long the device once went
    /// without a new force.
    pub fn longest_gap(&self) -> f64 {
        self.records
            .windows(2)
            .map(|w| w[1].time - w[0].time)
            .fold(0.0, f64::max)
    }

    /// The largest change of the rendered force between consecutive recorded ticks (N):
    /// `(between ticks that read the same model, across a new model)`.
    pub fn largest_force_jumps(&self) -> (f64, f64) {
        let (mut within, mut across) = (0.0f64, 0.0f64);
        for w in self.records.windows(2) {
            let jump = (w[1].force - w[0].force).length() as f64;
            if w[1].model_sequence == w[0].model_sequence {
                within = within.max(jump);
            } else {
                across = across.max(jump);
            }
        }
        (within, across)
    }
}

fn quantile(values: impl Iterator<Item = f64>, q: f64) -> f64 {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let i = ((v.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    v[i]
}

/// A servo loop running on its own thread.
#[derive(Debug)]
pub struct ServoThread<D: HapticDevice> {
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<(Servo<D>, ServoReport)>>,
}

impl<D: HapticDevice> ServoThread<D> {
    /// Stops the loop after its current tick and gives back the servo (and its device) with
    /// the report; `None` if the thread panicked.
    pub fn stop(mut self) -> Option<(Servo<D>, ServoReport)> {
        self.stop.store(true, Ordering::Release);
        self.handle.take()?.join().ok()
    }
}

impl<D: HapticDevice> Drop for ServoThread<D> {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

/// What a tick saw and rendered (world frame): the device's position, the proxy, the force
/// rendered (held over the next tick) and the surfaces' force at the proxy.
#[derive(Copy, Clone, Debug)]
struct LastTick {
    device: Vector,
    proxy: Vector,
    force: Vector,
    surface_force: Vector,
}

/// The share of the update interval over which a new model's offset fades: the ramp ends
/// before the next update when updates come regularly.
const FADE_SHARE: Real = 0.75;

/// Past its energy budget, the ramp's offset shrinks by this factor per tick (to 1 % in 90
/// ticks, 18 ms at 5 kHz): a step would knock the hand.
const OVER_BUDGET_DECAY: Real = 0.95;

/// The last stretch before a deadline is spun, not slept.
const SPIN: Duration = Duration::from_micros(150);

/// A loop late by up to this many periods catches up (ticks back to back); later than that it
/// restarts its schedule.
const CATCH_UP: u32 = 50;

fn run<D: HapticDevice>(
    mut servo: Servo<D>,
    stop: &AtomicBool,
    record: usize,
) -> (Servo<D>, ServoReport) {
    let period = Duration::from_secs_f64(servo.period as f64);
    let mut report = ServoReport {
        records: Vec::with_capacity(record),
        ..ServoReport::default()
    };
    let start = Instant::now();
    let mut deadline = start;
    while !stop.load(Ordering::Acquire) {
        let t0 = Instant::now();
        let tick = servo.tick();
        let t1 = Instant::now();
        report.ticks += 1;
        if report.records.len() < record {
            report.records.push(TickRecord {
                time: (t0 - start).as_secs_f64(),
                latency: (t1 - t0).as_secs_f64(),
                force: tick.force,
                model_sequence: tick.model_sequence,
            });
        }
        deadline += period;
        let now = Instant::now();
        if now > deadline + CATCH_UP * period {
            // Too far behind (the thread was descheduled): start the schedule again from now.
            report.overruns += 1;
            deadline = now;
            continue;
        }
        if let Some(rest) = deadline.checked_duration_since(now) {
            if rest > SPIN {
                std::thread::sleep(rest - SPIN);
            }
        }
        while Instant::now() < deadline {
            std::hint::spin_loop();
        }
    }
    report.elapsed = start.elapsed().as_secs_f64();
    (servo, report)
}
