//! Slow pairs rapier had no contact point for ([`measure_slow_pair`]), and among them fresh
//! impacts of two dynamic bodies ([`TouchOptions::rewind_dynamic_impacts`]): a pair that
//! closed by more than rapier's prediction distance but less than its safe step. It cannot
//! have passed through, but rapier's solver never saw it. The guard tells the many near
//! pairs of a pile that stayed apart cheaply ([`stayed_apart`], [`measure_apart`]), and
//! rewinds a pair that got deeper than the slop to its first touch on both bodies' paths
//! ([`first_touch_of_bodies`], [`impact_rewind`]).

use super::correction::normal_toward_mover;
use super::pair_view::{overlap_along, parry_overlap_within, PairState, PairStates};
use super::rapier_contacts::{collider_pose_now, supported};
use super::*;
use crate::geometry::{ContactConfiguration, RigidMotion};
use parry3d::bounding_volume::BoundingVolume;

/// Whether two touch meshes' boxes at their poses meet, each loosened by `slop` (a mesh and
/// its pose, and whether the mesh is the shape itself rather than a tessellation). A curved
/// shape's tessellation has the shape's extreme points along its axes; its box is loosened
/// by 2 % of its diagonal more for what the tessellation's faces miss.
fn boxes_meet(
    (mesh, pose, exact): (&TouchMesh, &Pose, bool),
    (partner_mesh, partner_pose, partner_exact): (&TouchMesh, &Pose, bool),
    slop: Real,
) -> bool {
    let boxed = |m: &TouchMesh, pose: &Pose, exact: bool| {
        let sag = if exact { 0.0 } else { 0.02 * m.scale() };
        m.local_aabb().transform_by(pose).loosened(slop + sag)
    };
    boxed(mesh, pose, exact).intersects(&boxed(partner_mesh, partner_pose, partner_exact))
}

/// Whether a dynamic pair rapier held no contact point for, whose mover moved `travel`
/// relative to the partner over the step (translation plus the mover's turn), is sure to
/// have stayed within the slop (`prediction` and `slop`: rapier's prediction distance and
/// the guard's slop), cheapest test first: the partner's turn added, the bound its last
/// measure left ([`PairState`] in `states`), its boxes at the poses now (most of a falling
/// pile's neighbours without rapier's points are still apart). The mover: its collider,
/// touch mesh, pose now and whether the mesh is exact; the partner: its collider.
pub(super) fn stayed_apart(
    (world, meshes, prev_poses, states): (
        &PhysicsWorld,
        &HashMap<ColliderHandle, CachedMesh>,
        &PoseHistory,
        &PairStates,
    ),
    (ch, mesh, pose, exact): (ColliderHandle, &TouchMesh, &Pose, bool),
    (ph, partner): (ColliderHandle, &rapier3d::geometry::Collider),
    travel: Real,
    (prediction, slop): (Real, Real),
) -> bool {
    let Some(pm) = meshes.get(&ph) else {
        return true;
    };
    let partner_pose = collider_pose_now(&world.bodies, partner);
    let partner_prev = previous_collider_pose(prev_poses, partner, partner_pose);
    let partner_turn = partner_prev.rotation.angle_between(partner_pose.rotation)
        * collider_reach(meshes, ph, partner);
    if travel + partner_turn <= prediction + slop {
        return true;
    }
    let reach = meshes.get(&ch).map_or(0.0, |m| m.reach);
    if states
        .get(&(ch, ph))
        .is_some_and(|st| st.bound(pose, &partner_pose, reach) <= slop)
    {
        return true;
    }
    !boxes_meet(
        (mesh, pose, exact),
        (&pm.mesh, &partner_pose, pm.exact),
        slop,
    )
}

