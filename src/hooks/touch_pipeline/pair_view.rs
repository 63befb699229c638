//! One pair as the step guard reads it ([`PairView`]), what it remembers of a pair between
//! steps ([`PairState`]), the checks that leave a slow or a resting pair to rapier
//! ([`slow_pair_calm`], [`resting_within`]), and the way out of an overlap ([`push_out`]).

use super::rapier_contacts::{collider_pose_now, corner_reach, rapier_contact_of, RapierContact};
use super::*;
use crate::geometry::{apart_from_mesh, contact_near, ContactConfiguration};
use crate::hooks::step_motion::point_travel;
use crate::math::Rotation;

/// The overlap of a pair when it was last measured, and the mover's collider pose relative
/// to the partner's then.
///
/// The overlap of two rigid shapes is a function of their relative pose alone, and moves by
/// no more than the mover's points moved in the partner's frame: at a later relative pose it
/// is at most [`PairState::bound`], however both bodies got there (their steps, the guard's
/// corrections). Two bodies falling side by side keep their bound for as long as they keep
/// their places. (The bodies' odometers, summed paths, bounded it before: every step of a
/// falling pile spent them, and a correction was left out of them.)
///
/// A pair found apart also keeps the direction that separated it (in the partner's frame):
/// bodies move little between steps, and the same direction usually separates them again at
/// two support points, where parry's query walks GJK over every vertex of a hull.
#[derive(Copy, Clone, Debug)]
pub(super) struct PairState {
    pub overlap: Real,
    pub relative: Pose,
    pub axis: Option<Vector>,
}

/// The [`PairState`]s of the pairs the guard measured, by (mover's collider, partner's).
pub(super) type PairStates = HashMap<(ColliderHandle, ColliderHandle), PairState>;

impl PairState {
    /// The pair measured `overlap` deep with the mover's collider at `pose` and the partner's
    /// at `partner_pose`.
    pub fn new(overlap: Real, pose: &Pose, partner_pose: &Pose) -> Self {
        Self {
            overlap,
            relative: partner_pose.inverse() * *pose,
            axis: None,
        }
    }

    /// [`PairState::new`], with the world direction `axis` (out of the partner toward the
    /// mover) that separated the pair.
    pub fn apart_along(overlap: Real, pose: &Pose, partner_pose: &Pose, axis: Vector) -> Self {
        Self {
            axis: Some(partner_pose.rotation.inverse() * axis).filter(|a| a.is_finite()),
            ..Self::new(overlap, pose, partner_pose)
        }
    }

    /// The separating direction kept, in world coordinates for the partner at `partner_pose`.
    pub fn world_axis(&self, partner_pose: &Pose) -> Option<Vector> {
        self.axis.map(|a| partner_pose.rotation * a)
    }

    /// The most the pair can overlap with the mover's collider at `pose` and the partner's at
    /// `partner_pose`; `reach` bounds how far the mover's points lie from its collider's
    /// origin. Infinite when a pose is not finite.
    pub fn bound(&self, pose: &Pose, partner_pose: &Pose, reach: Real) -> Real {
        let now = partner_pose.inverse() * *pose;
        let b = self.overlap + point_travel(&self.relative, &now, reach);
        if b.is_finite() {
            b
        } else {
            Real::INFINITY
        }
    }
}

/// One pair as the guard reads it, before deciding anything: the partner's pose now, its
/// translation over the step, the pair's relative travel (translation
/// plus both rotations' arcs), rapier's contact points of the pair and whether they are
/// trusted at that travel, how much deeper than those points a corner they do not hold may
/// have come, and whether the partner is dynamic.
#[derive(Copy, Clone, Debug)]
pub(super) struct PairView {
    pub partner_pose: Pose,
    pub dp: Vector,
    pub travel: Real,
    pub rapier: Option<RapierContact>,
    pub trusted: bool,
    /// How much deeper than rapier's deepest point, re-read now, another point of the pair
    /// may be ([`corner_reach`]); zero for shapes that turn no new corner in (a ball, a
    /// capsule, a polyhedron that did not turn).
    pub corner_reach: Real,
    pub partner_dynamic: bool,
    /// rapier's manifold was computed before the step, and the mover has turned since
    /// (`RapierContact::rotation_at_update`): its points and its depth when the step began
    /// miss what the turn brought down, and only `corner_reach` bounds it.
    pub turned_since_update: bool,
}

