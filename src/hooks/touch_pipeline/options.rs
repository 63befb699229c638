//! [`TouchOptions`]: the tuning of [`TouchPipeline`] (slops, the step guard's passes, the
//! opt-in modes, the reconstruction's options).

#[cfg(doc)]
use super::TouchPipeline;
use crate::geometry::ReconstructionOptions;
use crate::math::Real;

/// Tuning of [`TouchPipeline`].
///
/// # Example
/// The step guard ([`TouchOptions::correct_poses`]) is what stops a box falling through a thin
/// slab within one step; the hooks alone cannot:
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// // Drops a box at 60 m/s (1 m per step) on a 10 cm slab, rapier's CCD off; its final height.
/// let drop_box = |options: TouchOptions| -> Real {
///     let mut world = PhysicsWorld::default();
///     TouchPipeline::configure(&mut world.integration_parameters);
///     world.integration_parameters.max_ccd_substeps = 0;
///     let hooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;
///     world.insert_collider(ColliderBuilder::cuboid(2.0, 0.05, 2.0).active_hooks(hooks), None);
///     let body = world.insert_body(
///         RigidBodyBuilder::dynamic()
///             .translation(Vector::new(0.0, 1.5, 0.0))
///             .linvel(Vector::new(0.0, -60.0, 0.0)),
///     );
///     let cube = ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(hooks);
///     world.insert_collider(cube, Some(body));
///     let mut touch = TouchPipeline::new(());
///     touch.options = options;
///     for _ in 0..10 {
///         touch.step(&mut world);
///     }
///     world.bodies[body].translation().y
/// };
///
/// // The step guard (on by default) stops the box on the slab, its centre at 0.05 + 0.25.
/// let guarded = TouchOptions::default();
/// assert!(guarded.correct_poses);
/// assert!((drop_box(guarded) - 0.3).abs() < 2e-3);
/// // The hooks alone cannot: the box went through within a step, no manifold ever saw it.
/// let hooks_only = TouchOptions { correct_poses: false, ..guarded };
/// assert!(drop_box(hooks_only) < -1.0);
/// ```
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TouchOptions {
    /// Penetration (along the trajectory) the step guard tolerates before it moves a body back
    /// to first touch, in rapier's length unit (`IntegrationParameters::length_unit` metres,
    /// as rapier's own tolerances are; [`TouchOptions::in_length_unit`]). Default `2e-4` (at
    /// rapier's default unit, 0.2 mm): below rapier's own resting overlap noise, well below
    /// the 1 mm a user sees. Range `0 ..= 0.01`; smaller values correct more often.
    pub penetration_slop: Real,
    /// Correct poses between steps (the step guard). Default `true`. With `false` the crate only
    /// rewrites manifolds (hooks) and reports.
    pub correct_poses: bool,
    /// Penetration tolerated for a body that already overlapped a fixed or kinematic collider
    /// when the step began (a resting contact rapier is resolving with its own soft push-out;
    /// rapier's own contact points say whether it did). Deeper than this after a step, the
    /// guard pushes the body back along rapier's contact normal to the deeper of this depth and
    /// the depth the pair had when the step began, so a tumbling or pressed body never digs
    /// further into the floor, while rapier's steady overlap under a tall pile is left alone.
    /// Resting pairs of two dynamic bodies (a stack, whose soft contacts rapier lets overlap by
    /// about a millimetre, and by several under a tall pile) are left to rapier. A still body
    /// in contact with another dynamic body (in a pile) on a convex floor may rest in it as
    /// deep as the deeper of the pile's own contacts' overlap and ten times this slop, capped
    /// at 40 % of the smaller extent of the body and the floor (never below this slop): held
    /// harder against the floor than the pile's bodies hold each other, the bottom of a pile
    /// was pushed into the body above each step and the pile's compression went there.
    /// In rapier's length unit, as the slop above. Default `9e-4` (0.9 mm at rapier's default
    /// unit): above rapier's usual resting overlap, below the 1 mm a user sees. Range
    /// `slop ..= 0.01`.
    pub resting_slop: Real,
    /// Guard passes per step (a correction can push a body into a third one). Default 3.
    pub max_passes: usize,
    /// Rewind fresh impacts of two dynamic bodies. A pair rapier held no contact point for when
    /// the step began (farther apart than its prediction distance) that closed by less than
    /// the pair's safe step cannot have passed through, but rapier's solver never saw it and it
    /// can end the step deep: two boxes of rapier's pyramid 97 mm into each other, a ragdoll's
    /// forearm 126 mm into its torso. With `true` the guard measures such a pair (two support
    /// points along the direction that last separated it, else parry's contact query) and,
    /// deeper than the slop, moves both bodies back along their own step motions to their
    /// first touch (parry's nonlinear shape cast, the query of rapier's CCD) and takes off
    /// their closing velocity as a plastic impact, shared by inverse mass (momentum
    /// conserved, no energy gained); a body resting on a fixed or kinematic collider is held
    /// and takes no share. Default `false`, opt-in: it costs fast, dense piles 1.2-1.5× the
    /// guard's time (rapier's CCD, hull and TriMesh stress scenes), and the two-body impact
    /// leaves the rest of a stack to rapier's next step: 9 boxes of 2 m stacked 2 cm apart
    /// reached 24.5 mm, against vanilla's 19.8 mm (see the README).
    pub rewind_dynamic_impacts: bool,
    /// Manage the `ActiveHooks::MODIFY_SOLVER_CONTACTS` flag of the colliders opted in with
    /// it: the pipeline remembers them, clears the flag, and raises it after a step only on
    /// the colliders whose body moved more than rapier's prediction distance during it (a
    /// slower body meets nothing rapier's speculative contacts did not see coming, and the
    /// guard corrects poses anyway), and only on those whose pairs the hooks can rewrite:
    /// polyhedra that are not composite shapes (a ball's or a TriMesh's pairs are left as
    /// rapier made them, so a flag there only costs). While the guard corrects poses
    /// ([`TouchOptions::correct_poses`]), only the bodies its last pass moved get it: it puts
    /// the pairs it sees back to first touch, and the hooks found nothing to rewrite after it
    /// in five of rapier's six stress scenes. rapier never recycles the contacts
    /// of a pair with a hook flag (its narrow phase recomputes them every step), so a resting
    /// pile with the flag everywhere costs rapier itself about 1.7×. `false` in
    /// [`TouchPipeline::new`] (your hooks may need the flag on every manifold: a one-way
    /// platform), `true` in `TouchPipeline::default()` (no hooks of yours). With it on,
    /// [`TouchPipeline::untrack_collider`] also lets go of a flagged collider.
    pub hook_flags_on_demand: bool,
    /// Reconstruct and report touching pairs too. Default `false`: the guard then skips pairs
    /// that can neither have tunneled (relative step shorter than the safe step length) nor
    /// penetrate deeper than the slop (parry's contact query), and reports only the pairs it
    /// reconstructs. `true` reconstructs every pair whose swept boxes meet (slower).
    pub report_touching: bool,
    /// Options of the reconstructions.
    pub reconstruction: ReconstructionOptions,
}

