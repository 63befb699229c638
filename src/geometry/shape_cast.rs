//! The inverse trajectory mapping on curved shapes: the moving shape itself (not a
//! tessellation of it) is advanced along its [`RigidMotion`] to first touch with parry's
//! distance query, and pushed out of an overlap with parry's shape cast.
//!
//! A ball, a capsule, a cylinder, a cone or a rounded shape has no vertices, edges or faces:
//! its touch mesh ([`TouchMesh::from_shape`](super::TouchMesh::from_shape)) is a fine
//! tessellation, exact to a small fraction of the radius but hundreds of triangles, and a
//! tumbling curved body cost the exact method a full search on its rotating path (rapier's
//! rounded convex-hull stress scene ran 424× slower than vanilla rapier). Conservative
//! advancement on parry's GJK distance answers the same question, first touch on the path,
//! on the true surface in a handful of distance queries; the crate's own method stays for
//! polyhedra, where it names the touching features.

use super::contact::{
    ContactConfiguration, ContactKind, ContactPatch, DirectionSource, TouchState,
};
use super::motion::RigidMotion;
use super::reconstruction::{ReconstructionError, Reconstructor};
use super::tool_boundary::rounded;
use crate::math::{Pose, Real, Vector};
use parry3d::query;
use parry3d::shape::{Cuboid, Shape, SupportMap};