impl PairView {
    /// A slow pair the guard has nothing to do for, decided from rapier's points alone (the
    /// same rules the guard applies to every pair it looks at): a resting pair with a dynamic
    /// partner or within the resting slop, a non-resting one no deeper than the slop, or, with
    /// no points, one that travelled less than the slop.
    pub fn calm(&self, options: &TouchOptions) -> bool {
        let slop = options.penetration_slop;
        match &self.rapier {
            Some(r) if r.in_contact_at_start => {
                self.partner_dynamic
                    || (self.trusted && r.depth + self.corner_reach <= options.resting_slop)
            }
            Some(r) => {
                !options.report_touching && self.trusted && r.depth + self.corner_reach <= slop
            }
            None => !options.report_touching && self.travel <= slop,
        }
    }
}

/// The guard's mover, one collider of a body that moved: what [`PairView::read`] needs of it.
pub(super) struct Mover<'a> {
    pub collider: &'a rapier3d::geometry::Collider,
    pub mesh: &'a TouchMesh,
    /// Whether its touch mesh is its shape exactly (not a tessellation).
    pub exact: bool,
    /// Its pose now and at the step's start.
    pub pose: Pose,
    pub prev_pose: Pose,
    /// Its body's translation over the step.
    pub motion: Vector,
    /// The arc its rotation over the step moves its farthest point along.
    pub turn: Real,
    /// How far its farthest point lies from its centre (`turn` per radian).
    pub arm: Real,
    /// Whether it moved (translation plus the arc of its rotation) less than half the slop over
    /// the step.
    pub still: bool,
    /// Whether it moved less than a tenth of the slop since its pairs with still partners were
    /// last read ([`super::TouchPipeline`]'s `pairs_read_at`).
    pub unmoved_since_read: bool,
}

/// A shape turns no new corner into a contact if it has none (a ball, a capsule) or did not
/// turn (a polyhedron at rest, a floor). A rounded polyhedron, a cylinder or a cone that turns
/// does, as a polyhedron does.
fn no_new_corner(c: &rapier3d::geometry::Collider, exact: bool, turned: bool) -> bool {
    c.shape().as_ball().is_some() || c.shape().as_capsule().is_some() || (exact && !turned)
}

