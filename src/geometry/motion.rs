//! [`RigidMotion`]: the path a rigid object follows over one step, which the inverse trajectory
//! mapping walks back along.

use super::contact::{ContactConfiguration, DirectionSource, TouchState};
use super::reconstruction::{Reconstructor, Walk};
use super::touch_mesh::TouchMesh;
use crate::math::{Pose, Real, Vector};
use glamx::{DQuat, DVec3};

/// The cosine below which a direction grazes a contact plane (about 75° off its normal, 15°
/// from the plane): a sub-step's touch found within the tolerance along it is looked at again,
/// and the step guard pushes such a path out along the normal instead of walking it back.
pub(crate) const GRAZING: Real = 0.25;

/// The motion of a rigid object over one step, as rapier integrates a body: the object's
/// centre of mass `local_center` (in the object's own frame) moves on a straight line from its
/// place at `start` to its place at `end`, while the orientation turns at a constant angular
/// velocity about it (the shortest arc: a spherical interpolation of the two rotations).
///
/// rapier integrates each substep this way (linear velocity at the centre of mass, angular
/// velocity about it); over a whole step with several substeps the true path bends slightly
/// under gravity and contacts, and this motion is the constant-velocity path between the two
/// poses the step left, the one rapier's own nonlinear CCD assumes too.
///
/// # Example
/// ```
/// use rapier_touch::prelude::*;
/// // A body turning 2 rad about its centre of mass (1, 0, 0) while that centre rises by 2.
/// let com = Vector::new(1.0, 0.0, 0.0);
/// let start = Pose::IDENTITY;
/// let turn = Rotation::from_rotation_z(2.0);
/// let end = Pose::from_parts(Vector::new(1.0, 2.0, 0.0) - turn * com, turn);
/// let motion = RigidMotion::new(start, end, com);
/// let half = motion.pose_at(0.5);
/// // Half-way, the centre of mass is half-way up and the body has turned 1 rad.
/// assert!((half.transform_point(com) - Vector::new(1.0, 1.0, 0.0)).length() < 1e-5);
/// assert!(half.rotation.dot(Rotation::from_rotation_z(1.0)).abs() > 1.0 - 1e-6);
/// // (For exactly half a turn both arcs are equally short: rounding picks one.)
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RigidMotion {
    /// The pose at the start of the step (the previous pose).
    pub start: Pose,
    /// The pose at the end of the step (the current pose).
    pub end: Pose,
    /// The point the rotation turns about, in the object's frame: its centre of mass.
    pub local_center: Vector,
}

impl RigidMotion {
    /// The motion from `start` to `end` turning about `local_center` (object frame).
    pub fn new(start: Pose, end: Pose, local_center: Vector) -> Self {
        Self {
            start,
            end,
            local_center,
        }
    }

    /// The pose at time `t` (`0` = start, `1` = end).
    pub fn pose_at(&self, t: Real) -> Pose {
        let (q, p) = self.dpose_at(t as f64);
        Pose::from_parts(p.as_vec3(), q.as_quat())
    }

    /// The angle the object turns through over the step (radians, in `[0, π]`).
    pub fn angle(&self) -> Real {
        self.dangle() as Real
    }

    /// [`RigidMotion::angle`] in `f64`.
    pub(crate) fn dangle(&self) -> f64 {
        let (q0, q1) = self.rotations();
        q0.angle_between(q1)
    }