impl Reconstructor {
    /// First touch of `moving`, which followed `motion` over the step (its current pose is
    /// `motion.end`), against `fixed` at `pos_fixed`, on the shapes themselves: conservative
    /// advancement (Mirtich) on parry's distance query along the path. Meant for curved shapes,
    /// whose touch meshes are tessellations; [`Reconstructor::reconstruct_motion`] is the exact
    /// method for polyhedra.
    ///
    /// Shapes closer than ten tolerances ([`ReconstructionOptions::tolerance`](super::ReconstructionOptions)
    /// times the larger bounding diameter) touch. A pair in contact when the step began has no
    /// first touch on this path (`on_trajectory` false): walking it back would undo the whole
    /// step, freezing a rolling or sliding body; it is pushed out along the contact normal.
    ///
    /// The result reads as the mesh method's, with these differences:
    /// - the single patch is a [`ContactKind::Vertex`] at parry's witness point on `fixed`,
    ///   with parry's normal; a curved surface has no mesh features, so its `points` and
    ///   feature lists are empty;
    /// - `depth` on the path is the distance the witness point of `moving` travelled from first
    ///   touch to its place now;
    /// - a pair in contact when the step began (`on_trajectory` false) is pushed out along
    ///   parry's contact normal at the current pose (EPA), not along `-D`;
    /// - a perforation is told from a graze by advancing back from the current pose: a last
    ///   touch later than the first one.
    ///
    /// `Ok(None)` when parry has no distance query for the pair (custom shapes), a shape has no
    /// size (a ball of radius 0), or the advance does not converge in 128 queries (a body
    /// grazing along the other at a speed far below its rotation's): use the mesh method then.
    ///
    /// # Errors
    /// [`ReconstructionError::NonFinitePose`] if a pose or the centre is NaN or infinite.
    ///
    /// # Example
    /// A ball that fell 1 m in one step and now sinks 0.3 m into a slab touched it 0.3 m back:
    /// ```
    /// use rapier_touch::parry3d::shape::Ball;
    /// use rapier_touch::prelude::*;
    /// let slab = Cuboid::new(Vector::new(2.0, 0.5, 2.0));
    /// let ball = Ball::new(0.25);
    /// let slab_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
    /// let before = Pose::from_translation(Vector::new(0.0, 0.95, 0.0));
    /// let now = Pose::from_translation(Vector::new(0.0, -0.05, 0.0));
    /// let motion = RigidMotion::new(before, now, Vector::ZERO);
    /// let c = Reconstructor::default()
    ///     .reconstruct_shapes(&slab, &slab_pose, &ball, &motion)
    ///     .unwrap()
    ///     .unwrap();
    /// assert_eq!(c.state, TouchState::Penetrating);
    /// assert!((c.reversing_vector - Vector::new(0.0, 0.3, 0.0)).length() < 1e-4);
    /// assert!((c.touch_pose.translation.y - 0.25).abs() < 1e-4);
    /// ```
    pub fn reconstruct_shapes(
        &mut self,
        fixed: &dyn Shape,
        pos_fixed: &Pose,
        moving: &dyn Shape,
        motion: &RigidMotion,
    ) -> Result<Option<ContactConfiguration>, ReconstructionError> {
        if !(pos_fixed.is_finite() && motion.is_finite()) {
            return Err(ReconstructionError::NonFinitePose);
        }
        let sphere = moving.compute_local_bounding_sphere();
        let q = PairQuery::new(
            fixed,
            pos_fixed,
            moving,
            self.options.tolerance,
            [motion.start.translation, motion.end.translation],
        );
        let tol = q.tol;
        // The farthest any point of `moving` travels over the step: a bound on its speed
        // toward `fixed` (per unit of `t`).
        let reach = (sphere.radius + (sphere.center - motion.local_center).length()) as f64;
        let speed = motion.max_travel(reach) as Real;
        // The centre's displacement over the step and the arc a point `reach` from it turns
        // through (per unit of `t`), for the advance's bound along the separating direction.
        let (c0, c1) = motion.centres();
        // A ball is the same set however it turns about its centre: only its centre's arc
        // about the centre of mass closes on anything.
        let turning = match moving.as_ball() {
            Some(_) => (sphere.center - motion.local_center).length() as f64,
            None => reach,
        };
        let drift = ((c1 - c0).as_vec3(), (motion.dangle() * turning) as Real);
        // The walk along the path asks a huge box only for its part near the path (the same
        // first touch: see `near_part`), the contacts below the whole box.
        let places = [motion.start.translation, motion.end.translation];
        let near = near_part(
            fixed,
            pos_fixed,
            (c0.as_vec3(), c1.as_vec3()),
            reach as Real,
        );
        let near_query = near
            .as_ref()
            .map(|part| q.cut_to(part, moving, self.options.tolerance, places));
        let walk = near_query.as_ref().unwrap_or(&q);
        let end = motion.end;
        let d = end.translation - motion.start.translation;
        let (direction, direction_source) = match d.try_normalize() {
            Some(u) if d.length() > 1e-3 * tol => (u, DirectionSource::Trajectory),
            _ => (Vector::ZERO, DirectionSource::ZeroMotionFallback),
        };
        let mut result = ContactConfiguration::separated(direction, direction_source, false, end);
        let first = walk.advance(|t| motion.pose_at(t), speed, Some(drift), 1.0);
        match first {
            Advance::Unsupported => Ok(None),
            Advance::Apart => {
                // Separated all along (closer than the touch tolerance at the end: touching).
                if let Some(c) = q.contact(&end) {
                    result.state = TouchState::Touching;
                    result.patches.push(vertex_patch(c.point1, c.normal1));
                }
                Ok(Some(result))
            }
            Advance::InContact => {
                // In contact when the step began: no first touch on this path, the way out is
                // along the contact normal at the pose now.
                let Some(c) = q.contact(&end) else {
                    return Ok(Some(result));
                };
                result.patches.push(vertex_patch(c.point1, c.normal1));
                if c.dist < -tol {
                    result.state = TouchState::Penetrating;
                    result.reversing_vector = c.normal1 * -c.dist;
                    result.depth = -c.dist;
                    result.touch_pose =
                        Pose::from_parts(end.translation + result.reversing_vector, end.rotation);
                } else {
                    result.state = TouchState::Touching;
                }
                Ok(Some(result))
            }
            Advance::Touch(t) => {
                let touch = motion.pose_at(t);
                let Some(c) = q.contact(&touch) else {
                    return Ok(None);
                };
                result.patches.push(vertex_patch(c.point1, c.normal1));
                let witness = touch.inverse_transform_point(c.point2);
                let travelled =
                    (end.transform_point(witness) - touch.transform_point(witness)).length();
                let penetrating = q.contact(&end).is_some_and(|c| c.dist < -tol);
                result.state = if penetrating {
                    TouchState::Penetrating
                } else {
                    // Not overlapping now: a graze, unless the shape passed through. Advancing
                    // back from the pose now finds the last touch on the path; later than the
                    // first one by more than the touch tolerance, the shape went in and out.
                    let back = walk.advance(
                        |s| motion.pose_at(1.0 - s),
                        speed,
                        Some((-drift.0, drift.1)),
                        1.0 - t,
                    );
                    match back {
                        Advance::Touch(s) if ((1.0 - s) - t) * speed > 2.0 * q.touch => {
                            TouchState::Perforated
                        }
                        Advance::Unsupported => return Ok(None),
                        _ => TouchState::Touching,
                    }
                };
                if result.needs_correction() {
                    result.on_trajectory = true;
                    result.time_of_impact = Some(t);
                    result.touch_pose = touch;
                    result.reversing_vector = touch.translation - end.translation;
                    result.depth = travelled.max(result.reversing_vector.length());
                }
                Ok(Some(result))
            }
        }
    }
}