impl PairView {
    /// `mover`'s pair with the collider `ph` (`partner`; rapier's contact pair `pair` when it
    /// has one) as the guard reads it. `curved`: the pair has a tessellated touch mesh (it is
    /// measured on the shapes themselves).
    pub(super) fn read(
        world: &PhysicsWorld,
        (meshes, prev_poses): (&HashMap<ColliderHandle, CachedMesh>, &PoseHistory),
        mover: &Mover<'_>,
        (ph, partner, pair): (
            ColliderHandle,
            &rapier3d::geometry::Collider,
            Option<&rapier3d::geometry::ContactPair>,
        ),
        curved: bool,
        (slop, prediction): (Real, Real),
    ) -> Self {
        let partner_pose = collider_pose_now(&world.bodies, partner);
        let partner_prev = previous_collider_pose(prev_poses, partner, partner_pose);
        let dp = body_motion(prev_poses, &world.bodies, partner.parent());
        let partner_turn = partner_prev.rotation.angle_between(partner_pose.rotation)
            * collider_reach(meshes, ph, partner);
        let travel = (mover.motion - dp).length() + mover.turn + partner_turn;
        let smooth = no_new_corner(mover.collider, mover.exact, mover.turn > 0.0)
            && no_new_corner(
                partner,
                meshes.get(&ph).is_some_and(|m| m.exact),
                partner_turn > 0.0,
            );
        let mut rapier = pair.and_then(|p| {
            rapier_contact_of(
                p,
                ph,
                (&partner_pose, &partner_prev),
                (
                    &mover.pose,
                    &mover.prev_pose,
                    mover
                        .collider
                        .position_wrt_parent()
                        .map_or(Rotation::IDENTITY, |p| p.rotation),
                ),
                slop,
            )
        });
        // rapier's points are material points of the shapes: a ball or a capsule that rolled
        // carries its point up its side, where it reads the pair apart while the shape sinks
        // (a ball sliding at 70 sizes a second on a plate, spinning up to rolling, went 1 % of
        // its size into it step by step, as in vanilla rapier). Where a smooth pair turned
        // its points by more than the prediction distance, its depth now and its normal are
        // parry's, on the shapes.
        if let Some(r) = rapier
            .as_mut()
            .filter(|_| smooth && mover.turn + partner_turn > prediction)
        {
            match parry_overlap_within(
                (partner, &partner_pose),
                (mover.collider, &mover.pose),
                prediction,
            ) {
                Some((depth, n)) => {
                    r.depth = depth;
                    if let Some(n) = n.and_then(|n| n.try_normalize()) {
                        r.normal = n;
                    }
                }
                None => r.depth = Real::INFINITY,
            }
        }
        // A manifold rapier recycled since a turn (`RapierContact::rotation_at_update`): the
        // turn from then on may have brought corners down that it does not hold.
        let update_pose = rapier
            .and_then(|r| r.rotation_at_update)
            .map_or(mover.prev_pose, |q| {
                Pose::from_parts(mover.prev_pose.translation, q)
            });
        let turned_before =
            update_pose.rotation.angle_between(mover.prev_pose.rotation) * mover.arm;
        let turned_since_update = turned_before > 0.1 * slop;
        let smooth =
            smooth && (!turned_since_update || no_new_corner(mover.collider, mover.exact, true));
        // rapier's points are trusted (below) only along a normal the shapes agree with: for
        // two shapes with support points, the overlap along a contact normal is the pair's
        // depth, or minus its gap (a separating axis), and a recycled manifold's stays near it
        // while the pair moves within the prediction distance and turns within a size. One the
        // shapes overlap along by more than a size of the mover past what the points say holds
        // no normal of the pair: after a correction, rapier's manifold for a 0.33 mm hull on a
        // 13 um plate 100 times its size held a normal 47° off the plate's and read the hull
        // 3 um apart while it fell 6.2 um into the plate over three steps, read calm (two
        // support queries; a normal recycled from a 3° tilt of a 57 cm box stays trusted).
        // The shapes' overlap along rapier's normal, asked at most once (the corner reach
        // below bounds itself by it too).
        let overlap = std::cell::OnceCell::new();
        let normal_overlap = |r: &RapierContact| {
            *overlap.get_or_init(|| {
                overlap_along(
                    (partner, &partner_pose),
                    (mover.collider, &mover.pose),
                    r.normal,
                )
            })
        };
        let wrong_normal = || {
            rapier.is_some_and(|r| {
                let allowed = r.depth.max(0.0) + slop + prediction + mover.mesh.min_extent();
                normal_overlap(&r).is_some_and(|o| o > allowed)
            })
        };
        PairView {
            partner_pose,
            dp,
            travel,
            // rapier's contact points say whether the pair overlapped when the step began.
            // Their depth now is trusted while the pair moved less than rapier's prediction
            // distance (they hold every feature pair within it at the step's start; a spinning
            // body brings new corners in), and for curved shapes that turn no new corner in at
            // any travel (rapier's contacts are exact there; the touch mesh is a
            // tessellation). Trusted at any travel, rounded hulls sank 36 mm into the floor of
            // rapier's convex-hull stress scene, cones 139 mm into its CCD scene's.
            rapier,
            trusted: (travel <= prediction || (curved && smooth)) && !wrong_normal(),
            corner_reach: match rapier {
                Some(r) if !smooth => {
                    let reach = corner_reach(
                        mover.mesh,
                        r.deepest_at_start,
                        (&mover.pose, &update_pose),
                        (&partner_pose, &partner_prev),
                        r.normal,
                        partner_turn,
                    );
                    // Shapes with support points: their overlap along rapier's normal bounds
                    // the depth too (two support queries).
                    if r.depth + reach > slop {
                        normal_overlap(&r).map_or(reach, |o| reach.min((o - r.depth).max(0.0)))
                    } else {
                        reach
                    }
                }
                _ => 0.0,
            },
            partner_dynamic: partner
                .parent()
                .and_then(|pb| world.bodies.get(pb))
                .is_some_and(|b| b.is_dynamic()),
            turned_since_update,
        }
    }
}

