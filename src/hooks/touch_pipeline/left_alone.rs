//! The pairs the step guard leaves alone before it measures them: a dynamic partner within the
//! pair's safe step is rapier's ([`Screen::left_to_rapier`]), a fixed partner whose kept state
//! bounds the pair within the slop is calm ([`Screen::kept_apart`]), and a slow body looks only
//! at rapier's pairs whose contact points do not show them calm ([`Screen::restless_pairs`]).

use super::impacts::stayed_apart;
use super::pair_view::{safe_step, Mover, PairStates, PairView};
use super::rapier_contacts::{collider_pose_now, other_of};
use super::*;

/// One mover's view of its partners while the guard looks at them.
pub(super) struct Screen<'a> {
    pub world: &'a PhysicsWorld,
    pub meshes: &'a HashMap<ColliderHandle, CachedMesh>,
    pub prev_poses: &'a PoseHistory,
    pub options: &'a TouchOptions,
    /// The mover's collider and what [`PairView::read`] needs of it.
    pub ch: ColliderHandle,
    pub mover: Mover<'a>,
    /// The mover is a link of an articulation (`articulations.rs`).
    pub articulated: bool,
    /// Rapier's prediction distance and the penetration slop.
    pub prediction: Real,
    pub slop: Real,
}

impl Screen<'_> {
    /// Whether the pair with `ph` has a curved shape (a tessellated touch mesh): such a pair is
    /// measured on the shapes themselves.
    pub(super) fn curved_with(&self, ph: ColliderHandle) -> bool {
        !(self.mover.exact && self.meshes.get(&ph).is_some_and(|m| m.exact))
    }

    /// The body `partner` is attached to, if any.
    fn body_of(
        &self,
        partner: &rapier3d::geometry::Collider,
    ) -> Option<&rapier3d::dynamics::RigidBody> {
        partner.parent().and_then(|pb| self.world.bodies.get(pb))
    }

    /// The pair with `ph` (`partner`, rapier's contact pair `pair` when it has one) as the
    /// guard reads it ([`PairView::read`]).
    pub(super) fn read(
        &self,
        ph: ColliderHandle,
        partner: &rapier3d::geometry::Collider,
        pair: Option<&rapier3d::geometry::ContactPair>,
    ) -> PairView {
        PairView::read(
            self.world,
            (self.meshes, self.prev_poses),
            &self.mover,
            (ph, partner, pair),
            self.curved_with(ph),
            (self.slop, self.prediction),
        )
    }

    /// Whether the pair with the dynamic (or articulated) `partner` is rapier's solver's,
    /// decided before its contact points are read (rapier's points of every pair in a pile
    /// were most of the guard's time): a partner that moved less than the pair's safe step
    /// relative to this body, or one with no touch mesh.
    ///
    /// Except a fresh impact (`TouchOptions::rewind_dynamic_impacts`): a pair rapier held no
    /// contact point for when the step began (farther apart than its prediction distance, so
    /// its solver never saw them) that closed by more than that and the slop. It cannot have
    /// passed through, but it can end deep: a ragdoll's forearm, struck by the pile above, went
    /// 126 mm into its torso within one step. Such a pair is let go here only when it surely
    /// stayed apart (`impacts::stayed_apart`). A pair rapier held only speculative points for
    /// (within its prediction distance, apart) is rapier's too: its soft contact can leave it
    /// deep (a ball closing on a box at 6 m/s from 6 mm away, 6.3 mm into it), but rewinding
    /// such pairs made the stress scenes' piles much worse (README).
    pub(super) fn left_to_rapier(
        &self,
        ph: ColliderHandle,
        partner: &rapier3d::geometry::Collider,
        pair: Option<&rapier3d::geometry::ContactPair>,
        states: &PairStates,
    ) -> bool {
        let world = self.world;
        let dynamic = self.body_of(partner).is_some_and(|b| b.is_dynamic());
        if !dynamic && !self.articulated {
            return false;
        }
        let Some(pm) = self.meshes.get(&ph) else {
            return true;
        };
        let dp = body_motion(self.prev_poses, &world.bodies, partner.parent());
        let relative = (self.mover.motion - dp).length();
        if relative >= safe_step(self.mover.mesh, &pm.mesh) {
            return false;
        }
        if !dynamic {
            // A link of an articulation within its safe step (`articulations.rs`).
            return true;
        }
        let turn = self.mover.turn;
        if !self.options.rewind_dynamic_impacts || relative + turn <= self.prediction + self.slop {
            return true;
        }
        // (A swept partner's pair is looked up only here: most are let go above.)
        let had_points = pair
            .or_else(|| world.narrow_phase.contact_pair(self.ch, ph))
            .is_some_and(|p| p.manifolds().iter().any(|m| !m.points.is_empty()));
        if had_points {
            return true;
        }
        stayed_apart(
            (world, self.meshes, self.prev_poses, states),
            (self.ch, self.mover.mesh, &self.mover.pose, self.mover.exact),
            (ph, partner),
            relative + turn,
            (self.prediction, self.slop),
        )
    }

    /// Whether the pair with a fixed `partner` that rapier holds no point for is calm: its kept
    /// state ([`PairState`](super::pair_view::PairState)) still bounds it within the slop (a
    /// body falling toward a floor, once measured apart), so it is neither read nor measured
    /// (70 pairs a step on rapier's TriMesh-floor stress scene). Not past the pair's safe
    /// step: the state bounds the overlap, not a passage through a thin partner.
    pub(super) fn kept_apart(
        &self,
        ph: ColliderHandle,
        partner: &rapier3d::geometry::Collider,
        pair: Option<&rapier3d::geometry::ContactPair>,
        states: &PairStates,
    ) -> bool {
        let reach = self.meshes.get(&self.ch).map_or(0.0, |m| m.reach);
        let travel = self.mover.motion.length() + self.mover.turn;
        !self.options.report_touching
            && self.body_of(partner).is_none_or(|b| b.is_fixed())
            && pair.is_none_or(|p| p.manifolds().iter().all(|m| m.points.is_empty()))
            && self
                .meshes
                .get(&ph)
                .is_some_and(|pm| travel < safe_step(self.mover.mesh, &pm.mesh))
            && states.get(&(self.ch, ph)).is_some_and(|st| {
                st.bound(
                    &self.mover.pose,
                    &collider_pose_now(&self.world.bodies, partner),
                    reach,
                ) <= self.slop
            })
    }

    /// A slow body's partners worth a look: only rapier's pairs, and among them only those its
    /// own contact points (re-read at the poses now) do not show calm. A body that moved less
    /// than half the slop changes a pair's depth by less than the slop unless its partner moved
    /// too: a fixed partner did not, and a dynamic one that did checks the pair from its side.
    /// Each comes with its view (`Some`), as the guard's list of partners holds them.
    pub(super) fn restless_pairs(
        &self,
        states: &PairStates,
    ) -> Vec<(ColliderHandle, Option<PairView>)> {
        let world = self.world;
        let calm = !self.options.report_touching;
        let mut restless = Vec::new();
        for p in world.narrow_phase.contact_pairs_with(self.ch) {
            let ph = other_of(p, self.ch);
            let Some(partner) = world.colliders.get(ph) else {
                continue;
            };
            // A still mover is not read against a dynamic partner (that partner, if it moved,
            // reads the pair), nor against a fixed one it moved little against since they were
            // last read (`unmoved_since_read`).
            let skip = calm
                && match self.body_of(partner) {
                    Some(b) if b.is_kinematic() => false,
                    Some(b) if b.is_dynamic() => self.mover.still,
                    _ => self.mover.still && self.mover.unmoved_since_read,
                };
            if skip {
                continue;
            }
            if self.left_to_rapier(ph, partner, Some(p), states)
                || self.kept_apart(ph, partner, Some(p), states)
            {
                continue;
            }
            let view = self.read(ph, partner, Some(p));
            if !view.calm(self.options) {
                restless.push((ph, Some(view)));
            }
        }
        restless
    }
}