    /// `true` when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.start.is_finite() && self.end.is_finite() && self.local_center.is_finite()
    }

    /// First touch of two shapes that both moved over the step, `shape1` along `motion1` and
    /// `shape2` along `motion2`: the fraction of the step at which they first touch (`0` when
    /// they already touched at its start), the contact normal then, out of `shape1` toward
    /// `shape2`, and the touching point of `shape1` (world frame). `None` when they never
    /// touch on the step, when parry has no nonlinear shape cast for the shapes (a TriMesh
    /// against a TriMesh), or when the answer is not finite.
    ///
    /// This is parry's nonlinear shape cast on the shapes themselves, the query rapier's own
    /// CCD asks of two moving bodies: it gives the time and the normal only, not the touching
    /// features ([`Reconstructor`] names them for one shape moving against another held
    /// still).
    ///
    /// ```
    /// use rapier_touch::geometry::RigidMotion;
    /// use rapier_touch::math::{Pose, Vector};
    /// use parry3d::shape::Ball;
    /// // Two unit balls 4 m apart close 6 m over the step: they touch when 2 m closer,
    /// // a third of the way.
    /// let a = RigidMotion::new(Pose::translation(-2.0, 0.0, 0.0), Pose::translation(1.0, 0.0, 0.0), Vector::ZERO);
    /// let b = RigidMotion::new(Pose::translation(2.0, 0.0, 0.0), Pose::translation(-1.0, 0.0, 0.0), Vector::ZERO);
    /// let (t, n, p) = RigidMotion::first_touch_of_two(&Ball::new(1.0), &a, &Ball::new(1.0), &b).unwrap();
    /// assert!((t - 1.0 / 3.0).abs() < 1e-3);
    /// assert!((n - Vector::X).length() < 1e-3);
    /// assert!(p.length() < 1e-2); // where the balls meet
    /// ```
    /// Two balls that stay apart never touch:
    /// ```
    /// # use rapier_touch::geometry::RigidMotion;
    /// # use rapier_touch::math::{Pose, Vector};
    /// # use parry3d::shape::Ball;
    /// let a = RigidMotion::new(Pose::translation(-2.0, 0.0, 0.0), Pose::translation(-2.0, 1.0, 0.0), Vector::ZERO);
    /// let b = RigidMotion::new(Pose::translation(2.0, 0.0, 0.0), Pose::translation(2.0, 1.0, 0.0), Vector::ZERO);
    /// assert!(RigidMotion::first_touch_of_two(&Ball::new(1.0), &a, &Ball::new(1.0), &b).is_none());
    /// // A motion that is not finite has no first touch (no NaN handed on).
    /// let nan = RigidMotion::new(Pose::translation(f32::NAN, 0.0, 0.0), Pose::IDENTITY, Vector::ZERO);
    /// assert!(RigidMotion::first_touch_of_two(&Ball::new(1.0), &nan, &Ball::new(1.0), &b).is_none());
    /// // A degenerate shape, a ball of zero radius (a point), meets the other where its
    /// // surface sweeps over it: 3 m apart, closing 6 m, half-way.
    /// let p = RigidMotion::new(Pose::translation(-2.0, 0.0, 0.0), Pose::translation(1.0, 0.0, 0.0), Vector::ZERO);
    /// let q = RigidMotion::new(Pose::translation(2.0, 0.0, 0.0), Pose::translation(-1.0, 0.0, 0.0), Vector::ZERO);
    /// let (t, n, _) = RigidMotion::first_touch_of_two(&Ball::new(0.0), &p, &Ball::new(1.0), &q).unwrap();
    /// assert!((t - 0.5).abs() < 1e-3 && (n - Vector::X).length() < 1e-3);
    /// ```
    pub fn first_touch_of_two(
        shape1: &dyn parry3d::shape::Shape,
        motion1: &RigidMotion,
        shape2: &dyn parry3d::shape::Shape,
        motion2: &RigidMotion,
    ) -> Option<(Real, Vector, Vector)> {
        if !motion1.is_finite() || !motion2.is_finite() {
            return None;
        }
        let nonlinear = |m: &RigidMotion| {
            let linvel =
                m.end.transform_point(m.local_center) - m.start.transform_point(m.local_center);
            let mut turn = (m.end.rotation * m.start.rotation.inverse()).normalize();
            if turn.w < 0.0 {
                turn = -turn;
            }
            parry3d::query::NonlinearRigidMotion::new(
                m.start,
                m.local_center,
                linvel,
                turn.to_scaled_axis(),
            )
        };
        let (m1, m2) = (nonlinear(motion1), nonlinear(motion2));
        let hit = parry3d::query::cast_shapes_nonlinear(&m1, shape1, &m2, shape2, 0.0, 1.0, true)
            .ok()??;
        let t = hit.time_of_impact.clamp(0.0, 1.0);
        // The normal joins the two shapes' closest points a little before the touch, where
        // they are apart by about a hundredth of their size (GJK's answer there is exact to
        // its tolerance). The cast's own normal (its iterate's closest points) came 15° off
        // a face for a spinning box's corner, and parry's contact query at the touching
        // poses answered 11° out of the plane two nearly parallel edges share (at zero
        // distance its normal is one of a whole cone): an impact given either threw two
        // boxes sideways at 15 m/s.
        let pose1 = m1.position_at_time(t);
        let size = shape1.compute_local_bounding_sphere().radius
            + shape2.compute_local_bounding_sphere().radius;
        let closing =
            (m2.linvel - m1.linvel).length() + (m1.angvel.length() + m2.angvel.length()) * size;
        let before = if closing > 0.0 {
            (t - 0.01 * size / closing).max(0.0)
        } else {
            t
        };
        let (b1, b2) = (m1.position_at_time(before), m2.position_at_time(before));
        let apart = parry3d::query::closest_points(&b1, shape1, &b2, shape2, 0.1 * size);
        let (n, p) = match apart {
            Ok(parry3d::query::ClosestPoints::WithinMargin(p1, p2))
                if (p2 - p1).length() > 1e-4 * size =>
            {
                ((p2 - p1), pose1 * (b1.inverse() * p1))
            }
            _ => (pose1.rotation * hit.normal1, pose1 * hit.witness1),
        };
        let n = n.try_normalize()?;
        (t.is_finite() && n.is_finite() && p.is_finite()).then_some((t, n, p))
    }

    fn rotations(&self) -> (DQuat, DQuat) {
        (
            self.start.rotation.as_dquat().normalize(),
            self.end.rotation.as_dquat().normalize(),
        )
    }

    /// The world positions of the centre of mass at the start and at the end, in `f64`.
    pub(crate) fn centres(&self) -> (DVec3, DVec3) {
        let (q0, q1) = self.rotations();
        let lc = self.local_center.as_dvec3();
        (
            q0 * lc + self.start.translation.as_dvec3(),
            q1 * lc + self.end.translation.as_dvec3(),
        )
    }

    /// The pose at time `t`, in `f64`: (rotation, translation).
    pub(crate) fn dpose_at(&self, t: f64) -> (DQuat, DVec3) {
        let (q0, q1) = self.rotations();
        let lc = self.local_center.as_dvec3();
        let (c0, c1) = self.centres();
        // glam's slerp takes the shortest arc (it flips `q1` when the dot product is negative).
        let q = if t <= 0.0 {
            q0
        } else if t >= 1.0 {
            q1
        } else {
            q0.slerp(q1, t).normalize()
        };
        let c = c0 + (c1 - c0) * t;
        (q, c - q * lc)
    }

    /// The largest distance any point within `radius` of the centre of mass travels over the
    /// step: the centre's displacement plus the arc of the rotation.
    pub(crate) fn max_travel(&self, radius: f64) -> f64 {
        let (c0, c1) = self.centres();
        c0.distance(c1) + self.dangle() * radius
    }
}