/// The relative motion over one step under which two bodies cannot have passed through each
/// other: the smaller of their touch meshes' thinnest extents (a flat partner, of zero extent,
/// counts as the mover's).
pub(super) fn safe_step(mesh: &TouchMesh, partner_mesh: &TouchMesh) -> Real {
    match (mesh.min_extent(), partner_mesh.min_extent()) {
        (a, b) if b > 0.0 => a.min(b),
        (a, _) => a,
    }
}

/// Whether a resting pair (rapier's contact `r`, re-read at the poses now, and `corner_reach`
/// how far a turn may have brought another corner past its points) is no deeper than `keep`,
/// the depth its push back would leave it at (and the push's tolerance): rapier's, before the
/// push measures it.
///
/// No deeper by rapier's points and what a turn may have added: the pyramid asked for 0.65
/// such measures a step, 30 µs each, two in three leaving the pair as it was. Otherwise only
/// a corner rapier held no point for may be deeper (the pair turned): lifted along rapier's
/// normal by `keep`, a pair parry finds apart needs no push (an intersection test, a tenth of
/// the push out; a TriMesh has no support points for `corner_reach`'s own bound). (Lifted by
/// the resting slop only, about a third of the TriMesh-floor stress scene's pushes found their
/// pair within what they would leave: 236 pushes in 300 steps on its hook side, 189 with this
/// lift.)
pub(super) fn resting_within(
    (r, corner_reach): (&RapierContact, Real),
    keep: Real,
    (partner, partner_pose): (&rapier3d::geometry::Collider, &Pose),
    (co, pose_now): (&rapier3d::geometry::Collider, &Pose),
) -> bool {
    r.depth + corner_reach <= keep
        || (r.depth <= keep
            && apart_when_lifted((partner, partner_pose), (co, pose_now), r.normal * keep))
}

