//! The queries the shape method ([`super`]) walks on: parry's distance and contact for one
//! pair of shapes, on coordinates scaled to the smaller one, with conservative advancement
//! along a path (`PairQuery`), and a huge box cut down to the part near a path
//! (`near_part`).

use super::super::tool_boundary::rounded;
use crate::math::{Pose, Real, Vector};
use parry3d::query;
use parry3d::shape::{Cuboid, Shape, SupportMap};

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
pub(super) fn near_part(
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
/// The least tolerance of a huge box's part near a path (`PairQuery::cut_to`), relative to the
/// smaller shape's diameter, where the whole box's is coarser: a touch band of a thousandth of
/// the shape. Down at the `f32` resolution of the coordinates near the path, conservative
/// advancement took more steps to reach its band, and the guard measured rolling bodies'
/// steady millimetre overlaps (rapier's own) and pushed them back each step: rapier's CCD
/// stress scene took 40 % longer (its convex-hull pile 20 %), and a cone rolling on a 200 m
/// floor (`tests/it/toppling.rs`) rolled less than half as far as in vanilla rapier.
const PART_TOLERANCE: Real = 1e-4;
/// parry's GJK stops when its distance bound improves by less than `√(eps)` of itself (about
/// `1.1e-3`): the distance it answers may be that much too large.
const GJK_REL: Real = 2.0e-3;
/// Advances at most this many times before giving up (to the mesh method).
const MAX_ADVANCES: usize = 128;

/// What conservative advancement found along a path.
pub(super) enum Advance {
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
pub(super) struct PairQuery<'a> {
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
    pub(super) tol: Real,
    /// Shapes closer than this touch.
    pub(super) touch: Real,
    /// The relative tolerance and the places the query was asked for (`cut_to` sets its own
    /// tolerances from them).
    relative: Real,
    places: [Vector; 2],
}

impl<'a> PairQuery<'a> {
    pub(super) fn new(
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
            relative: tolerance,
            places,
        }
    }

    /// The same query on `part` of the fixed shape ([`near_part`]), with this one's moving
    /// shape, relative tolerance and places. Its tolerance is the `f32` resolution of the
    /// coordinates near the path, not of the whole box's far corners (the whole of rapier's
    /// 200 m CCD floor made a touch band of 2.7 mm: a ball 1.3 cm across sliding on a plate
    /// 400 times its size, 0.53 mm thick, read touching 0.13 of the thickness deep), but no
    /// finer than [`PART_TOLERANCE`] of the smaller shape where the whole box's was coarser.
    pub(super) fn cut_to<'b>(&self, part: &'b (Cuboid, Pose)) -> PairQuery<'b>
    where
        'a: 'b,
    {
        let mut q = PairQuery::new(&part.0, &part.1, self.moving, self.relative, self.places);
        let tol = q.tol.max(self.tol.min(PART_TOLERANCE * q.unit));
        (q.tol, q.touch) = (tol, TOUCH * tol);
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
    pub(super) fn distance(&self, pose: &Pose) -> Option<Real> {
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
            let gap = self.gap_local((f, m), &pos12, n);
            let n = self.pos_fixed.rotation * n;
            (gap.is_finite() && n.is_finite()).then_some((n, gap))
        });
        Some(Separation { distance, along })
    }

    /// For two support-map shapes: how far apart they are along the unit world direction `n`
    /// (out of `fixed`) with `moving` at `pose`, from one support point of each: a bound on
    /// their distance from below (negative where they overlap along `n`). `None` for other
    /// pairs.
    fn gap_along(&self, pose: &Pose, n: Vector) -> Option<Real> {
        let shapes = self.convex.as_ref().filter(|_| self.sized)?;
        let n = self.pos_fixed.rotation.inverse() * n;
        let gap = self.gap_local((&shapes.0, &shapes.1), &self.scaled_pose(pose), n);
        gap.is_finite().then_some(gap)
    }

    /// [`PairQuery::gap_along`] on the scaled shapes `(f, m)`, `m` at `pos12` and `n` in
    /// `fixed`'s frame.
    fn gap_local(&self, (f, m): (&Scaled<'_>, &Scaled<'_>), pos12: &Pose, n: Vector) -> Real {
        let top = f.local_support_point_toward(n).dot(n);
        let bottom = m.support_point_toward(pos12, -n).dot(n);
        (bottom - top) * self.unit - self.border()
    }

    /// The contact with `moving` at `pose` (in world space), if closer than twice the touch
    /// tolerance.
    pub(super) fn contact(&self, pose: &Pose) -> Option<query::Contact> {
        self.contact_within(pose, 2.0 * self.touch).flatten()
    }

    /// The contact with `moving` at `pose` (in world space) if closer than `prediction`
    /// (`Some(None)` when farther), `None` when parry has no query for the pair or answers a
    /// contact that is not finite.
    pub(super) fn contact_within(
        &self,
        pose: &Pose,
        prediction: Real,
    ) -> Option<Option<query::Contact>> {
        if !self.sized {
            return None;
        }
        let c = match &self.convex {
            Some((f, m)) => {
                let (bf, bm) = self.borders;
                let Some(c) = query::details::contact_support_map_support_map(
                    &self.scaled_pose(pose),
                    f,
                    m,
                    (prediction + bf + bm) / self.unit,
                ) else {
                    return Some(None);
                };
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
            None => {
                match query::contact(&self.pos_fixed, self.fixed, pose, self.moving, prediction)
                    .ok()?
                {
                    Some(c) => c,
                    None => return Some(None),
                }
            }
        };
        // (A contact that is not finite is no answer, not an answer of apart.)
        (c.dist.is_finite() && c.normal1.is_finite()).then_some(Some(c))
    }

    /// The last time of `[lo, hi]` found apart along `pose_at` (`lo` apart, `hi` overlapping),
    /// by bisection on parry's distance, whose overlap test holds where its distance does not,
    /// down to the touch tolerance's travel at `speed` (any point's travel per unit of time;
    /// at most [`MAX_ADVANCES`] halvings). `None` where parry answers no distance.
    pub(super) fn last_apart(
        &self,
        pose_at: impl Fn(Real) -> Pose,
        speed: Real,
        (mut lo, mut hi): (Real, Real),
    ) -> Option<Real> {
        for _ in 0..MAX_ADVANCES {
            if (hi - lo) * speed <= self.touch {
                break;
            }
            let mid = 0.5 * (lo + hi);
            if self.distance(&pose_at(mid))? > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(lo)
    }

    /// Conservative advancement (Mirtich) along `pose_at` over `[0, until]`: at a distance `d`
    /// nothing of `moving` can reach `fixed` sooner than `d / speed`, where `speed` bounds how
    /// fast any of its points moves; advancing by that much never steps past the first touch,
    /// however the shape turns. (parry's own nonlinear shape cast, which bisects along one
    /// separating axis, answered a first touch at `t = 1e-6` for a spinning rounded hull still
    /// 38 mm from the floor, which froze the hull in place step after step.)
    pub(super) fn advance(
        &self,
        pose_at: impl Fn(Real) -> Pose,
        speed: Real,
        drift: Option<(Vector, Real)>,
        until: Real,
    ) -> Advance {
        let mut t: Real = 0.0;
        let mut apart: Real = 0.0;
        // The last direction the shapes were found apart along (`separation`).
        let mut last_apart: Option<Vector> = None;
        for _ in 0..MAX_ADVANCES {
            let pose = pose_at(t);
            let sep = self.separation(&pose);
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
                return match self.last_apart(&pose_at, speed, (apart, t)) {
                    Some(lo) => Advance::Touch(lo),
                    None => Advance::Unsupported,
                };
            }
            if speed <= 0.0 {
                return Advance::Apart;
            }
            apart = t;
            // Stop inside the touch band, not at its edge. GJK's distance is an upper bound
            // that stops within `GJK_REL` of itself: advance by what surely separates. Where
            // GJK stopped on a direction that does not separate the shapes, its distance is
            // no measure: a cylinder 12.6 m across coming down onto a box's face, 0.065 m over
            // it, read 6.08 m apart along a direction it overlapped the box 37.5 m along, and
            // the advance stepped past the whole box (a push out of it, 0.67 m deep, read
            // `Separated`). So where the support points' gap along GJK's direction (a bound
            // from below) is under half its distance, the step is bounded by that gap or by
            // the gap along the last direction the shapes were found apart along, whichever
            // is larger; with neither apart, it crawls by half the touch band (an overlap it
            // runs into is bisected, above). (Asked at every step, the second gap's support
            // points cost rapier's CCD scene 10 % of its touch step.)
            let gjk_sure = d * (1.0 - GJK_REL);
            let along_now = sep.as_ref().and_then(|s| s.along);
            let sure = match along_now {
                Some((_, gap)) if gap < 0.5 * d => {
                    let below = last_apart
                        .and_then(|n| self.gap_along(&pose, n))
                        .map_or(gap, |g| g.max(gap));
                    below.min(gjk_sure).max(self.touch)
                }
                _ => gjk_sure,
            };
            if let Some((n, _)) = along_now.filter(|(_, gap)| *gap > 0.0) {
                last_apart = Some(n);
            }
            let mut step = (sure - 0.5 * self.touch) / speed;
            // Two convex shapes are at least `gap` apart along `n`, and that gap shrinks no
            // faster than the centre closes along `n` plus the arc any point turns through:
            // a body sliding past (a rolling cone, a box skidding on the floor) closes slowly
            // along `n` however fast it goes. (These queries were a quarter of the touch
            // pipeline's time on rapier's CCD scene; with this bound a call takes 4.8 of them
            // on average there, and the scene's step 7-10 % less.)
            if let (Some((v, arc)), Some((n, gap))) = (drift, along_now) {
                let closing = (-v.dot(n)).max(0.0) + arc;
                let safe = gap.min(gjk_sure) - 0.5 * self.touch;
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