/// Most conservative advancements between two samples of a rotating path's first-touch
/// search.
const MAX_ADVANCES: usize = 64;

/// The largest distance from `center` (mesh frame) to a point of `mesh`: a bound through the
/// corners of its bounding box.
pub(super) fn bounding_radius(mesh: &TouchMesh, center: Vector) -> f64 {
    let b = mesh.local_aabb();
    let c = center.as_dvec3();
    let (lo, hi) = (b.mins.as_dvec3() - c, b.maxs.as_dvec3() - c);
    lo.abs().max(hi.abs()).length()
}

impl Reconstructor {
    /// First touch along a path that turns (see [`Reconstructor::reconstruct_motion`]).
    ///
    /// `tau` runs backward along the path: `0` is the current pose, `1` the previous one.
    /// 1. A step that started penetrating has no first touch on its path: the translation
    ///    method at the current orientation gives the nearest way out (`on_trajectory` false).
    /// 2. The path is sampled forward in time with spacing below half the larger of the two
    ///    objects' smallest extents, so that neither can pass through the other between two
    ///    samples; the first penetrating sample brackets the first touch. Between samples a
    ///    pair apart is advanced conservatively on its vertex hulls' gap
    ///    ([`Reconstructor::hull_gap`]), so that a graze between two samples is not missed.
    /// 3. Bisection on "penetrating" (transversal crossing or containment, `f64`) narrows the
    ///    bracket until the rotation over it moves no point by more than the tolerance.
    /// 4. Over that sub-step the motion is a translation to within the tolerance: the paper's
    ///    exact method (eq. 1-3) finds the touching features and the touch pose.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn rotate_back(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        motion: &RigidMotion,
        tol: f64,
        radius: f64,
        angle: f64,
    ) -> ContactConfiguration {
        let now = motion.end;
        let back = |tau: f64| motion.pose_at((1.0 - tau) as Real);
        let travel = motion.max_travel(radius);
        // Direction of travel: the centre of mass's, or toward the fixed object when it only
        // spins.
        let (qf, tf) = (
            pos_fixed.rotation.as_dquat(),
            pos_fixed.translation.as_dvec3(),
        );
        let (c_start, c_end) = motion.centres();
        let u_world = (c_end - c_start)
            .try_normalize()
            .or_else(|| {
                let cf = qf * fixed.local_aabb().center().as_dvec3() + tf;
                (cf - c_end).try_normalize()
            })
            .unwrap_or(DVec3::NEG_Y);
        let separated = ContactConfiguration::separated(
            u_world.as_vec3(),
            DirectionSource::Trajectory,
            true,
            now,
        );

        // Quick reject: the swept bounding sphere misses the fixed object's box.
        let inv_f = qf.conjugate();
        let (a, b) = (inv_f * (c_start - tf), inv_f * (c_end - tf));
        let fb = fixed.local_aabb();
        let pad = DVec3::splat(radius + 4.0 * tol);
        if (a.min(b) - pad).cmpgt(fb.maxs.as_dvec3()).any()
            || (a.max(b) + pad).cmplt(fb.mins.as_dvec3()).any()
        {
            return separated;
        }

        let pen = |this: &mut Self, tau: f64| {
            let fr = this.frame_at(fixed, pos_fixed, moving, &back(tau), u_world, tol);
            this.penetrating_at(fixed, moving, &fr, 0.0)
        };
        if pen(self, 1.0) {
            // Already penetrating when the step began: not a first touch of this step.
            if self.first_touch_only && pen(self, 0.0) {
                return ContactConfiguration {
                    state: TouchState::Penetrating,
                    on_trajectory: false,
                    ..separated
                };
            }
            let mut c = self
                .translate_back_within(
                    fixed,
                    pos_fixed,
                    moving,
                    &now,
                    &motion.start,
                    Walk::first_touch_if(self.first_touch_only),
                )
                .unwrap_or(separated);
            c.on_trajectory = false;
            c.time_of_impact = None;
            return c;
        }
        // Sample spacing: half the larger smallest extent (a flat object has none).
        let h = 0.5
            * (fixed.min_extent().max(moving.min_extent()) as f64)
                .max(0.5 * fixed.scale().min(moving.scale()) as f64);
        let budget = 4 * self.options.max_perforation_samples.max(1);
        let k = ((travel / h).ceil() as usize).clamp(1, budget);
        let gap = |this: &mut Self, tau: f64| {
            let fr = this.frame_at(fixed, pos_fixed, moving, &back(tau), u_world, tol);
            this.hull_gap(fixed, moving, &fr)
        };
        // (A pair touching when the step began is sampled as before: probed, a body tumbling
        // on a floor was walked back to an earlier dip of a corner and ended deeper.)
        let mut advance = gap(self, 1.0).is_some_and(|d| d > 2.0 * tol);
        let mut tau_b = 1.0;
        let mut tau_a = None;
        'samples: for i in 1..=k {
            let tau = 1.0 - i as f64 / k as f64;
            // Samples spaced by the bodies' thickness miss a graze that clips in and out
            // between two of them (a pyramid turning past a flat triangle clipped its corner
            // 22 mm deep between two samples, and the first touch was reported later:
            // `PROPTEST_RNG_SEED=4102` of `tests/it/rigid_motion.rs`). Where the distance of
            // the meshes' vertex hulls is known (a lower bound of theirs), the pair is
            // advanced conservatively toward the next sample while apart; where it comes
            // within two tolerances of touching, short of the sample, a quarter and a half of
            // the way left are probed too. The samples themselves are all still tested.
            let mut t = tau_b;
            for _ in 0..MAX_ADVANCES {
                // (The hulls' gap is asked only while it advances: a hull that holds the other
                // mesh, such as a bumpy floor's, reads zero at every pose.)
                let Some(d) = advance.then(|| gap(self, t)).flatten() else {
                    advance = false;
                    break;
                };
                if d <= 2.0 * tol {
                    for share in [0.25, 0.5] {
                        let probe = t - share * (t - tau);
                        if pen(self, probe) {
                            tau_a = Some(probe);
                            break 'samples;
                        }
                        tau_b = probe;
                    }
                    break;
                }
                t -= (d - tol) / travel;
                if t.is_nan() || t <= tau {
                    break;
                }
                // Apart by at least the tolerance here: no penetration test needed.
                tau_b = t;
            }
            if pen(self, tau) {
                tau_a = Some(tau);
                break;
            }
            tau_b = tau;
        }
        let Some(mut tau_a) = tau_a else {
            // Not penetrating at any sample, now included: touching or apart now, decided by
            // the translation method over the last sub-step.
            let c = self
                .translate_back(fixed, pos_fixed, moving, &now, &back(1.0 / k as f64))
                .unwrap_or(separated.clone());
            return match c.state {
                TouchState::Touching => ContactConfiguration {
                    time_of_impact: Some(1.0),
                    ..c
                },
                _ => separated,
            };
        };
        let penetrating_now = tau_a == 0.0 || pen(self, 0.0);
        // Bisection on "penetrating" until the bracket, times `rate` (the largest distance a
        // point travels per unit of `tau`), is below the tolerance; at most 64 halvings.
        let bisect = |this: &mut Self, tau_a: &mut f64, tau_b: &mut f64, rate: f64| {
            for _ in 0..64 {
                if (*tau_b - *tau_a) * rate <= tol {
                    break;
                }
                let mid = 0.5 * (*tau_a + *tau_b);
                if pen(this, mid) {
                    *tau_a = mid;
                } else {
                    *tau_b = mid;
                }
            }
        };
        // First until the rotation over the bracket is below the tolerance.
        bisect(self, &mut tau_a, &mut tau_b, angle * radius);
        let (mut pa, mut pb) = (back(tau_a), back(tau_b));
        let mut sub = self
            .translate_back_within(fixed, pos_fixed, moving, &pa, &pb, Walk::SubStep)
            .unwrap_or(separated.clone());
        // A touch the sub-step put within the tolerance of its end ([`Walk::SubStep`]) along
        // a direction that grazes its contact plane shows only the features nearest along it
        // (a cube turning on a floor it rested on, walked back nearly along the floor, showed
        // one of its four corners): such a touch is looked at as the paper's method would.
        let grazing = || {
            sub.reversing_vector.length() as f64 <= tol
                && sub
                    .patches
                    .iter()
                    .any(|p| p.normal.dot(sub.direction).abs() < GRAZING)
        };
        if sub.needs_correction() && (!sub.on_trajectory || grazing()) {
            // The sub-step's start already overlaps by a rounding of the predicate (its way
            // out would leave the path): bisect on, until the whole motion over the bracket is
            // below the tolerance, and try again.
            bisect(self, &mut tau_a, &mut tau_b, travel);
            (pa, pb) = (back(tau_a), back(tau_b));
            sub = self
                .translate_back(fixed, pos_fixed, moving, &pa, &pb)
                .unwrap_or(separated.clone());
        }
        let (touch, t_sub) = if sub.needs_correction() && sub.on_trajectory {
            // Where on the path: the sub-step's own time of impact (0 = pb, 1 = pa).
            (sub.touch_pose, sub.time_of_impact.unwrap_or(1.0) as f64)
        } else if !sub.needs_correction() {
            (pa, 1.0)
        } else {
            // `pb` is within the tolerance of first touch: the features touching there. For
            // two convex meshes a zero-length translation query answers from GJK (its convex
            // path); otherwise it would walk the whole overlap of the boxes along a fallback
            // direction (see `touching_at`).
            sub = if self.options.convex_fast_path && fixed.is_convex() && moving.is_convex() {
                self.translate_back(fixed, pos_fixed, moving, &pb, &pb)
                    .unwrap_or(separated.clone())
            } else {
                // Looked at along the sub-step's own contact normal where it has one.
                let normal = sub.patches.first().map(|p| -p.normal.as_dvec3());
                let along = normal.into_iter().chain([u_world]);
                self.touching_at(fixed, pos_fixed, moving, &pb, along, tol)
            };
            (pb, 0.0)
        };
        let tau_star = tau_b - t_sub * (tau_b - tau_a);
        // Depth: how far the touching material points travelled past first touch.
        let to_now = now * touch.inverse();
        let depth = sub
            .patches
            .iter()
            .flat_map(|p| p.points.iter())
            .map(|p| (to_now.transform_point(p.point) - p.point).length())
            .fold(0.0, Real::max);
        let reversing_vector = touch.translation - now.translation;
        ContactConfiguration {
            state: if penetrating_now {
                TouchState::Penetrating
            } else {
                TouchState::Perforated
            },
            reversing_vector,
            depth: if sub.patches.is_empty() {
                reversing_vector.length()
            } else {
                depth
            },
            direction: sub.direction,
            direction_source: DirectionSource::Trajectory,
            on_trajectory: true,
            time_of_impact: Some((1.0 - tau_star).clamp(0.0, 1.0) as Real),
            touch_pose: touch,
            patches: sub.patches,
            candidate_pairs: sub.candidate_pairs,
        }
    }
}