/// Whether a slow pair (one that moved less than its safe step, so that it cannot have passed
/// through) is surely within the slop, and left to rapier: `rapier` its contact re-read at the
/// poses now (`trusted` when the pair moved little enough for its points to be read;
/// `corner_reach` how far a turn may have brought another corner past them), `travel` the
/// pair's relative travel over the step, `overlapped` when rapier had it in contact when the
/// step began, `curved` for a pair with a curved shape; `resting_slop` and `slop` as the
/// guard's options say.
///
/// Rapier's own contact points, re-read at the poses now, say how deep the pair is; with no
/// points rapier found it apart (beyond its prediction distance) when the step began, so it
/// can be no deeper than the pair's relative travel.
///
/// Points rapier had but that moved too far to be read (a body sliding faster than the
/// prediction distance per step): moved out along rapier's normal by the slop, a pair GJK
/// finds apart overlaps by no more than the slop (a sliding cube on a TriMesh floor was
/// otherwise reconstructed every step). A pair already in contact when the step began is only
/// ever pushed back to the resting slop along that normal, so it is lifted by that: rapier's
/// own resting overlap (up to a millimetre) is deeper than the slop, and 677 of the TriMesh
/// stress scene's 911 reconstructions were such pairs, none corrected. So are trusted points
/// a turn may have brought another corner past (`corner_reach`).
pub(super) fn slow_pair_calm(
    (rapier, trusted, corner_reach): (Option<RapierContact>, bool, Real),
    (travel, overlapped, curved): (Real, bool, bool),
    (resting_slop, slop): (Real, Real),
    (partner, partner_pose): (&rapier3d::geometry::Collider, &Pose),
    (co, pose_now): (&rapier3d::geometry::Collider, &Pose),
) -> bool {
    let bound = match rapier {
        Some(r) if trusted => r.depth + corner_reach,
        _ => travel,
    };
    if bound <= slop {
        return true;
    }
    let Some(r) = rapier.filter(|_| !trusted || corner_reach > 0.0) else {
        return false;
    };
    let lift = if overlapped {
        resting_slop.max(slop)
    } else {
        slop
    };
    // One axis first (rapier's normal): two support points.
    if within_along((partner, partner_pose), (co, pose_now), r.normal, lift) {
        return true;
    }
    // A curved pair (a rolling rounded hull, whose re-read normal can be off): parry's exact
    // query, the one its reconstruction walks on, says how deep it is; within the lift it is
    // left to rapier, as the pairs rapier has no points for are below (7,000 of the hull
    // scene's 10,000 reconstructions were such pairs already in contact, almost none
    // corrected). Asked before the lifted test below, which only one in five of that scene's
    // pairs passed (either one lets a pair go: the order only saves queries).
    if curved && parry_depth((partner, partner_pose), (co, pose_now)).is_some_and(|d| d <= lift) {
        return true;
    }
    apart_when_lifted((partner, partner_pose), (co, pose_now), r.normal * lift)
}

/// Whether `mover` (at `pose`) overlaps `partner` (at `partner_pose`) by less than `gap` along
/// the unit direction `n` (out of `partner` toward `mover`), from the two shapes' support
/// points alone: the highest point of `partner` along `n` less the lowest of `mover`. The
/// overlap along any direction bounds the depth from above, so `true` means the pair is less
/// than `gap` deep, and the mover lifted by `gap` along `n` is apart (what parry's
/// intersection test would find there, at two support queries instead of a GJK run). `false`
/// when either shape has no support map (a TriMesh, a compound) or the answer is not finite.
/// Computed in `partner`'s frame, as parry's pair queries are (no rounding of world
/// coordinates far from the origin).
pub(super) fn within_along(
    (partner, partner_pose): (&rapier3d::geometry::Collider, &Pose),
    (mover, pose): (&rapier3d::geometry::Collider, &Pose),
    n: Vector,
    gap: Real,
) -> bool {
    overlap_along((partner, partner_pose), (mover, pose), n).is_some_and(|o| o < gap)
}

/// How far `mover` (at `pose`) and `partner` (at `partner_pose`) overlap along the unit
/// direction `n` (out of `partner` toward `mover`): the highest point of `partner` along `n`
/// less the lowest of `mover` ([`within_along`]). It bounds the depth from above, and a
/// negative answer is a separating axis: the shapes are at least that far apart. `None` when
/// either shape has no support map or the answer is not finite.
pub(super) fn overlap_along(
    (partner, partner_pose): (&rapier3d::geometry::Collider, &Pose),
    (mover, pose): (&rapier3d::geometry::Collider, &Pose),
    n: Vector,
) -> Option<Real> {
    let sp = partner.shape().as_support_map()?;
    let sm = mover.shape().as_support_map()?;
    let rel = partner_pose.inv_mul(pose);
    let n = partner_pose.rotation.inverse() * n;
    let top = sp.local_support_point_toward(n).dot(n);
    let bottom = sm.support_point_toward(&rel, -n).dot(n);
    let overlap = top - bottom;
    overlap.is_finite().then_some(overlap)
}