/// A box `fixed` far larger than the region a path sweeps (`centres`: where the moving
/// shape's centre of mass starts and ends, every point of it within `reach` of that centre):
/// the box cut down to that segment grown by three times the reach, and its pose. `None` for
/// other shapes, or where the cut saves little.
///
/// Along the path every point of the moving shape stays within `reach` of the centre's
/// segment, so the cut's own faces stay at least twice the reach away from it, farther than
/// the touch tolerance: the path first touches the cut part where and when it first touches
/// the box, and the distances the walk reads below the reach are the box's own. GJK in `f32`
/// is no match for a box hundreds of times the shape's size: balls, capsules and cylinders
/// rolling a few millimetres over a 200 m box were answered overlapping at some poses
/// (rapier's CCD stress scene), and the reconstruction took them through the box, walking
/// them back 0.2-1.1 of their size.
fn near_part(
    fixed: &dyn Shape,
    pos_fixed: &Pose,
    centres: (Vector, Vector),
    reach: Real,
) -> Option<(Cuboid, Pose)> {
    let h = fixed.as_cuboid()?.half_extents;
    let (a, b) = (
        pos_fixed.inverse_transform_point(centres.0),
        pos_fixed.inverse_transform_point(centres.1),
    );
    let grow = Vector::splat(3.0 * reach);
    let lo = (a.min(b) - grow).max(-h);
    let hi = (a.max(b) + grow).min(h);
    let half = 0.5 * (hi - lo);
    if !(half.is_finite() && reach.is_finite() && reach > 0.0)
        || half.min_element() <= 0.0
        || 4.0 * half.max_element() > h.max_element()
    {
        return None;
    }
    let center = 0.5 * (hi + lo);
    Some((
        Cuboid::new(half),
        *pos_fixed * Pose::from_translation(center),
    ))
}

/// Shapes closer than this many tolerances touch.
const TOUCH: Real = 10.0;
/// parry's GJK stops when its distance bound improves by less than `√(eps)` of itself (about
/// `1.1e-3`): the distance it answers may be that much too large.
const GJK_REL: Real = 2.0e-3;
/// Advances at most this many times before giving up (to the mesh method).
const MAX_ADVANCES: usize = 128;

/// What conservative advancement found along a path.
enum Advance {
    /// In contact (overlapping or within the touch tolerance) at the path's start.
    InContact,
    /// First within the touch tolerance at this time.
    Touch(Real),
    /// Apart all along.
    Apart,
    /// parry has no distance query for the pair, or the advance did not converge.
    Unsupported,
}

/// A support-map shape on coordinates divided by a unit length.
struct Scaled<'a> {
    shape: &'a dyn SupportMap,
    k: Real,
}

impl SupportMap for Scaled<'_> {
    fn local_support_point(&self, dir: Vector) -> Vector {
        self.shape.local_support_point(dir) * self.k
    }
}

/// [`PairQuery::separation`]'s answer.
struct Separation {
    distance: Real,
    along: Option<(Vector, Real)>,
}

