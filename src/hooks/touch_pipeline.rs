//! [`TouchPipeline`]: one call that steps a rapier `PhysicsWorld` with the touch hooks, the
//! step guard, the tools' proxies and the contact report.

use super::report::{PairReport, ToolFeedback};
use super::touch_hooks::{body_motion, pair_configuration, CachedMesh, TouchHooks};
use crate::geometry::{ReconstructionOptions, Reconstructor, TouchMesh, TouchState};
use crate::math::{Pose, Real, Vector};
use parry3d::bounding_volume::BoundingVolume;
use rapier3d::dynamics::{IntegrationParameters, RigidBodyHandle};
use rapier3d::geometry::{ColliderHandle, ColliderSet};
use rapier3d::pipeline::{ActiveHooks, EventHandler, PhysicsHooks, PhysicsWorld, QueryFilter};
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

/// Tuning of [`TouchPipeline`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TouchOptions {
    /// Penetration (along the trajectory) the step guard tolerates before it moves a body back
    /// to first touch. Default `2e-4` m: below rapier's own resting overlap noise, well below the
    /// 1 mm a user sees. Range `0 ..= 0.01`; smaller values correct more often.
    pub penetration_slop: Real,
    /// Correct poses between steps (the step guard). Default `true`. With `false` the crate only
    /// rewrites manifolds (hooks) and reports.
    pub correct_poses: bool,
    /// Guard passes per step (a correction can push a body into a third one). Default 3.
    pub max_passes: usize,
    /// Reconstruct and report touching pairs too. Default `false`: the guard then skips pairs
    /// that can neither have tunneled (relative step shorter than the safe step length) nor
    /// penetrate deeper than the slop (parry's contact query), and reports only the pairs it
    /// reconstructs. `true` reconstructs every pair whose swept boxes meet (slower).
    pub report_touching: bool,
    /// Options of the reconstructions.
    pub reconstruction: ReconstructionOptions,
}

impl Default for TouchOptions {
    fn default() -> Self {
        Self {
            penetration_slop: 2.0e-4,
            correct_poses: true,
            max_passes: 3,
            report_touching: false,
            reconstruction: ReconstructionOptions::default(),
        }
    }
}

/// A user-driven tool (god-object / proxy): where the device puts it, and where the crate lets
/// it be.
#[derive(Copy, Clone, Debug)]
struct Tool {
    device: Pose,
    proxy: Pose,
}

/// Steps a rapier [`PhysicsWorld`] with exact touch contacts.
///
/// Colliders take part when they have `ActiveHooks::MODIFY_SOLVER_CONTACTS` and a shape with a
/// triangle-mesh form ([`TouchMesh::from_shape`]). Each [`TouchPipeline::step`]:
/// 1. records every body's pose (the history the reconstruction walks back along);
/// 2. runs rapier's step with [`TouchHooks`] (which forward to your hooks);
/// 3. **step guard:** for every moving dynamic body, reconstructs it against each opted-in
///    collider its swept box touches; a body that penetrates deeper than the slop, or that went
///    through a thin object (perforation), is moved back along its own trajectory to first touch
///    and loses its velocity into the surface. This *clamps the motion to first touch*, so fast
///    objects do not tunnel even with rapier's CCD off, and moving TriMesh bodies (which
///    rapier's CCD never sweeps) are guarded too;
/// 4. **tools:** a kinematic body registered with [`TouchPipeline::set_tool_target`] is put at
///    the last pose that does not penetrate (its proxy), and
///    [`TouchPipeline::tool_feedback`] gives the device-to-proxy offset for a feedback force;
/// 5. fills the [`PairReport`]s of the step ([`TouchPipeline::reports`]).
///
/// # Example
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::*;
///
/// let mut world = PhysicsWorld::default();
/// world.integration_parameters.contact_clustering = false;
/// world.insert_collider(
///     ColliderBuilder::cuboid(5.0, 0.05, 5.0).active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS),
///     None,
/// );
/// let body = world.insert_body(
///     RigidBodyBuilder::dynamic()
///         .translation(Vector::new(0.0, 2.0, 0.0))
///         .linvel(Vector::new(0.0, -100.0, 0.0)),
/// );
/// world.insert_collider(
///     ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS),
///     Some(body),
/// );
/// let mut touch = TouchPipeline::default();
/// for _ in 0..60 {
///     touch.step(&mut world);
/// }
/// // A 100 m/s box does not go through a 10 cm slab (rapier's CCD is on by default, but the
/// // guard does not need it).
/// assert!(world.bodies[body].translation().y > 0.0);
/// ```
pub struct TouchPipeline<H: PhysicsHooks = ()> {
    /// The hooks handed to rapier's step (they forward to your hooks).
    pub hooks: TouchHooks<H>,
    /// Tuning.
    pub options: TouchOptions,
    reconstructor: Reconstructor,
    reports: Vec<PairReport>,
    tools: HashMap<RigidBodyHandle, Tool>,
    corrections: usize,
}

