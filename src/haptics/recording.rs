//! Device trajectories recorded and replayed as CSV.

use super::DeviceState;
use crate::math::{Pose, Real, Rotation, Vector};

/// Why a recording could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RecordingError {
    /// The first line is not the header [`Recording::HEADER`].
    #[error("the first line is not the header `{}`", Recording::HEADER)]
    Header,
    /// A line has the wrong number of fields or a field that is not a finite number.
    #[error("line {0}: expected 9 finite numbers (time, position, quaternion, buttons)")]
    Line(usize),
    /// Times do not increase.
    #[error("line {0}: time does not increase")]
    Time(usize),
    /// No samples.
    #[error("the recording has no samples")]
    Empty,
}

/// Device states against time: recorded from a device (a [`super::SimulatedHand`] or a real
/// one), saved and read as CSV (`t,x,y,z,qx,qy,qz,qw,buttons`), and replayed as a trajectory
/// (positions interpolated linearly, rotations by slerp, buttons held).
///
/// # Example
/// ```
/// use rapier_touch::haptics::{DeviceState, Recording};
/// use rapier_touch::prelude::{Pose, Vector};
///
/// let mut rec = Recording::default();
/// for k in 0..3 {
///     let pose = Pose::from_translation(Vector::new(0.0, -0.01 * k as f32, 0.0));
///     rec.record(0.001 * k as f32, DeviceState { pose, buttons: k }).unwrap();
/// }
/// let csv = rec.to_csv();
/// let back = Recording::from_csv(&csv).unwrap();
/// assert_eq!(back, rec);
/// // Half-way between the second and third samples.
/// assert!((back.pose_at(0.0015).translation.y + 0.015).abs() < 1e-6);
/// assert!(Recording::from_csv("t,x\n1,2").is_err());
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Recording {
    samples: Vec<(Real, DeviceState)>,
}

impl Recording {
    /// The CSV header.
    pub const HEADER: &'static str = "t,x,y,z,qx,qy,qz,qw,buttons";

    /// Appends a sample at time `t` (s).
    ///
    /// # Errors
    /// [`RecordingError::Line`] for a non-finite sample, [`RecordingError::Time`] when `t`
    /// is not after the last sample's (the line numbers count samples from 2).
    pub fn record(&mut self, t: Real, state: DeviceState) -> Result<(), RecordingError> {
        let line = self.samples.len() + 2;
        if !(t.is_finite() && state.pose.is_finite()) {
            return Err(RecordingError::Line(line));
        }
        if self.samples.last().is_some_and(|(last, _)| t <= *last) {
            return Err(RecordingError::Time(line));
        }
        self.samples.push((t, state));
        Ok(())
    }

    /// The samples, oldest first.
    pub fn samples(&self) -> &[(Real, DeviceState)] {
        &self.samples
    }

    /// The recording as CSV, with its header.
    pub fn to_csv(&self) -> String {
        let mut out = String::from(Self::HEADER);
        out.push('\n');
        for (t, s) in &self.samples {
            let (p, q) = (s.pose.translation, s.pose.rotation);
            out += &format!(
                "{t},{},{},{},{},{},{},{},{}\n",
                p.x, p.y, p.z, q.x, q.y, q.z, q.w, s.buttons
            );
        }
        out
    }

    /// Reads a recording written by [`Recording::to_csv`] (or by hand: blank lines are
    /// skipped, quaternions are normalized).
    ///
    /// # Errors
    /// See [`RecordingError`].
    pub fn from_csv(csv: &str) -> Result<Self, RecordingError> {
        let mut lines = csv.lines().enumerate();
        match lines.next() {
            Some((_, h)) if h.trim() == Self::HEADER => {}
            _ => return Err(RecordingError::Header),
        }
        let mut rec = Recording::default();
        for (i, line) in lines {
            if line.trim().is_empty() {
                continue;
            }
            let fields: Vec<f64> = line
                .split(',')
                .map(|f| f.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| RecordingError::Line(i + 1))?;
            if fields.len() != 9 || !fields.iter().all(|f| f.is_finite()) {
                return Err(RecordingError::Line(i + 1));
            }
            let f = |k: usize| fields[k] as Real;
            let rotation = Rotation::from_xyzw(f(4), f(5), f(6), f(7));
            if rotation.length() < 1e-6 {
                return Err(RecordingError::Line(i + 1));
            }
            let buttons = fields[8];
            if buttons < 0.0 || buttons > u32::MAX as f64 || buttons.fract() != 0.0 {
                return Err(RecordingError::Line(i + 1));
            }
            let pose = Pose::from_parts(Vector::new(f(1), f(2), f(3)), rotation.normalize());
            let state = DeviceState {
                pose,
                buttons: buttons as u32,
            };
            rec.record(f(0), state).map_err(|e| match e {
                RecordingError::Time(_) => RecordingError::Time(i + 1),
                _ => RecordingError::Line(i + 1),
            })?;
        }
        if rec.samples.is_empty() {
            return Err(RecordingError::Empty);
        }
        Ok(rec)
    }

    /// The pose at time `t`: interpolated between samples, held before the first and after
    /// the last (the identity for an empty recording).
    pub fn pose_at(&self, t: Real) -> Pose {
        let s = &self.samples;
        let Some(first) = s.first() else {
            return Pose::IDENTITY;
        };
        if t.is_nan() || t <= first.0 {
            return first.1.pose;
        }
        let k = s.partition_point(|(ts, _)| *ts <= t);
        if k >= s.len() {
            return s[s.len() - 1].1.pose;
        }
        let ((t0, a), (t1, b)) = (s[k - 1], s[k]);
        let u = (t - t0) / (t1 - t0);
        Pose::from_parts(
            a.pose.translation.lerp(b.pose.translation, u),
            a.pose.rotation.slerp(b.pose.rotation, u),
        )
    }
}