impl TouchOptions {
    /// These options with the slops given in rapier's length unit (`length_unit` metres,
    /// rapier's `IntegrationParameters::length_unit`) turned into metres, as the pipeline
    /// uses them at each step; a unit that is not positive and finite counts as 1.
    ///
    /// ```
    /// use rapier_touch::prelude::*;
    /// let options = TouchOptions::default().in_length_unit(0.01);
    /// assert!((options.penetration_slop - 2e-6).abs() < 1e-12);
    /// // A unit that is no length leaves the slops as they are.
    /// for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
    ///     assert_eq!(TouchOptions::default().in_length_unit(bad), TouchOptions::default());
    /// }
    /// ```
    pub fn in_length_unit(self, length_unit: Real) -> Self {
        let unit = if length_unit.is_finite() && length_unit > 0.0 {
            length_unit
        } else {
            1.0
        };
        Self {
            penetration_slop: self.penetration_slop * unit,
            resting_slop: self.resting_slop * unit,
            ..self
        }
    }
}

impl Default for TouchOptions {
    fn default() -> Self {
        Self {
            penetration_slop: 2.0e-4,
            resting_slop: 9.0e-4,
            correct_poses: true,
            max_passes: 3,
            rewind_dynamic_impacts: false,
            hook_flags_on_demand: false,
            report_touching: false,
            reconstruction: ReconstructionOptions::default(),
        }
    }
}