/// parry's distance and contact queries for one pair, the fixed shape at a fixed pose.
///
/// Two support-map shapes are queried (GJK, EPA) on coordinates divided by the smaller
/// shape's diameter: GJK stops at absolute tolerances, and a capsule 1.3 mm long above a box
/// was reported 3.4 mm away when it was 2.3 mm, then overlapping when it was not. A rounded
/// polyhedron is queried as its inner shape, the border radius taken off the distance: GJK on
/// the rounded support map converged to distances millimetres too large near contact (a
/// rounded cuboid turning onto a box read 3.2 mm apart where it overlapped by 1.4 mm, and the
/// advance ended its walk back there, still 1.6 mm in; the random-seed case in
/// `tests/proptest-regressions/curved_reconstruction.txt`). Other pairs (a TriMesh, a
/// compound) go through parry's dispatcher in world units.
struct PairQuery<'a> {
    fixed: &'a dyn Shape,
    pos_fixed: Pose,
    moving: &'a dyn Shape,
    convex: Option<(Scaled<'a>, Scaled<'a>)>,
    /// The border radii of the fixed and the moving shape (world units) around the support
    /// maps in `convex` (zero for shapes that are not rounded).
    borders: (Real, Real),
    /// Both shapes have a size (no query otherwise).
    sized: bool,
    /// One shape is a ball and the other convex: parry's dispatcher answers such a pair
    /// exactly, by projecting the ball's centre (`separation` too).
    ball: bool,
    unit: Real,
    /// The tolerance: the relative tolerance times the smaller diameter, and never below the
    /// `f32` resolution of the coordinates involved.
    tol: Real,
    /// Shapes closer than this touch.
    touch: Real,
}