/// How deep two dynamic colliders overlap, or how far apart they are (negative), and the
/// direction that separated them (world, out of the partner) when one did.
///
/// Two support points first, along `kept` (the direction that separated the pair when it was
/// last measured: bodies move little between steps) and then along the axis between the two
/// boxes' centres; most pairs of a falling pile are told apart there. Otherwise parry's
/// contact query, looking for a gap up to four times the pair's `travel` this step (a
/// positive distance is taken as parry's answer). The gap kept in the pair's state lets the
/// next steps skip it while it keeps its distance: one query a step for every near pair of a
/// falling pile cost more than the rest of the guard. `(None, None)` when parry has no query
/// for the shapes.
fn measure_apart(
    (partner, partner_pose, partner_mesh): (&rapier3d::geometry::Collider, &Pose, &TouchMesh),
    (mover, pose, mesh): (&rapier3d::geometry::Collider, &Pose, &TouchMesh),
    kept: Option<Vector>,
    (travel, slop): (Real, Real),
) -> (Option<Real>, Option<Vector>) {
    let centres = (*pose * mesh.local_aabb().center()
        - *partner_pose * partner_mesh.local_aabb().center())
    .try_normalize();
    let separated = kept.into_iter().chain(centres).find_map(|n| {
        overlap_along((partner, partner_pose), (mover, pose), n)
            .filter(|o| *o < -slop)
            .map(|o| (o, n))
    });
    if let Some((o, n)) = separated {
        return (Some(o), Some(n));
    }
    match parry_overlap_within((partner, partner_pose), (mover, pose), 4.0 * travel) {
        Some((o, n)) => (Some(o), n.filter(|_| o < 0.0)),
        None => (None, None),
    }
}

/// First touch of two colliders over the step, each moving with its body from where it was
/// when the step began ([`PoseHistory`]) to its pose now (`partner_pose`, `pose`), turning
/// about its body's centre of mass ([`RigidMotion::first_touch_of_two`]: parry's nonlinear
/// shape cast, the query rapier's CCD asks; the crate's reconstruction walks one body
/// against the other held still, and cost five times as much on rapier's CCD stress scene).
/// The fraction of the step, the normal out of the partner, and the touching point.
fn first_touch_of_bodies(
    world: &PhysicsWorld,
    prev_poses: &PoseHistory,
    (partner, partner_pose): (&rapier3d::geometry::Collider, Pose),
    (mover, pose): (&rapier3d::geometry::Collider, Pose),
) -> Option<(Real, Vector, Vector)> {
    let motion = |c: &rapier3d::geometry::Collider, now: Pose| {
        let prev = previous_collider_pose(prev_poses, c, now);
        let center = c
            .parent()
            .and_then(|h| world.bodies.get(h))
            .map_or(Vector::ZERO, |b| {
                let com = b.local_center_of_mass();
                c.position_wrt_parent()
                    .map_or(com, |rel| rel.inverse_transform_point(com))
            });
        RigidMotion::new(prev, now, center)
    };
    RigidMotion::first_touch_of_two(
        partner.shape(),
        &motion(partner, partner_pose),
        mover.shape(),
        &motion(mover, pose),
    )
}

