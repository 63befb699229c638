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
use super::shapes::shape_reach;
use crate::math::{Pose, Real, Vector};
use pair_query::{near_part, Advance, PairQuery};
use parry3d::shape::Shape;

mod pair_query;

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
        let places = [motion.start.translation, motion.end.translation];
        let q = PairQuery::new(fixed, pos_fixed, moving, self.options.tolerance, places);
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
        // The walk along the path and the contacts below ask a huge box only for its part near
        // the path (the same first touch and the same contacts: see `near_part`). Asked of the
        // whole 188 km slab, a 940 m capsule sliding on it 5 m deep read touching.
        let near = near_part(
            fixed,
            pos_fixed,
            (c0.as_vec3(), c1.as_vec3()),
            reach as Real,
        );
        let near_query = near.as_ref().map(|part| q.cut_to(part));
        let walk = near_query.as_ref().unwrap_or(&q);
        let tol = walk.tol;
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
            // In contact when the step began: no first touch on this path, the way out is
            // along the contact normal at the pose now. A path read apart all along whose end
            // overlaps (closer than the touch tolerance there, it only touches) is one where
            // the advance's bound on parry's distance missed the touch (a 13 m cone tumbling
            // onto a plate 50 times its size, 0.34 m deep at the end, was read apart all along
            // and left there): its crossing is looked for on the path (below), and the way out
            // is along the normal only where none is found.
            Advance::Apart | Advance::InContact => {
                let Some(c) = walk.contact(&end) else {
                    return Ok(Some(result));
                };
                // Read apart all along but overlapping at the end: the path crosses into
                // `fixed` somewhere the advance's bound missed. Apart at the start, the
                // crossing is found on the path itself (bisection on parry's distance) and
                // walked back to, as a first touch the advance found would be.
                if matches!(first, Advance::Apart) && c.dist < -tol {
                    if let Some(t) = crossing(walk, motion, speed) {
                        let touch = motion.pose_at(t);
                        if let Some(c) = walk.contact(&touch) {
                            result.patches.push(vertex_patch(c.point1, c.normal1));
                            result.state = TouchState::Penetrating;
                            walk_back_to(&mut result, (t, touch), &end, c.point2);
                            return Ok(Some(result));
                        }
                    }
                }
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
                let Some(c) = walk.contact(&touch) else {
                    return Ok(None);
                };
                result.patches.push(vertex_patch(c.point1, c.normal1));
                let penetrating = walk.contact(&end).is_some_and(|c| c.dist < -tol);
                result.state = if penetrating {
                    TouchState::Penetrating
                } else {
                    // Not overlapping now: a graze, unless the shape passed through. Advancing
                    // back from the pose now finds the last touch on the path; later than the
                    // first one by more than the touch tolerance, the shape went in and out,
                    // and then it overlaps halfway between the two (a shape that passed
                    // through a plate is halfway through it there). A path that only closed
                    // on the surface does not: a rounded cylinder sliding down to 0.19 % of its
                    // size over a box 80 times larger, in the touch band at the end by parry's
                    // contact but not by the advance's bound, had its last touch at 0.9995 of
                    // the step and its first at 0.9951, and was read perforated.
                    let back = walk.advance(
                        |s| motion.pose_at(1.0 - s),
                        speed,
                        Some((-drift.0, drift.1)),
                        1.0 - t,
                    );
                    match back {
                        Advance::Touch(s)
                            if passed_through(walk, motion, (speed, drift), (t, 1.0 - s), 3) =>
                        {
                            TouchState::Perforated
                        }
                        Advance::Unsupported => return Ok(None),
                        _ => TouchState::Touching,
                    }
                };
                if result.needs_correction() {
                    walk_back_to(&mut result, (t, touch), &end, c.point2);
                }
                Ok(Some(result))
            }
        }
    }
}

/// Whether `moving` (along `motion`, its speed bound and drift as [`PairQuery::advance`]
/// takes them) went into `fixed` and out again between a first touch and a last touch
/// (`first`, `last`): it overlaps halfway between them (a shape that passed through a plate is
/// halfway through it there), unless they are within the touch tolerance's travel of each
/// other (a graze). Apart halfway, the stretch holds two contacts, each checked the same way
/// (up to `splits` times deep): the last touch before the middle and the first after it
/// bound them. A rounded box turning as it slid over a box dipped in 2.6 mm and came out,
/// then dipped in 2.3 mm and came out again; apart halfway between its first and last touch,
/// it was read as a graze, and left as it was.
fn passed_through(
    walk: &PairQuery<'_>,
    motion: &RigidMotion,
    (speed, drift): (Real, (Vector, Real)),
    (first, last): (Real, Real),
    splits: u32,
) -> bool {
    if (last - first) * speed <= 2.0 * walk.touch {
        return false;
    }
    let mid = 0.5 * (first + last);
    if walk.distance(&motion.pose_at(mid)).is_none_or(|d| d <= 0.0) {
        return true;
    }
    if splits == 0 {
        return false;
    }
    let before = match walk.advance(
        |s| motion.pose_at(mid - s),
        speed,
        Some((-drift.0, drift.1)),
        mid - first,
    ) {
        Advance::Touch(s) => mid - s,
        _ => first,
    };
    let after = match walk.advance(|s| motion.pose_at(mid + s), speed, Some(drift), last - mid) {
        Advance::Touch(s) => mid + s,
        _ => last,
    };
    let next = (speed, drift);
    passed_through(walk, motion, next, (first, before), splits - 1)
        || passed_through(walk, motion, next, (after, last), splits - 1)
}