/// Whether parry's intersection test finds `mover` (at `pose`) apart from `partner` (at
/// `partner_pose`) once lifted by `lift` (world): then the pair overlaps by no more than
/// `lift`'s length along its direction. `false` when parry has no test for the shapes.
pub(super) fn apart_when_lifted(
    (partner, partner_pose): (&rapier3d::geometry::Collider, &Pose),
    (mover, pose): (&rapier3d::geometry::Collider, &Pose),
    lift: Vector,
) -> bool {
    let lifted = Pose::from_parts(pose.translation + lift, pose.rotation);
    if let Some(mesh) = partner.shape().as_trimesh() {
        if mover.shape().as_support_map().is_some() {
            // parry's test below, triangle by triangle along the cheapest axes first
            // (`mesh_separation.rs`, checked against parry's distance and depth).
            return apart_from_mesh(
                mesh,
                mover.shape(),
                &partner_pose.inv_mul(&lifted),
                partner_pose.rotation.inverse() * lift,
            );
        }
    }
    parry3d::query::intersection_test(partner_pose, partner.shape(), &lifted, mover.shape())
        .is_ok_and(|i| !i.intersecting)
}

/// How deep `mover` (at `pose`) overlaps `partner` (at `partner_pose`) by parry's contact
/// query with a prediction of 0: 0 for shapes apart (parry answers `None`), minus the
/// distance of the contact it answers (negative for a positive distance, one of its wrong
/// answers: seen for a small tumbling cuboid on a large one, +1.1 mm where a corner was
/// 1.1 mm deep), `None` when parry has no query for the shapes.
pub(super) fn parry_depth(
    (partner, partner_pose): (&rapier3d::geometry::Collider, &Pose),
    (mover, pose): (&rapier3d::geometry::Collider, &Pose),
) -> Option<Real> {
    parry3d::query::contact(partner_pose, partner.shape(), pose, mover.shape(), 0.0)
        .ok()
        .map(|c| c.map_or(0.0, |c| -c.dist))
}

/// How deep `mover` (at `pose`) overlaps `partner` (at `partner_pose`) by parry's contact
/// query with a prediction of `margin`, asked as the shape method asks it (a huge box only for
/// its part near the mover: `geometry::contact_near`), and the contact's normal (world, out of
/// `partner`) when parry found one. The overlap is negative for a pair apart (minus its
/// distance, or minus `margin` when it is farther). `None` when parry has no query for the
/// shapes or the answer is not finite. (Unlike [`parry_depth`], a positive distance is taken
/// as parry's answer.)
pub(super) fn parry_overlap_within(
    (partner, partner_pose): (&rapier3d::geometry::Collider, &Pose),
    (mover, pose): (&rapier3d::geometry::Collider, &Pose),
    margin: Real,
) -> Option<(Real, Option<Vector>)> {
    let margin = if margin.is_finite() {
        margin.max(0.0)
    } else {
        0.0
    };
    contact_near(partner.shape(), partner_pose, mover.shape(), pose, margin)
        .map(|c| c.map_or((-margin, None), |c| (-c.dist, Some(c.normal1))))
        .filter(|(d, n)| d.is_finite() && n.is_none_or(|n| n.is_finite()))
}