/// A fresh impact between two dynamic bodies (neither in rapier's contacts when the step
/// began), rewound: both bodies go back along their own step motions to `t`, the fraction of
/// the step at which they first touched, and the velocity that still closes along the contact
/// normal `n` (out of `pb`'s collider `ph` toward `bh`'s collider `ch`) is taken off as a
/// plastic impact would, shared by inverse mass (momentum conserved). Neither is pushed
/// anywhere it was not during the step: splitting a push between them instead drove one into
/// a third body of a falling pile (rapier's convex-hull stress scene: 0.4 m pushes, a pair
/// 0.9 m deep). A body resting on a fixed or kinematic collider is held where it is and takes
/// no share, as in [`super::correction::apply_correction`]: its share of the impact drove a
/// thin dynamic plate, struck at 20 m/s, 4 mm into the floor under it. `None` when both rest
/// so, or either is not a dynamic body with a pose at the step's start.
fn impact_rewind(
    world: &PhysicsWorld,
    prev_poses: &PoseHistory,
    (t, n): (Real, Vector),
    (bh, pb): (RigidBodyHandle, RigidBodyHandle),
    (ch, ph): (ColliderHandle, ColliderHandle),
) -> Option<[(RigidBodyHandle, Pose, Vector); 2]> {
    let t = t.clamp(0.0, 1.0);
    let body_at = |h: RigidBodyHandle, c: ColliderHandle| -> Option<(Pose, Real, Vector)> {
        let b = world.bodies.get(h).filter(|b| b.is_dynamic())?;
        let v = b.linvel();
        if supported(world, c) {
            return v.is_finite().then_some((*b.position(), 0.0, v));
        }
        let prev = *prev_poses.get(&h)?;
        let motion = RigidMotion::new(prev, *b.position(), b.local_center_of_mass());
        let pose = motion.pose_at(t);
        let inv_mass = if b.mass() > 0.0 { 1.0 / b.mass() } else { 0.0 };
        (pose.is_finite() && v.is_finite()).then_some((pose, inv_mass, v))
    };
    let (pose_a, inv_a, v_a) = body_at(bh, ch)?;
    let (pose_b, inv_b, v_b) = body_at(pb, ph)?;
    if inv_a + inv_b <= 0.0 {
        return None;
    }
    let impulse = n * (v_a - v_b).dot(n).min(0.0) / (inv_a + inv_b);
    let impulse = if impulse.is_finite() {
        impulse
    } else {
        Vector::ZERO
    };
    Some([
        (bh, pose_a, v_a - impulse * inv_a),
        (pb, pose_b, v_b + impulse * inv_b),
    ])
}

/// What a fresh impact of two dynamic bodies comes to ([`fresh_impact_rewind`]).
enum FreshImpact {
    /// parry has no nonlinear shape cast for the shapes (two TriMeshes): the reconstruction
    /// is asked instead ([`rewind_from`]).
    NoShapeCast,
    /// Nothing to do: no touch on the step, the user's hooks remove the contact, or a body
    /// is not dynamic or has no pose at the step's start.
    Leave,
    /// The two bodies' poses and velocities at their first touch ([`apply_rewind`]).
    Rewind([(RigidBodyHandle, Pose, Vector); 2]),
}

/// A fresh impact of dynamic collider `co` (handle `ch`, pose now `pose`, on body `bh`) with dynamic
/// collider `partner` (handle `ph`, pose now `partner_pose`, on body `pb`), found `overlap`
/// deep: their first touch ([`first_touch_of_bodies`]), unless the user's
/// `modify_solver_contacts` removes that contact (asked in rapier's pair order `(a, b)`, as
/// for every correction), and the rewind to it ([`impact_rewind`]).
fn fresh_impact_rewind(
    world: &PhysicsWorld,
    (prev_poses, hooks): (&PoseHistory, &dyn PhysicsHooks),
    (a, b): (ColliderHandle, ColliderHandle),
    (ph, partner, partner_pose): (ColliderHandle, &rapier3d::geometry::Collider, Pose),
    (ch, co, pose): (ColliderHandle, &rapier3d::geometry::Collider, Pose),
    (bh, pb): (RigidBodyHandle, RigidBodyHandle),
    overlap: Real,
) -> FreshImpact {
    let Some((t, n, at)) =
        first_touch_of_bodies(world, prev_poses, (partner, partner_pose), (co, pose))
    else {
        return FreshImpact::NoShapeCast;
    };
    if user_removes_contact(world, hooks, (a, b), ph, n, at, overlap) {
        return FreshImpact::Leave;
    }
    impact_rewind(world, prev_poses, (t, n), (bh, pb), (ch, ph))
        .map_or(FreshImpact::Leave, FreshImpact::Rewind)
}