impl Default for TouchPipeline<()> {
    fn default() -> Self {
        Self::new(())
    }
}

impl TouchPipeline<()> {
    /// Sets the integration parameters this crate expects: no contact clustering (mesh
    /// manifolds keep their triangles).
    pub fn configure(params: &mut IntegrationParameters) {
        params.contact_clustering = false;
    }
}

impl<H: PhysicsHooks> TouchPipeline<H> {
    /// A pipeline whose hooks forward to `inner`.
    pub fn new(inner: H) -> Self {
        Self {
            hooks: TouchHooks::new(inner),
            options: TouchOptions::default(),
            reconstructor: Reconstructor::default(),
            reports: Vec::new(),
            tools: HashMap::new(),
            corrections: 0,
        }
    }

    /// The reports of the last step: one per reconstructed pair that touched, penetrated or
    /// perforated.
    pub fn reports(&self) -> &[PairReport] {
        &self.reports
    }

    /// How many body poses the step guard corrected during the last step.
    pub fn corrections(&self) -> usize {
        self.corrections
    }

    /// Drives kinematic body `body` as a tool toward `device` (a mouse or haptic device pose).
    /// At each step the body moves toward the device pose but stops at first touch; see
    /// [`TouchPipeline::tool_feedback`].
    pub fn set_tool_target(&mut self, body: RigidBodyHandle, device: Pose) {
        let e = self.tools.entry(body).or_insert(Tool {
            device,
            proxy: device,
        });
        e.device = device;
    }

    /// Stops treating `body` as a tool.
    pub fn remove_tool(&mut self, body: RigidBodyHandle) {
        self.tools.remove(&body);
    }

    /// The device pose, the proxy pose and their offset for tool `body`, after the last step.
    pub fn tool_feedback(&self, body: RigidBodyHandle) -> Option<ToolFeedback> {
        self.tools.get(&body).map(|t| ToolFeedback {
            device: t.device,
            proxy: t.proxy,
            offset: t.proxy.translation - t.device.translation,
        })
    }

    /// Steps `world` once: see the type's documentation.
    pub fn step(&mut self, world: &mut PhysicsWorld) {
        self.step_with_events(world, &());
    }

    /// Like [`TouchPipeline::step`], with rapier's event handler.
    pub fn step_with_events(&mut self, world: &mut PhysicsWorld, events: &dyn EventHandler) {
        self.refresh_meshes(&world.colliders);
        self.hooks.options = self.options.reconstruction;
        self.hooks.slop = self.options.penetration_slop;
        self.reconstructor.options = self.options.reconstruction;

        // Tools: aim the kinematic bodies at their device pose.
        self.tools.retain(|h, _| world.bodies.contains(*h));
        for (h, tool) in &self.tools {
            if let Some(b) = world.bodies.get_mut(*h) {
                if b.is_kinematic() {
                    b.set_next_kinematic_position(tool.device);
                }
            }
        }

        // Pose history: where every body starts this step.
        let prev: HashMap<RigidBodyHandle, Pose> = world
            .bodies
            .iter()
            .map(|(h, b)| (h, *b.position()))
            .collect();
        self.hooks.begin_step();
        world.step_with_events(&self.hooks, events);
        self.hooks.prev_poses = prev;

        self.reports.clear();
        self.corrections = 0;
        self.guard(world);
        let proxies: Vec<(RigidBodyHandle, Pose)> = self
            .tools
            .keys()
            .filter_map(|h| Some((*h, *world.bodies.get(*h)?.position())))
            .collect();
        for (h, p) in proxies {
            if let Some(t) = self.tools.get_mut(&h) {
                t.proxy = p;
            }
        }
    }