/// The way out of an overlap along `out` (a world direction out of the partner) for the mover
/// at its pose now: on the shapes themselves when the pair is `curved`
/// ([`Reconstructor::push_out_shapes`]), by the exact method on the touch meshes otherwise
/// (and when parry has no distance query for the shapes).
pub(super) fn push_out(
    options: ReconstructionOptions,
    curved: bool,
    (partner, partner_mesh, partner_pose): (&rapier3d::geometry::Collider, &TouchMesh, &Pose),
    (mover, mesh, pose): (&rapier3d::geometry::Collider, &TouchMesh, &Pose),
    out: Vector,
) -> Option<ContactConfiguration> {
    let mut rec = Reconstructor::new(ReconstructionOptions {
        zero_motion_direction: Some(-out),
        ..options
    });
    if curved {
        match rec.push_out_shapes(partner.shape(), partner_pose, mover.shape(), pose, out) {
            Ok(Some(c)) => return Some(c),
            Ok(None) => {}
            Err(_) => return None,
        }
    }
    rec.reconstruct(partner_mesh, partner_pose, mesh, pose, pose)
        .ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rotation;
    use rapier3d::geometry::{ColliderBuilder, SharedShape};

    /// `within_along` never lets a pair go that parry's intersection test, with the mover
    /// lifted by the gap along the axis, still finds overlapping; and it lets go the pairs that
    /// are apart along the axis by more than a rounding (it is not a test that never answers).
    #[test]
    fn a_pair_within_the_gap_along_the_axis_is_apart_once_lifted_by_it() {
        let points = [
            Vector::new(0.0, 0.0, 0.0),
            Vector::new(1.0, 0.1, 0.0),
            Vector::new(0.2, 0.9, 0.1),
            Vector::new(0.1, 0.2, 1.0),
            Vector::new(0.8, 0.7, 0.6),
        ];
        let shapes = [
            SharedShape::cuboid(0.5, 0.2, 0.3),
            SharedShape::ball(0.4),
            SharedShape::capsule_y(0.3, 0.1),
            SharedShape::round_convex_hull(&points, 0.05).unwrap(),
            SharedShape::cylinder(0.2, 0.5),
        ];
        let floor = ColliderBuilder::cuboid(1.0, 0.5, 1.0).build();
        let floor_pose = Pose::from_translation(Vector::new(0.3, -0.5, -0.2));
        let (mut let_go, mut kept) = (0, 0);
        for (i, shape) in shapes.iter().enumerate() {
            let mover = ColliderBuilder::new(shape.clone()).build();
            for k in 0..40 {
                let t = k as Real;
                let turn = Rotation::from_axis_angle(
                    Vector::new((0.7 * t).sin(), 1.0, (1.3 * t).cos()).normalize(),
                    0.37 * t + i as Real,
                );
                // From 5 cm apart down to 5 cm deep (the turned shape's lowest point on the
                // floor's top at 0), along tilted axes.
                let lowest = shape.compute_aabb(&Pose::from_rotation(turn)).mins.y;
                let height = -lowest - 0.05 + 0.1 * (k % 11) as Real / 10.0;
                let pose = Pose::from_parts(Vector::new(0.1 * (k % 5) as Real, height, 0.0), turn);
                // rapier's normal, as far off the floor's as a rounded shape's can be.
                let n =
                    Vector::new(0.002 * (k % 3) as Real, 1.0, -0.001 * (k % 4) as Real).normalize();
                let gap = 0.01;
                if within_along((&floor, &floor_pose), (&mover, &pose), n, gap) {
                    let_go += 1;
                    let lifted = Pose::from_parts(pose.translation + n * gap, pose.rotation);
                    let overlaps = parry3d::query::intersection_test(
                        &floor_pose,
                        floor.shape(),
                        &lifted,
                        mover.shape(),
                    )
                    .unwrap();
                    assert!(!overlaps.intersecting, "shape {i}, case {k}");
                } else {
                    kept += 1;
                }
            }
        }
        assert!(let_go > 40 && kept > 40, "{let_go} let go, {kept} kept");
        // A mesh shape has no support map: never let go from this test.
        let mesh =
            ColliderBuilder::trimesh(vec![Vector::ZERO, Vector::X, Vector::Z], vec![[0, 1, 2]])
                .unwrap()
                .build();
        let far = Pose::from_translation(Vector::new(0.0, 10.0, 0.0));
        assert!(!within_along(
            (&floor, &floor_pose),
            (&mesh, &far),
            Vector::Y,
            0.01
        ));
    }
}