/// The rewind of a fresh impact to the first touch the reconstruction found (`config`, of
/// body `bh`'s collider `ch` against body `pb`'s collider `ph`): for shapes parry has no
/// shape cast for.
pub(super) fn rewind_from(
    world: &PhysicsWorld,
    prev_poses: &PoseHistory,
    config: &ContactConfiguration,
    (bh, pb): (RigidBodyHandle, RigidBodyHandle),
    (ch, ph): (ColliderHandle, ColliderHandle),
) -> Option<[(RigidBodyHandle, Pose, Vector); 2]> {
    let (t, n) = (config.time_of_impact?, normal_toward_mover(config)?);
    impact_rewind(world, prev_poses, (t, n), (bh, pb), (ch, ph))
}

/// What a slow pair rapier had no contact point for comes to ([`measure_slow_pair`]).
pub(super) enum SlowPair {
    /// Within the slop: nothing to do.
    Within,
    /// A fresh impact of two dynamic bodies, rewound ([`apply_rewind`]).
    Rewind([(RigidBodyHandle, Pose, Vector); 2]),
    /// Deeper than the slop, or not measured: the reconstruction decides.
    Reconstruct,
}

/// A pair that cannot have tunneled (it closed by less than its safe step) and that rapier had
/// no contact point for, measured: mover `co` (handle `ch`, pose now `pose`, touch mesh `mesh`,
/// its points within `reach` of its origin) against `partner` (its handle, pose now and touch
/// mesh), `travel` its relative travel over the step, `slop` the guard's.
///
/// - A pair whose state in `states` bounds its overlap within the slop is [`SlowPair::Within`]
///   unmeasured.
/// - Against a fixed or kinematic partner, parry's depth ([`parry_overlap_within`]; a contact at a
///   positive distance is one of its wrong answers, and such a pair is reconstructed).
/// - Two dynamic bodies (`bodies`: the mover's and the partner's) are measured by
///   [`measure_apart`], which keeps the gap of a pair still apart; a fresh impact deeper than
///   the slop is rewound to its first touch ([`fresh_impact_rewind`], the user's hooks asked in
///   rapier's pair order `(a, b)`).
///
/// The measure is kept in `states`.
#[allow(clippy::too_many_arguments)]
pub(super) fn measure_slow_pair(
    world: &PhysicsWorld,
    (prev_poses, hooks): (&PoseHistory, &dyn PhysicsHooks),
    states: &mut PairStates,
    (ch, co, pose, mesh, reach): (
        ColliderHandle,
        &rapier3d::geometry::Collider,
        Pose,
        &TouchMesh,
        Real,
    ),
    (ph, partner, partner_pose, partner_mesh): (
        ColliderHandle,
        &rapier3d::geometry::Collider,
        Pose,
        &TouchMesh,
    ),
    (a, b): (ColliderHandle, ColliderHandle),
    bodies: Option<(RigidBodyHandle, RigidBodyHandle)>,
    (travel, slop): (Real, Real),
) -> SlowPair {
    let state = states.get(&(ch, ph));
    if state.is_some_and(|st| st.bound(&pose, &partner_pose, reach) <= slop) {
        return SlowPair::Within;
    }
    let (measured, apart_axis) = if bodies.is_some() {
        let kept = state.and_then(|st| st.world_axis(&partner_pose));
        measure_apart(
            (partner, &partner_pose, partner_mesh),
            (co, &pose, mesh),
            kept,
            (travel, slop),
        )
    } else {
        // Against a fixed or kinematic partner, a mover clearly apart keeps its gap: the
        // next steps skip the pair until it may have closed it. (Measured at 0 each step, a
        // falling body asked parry's contact query every step on its way down: a tenth of the
        // guard on rapier's TriMesh-floor stress scene.)
        let gap = sphere_gap(
            (partner, &partner_pose, partner_mesh),
            pose.translation,
            reach,
        );
        if gap > slop {
            states.insert((ch, ph), PairState::new(-gap, &pose, &partner_pose));
            return SlowPair::Within;
        }
        // Asked as the shape method asks it: below a millimetre parry's query on world
        // coordinates read a 0.13 mm hull 2 µm into a 5 µm plate as apart (rapier itself holds
        // no contact at that size), and the guard let the hull fall through.
        let depth = parry_overlap_within((partner, &partner_pose), (co, &pose), 0.0).map(|o| o.0);
        (depth.filter(|d| *d >= 0.0), None)
    };
    let Some(overlap) = measured else {
        return SlowPair::Reconstruct;
    };
    let state = match apart_axis {
        Some(n) => PairState::apart_along(overlap, &pose, &partner_pose, n),
        None => PairState::new(overlap, &pose, &partner_pose),
    };
    states.insert((ch, ph), state);
    if overlap <= slop {
        return SlowPair::Within;
    }
    let Some(bodies) = bodies else {
        return SlowPair::Reconstruct;
    };
    match fresh_impact_rewind(
        world,
        (prev_poses, hooks),
        (a, b),
        (ph, partner, partner_pose),
        (ch, co, pose),
        bodies,
        overlap,
    ) {
        FreshImpact::NoShapeCast => SlowPair::Reconstruct,
        FreshImpact::Leave => SlowPair::Within,
        FreshImpact::Rewind(r) => SlowPair::Rewind(r),
    }
}