    /// Cheap test before a reconstruction: could the moving collider have tunneled (its
    /// motion relative to the partner is at least the pair's safe step), or does parry's
    /// contact query find it deeper than the slop? Shape pairs parry cannot answer for
    /// (TriMesh against TriMesh) are always reconstructed.
    fn needs_reconstruction(
        &self,
        world: &PhysicsWorld,
        ch: ColliderHandle,
        pose: &Pose,
        d: Vector,
        ph: ColliderHandle,
        partner_pose: &Pose,
    ) -> bool {
        let (Some(m), Some(f)) = (self.hooks.meshes.get(&ch), self.hooks.meshes.get(&ph)) else {
            return false;
        };
        let (Some(co), Some(partner)) = (world.colliders.get(ch), world.colliders.get(ph)) else {
            return false;
        };
        let dp = body_motion(&self.hooks.prev_poses, &world.bodies, partner.parent());
        // A flat partner (zero extent) bounds nothing: the moving object's own extent does.
        let safe = match (m.mesh.min_extent(), f.mesh.min_extent()) {
            (a, b) if b > 0.0 => a.min(b),
            (a, _) => a,
        };
        if (d - dp).length() >= safe {
            return true;
        }
        match parry3d::query::contact(partner_pose, partner.shape(), pose, co.shape(), 0.0) {
            Ok(Some(c)) => c.dist < -self.options.penetration_slop,
            Ok(None) => false,
            Err(_) => true,
        }
    }

    /// Builds (or drops) the touch meshes of opted-in colliders.
    fn refresh_meshes(&mut self, colliders: &ColliderSet) {
        let meshes = &mut self.hooks.meshes;
        meshes.retain(|h, _| colliders.contains(*h));
        for (h, co) in colliders.iter() {
            if !co
                .active_hooks()
                .contains(ActiveHooks::MODIFY_SOLVER_CONTACTS)
            {
                meshes.remove(&h);
                continue;
            }
            let ptr = Arc::as_ptr(&co.shared_shape().0) as *const u8 as usize;
            if meshes.get(&h).is_some_and(|m| m.shape_ptr == ptr) {
                continue;
            }
            match TouchMesh::from_shape(co.shape()) {
                Ok(mesh) => {
                    meshes.insert(
                        h,
                        CachedMesh {
                            shape_ptr: ptr,
                            mesh: Arc::new(mesh),
                        },
                    );
                }
                Err(_) => {
                    meshes.remove(&h);
                }
            }
        }
    }

