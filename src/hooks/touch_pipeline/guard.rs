//! The step guard of [`TouchPipeline`]: after rapier's step, moves bodies that penetrate (or
//! went through something) back to first touch; then the moved bodies' colliders are synced
//! (`pose_sync.rs`) and the hook flags of fast bodies kept (`hook_flags.rs`). The partners it
//! leaves alone before measuring them are sorted out in `left_alone.rs`.

use super::articulations::{articulated, same_articulation};
use super::correction::{apply_correction, undone_almost_whole};
use super::impacts::{apply_rewind, measure_slow_pair, rewind_from, SlowPair};
use super::left_alone::Screen;
use super::misread::{
    deeper_than_at_start, depth_misread, normal_out_of_convex, touching_at_start,
};
use super::pair_view::{push_out, resting_within, safe_step, slow_pair_calm, Mover, PairView};
use super::pose_sync::sync_moved_colliders;
use super::rapier_contacts::{rapier_normal, resting_slop};
use super::swept::{swept_partners, StillPartners};
use super::swept_calm::stayed_within_slop;
use super::*;
use crate::geometry::contact_near;

impl<H: PhysicsHooks> TouchPipeline<H> {
    /// The step guard: moves bodies that penetrate (or went through something) back to first
    /// touch, and records the reports.
    ///
    /// A calm pile costs little: rapier's own contact points (computed at the step's start,
    /// local to the colliders) are re-read at the poses now, as rapier's solver does, and say
    /// whether a pair already overlapped when the step began and how deep it is now. They are
    /// trusted while the pair moved less than rapier's prediction distance (they hold every
    /// feature pair within it), and for curved shapes (rapier's contacts are exact there; the
    /// touch mesh is a tessellation). A body that moved less than half the slop over the step is
    /// skipped against dynamic partners (a dynamic partner that moved checks the pair), and
    /// against fixed ones while it moved less than a tenth of the slop since its pairs were last
    /// read.
    ///
    /// Work is bounded three ways. A body slower than its safe step length cannot have tunneled,
    /// so only the partners rapier's narrow phase already pairs it with are looked at (a swept
    /// box query otherwise). A pair whose last measured overlap plus how far the mover moved
    /// relative to its partner since ([`PairState`]) stays under the slop is skipped. Other
    /// pairs get parry's contact query, and a reconstruction only when it finds them deeper
    /// than the slop (or when parry has no query for the shapes, such as TriMesh against
    /// TriMesh). A fast body whose path kept it within the slop of a still partner along one
    /// direction is not reconstructed either (`swept_calm.rs`).
    pub(super) fn guard(&mut self, world: &mut PhysicsWorld) {
        let passes = if self.options.correct_poses {
            self.options.max_passes.max(1)
        } else {
            1
        };
        let slop = self.options.penetration_slop;
        let prediction = world.integration_parameters.prediction_distance();
        self.prune_pair_states(world);
        let mut reported: HashSet<(ColliderHandle, ColliderHandle)> = HashSet::default();
        let mut moved_bodies: Vec<RigidBodyHandle> = Vec::new();
        let mut moved_before = 0;
        // The bodies the guard may have left in deep contact (`sync_hook_flags`).
        let mut unsettled: HashSet<RigidBodyHandle> = HashSet::default();
        let mut still: Option<StillPartners> = None;
        let rewind = self.options.rewind_dynamic_impacts;
        for pass in 0..passes {
            let mut moved = false;
            // Later passes look again only at the bodies the previous pass moved (a correction
            // can push a body into a third one).
            let movers = if pass == 0 {
                self.movers(world)
            } else {
                let mut m = moved_bodies[moved_before..].to_vec();
                m.sort_unstable_by_key(|h| h.into_raw_parts());
                m.dedup();
                m
            };
            moved_before = moved_bodies.len();
            for bh in movers {
                let Some(body) = world.bodies.get(bh) else {
                    continue;
                };
                let body_pose = *body.position();
                let d = body_motion(&self.hooks.prev_poses, &world.bodies, Some(bh));
                let is_tool = self.tools.contains_key(&bh);
                // A link of an articulation (`articulations.rs`).
                let articulated = articulated(world, bh);
                let own: Vec<ColliderHandle> = body.colliders().to_vec();
                for ch in own {
                    let mesh_exact = self.hooks.meshes.get(&ch).is_some_and(|m| m.exact);
                    let Some(mesh) = self.hooks.meshes.get(&ch).map(|m| m.mesh.clone()) else {
                        continue;
                    };
                    let Some(co) = world.colliders.get(ch) else {
                        continue;
                    };
                    let co_rel = co.position_wrt_parent().copied();
                    let pose_now = co_rel.map_or(*co.position(), |rel| body_pose * rel);
                    let prev_pose = previous_collider_pose(&self.hooks.prev_poses, co, pose_now);
                    // How far a point of the collider may have travelled: translation plus the
                    // arc of its rotation.
                    let arm = collider_reach(&self.hooks.meshes, ch, co);
                    let turn = prev_pose.rotation.angle_between(pose_now.rotation) * arm;
                    let travelled = d.length() + turn;
                    // A body that moved less than rapier's prediction distance met nothing that
                    // stood still without rapier seeing it coming. With the rewind on, one that
                    // moved half of it may have met a partner that closed the other half: two
                    // 5 cm boxes 20.2 mm apart, each moving 1.8 cm toward the other, were
                    // found by neither (no rapier pair, neither fast) and ended 15.5 mm deep.
                    let fast_at = if rewind { 0.5 * prediction } else { prediction };
                    let fast = travelled >= mesh.min_extent().min(fast_at);
                    // A body still over the step (less than half the slop) is not read against
                    // dynamic partners, nor against fixed ones while it moved less than a tenth
                    // of the slop (the resting push's tolerance) since its pairs were last read
                    // (over the step where they never were). With the step's motion alone, a
                    // 57 cm box at rest on a corner tile, its manifold recycled from a 3° tilt
                    // and reading it apart, crept 0.01-0.02 mm a step, each too little to look,
                    // from the 0.90 mm resting slop to 1.06 mm (`swept_partners`); measured
                    // since the last read, against half the slop it still reached 1.06 mm,
                    // against a quarter 1.04. (Against dynamic partners too, the measure since
                    // the last read made the pyramid stress scene's step 3-4 % dearer.)
                    let since_read = self.pairs_read_at.get(&ch).map_or(travelled, |p| {
                        (pose_now.translation - p.translation).length()
                            + p.rotation.angle_between(pose_now.rotation) * arm
                    });
                    let still_step = travelled <= 0.5 * slop;
                    let unmoved_since_read = since_read <= 0.1 * slop;
                    if pass == 0 && !(still_step && unmoved_since_read) {
                        self.pairs_read_at.insert(ch, pose_now);
                    }
                    // The partners the guard leaves alone before measuring them, and how it
                    // reads the others (`left_alone.rs`).
                    let screen = Screen {
                        world,
                        meshes: &self.hooks.meshes,
                        prev_poses: &self.hooks.prev_poses,
                        options: &self.options,
                        ch,
                        mover: Mover {
                            collider: co,
                            mesh: &mesh,
                            exact: mesh_exact,
                            pose: pose_now,
                            prev_pose,
                            motion: d,
                            turn,
                            arm,
                            still: still_step,
                            unmoved_since_read,
                        },
                        articulated,
                        prediction,
                        slop,
                    };
                    let reach = self.hooks.meshes.get(&ch).map_or(0.0, |m| m.reach);
                    // Tools (kinematic) may have no narrow-phase pairs with fixed colliders
                    // (rapier's default collision types): always query them.
                    let partners: Vec<(ColliderHandle, Option<PairView>)> =
                        if fast || pass > 0 || is_tool {
                            // In the first pass, a dynamic body whose dynamic partners are
                            // all rapier's needs only the still ones (`swept.rs`).
                            let still = (pass == 0 && !is_tool && !rewind).then(|| {
                                let s = still.get_or_insert_with(|| {
                                    StillPartners::collect(world, &self.hooks, prediction + slop)
                                });
                                s.take_in_moved(world, &self.hooks.prev_poses, &moved_bodies);
                                &*s
                            });
                            let path = (&pose_now, &prev_pose, turn);
                            swept_partners(world, still, co, path, (d.length(), &mesh))
                                .map(|h| (h, None))
                                .collect()
                        } else {
                            screen.restless_pairs(&self.pair_states)
                        };
                    for (ph, view) in partners {
                        let Some(partner) = world.colliders.get(ph) else {
                            continue;
                        };
                        if ph == ch || partner.parent() == Some(bh) {
                            continue;
                        }
                        // (Most of a pile's swept partners; a slow body's were left out above.)
                        if view.is_none()
                            && screen.left_to_rapier(ph, partner, None, &self.pair_states)
                        {
                            continue;
                        }
                        // Only pairs rapier itself would solve (sensors, groups, disabled
                        // colliders, collision types and the user's pair filter are rapier's
                        // say), asked in rapier's own pair order when it has the pair. rapier
                        // finds a pair by scanning the first collider's pairs: the mover's are
                        // few, a floor's are every body on it (scanning the floor's was a
                        // twelfth of the guard on the TriMesh-floor stress scene).
                        let rapier_pair = world.narrow_phase.contact_pair(ch, ph);
                        if view.is_none()
                            && screen.kept_apart(ph, partner, rapier_pair, &self.pair_states)
                        {
                            continue;
                        }
                        let (a, b) = rapier_pair.map_or((ph, ch), |p| (p.collider1, p.collider2));
                        if !rapier_solves_pair(
                            &world.bodies,
                            &world.colliders,
                            (&world.impulse_joints, &world.multibody_joints),
                            &self.hooks.inner,
                            a,
                            b,
                            is_tool,
                        ) {
                            continue;
                        }
                        let Some(partner_mesh) = self.hooks.meshes.get(&ph).map(|m| m.mesh.clone())
                        else {
                            continue;
                        };
                        let partner_body = partner.parent();
                        let curved = screen.curved_with(ph);
                        // A pair rapier's manifold shows overlapping when the step began is a
                        // resting contact rapier is resolving: no first touch on this step's
                        // path. Pairs of two dynamic bodies (a stack) are rapier's; against a
                        // fixed or kinematic partner, only a pair now deeper than the resting
                        // slop is measured (along rapier's normal) and pushed back. Nothing is
                        // reconstructed for the resting pairs of a calm pile.
                        let PairView {
                            partner_pose,
                            dp,
                            travel,
                            rapier,
                            trusted,
                            corner_reach,
                            partner_dynamic,
                            turned_since_update,
                        } = view.unwrap_or_else(|| screen.read(ph, partner, rapier_pair));
                        // rapier's points on a body far smaller than its still partner can be
                        // wrong; a deep resting overlap they claim is checked (`misread.rs`),
                        // and, misread, they are set aside: the pair is read as one rapier
                        // holds no point for.
                        // (Where the partner was when the step began: asked only by the few
                        // pairs that need it, not by every pair of a pile.)
                        let partner_prev = || {
                            previous_collider_pose(&self.hooks.prev_poses, partner, partner_pose)
                        };
                        let rapier = rapier.filter(|r| {
                            partner_dynamic
                                || !r.in_contact_at_start
                                || !depth_misread(
                                    r.depth_at_start,
                                    self.options.resting_slop.max(0.25 * mesh.min_extent()),
                                    (partner, &partner_prev()),
                                    (co, &prev_pose),
                                )
                        });
                        let overlapped = rapier.is_some_and(|r| r.in_contact_at_start);
                        let safe = safe_step(&mesh, &partner_mesh);
                        let may_tunnel = (d - dp).length() >= safe;
                        // Two dynamic bodies rapier already had in contact when the step began
                        // (its manifold holds points for them) that moved less than their safe
                        // step length relative to each other: rapier's solver held that contact
                        // through the step and neither passed through the other. What overlap
                        // is left is rapier's soft contact, left as vanilla rapier leaves it:
                        // pushing one body of a falling pile out of the body under it drove the
                        // body above 0.9 m into it (rapier's convex-hull stress scene). (A
                        // dynamic partner within the safe step was already left out above,
                        // before its points were read: `left_to_rapier`; `!may_tunnel` only
                        // restates that.)
                        // A link of an articulation that cannot have passed through its
                        // partner, or whose partner is a link of the same articulation, is
                        // rapier's (`articulations.rs`). On rapier's ragdolls stress scene,
                        // whose limbs the guard stopped at the floor one at a time while the
                        // rest of each ragdoll fell on, the ragdolls went deeper into each
                        // other than in vanilla rapier (over 15 runs with gravity scaled by
                        // 1 + k·1e-6, |k| ≤ 7: median 81.5 mm, at most 100.2 mm, against
                        // vanilla's 59.9 and 69.5 mm). A chain of three boxes slammed onto a
                        // plate at 49 m/s folded, and the guard walked its first link back out
                        // of its third, 0.92 of its half-size down into the plate.
                        if articulated
                            && (!may_tunnel
                                || partner_body.is_some_and(|pb| same_articulation(world, bh, pb)))
                        {
                            continue;
                        }
                        let fresh_impact = self.options.rewind_dynamic_impacts
                            && rapier.is_none()
                            && travel > prediction + slop;
                        if partner_dynamic && (overlapped || (!may_tunnel && !fresh_impact)) {
                            continue;
                        }
                        // (A pair that moved farther is measured on its own path below.)
                        let resting = rapier.filter(|_| overlapped && trusted);
                        let resting_slop = resting.map_or(self.options.resting_slop, |_| {
                            let extent = mesh.min_extent().min(partner_mesh.min_extent());
                            resting_slop(&self.options, world, (ch, extent), partner, d)
                        });
                        // A resting pair is pushed back (below) to the depth it had when the
                        // step began, at least the resting slop; a push within a tenth of the
                        // slop of that is not made.
                        let resting_target = resting.map(|r| r.depth_at_start.max(resting_slop));
                        let push_tolerance = 0.1 * slop;
                        // A resting pair no deeper than its push would leave it is rapier's
                        // (`resting_within`).
                        if let (Some(r), Some(target)) = (&resting, resting_target) {
                            if resting_within(
                                (r, corner_reach),
                                target + push_tolerance,
                                (partner, &partner_pose),
                                (co, &pose_now),
                            ) {
                                continue;
                            }
                        }
                        // parry's contact normal at the pose now, on a huge box's part near
                        // the mover (`geometry::contact_near`), against a still convex partner.
                        let near_normal = || {
                            (!partner_dynamic && partner.shape().is_convex())
                                .then(|| {
                                    contact_near(
                                        partner.shape(),
                                        &partner_pose,
                                        co.shape(),
                                        &pose_now,
                                        0.0,
                                    )
                                })
                                .flatten()
                                .flatten()
                                .map(|c| c.normal1)
                        };
                        let push_out = |out: Vector| {
                            push_out(
                                self.options.reconstruction,
                                curved,
                                (partner, &partner_mesh, &partner_pose),
                                (co, &mesh, &pose_now),
                                out,
                            )
                        };
                        // A slow pair rapier holds points for but read apart when the step
                        // began and reads apart now, on a still convex partner, that overlapped
                        // when the step began and got deeper (`deeper_than_at_start`): no
                        // first touch on its path, and no resting pair. How deep it was then.
                        let misread_start = (resting.is_none()
                            && rapier.is_some()
                            && !overlapped
                            && !partner_dynamic
                            && !may_tunnel
                            && partner.shape().is_convex())
                        .then(|| {
                            deeper_than_at_start(
                                (partner, &partner_prev(), &partner_pose),
                                (co, &prev_pose, &pose_now),
                                (resting_slop, push_tolerance),
                            )
                        })
                        .flatten()
                        .filter(|&start| start > 0.0);
                        let (config, along_normal, blocked_at_start) = if let Some(r) = &resting {
                            let Some(c) = push_out(r.normal) else {
                                continue;
                            };
                            (c.clone(), Some(c), false)
                        } else if misread_start.is_some() {
                            // Pushed back along parry's normal at the pose now to the depth it
                            // had then (at least the resting slop), as a resting pair is.
                            let Some(c) = near_normal().and_then(push_out) else {
                                continue;
                            };
                            (c.clone(), Some(c), false)
                        } else {
                            // A slow pair that rapier's own points, or the shapes lifted along
                            // rapier's normal, show within the slop (`slow_pair_calm`).
                            if !self.options.report_touching
                                && !may_tunnel
                                && slow_pair_calm(
                                    (rapier, trusted, corner_reach),
                                    (travel, overlapped, curved),
                                    (resting_slop, slop),
                                    (partner, &partner_pose),
                                    (co, &pose_now),
                                )
                            {
                                continue;
                            }
                            // A pair rapier has contact points for, but that moved too far to
                            // read them, is reconstructed: parry's contact query is not asked
                            // (it answered wrongly for a 4 m plate lying on a 100 m floor).
                            if !self.options.report_touching && !may_tunnel && rapier.is_none() {
                                let measured = measure_slow_pair(
                                    world,
                                    (&self.hooks.prev_poses, &self.hooks.inner),
                                    &mut self.pair_states,
                                    (ch, co, pose_now, &mesh, reach),
                                    (ph, partner, partner_pose, &partner_mesh),
                                    (a, b),
                                    partner_body.filter(|_| partner_dynamic).map(|pb| (bh, pb)),
                                    (travel, slop),
                                );
                                match measured {
                                    SlowPair::Within => continue,
                                    SlowPair::Rewind(_) if !self.options.correct_poses => continue,
                                    SlowPair::Rewind(rewind) => {
                                        apply_rewind(world, &rewind);
                                        moved_bodies.extend(rewind.map(|(h, _, _)| h));
                                        self.record_correction(world, ch, ph);
                                        moved = true;
                                        break;
                                    }
                                    SlowPair::Reconstruct => {}
                                }
                            }
                            // A fast pair with a still partner that stayed within the slop
                            // over the whole step (`swept_calm.rs`).
                            if !self.options.report_touching
                                && !is_tool
                                && !partner_dynamic
                                && may_tunnel
                                && stayed_within_slop(
                                    (world, &self.hooks.prev_poses),
                                    (partner, &partner_pose),
                                    (co, &pose_now, &mesh),
                                    rapier.map(|r| r.normal),
                                    (travel, slop),
                                )
                            {
                                continue;
                            }
                            // A pair whose first touch is not on the step is pushed out along
                            // rapier's normal (below): its way out along the path is walked
                            // only when there is none.
                            let configuration = |rec: &mut Reconstructor, first_touch_only| {
                                rec.set_first_touch_only(first_touch_only);
                                pair_configuration(
                                    rec,
                                    &self.hooks.meshes,
                                    &self.hooks.prev_poses,
                                    &world.bodies,
                                    &world.colliders,
                                    ph,
                                    Some(partner_pose),
                                    ch,
                                    Some(pose_now),
                                )
                            };
                            let Some(config) = configuration(&mut self.reconstructor, true) else {
                                continue;
                            };
                            // A pair that already overlapped when the step began has no first touch
                            // on this step's path: it is measured along rapier's own contact normal
                            // instead (its exit along -D can be far away). So is a pair rapier had
                            // in contact when the step began whose first touch is at the path's
                            // very start (a cube spinning on its edge, too fast for rapier's points
                            // to be read): undoing the whole step froze such bodies on the floor,
                            // balanced on an edge, for hundreds of steps (CCD stress scene).
                            // Only on a convex partner: on an open TriMesh floor the push along
                            // rapier's normal left a spinning L-shaped body 1.7 mm in.
                            // A curved shape rolling on its partner is such a pair too, whatever
                            // rapier's points say (they stay where the shape touched, and it rolls
                            // away from them): within the resting slop of it when the step began,
                            // by parry's distance on the shapes.
                            let rolling = || {
                                curved
                                    && parry3d::query::distance(
                                        &partner_prev(),
                                        partner.shape(),
                                        &prev_pose,
                                        co.shape(),
                                    )
                                    .is_ok_and(|d| d.distance <= resting_slop)
                            };
                            // rapier's manifold may miss a pair that touched when the step
                            // began (`misread.rs`): a still pair whose path is undone almost
                            // whole while rapier showed it apart, touching at the step's start
                            // by the scaled query, is blocked at its start, and pushed out along
                            // parry's normal at the pose now, not rapier's.
                            let missed_at_start = config.on_trajectory
                                && !overlapped
                                && !is_tool
                                && !partner_dynamic
                                && partner.shape().is_convex()
                                && undone_almost_whole(&config)
                                && touching_at_start(
                                    (partner, &partner_prev()),
                                    (co, &prev_pose),
                                    slop,
                                );
                            let blocked_at_start = missed_at_start
                                || config.on_trajectory
                                    && partner.shape().is_convex()
                                    && ((overlapped && undone_almost_whole(&config)) || rolling());
                            // A path that met a still, convex partner at a graze (within about
                            // 15° of the contact plane) is pushed out along the contact's normal
                            // too, keeping its motion along the plane: walked back along its
                            // path, a hull sliding at 40 sizes a second over a plate went back
                            // most of a step, and stopped dead, and so did a cone at 29 sizes a
                            // second. (A curved pair's push asks only the near part of a huge
                            // box: asked of the whole plate, 200 times their size, it read
                            // cones apart while they were in it, and they went through.)
                            // (Its normal turned out of the partner: `misread.rs`.)
                            let graze_normal = (config.on_trajectory
                                && !blocked_at_start
                                && !partner_dynamic
                                && partner.shape().is_convex())
                            .then(|| normal_out_of_convex(&config, (partner, &partner_pose)))
                            .flatten()
                            .filter(|n| n.dot(config.direction).abs() < crate::geometry::GRAZING);
                            let along_normal = if (config.on_trajectory
                                && !blocked_at_start
                                && graze_normal.is_none())
                                || !config.needs_correction()
                            {
                                None
                            } else if let Some(n) = graze_normal {
                                push_out(n)
                            } else {
                                // (rapier holds no normal for a pair it found apart when the
                                // step began: parry's at the pose now, as below.)
                                rapier
                                    .filter(|_| !missed_at_start)
                                    .and_then(|_| rapier_normal(world, ph, ch))
                                    .or_else(near_normal)
                                    .and_then(push_out)
                            };
                            let blocked_at_start = blocked_at_start || graze_normal.is_some();
                            let config = match along_normal {
                                None if !config.on_trajectory && config.needs_correction() => {
                                    let Some(c) = configuration(&mut self.reconstructor, false)
                                    else {
                                        continue;
                                    };
                                    c
                                }
                                _ => config,
                            };
                            (config, along_normal, blocked_at_start)
                        };
                        if pass == 0
                            && config.state != TouchState::Separated
                            && reported.insert((ph, ch))
                        {
                            self.reports.push(PairReport::new(
                                ph,
                                ch,
                                along_normal.as_ref().unwrap_or(&config),
                            ));
                        }
                        // A first touch on this step's own path is undone to first touch. A pair
                        // that already overlapped when the step began (a resting contact rapier
                        // is resolving) against a fixed or kinematic partner is only pushed
                        // back, along rapier's normal, to the resting slop when it got deeper;
                        // resting pairs of two dynamic bodies (a stack) are rapier's.
                        let on_path =
                            config.on_trajectory && resting.is_none() && along_normal.is_none();
                        // A resting contact is pushed back to the depth it had when the step
                        // began (at least the resting slop): whatever got deeper than the
                        // resting slop never gets deeper still, and rapier's steady overlap is
                        // left alone.
                        // So is a pair rapier misread (`misread_start`). A path blocked at its
                        // start (above) is pushed back to the slop.
                        // (How deep the resting or misread pair was when the step began.)
                        let at_start = resting.map(|r| r.depth_at_start).or(misread_start);
                        let target = match at_start {
                            Some(d) => d.max(resting_slop),
                            None if blocked_at_start => slop,
                            None => resting_slop,
                        };
                        // Over one step a pair gets deeper by at most its relative travel: an
                        // overlap along the normal beyond that (and beyond what rapier's points
                        // showed when the step began) is a measure gone wrong, not a motion to
                        // undo. (An open, bumpy TriMesh floor gave a way out 3.8 m long for a
                        // cube that had moved 5 mm; the push put it inside a ball.)
                        // (On a manifold rapier recycled since a turn, the depth when the
                        // step began is not known: rapier's points re-read now and what the
                        // turn may have brought past them bound it instead.)
                        let recycled_bound = rapier
                            .filter(|_| turned_since_update)
                            .map_or(0.0, |r| r.depth + corner_reach + resting_slop);
                        let deepest_possible =
                            (travel + at_start.unwrap_or(0.0) + resting_slop).max(recycled_bound);
                        // A push along rapier's normal that is no measure may be along a wrong
                        // normal (rapier's, against a box far larger than the mover, can be
                        // tens of degrees off): pushed along parry's at the pose now instead,
                        // asked of the box's part near the mover (`geometry::contact_near`).
                        // A cone sliding on a plate 200 times its size was left 2.8 plate
                        // thicknesses in, its push along rapier's normal 0.6 m long.
                        let along_normal = match along_normal {
                            Some(c) if c.depth > deepest_possible => near_normal()
                                .and_then(push_out)
                                .filter(|c| c.depth <= deepest_possible)
                                .or(Some(c)),
                            other => other,
                        };
                        let config = match (&along_normal, on_path) {
                            (_, true) => config,
                            (Some(c), false) if c.depth <= deepest_possible && !partner_dynamic => {
                                if c.depth <= target + push_tolerance {
                                    continue;
                                }
                                let keep = target / c.depth;
                                let mut c = c.clone();
                                c.reversing_vector *= 1.0 - keep;
                                c.touch_pose.translation =
                                    pose_now.translation + c.reversing_vector;
                                c.depth -= target;
                                c
                            }
                            // A blocked path whose push along rapier's normal is no measure
                            // (deeper than the pair could have got) is undone to first touch.
                            _ if blocked_at_start => config,
                            _ => continue,
                        };
                        // (A resting push is already net of its slop.)
                        if !self.options.correct_poses
                            || !config.needs_correction()
                            || (config.on_trajectory
                                && config.state == TouchState::Penetrating
                                && config.depth <= slop)
                        {
                            continue;
                        }
                        // Contacts the user's `modify_solver_contacts` removes (a one-way
                        // platform passed from below) are not solved by rapier either.
                        if let Some(patch) = config.patches.first() {
                            if user_removes_contact(
                                world,
                                &self.hooks.inner,
                                (a, b),
                                ph,
                                patch.normal,
                                patch.center(),
                                config.depth,
                            ) {
                                continue;
                            }
                        }
                        // (A fresh impact parry has no shape cast for, such as two dynamic
                        // TriMeshes: rewound to the reconstruction's first touch.)
                        let rewound = partner_body
                            .filter(|_| fresh_impact && partner_dynamic && on_path)
                            .and_then(|pb| {
                                rewind_from(
                                    world,
                                    &self.hooks.prev_poses,
                                    &config,
                                    (bh, pb),
                                    (ch, ph),
                                )
                            });
                        if let Some(rewind) = rewound {
                            apply_rewind(world, &rewind);
                            moved_bodies.extend(rewind.map(|(h, _, _)| h));
                        } else {
                            moved_bodies.push(bh);
                            moved_bodies.extend(apply_correction(
                                world,
                                &config,
                                (bh, co_rel, &pose_now),
                                (ph, partner_body),
                            ));
                        }
                        self.record_correction(world, ch, ph);
                        moved = true;
                        break;
                    }
                }
            }
            if !moved {
                break;
            }
            if pass + 1 == passes {
                // Moved by the last pass, with none left to look at them again.
                unsettled.extend(moved_bodies[moved_before..].iter().copied());
            }
        }
        // A body the guard moved was read at the pose it was moved from: measured from there,
        // one that sank back toward it read as unmoved since its pairs were read, and was not
        // read again. A 51 cm box at rest across two tiles, pushed back to the resting slop
        // from 0.99 mm, sank back by a step of rapier's contact and was skipped there, 0.99-1.015
        // mm deep, at one step in three or four. Forgotten, its next step's motion is measured.
        for bh in &moved_bodies {
            if let Some(body) = world.bodies.get(*bh) {
                for ch in body.colliders() {
                    self.pairs_read_at.remove(ch);
                }
            }
        }
        sync_moved_colliders(world, &mut moved_bodies);
        self.sync_hook_flags(world, &unsettled);
    }
}