/// A lower bound of the gap between `partner` (at `partner_pose`, `partner_mesh` its touch
/// mesh) and a mover whose points all lie within `reach` of `center` (world): the centre's
/// distance to the partner, less the reach. Zero when the centre lies inside the partner by
/// parry's test, may lie inside it (a closed partner with no support map: a closed TriMesh, a
/// compound), or the answer is not finite. Otherwise the distance is to the partner's surface
/// (an open TriMesh floor or a height field with no inside of parry's has no other).
fn sphere_gap(
    (partner, partner_pose, partner_mesh): (&rapier3d::geometry::Collider, &Pose, &TouchMesh),
    center: Vector,
    reach: Real,
) -> Real {
    let shape = partner.shape();
    if shape.as_support_map().is_none() && partner_mesh.is_closed() {
        return 0.0;
    }
    // One projection onto the partner as a solid says both: parry's own inside, where it has
    // one (a TriMesh with pseudo-normals has one, open or not, and its queries find a body
    // under such a floor overlapping it), and the distance outside.
    let projection = shape.project_point(partner_pose, center, true);
    if projection.is_inside {
        return 0.0;
    }
    let gap = projection.point.distance(center) - reach;
    if gap.is_finite() {
        gap
    } else {
        0.0
    }
}

/// Moves the bodies of an [`impact_rewind`] to their poses and velocities.
pub(super) fn apply_rewind(world: &mut PhysicsWorld, rewind: &[(RigidBodyHandle, Pose, Vector)]) {
    for (h, pose, v) in rewind {
        if let Some(b) = world.bodies.get_mut(*h) {
            b.set_position(*pose, true);
            b.set_linvel(*v, true);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rotation;
    use proptest::prelude::*;
    use rapier3d::geometry::ColliderBuilder;

    /// At scale `k`: a height-field floor as an open TriMesh, a box, a ball, and a closed
    /// TriMesh (a box's triangles), each with its touch mesh.
    fn partner(which: usize, k: Real) -> (rapier3d::geometry::Collider, TouchMesh) {
        let co = match which {
            0 => {
                let n = 6;
                let mut heights = parry3d::utils::Array2::repeat(n + 1, n + 1, 0.0);
                for i in 0..=n {
                    for j in 0..=n {
                        heights[(i, j)] = k * ((i as Real).sin() + (j as Real * 0.7).cos());
                    }
                }
                let size = Vector::new(12.0 * k, 1.0, 12.0 * k);
                let (v, i) = parry3d::shape::HeightField::new(heights, size).to_trimesh();
                ColliderBuilder::trimesh(v, i).unwrap().build()
            }
            1 => ColliderBuilder::cuboid(2.0 * k, 0.5 * k, k).build(),
            2 => ColliderBuilder::ball(1.5 * k).build(),
            _ => {
                let (v, i) =
                    parry3d::shape::Cuboid::new(Vector::new(k, 0.5 * k, 2.0 * k)).to_trimesh();
                ColliderBuilder::trimesh(v, i).unwrap().build()
            }
        };
        let mesh = TouchMesh::from_shape(co.shape()).unwrap();
        (co, mesh)
    }

    proptest! {
        /// The gap `sphere_gap` keeps is never more than the distance between the shapes (a
        /// lower bound, not a measure of its own), at every scale; it is zero for a closed
        /// TriMesh partner, and positive for a mover well clear of a ball (it is not a bound
        /// that never lets a pair go).
        #[test]
        fn the_kept_gap_is_at_most_parrys_distance(
            which in 0usize..4,
            ball in any::<bool>(),
            x in -8.0f32..8.0, y in -3.0f32..6.0, z in -8.0f32..8.0,
            ax in -1.0f32..1.0, ay in -1.0f32..1.0, az in -1.0f32..1.0, angle in 0.0f32..3.0,
            k in prop::sample::select(vec![1e-4f32, 1e-3, 1.0, 1e3, 1e4]),
        ) {
            let (partner, partner_mesh) = partner(which, k);
            // The mover: a ball of radius 0.3 or a box of half-extents `half`, its points
            // within `reach` of its centre.
            let half = Vector::new(0.4, 0.2, 0.3) * k;
            let reach = if ball { 0.3 * k } else { half.length() };
            let axis = Vector::new(ax, ay, az).try_normalize().unwrap_or(Vector::Y);
            let partner_pose = Pose::from_parts(
                Vector::new(0.3, -0.2, 0.1) * k,
                Rotation::from_axis_angle(Vector::Z, 0.2),
            );
            let pose = Pose::from_parts(
                Vector::new(x, y, z) * k,
                Rotation::from_axis_angle(axis, angle),
            );
            let gap = sphere_gap((&partner, &partner_pose, &partner_mesh), pose.translation, reach);
            prop_assert!(gap.is_finite());
            // An upper bound of the shapes' distance, independent of the bound under test:
            // the distance to the partner of points on the mover's surface (a 9 × 9 grid on
            // each face of its box; a ball's points along 200 spiral directions). (parry's
            // distance query answered 0 for a 1 mm box 0.44 mm over the height field.)
            let samples: Vec<Vector> = if ball {
                (0..200)
                    .map(|i| {
                        let t = (i as Real + 0.5) / 200.0;
                        let (zc, phi) = (1.0 - 2.0 * t, i as Real * 2.399_963);
                        let r = (1.0 - zc * zc).sqrt();
                        Vector::new(r * phi.cos(), zc, r * phi.sin()) * reach
                    })
                    .collect()
            } else {
                let mut out = Vec::new();
                for axis in 0..3 {
                    for side in [-1.0, 1.0] {
                        for i in 0..9 {
                            for j in 0..9 {
                                let (u, v) = (i as Real / 4.0 - 1.0, j as Real / 4.0 - 1.0);
                                let mut p = [u, v, 0.0];
                                p.rotate_right((axis + 1) % 3);
                                p[axis] = side;
                                out.push(Vector::from(p) * half);
                            }
                        }
                    }
                }
                out
            };
            let distance = samples
                .iter()
                .map(|p| {
                    partner
                        .shape()
                        .distance_to_point(&partner_pose, pose.transform_point(*p), true)
                })
                .fold(Real::INFINITY, Real::min);
            prop_assert!(gap <= distance + 1e-5 * k, "gap {gap} beyond the mover's distance {distance}");
            if which == 3 {
                prop_assert_eq!(gap, 0.0);
            }
            if which == 2 && distance > 2.0 * reach {
                prop_assert!(gap > 0.0, "{gap} at distance {distance}");
            }
        }
    }
}