impl<'a> PairQuery<'a> {
    fn new(
        fixed: &'a dyn Shape,
        pos_fixed: &Pose,
        moving: &'a dyn Shape,
        tolerance: Real,
        places: [Vector; 2],
    ) -> Self {
        let (df, dm) = (
            2.0 * fixed.compute_local_bounding_sphere().radius,
            2.0 * moving.compute_local_bounding_sphere().radius,
        );
        // A shape of no size (a ball of radius 0) is no surface to touch: parry's EPA indexes
        // out of bounds on it. Such a pair gets no query (the mesh method decides).
        let sized = df > 0.0 && dm > 0.0 && df.is_finite() && dm.is_finite();
        let unit = df.min(dm).max(Real::MIN_POSITIVE);
        let magnitude = places
            .iter()
            .map(|p| p.abs().max_element())
            .fold(pos_fixed.translation.abs().max_element(), Real::max)
            .max(df.max(dm));
        let tol = (tolerance.clamp(1e-9, 1e-3) * unit).max(8.0 * Real::EPSILON * magnitude);
        let k = 1.0 / unit;
        // A support map and its border: a rounded polyhedron's inner shape (GJK converges on
        // its finitely many support points), or the shape itself (a rounded cylinder or cone
        // too: its inner shape is as curved, and querying it cost rapier's CCD stress scene
        // 6-18 % for no gain found).
        let split = |s: &'a dyn Shape| match rounded(s) {
            Some((inner, r))
                if inner.as_cuboid().is_some()
                    || inner.as_triangle().is_some()
                    || inner.as_convex_polyhedron().is_some() =>
            {
                inner.as_support_map().map(|i| (i, r))
            }
            _ => s.as_support_map().map(|i| (i, 0.0)),
        };
        // A ball and a convex shape: GJK on the support maps is no match for parry's exact
        // projection of the ball's centre. A ball of 1 m rolling 3-4 mm over a 200 m box
        // (rapier's CCD stress scene) was answered overlapping by GJK at some poses,
        // taken through the box and walked back 0.2-0.9 m.
        let ball = (fixed.as_ball().is_some() && moving.is_convex())
            || (moving.as_ball().is_some() && fixed.is_convex());
        let (convex, borders) = match (split(fixed), split(moving)) {
            _ if ball => (None, (0.0, 0.0)),
            (Some((f, bf)), Some((m, bm))) if bf.is_finite() && bm.is_finite() => (
                Some((Scaled { shape: f, k }, Scaled { shape: m, k })),
                (bf.max(0.0), bm.max(0.0)),
            ),
            _ => (None, (0.0, 0.0)),
        };
        Self {
            fixed,
            pos_fixed: *pos_fixed,
            moving,
            convex,
            borders,
            sized,
            ball,
            unit,
            tol,
            touch: TOUCH * tol,
        }
    }

    /// The same query on `part` of the fixed shape ([`near_part`]), with this one's
    /// tolerances.
    fn cut_to<'b>(
        &self,
        part: &'b (Cuboid, Pose),
        moving: &'b dyn Shape,
        tolerance: Real,
        places: [Vector; 2],
    ) -> PairQuery<'b> {
        let mut q = PairQuery::new(&part.0, &part.1, moving, tolerance, places);
        (q.tol, q.touch) = (self.tol, self.touch);
        q
    }

    /// The two border radii together (world units).
    fn border(&self) -> Real {
        self.borders.0 + self.borders.1
    }

    /// The moving shape's pose in the fixed one's frame, on the scaled coordinates.
    fn scaled_pose(&self, pose: &Pose) -> Pose {
        let mut p = self.pos_fixed.inv_mul(pose);
        p.translation /= self.unit;
        p
    }

    /// The distance with `moving` at `pose` (0 when overlapping), `None` when parry has no
    /// query for the pair.
    fn distance(&self, pose: &Pose) -> Option<Real> {
        if !self.sized {
            return None;
        }
        let d = match &self.convex {
            Some((f, m)) => {
                let inner =
                    query::details::distance_support_map_support_map(&self.scaled_pose(pose), f, m);
                (inner * self.unit - self.border()).max(0.0)
            }
            None => {
                query::distance(&self.pos_fixed, self.fixed, pose, self.moving)
                    .ok()?
                    .distance
            }
        };
        d.is_finite().then_some(d)
    }

    /// For two support-map shapes: GJK's distance at `pose` (as [`PairQuery::distance`]) and,
    /// apart, the unit direction (world) from `fixed`'s closest point to `moving`'s and how
    /// far apart the two are along it, exactly, from one support point of each (GJK's distance
    /// is an upper bound; this one bounds the true distance from below). For a ball and a
    /// convex shape, parry's exact distance and normal. `None` for other pairs, or where GJK
    /// does not converge.
    fn separation(&self, pose: &Pose) -> Option<Separation> {
        if self.ball && self.sized {
            // Exact: the ball's centre projected onto the other shape. Apart, the convex
            // shape lies behind the tangent plane at the projection, the ball `dist` in front.
            let c = query::contact(&self.pos_fixed, self.fixed, pose, self.moving, Real::MAX)
                .ok()??;
            if !(c.dist.is_finite() && c.normal1.is_finite()) {
                return None;
            }
            return Some(Separation {
                distance: c.dist.max(0.0),
                along: (c.dist > 0.0).then_some((c.normal1, c.dist)),
            });
        }
        let (f, m) = self.convex.as_ref().filter(|_| self.sized)?;
        let pos12 = self.scaled_pose(pose);
        let dir = (-pos12.translation).try_normalize().unwrap_or(Vector::X);
        let mut simplex = query::gjk::VoronoiSimplex::new();
        simplex.reset(query::gjk::CsoPoint::from_shapes(&pos12, f, m, dir));
        let (p1, p2) = match query::gjk::closest_points(&pos12, f, m, Real::MAX, true, &mut simplex)
        {
            query::gjk::GJKResult::ClosestPoints(p1, p2, _) => (p1, p2),
            query::gjk::GJKResult::Intersection => {
                return Some(Separation {
                    distance: 0.0,
                    along: None,
                })
            }
            _ => return None,
        };
        let distance = ((p2 - p1).length() * self.unit - self.border()).max(0.0);
        if !distance.is_finite() {
            return None;
        }
        let along = (p2 - p1).try_normalize().and_then(|n| {
            let top = f.local_support_point_toward(n).dot(n);
            let bottom = m.support_point_toward(&pos12, -n).dot(n);
            let gap = (bottom - top) * self.unit - self.border();
            let n = self.pos_fixed.rotation * n;
            (gap.is_finite() && n.is_finite()).then_some((n, gap))
        });
        Some(Separation { distance, along })
    }

    /// The contact with `moving` at `pose` (in world space), if closer than twice the touch
    /// tolerance.
    fn contact(&self, pose: &Pose) -> Option<query::Contact> {
        if !self.sized {
            return None;
        }
        let prediction = 2.0 * self.touch;
        let c = match &self.convex {
            Some((f, m)) => {
                let (bf, bm) = self.borders;
                let c = query::details::contact_support_map_support_map(
                    &self.scaled_pose(pose),
                    f,
                    m,
                    (prediction + bf + bm) / self.unit,
                )?;
                // The inner shapes' contact, moved out to the borders along the normals.
                query::Contact::new(
                    self.pos_fixed
                        .transform_point(c.point1 * self.unit + c.normal1 * bf),
                    pose.transform_point(c.point2 * self.unit + c.normal2 * bm),
                    self.pos_fixed.rotation * c.normal1,
                    pose.rotation * c.normal2,
                    c.dist * self.unit - bf - bm,
                )
            }
            None => query::contact(&self.pos_fixed, self.fixed, pose, self.moving, prediction)
                .ok()??,
        };
        (c.dist.is_finite() && c.normal1.is_finite()).then_some(c)
    }

    /// Conservative advancement (Mirtich) along `pose_at` over `[0, until]`: at a distance `d`
    /// nothing of `moving` can reach `fixed` sooner than `d / speed`, where `speed` bounds how
    /// fast any of its points moves; advancing by that much never steps past the first touch,
    /// however the shape turns. (parry's own nonlinear shape cast, which bisects along one
    /// separating axis, answered a first touch at `t = 1e-6` for a spinning rounded hull still
    /// 38 mm from the floor, which froze the hull in place step after step.)
    fn advance(
        &self,
        pose_at: impl Fn(Real) -> Pose,
        speed: Real,
        drift: Option<(Vector, Real)>,
        until: Real,
    ) -> Advance {
        let mut t: Real = 0.0;
        let mut apart: Real = 0.0;
        for _ in 0..MAX_ADVANCES {
            let pose = pose_at(t);
            let sep = drift.and_then(|_| self.separation(&pose));
            let Some(d) = sep
                .as_ref()
                .map(|s| s.distance)
                .or_else(|| self.distance(&pose))
            else {
                return Advance::Unsupported;
            };
            if t == 0.0 && d <= self.touch {
                return Advance::InContact;
            }
            if d > 0.0 && d <= self.touch {
                return Advance::Touch(t);
            }
            if d == 0.0 {
                // Overlapping: GJK's distance at the last step was too large (it can be, where
                // a support map jumps: 5.2e-4 answered for 1e-4 at a cone's rim). Between the
                // last pose found apart and this one the motion is short: bisect on GJK's
                // overlap test, which does not suffer from that, down to the touch tolerance.
                let (mut lo, mut hi) = (apart, t);
                for _ in 0..MAX_ADVANCES {
                    if (hi - lo) * speed <= self.touch {
                        break;
                    }
                    let mid = 0.5 * (lo + hi);
                    match self.distance(&pose_at(mid)) {
                        Some(d) if d > 0.0 => lo = mid,
                        Some(_) => hi = mid,
                        None => return Advance::Unsupported,
                    }
                }
                return Advance::Touch(lo);
            }
            if speed <= 0.0 {
                return Advance::Apart;
            }
            apart = t;
            // Stop inside the touch band, not at its edge. GJK's distance is an upper bound
            // that stops within `GJK_REL` of itself: advance by what surely separates.
            let mut step = (d * (1.0 - GJK_REL) - 0.5 * self.touch) / speed;
            // Two convex shapes are at least `gap` apart along `n`, and that gap shrinks no
            // faster than the centre closes along `n` plus the arc any point turns through:
            // a body sliding past (a rolling cone, a box skidding on the floor) closes slowly
            // along `n` however fast it goes. (These queries were a quarter of the touch
            // pipeline's time on rapier's CCD scene; with this bound a call takes 4.8 of them
            // on average there, and the scene's step 7-10 % less.)
            if let (Some((v, arc)), Some((n, gap))) = (drift, sep.and_then(|s| s.along)) {
                let closing = (-v.dot(n)).max(0.0) + arc;
                let safe = gap.min(d * (1.0 - GJK_REL)) - 0.5 * self.touch;
                if closing <= 0.0 && safe > 0.0 {
                    return Advance::Apart;
                }
                if closing > 0.0 {
                    step = step.max(safe / closing);
                }
            }
            t += step;
            if t > until {
                return Advance::Apart;
            }
        }
        Advance::Unsupported
    }
}