/// Where `motion`, apart from `walk`'s fixed shape at its start and overlapping it at its end,
/// crosses into it: the last time found apart by bisection on parry's distance, within the
/// touch tolerance's travel of an overlapping one (`speed` bounds any point's travel per unit
/// of `t`). `None` when the start is not apart or a distance is not answered.
fn crossing(walk: &PairQuery<'_>, motion: &RigidMotion, speed: Real) -> Option<Real> {
    if walk.distance(&motion.pose_at(0.0))? <= 0.0 {
        return None;
    }
    walk.last_apart(|t| motion.pose_at(t), speed, (0.0, 1.0))
}

/// Sets `result` to be walked back along `motion` to its first touch at `t`: the touch pose,
/// the translation back to it from the pose now (`end`), and the depth, at least how far the
/// point of the moving shape that touches there (`witness`, world, at the touch) travelled
/// since.
fn walk_back_to(
    result: &mut ContactConfiguration,
    (t, touch): (Real, Pose),
    end: &Pose,
    witness: Vector,
) {
    let local = touch.inverse_transform_point(witness);
    let travelled = (end.transform_point(local) - touch.transform_point(local)).length();
    result.on_trajectory = true;
    result.time_of_impact = Some(t);
    result.touch_pose = touch;
    result.reversing_vector = touch.translation - end.translation;
    result.depth = travelled.max(result.reversing_vector.length());
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

/// parry's contact of `moving` at `pos_moving` with `fixed` at `pos_fixed` (world: points,
/// `normal1` out of `fixed`, `dist` negative when they overlap) when closer than `prediction`
/// (`Some(None)` when farther), asked as the shape method asks it: on coordinates scaled to the
/// smaller shape, a rounded polyhedron as its inner shape and border, and of a huge box only its
/// part near `moving` (`near_part`). `None` when parry has no contact query for the pair, a
/// shape has no size or a pose is not finite. parry's query on the whole box is no match for a
/// box hundreds of times the shape's size: rapier's own contact normal (the same `f32` query)
/// for a cone lying on the top of a box 200 times its size read (-0.69, 0.19, -0.69), and a
/// 938 m capsule rolling on a plate 100 times its size, its depth read on the whole plate, sank
/// 0.34 of the plate's thickness (0.02 with this query).
pub(crate) fn contact_near(
    fixed: &dyn Shape,
    pos_fixed: &Pose,
    moving: &dyn Shape,
    pos_moving: &Pose,
    prediction: Real,
) -> Option<Option<parry3d::query::Contact>> {
    if !(pos_fixed.is_finite() && pos_moving.is_finite() && prediction.is_finite()) {
        return None;
    }
    let reach = shape_reach(moving);
    let places = [pos_moving.translation; 2];
    let tolerance = super::ReconstructionOptions::default().tolerance;
    let q = PairQuery::new(fixed, pos_fixed, moving, tolerance, places);
    let prediction = prediction.max(0.0);
    // The cut keeps the box's own answers within twice the reach of the shape; a prediction
    // beyond that is asked of the whole box.
    let part =
        near_part(fixed, pos_fixed, (places[0], places[1]), reach).filter(|_| prediction <= reach);
    match &part {
        Some(part) => q.cut_to(part).contact_within(pos_moving, prediction),
        None => q.contact_within(pos_moving, prediction),
    }
}

impl Reconstructor {
    /// The way out of an overlap along a given direction, on the shapes themselves: `moving`
    /// at `pos_moving` is translated along `out` (a world direction, out of `fixed`) to where
    /// it only touches `fixed`, advancing (as [`Reconstructor::reconstruct_shapes`] does) from
    /// a pose outside back toward the pose now. The curved-shape counterpart of [`Reconstructor::reconstruct`] with
    /// [`ReconstructionOptions::zero_motion_direction`](super::ReconstructionOptions) set to
    /// `-out` and no motion: `on_trajectory` is false and the single patch is a
    /// [`ContactKind::Vertex`] without features. A box far larger than `moving` is asked only
    /// for its part near the way back, as the walk along a path asks it (parry's `f32` queries
    /// on the whole of a box 200 times a cone's size read the cone apart while it was 1.9 m
    /// in).
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
        let reach_m = shape_reach(moving);
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
            // Of a huge box, only its part near the way back (`near_part`: every point of
            // `moving` stays within `reach_m` of its origin's segment).
            let places = [pose_at(0.0).translation, pos_moving.translation];
            let near = near_part(fixed, pos_fixed, (places[0], places[1]), reach_m);
            let near_query = near.as_ref().map(|part| q.cut_to(part));
            let q = near_query.as_ref().unwrap_or(&q);
            let s = match q.advance(pose_at, reach, None, 1.0) {
                Advance::Unsupported => return Ok(None),
                Advance::InContact => continue,
                Advance::Apart => return Ok(Some(result)),
                Advance::Touch(s) => s,
            };
            let touch = pose_at(s);
            // The contact where the advance touched, however far parry's contact query reads
            // it: the two queries can disagree near a rim (a cone 3.2 % of its size into a box
            // stopped at a touch its contact read 1.29e-4 off, past twice the 5.6e-5 band,
            // and got no way out at all). Its distance is the gap the depth leaves.
            let Some(c) = q.contact_within(&touch, Real::MAX).flatten() else {
                return Ok(None);
            };
            result.patches.push(vertex_patch(c.point1, c.normal1));
            // The advance stops within the touch band, up to `touch` short of touching: moved
            // back by the gap left there, no point of the mover gets closer than that gap
            // (`c.dist`), so the shapes still do not overlap. Taken as the depth, the gap
            // lifted a ball rolling on rapier's 200 m CCD floor (then a 2.7 mm band) 0.5 mm
            // off the floor at every push, and it fell back in: a push out of nothing.
            let depth = reach * (1.0 - s) - c.dist.max(0.0);
            if depth > q.touch {
                result.state = TouchState::Penetrating;
                result.reversing_vector = out * depth;
                result.depth = depth;
                result.touch_pose =
                    Pose::from_parts(pos_moving.translation + out * depth, pos_moving.rotation);
            } else {
                result.state = TouchState::Touching;
            }
            return Ok(Some(result));
        }
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rotation;
    use parry3d::shape::{Ball, Capsule, Cone, Cuboid};

    /// A cone, a capsule and a cuboid lying 0.1-0.3 % of their size into the top of a plate 400
    /// times their size, turned every way, at 1 mm, 1 m and 1 km: `contact_near`'s depth is the
    /// depth of the shape's lowest point under the plate's top (its support point, computed
    /// here) within 1e-5 of the shape's size (the cone: 2e-3; measured 1.2e-7, 1.1e-6 and
    /// 1.3e-3), and its normal is the plate's up. parry's query on the whole plate read the same
    /// depths up to 3.8 % of the size off (not asserted: the test does not rest on it). Bad
    /// input: a pose that is not finite and a ball of no size get no answer.
    #[test]
    fn contact_near_reads_a_shape_on_a_huge_plate_as_its_lowest_point_says() {
        for scale in [1e-3, 1.0, 1e3] {
            let plate = Cuboid::new(Vector::new(200.0, 0.02, 200.0) * scale);
            let plate_pose = Pose::from_translation(Vector::new(30.0, -0.02, -40.0) * scale);
            let shapes: [Box<dyn Shape>; 3] = [
                Box::new(Cone::new(0.5 * scale, 0.4 * scale)),
                Box::new(Capsule::new_y(0.3 * scale, 0.2 * scale)),
                Box::new(Cuboid::new(Vector::new(0.5, 0.2, 0.3) * scale)),
            ];
            // parry's EPA at a cone's tip or rim is good to about a thousandth of its size.
            let tolerance = [2e-3, 1e-5, 1e-5];
            for (i, shape) in shapes.iter().enumerate() {
                for k in 0..40 {
                    let t = k as Real;
                    let rot = Rotation::from_axis_angle(
                        Vector::new((0.7 * t).sin(), 1.0, (1.3 * t + i as Real).cos()).normalize(),
                        0.41 * t,
                    );
                    let depth = (0.001 + 0.002 * (0.3 * t).sin().abs()) * scale;
                    let sm = shape.as_support_map().unwrap();
                    let low = sm
                        .support_point_toward(&Pose::from_rotation(rot), -Vector::Y)
                        .y;
                    let at = Vector::new(5.0 + (0.9 * t).sin(), 0.0, (0.5 * t).cos() - 3.0) * scale
                        - Vector::Y * (depth + low);
                    let pose = Pose::from_parts(at, rot);
                    let c = contact_near(&plate, &plate_pose, &**shape, &pose, 0.0)
                        .expect("a query")
                        .unwrap_or_else(|| panic!("shape {i} at {scale}, pose {k}: apart"));
                    assert!(
                        (-c.dist - depth).abs() <= tolerance[i] * scale && c.normal1.y > 0.999,
                        "shape {i} at {scale}, pose {k}: depth {} for {depth}, normal {:?}",
                        -c.dist,
                        c.normal1
                    );
                }
            }
        }
        let plate = Cuboid::new(Vector::new(200.0, 0.02, 200.0));
        let nan = Pose::from_translation(Vector::new(Real::NAN, 0.0, 0.0));
        let ball = Ball::new(0.5);
        assert!(contact_near(&plate, &Pose::IDENTITY, &ball, &nan, 0.0).is_none());
        let point = Ball::new(0.0);
        assert!(contact_near(&plate, &Pose::IDENTITY, &point, &Pose::IDENTITY, 0.0).is_none());
    }
}