    /// The step guard: moves bodies that penetrate (or went through something) back to first
    /// touch, and records the reports.
    fn guard(&mut self, world: &mut PhysicsWorld) {
        let passes = if self.options.correct_poses {
            self.options.max_passes.max(1)
        } else {
            1
        };
        let mut reported: HashSet<(ColliderHandle, ColliderHandle)> = HashSet::new();
        for pass in 0..passes {
            let mut moved = false;
            // Moving bodies with opted-in colliders.
            let movers: Vec<RigidBodyHandle> = world
                .bodies
                .iter()
                .filter(|(h, b)| {
                    (b.is_dynamic() || self.tools.contains_key(h))
                        && !b.is_sleeping()
                        && b.colliders()
                            .iter()
                            .any(|c| self.hooks.meshes.contains_key(c))
                })
                .map(|(h, _)| h)
                .collect();
            for bh in movers {
                let Some(body) = world.bodies.get(bh) else {
                    continue;
                };
                let body_pose = *body.position();
                let d = body_motion(&self.hooks.prev_poses, &world.bodies, Some(bh));
                let own: Vec<ColliderHandle> = body.colliders().to_vec();
                for ch in own {
                    if !self.hooks.meshes.contains_key(&ch) {
                        continue;
                    }
                    let Some(co) = world.colliders.get(ch) else {
                        continue;
                    };
                    let pose_now = co
                        .position_wrt_parent()
                        .map_or(*co.position(), |rel| body_pose * *rel);
                    let prev_pose = Pose::from_parts(pose_now.translation - d, pose_now.rotation);
                    let swept = co
                        .shape()
                        .compute_aabb(&pose_now)
                        .merged(&co.shape().compute_aabb(&prev_pose));
                    let partners: Vec<ColliderHandle> = world
                        .intersect_aabb_conservative(swept, QueryFilter::default())
                        .filter(|(h, c)| {
                            *h != ch && c.parent() != Some(bh) && self.hooks.meshes.contains_key(h)
                        })
                        .map(|(h, _)| h)
                        .collect();
                    for ph in partners {
                        let Some(partner) = world.colliders.get(ph) else {
                            continue;
                        };
                        let partner_pose = match partner.parent() {
                            Some(pb) => match (world.bodies.get(pb), partner.position_wrt_parent())
                            {
                                (Some(b), Some(rel)) => *b.position() * *rel,
                                _ => *partner.position(),
                            },
                            None => *partner.position(),
                        };
                        let partner_body = partner.parent();
                        if !self.options.report_touching
                            && !self.needs_reconstruction(
                                world,
                                ch,
                                &pose_now,
                                d,
                                ph,
                                &partner_pose,
                            )
                        {
                            continue;
                        }
                        let Some(config) = pair_configuration(
                            &mut self.reconstructor,
                            &self.hooks.meshes,
                            &self.hooks.prev_poses,
                            &world.bodies,
                            &world.colliders,
                            ph,
                            Some(partner_pose),
                            ch,
                            Some(pose_now),
                        ) else {
                            continue;
                        };
                        if pass == 0
                            && config.state != TouchState::Separated
                            && reported.insert((ph, ch))
                        {
                            // A pair that already overlapped when the step began has no first
                            // touch on this step's path: report it along rapier's own contact
                            // normal instead (its exit along -D can be far away).
                            let shown = if config.on_trajectory {
                                None
                            } else {
                                rapier_normal(world, ph, ch).and_then(|n| {
                                    let mut rec = Reconstructor::new(ReconstructionOptions {
                                        zero_motion_direction: Some(-n),
                                        ..self.options.reconstruction
                                    });
                                    let fixed = &self.hooks.meshes.get(&ph)?.mesh;
                                    let moving = &self.hooks.meshes.get(&ch)?.mesh;
                                    rec.reconstruct(
                                        fixed,
                                        &partner_pose,
                                        moving,
                                        &pose_now,
                                        &pose_now,
                                    )
                                    .ok()
                                })
                            };
                            self.reports.push(PairReport::new(
                                ph,
                                ch,
                                shown.as_ref().unwrap_or(&config),
                            ));
                        }
                        // Only a first touch on this step's own path is corrected: a pair that
                        // already overlapped when the step began (a resting contact rapier is
                        // pushing apart) is rapier's to resolve.
                        if !self.options.correct_poses
                            || !config.needs_correction()
                            || !config.on_trajectory
                            || (config.state == TouchState::Penetrating
                                && config.depth <= self.options.penetration_slop)
                        {
                            continue;
                        }
                        let r = config.reversing_vector;
                        let n = config.patches.first().map(|p| p.normal);
                        // Split the correction by inverse mass when the partner is dynamic too.
                        let partner_dynamic = partner_body
                            .and_then(|pb| world.bodies.get(pb))
                            .filter(|b| b.is_dynamic())
                            .map(|b| b.mass());
                        let own_mass = world.bodies.get(bh).map_or(1.0, |b| b.mass());
                        let share = match partner_dynamic {
                            Some(mp) if mp > 0.0 && own_mass > 0.0 => {
                                (1.0 / own_mass) / (1.0 / own_mass + 1.0 / mp)
                            }
                            _ => 1.0,
                        };
                        if let Some(b) = world.bodies.get_mut(bh) {
                            let t = b.translation() + r * share;
                            if t.is_finite() {
                                b.set_translation(t, true);
                            }
                            if let Some(n) = n {
                                // n points out of the partner toward this body: remove the
                                // velocity into the partner (inelastic).
                                let v = b.linvel();
                                let vn = v.dot(n);
                                if vn < 0.0 && b.is_dynamic() {
                                    b.set_linvel(v - vn * n, true);
                                }
                            }
                        }
                        if let (Some(pb), true) = (partner_body, share < 1.0) {
                            if let Some(b) = world.bodies.get_mut(pb) {
                                let t = b.translation() - r * (1.0 - share);
                                if t.is_finite() {
                                    b.set_translation(t, true);
                                }
                            }
                        }
                        moved = true;
                        self.corrections += 1;
                        break;
                    }
                }
            }
            if !moved {
                break;
            }
        }
    }
}

/// rapier's contact normal for the pair (from its deepest contact), oriented out of `fixed`
/// toward `moving`.
fn rapier_normal(
    world: &PhysicsWorld,
    fixed: ColliderHandle,
    moving: ColliderHandle,
) -> Option<Vector> {
    let pair = world.narrow_phase.contact_pair(fixed, moving)?;
    let (manifold, _) = pair.find_deepest_contact()?;
    let n = manifold.data.normal;
    let n = if pair.collider1 == fixed { n } else { -n };
    n.try_normalize()
}