/// The single patch of a curved contact: a point with the fixed shape's normal, no features.
fn vertex_patch(point: Vector, normal: Vector) -> ContactPatch {
    ContactPatch {
        kind: ContactKind::Vertex,
        normal,
        polygon: vec![point],
        points: Vec::new(),
        fixed_features: Vec::new(),
        moving_features: Vec::new(),
    }
}

impl Reconstructor {
    /// The way out of an overlap along a given direction, on the shapes themselves: `moving`
    /// at `pos_moving` is translated along `out` (a world direction, out of `fixed`) to where
    /// it only touches `fixed`, advancing (as [`Reconstructor::reconstruct_shapes`] does) from
    /// a pose outside back toward the pose now. The curved-shape counterpart of [`Reconstructor::reconstruct`] with
    /// [`ReconstructionOptions::zero_motion_direction`](super::ReconstructionOptions) set to
    /// `-out` and no motion: `on_trajectory` is false and the single patch is a
    /// [`ContactKind::Vertex`] without features.
    ///
    /// `Ok(None)` when parry has no distance query for the pair, a shape has no size, or the
    /// shapes still overlap after a translation by both bounding diameters (use the mesh
    /// method then).
    ///
    /// # Errors
    /// [`ReconstructionError::NonFinitePose`] for a NaN or infinite pose,
    /// [`ReconstructionError::InvalidFallbackDirection`] for a zero or non-finite `out`.
    ///
    /// # Example
    /// ```
    /// use rapier_touch::parry3d::shape::Ball;
    /// use rapier_touch::prelude::*;
    /// let slab = Cuboid::new(Vector::new(2.0, 0.5, 2.0));
    /// let ball = Ball::new(0.25);
    /// // The ball sinks 0.1 m into the slab's top face (y = 0).
    /// let now = Pose::from_translation(Vector::new(0.0, 0.15, 0.0));
    /// let c = Reconstructor::default()
    ///     .push_out_shapes(&slab, &Pose::from_translation(Vector::new(0.0, -0.5, 0.0)), &ball, &now, Vector::Y)
    ///     .unwrap()
    ///     .unwrap();
    /// assert_eq!(c.state, TouchState::Penetrating);
    /// assert!((c.depth - 0.1).abs() < 1e-4);
    /// ```
    pub fn push_out_shapes(
        &mut self,
        fixed: &dyn Shape,
        pos_fixed: &Pose,
        moving: &dyn Shape,
        pos_moving: &Pose,
        out: Vector,
    ) -> Result<Option<ContactConfiguration>, ReconstructionError> {
        if !(pos_fixed.is_finite() && pos_moving.is_finite()) {
            return Err(ReconstructionError::NonFinitePose);
        }
        let Some(out) = out.try_normalize().filter(|o| o.is_finite()) else {
            return Err(ReconstructionError::InvalidFallbackDirection);
        };
        let (rf, rm) = (
            fixed.compute_local_bounding_sphere().radius,
            moving.compute_local_bounding_sphere().radius,
        );
        let q = PairQuery::new(
            fixed,
            pos_fixed,
            moving,
            self.options.tolerance,
            [pos_moving.translation; 2],
        );
        let mut result = ContactConfiguration::separated(
            -out,
            DirectionSource::ZeroMotionFallback,
            false,
            *pos_moving,
        );
        // Come back toward the pose now from a moving diameter out (an overlap is rarely
        // deeper), then from past both shapes, until first touch.
        for reach in [4.0 * rm, 2.0 * (rf + rm)] {
            let pose_at = |s: Real| {
                Pose::from_parts(
                    pos_moving.translation + out * (reach * (1.0 - s)),
                    pos_moving.rotation,
                )
            };
            let s = match q.advance(pose_at, reach, None, 1.0) {
                Advance::Unsupported => return Ok(None),
                Advance::InContact => continue,
                Advance::Apart => return Ok(Some(result)),
                Advance::Touch(s) => s,
            };
            let touch = pose_at(s);
            let Some(c) = q.contact(&touch) else {
                return Ok(None);
            };
            result.patches.push(vertex_patch(c.point1, c.normal1));
            let depth = reach * (1.0 - s);
            if depth > q.touch {
                result.state = TouchState::Penetrating;
                result.reversing_vector = out * depth;
                result.depth = depth;
                result.touch_pose = touch;
            } else {
                result.state = TouchState::Touching;
            }
            return Ok(Some(result));
        }
        Ok(None)
    }
}
