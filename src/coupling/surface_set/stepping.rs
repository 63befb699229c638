//! Stepping a set: the haptic path, the main loop's step around rapier's, and the surfaces'
//! substeps with the tools' reactions and the dynamic tools moved by them.

use super::*;
use rapier3d::dynamics::RigidBodySet;

impl SurfaceSet {
    /// The haptic path: puts `tool` at the device pose `device` (world), steps every surface
    /// once at its own time step with that tool moving from its last haptic pose (the other
    /// tools stay where they are), and returns the tool's reaction. No rigid step and no
    /// collider update: call it at the device's rate (1 kHz and more) between
    /// [`SurfaceSet::step`]s, which keep the rest of the scene going.
    pub fn haptic_step(
        &mut self,
        world: &PhysicsWorld,
        tool: ColliderHandle,
        device: Pose,
    ) -> Option<ToolReaction> {
        if !device.is_finite() || !world.colliders.contains(tool) {
            return None;
        }
        let state = self.tools.get_mut(&tool)?;
        let start = state.haptic_prev.unwrap_or(device);
        state.haptic_prev = Some(device);
        let (shape, friction, grasp) = (state.shape.clone(), state.friction, state.grasp);
        let others: Vec<ToolMotion> = self
            .tools
            .iter()
            .filter(|(h, _)| **h != tool)
            .filter_map(|(h, t)| {
                let p = *world.colliders.get(*h)?.position();
                Some(ToolMotion {
                    handle: *h,
                    start: p,
                    end: p,
                    shape: t.shape.clone(),
                    friction: t.friction,
                    grasp: t.grasp,
                    record: false,
                    holder: None,
                })
            })
            .chain(std::iter::once(ToolMotion {
                handle: tool,
                start,
                end: device,
                shape,
                friction,
                grasp,
                record: false,
                holder: None,
            }))
            .collect();
        let mut total = ToolReaction::default();
        let mut held = Vec::new();
        for (_, s, body_pose) in attached_with_pose(&mut self.entries, world) {
            let h = s.surface.dt();
            for (th, r, contacts) in surface_substep(s, world, &body_pose, (&others, &mut []), h) {
                if th == tool {
                    held.extend(contacts);
                    total.force += r.force;
                    total.torque += r.torque;
                    total.mean_force += r.mean_force;
                    total.held_vertices += r.held_vertices;
                    total.sticking_vertices += r.sticking_vertices;
                    total.pressed_points += r.pressed_points;
                }
            }
        }
        if let Some(state) = self.tools.get_mut(&tool) {
            state.reaction = total;
            state.held = held;
        }
        Some(total)
    }

    /// Steps rapier, then every surface (see the type's docs).
    pub fn step(&mut self, world: &mut PhysicsWorld) {
        self.step_with(world, |w| w.step());
    }

    /// Like [`SurfaceSet::step`] with your own rigid step (e.g. a
    /// [`crate::hooks::TouchPipeline`]).
    pub fn step_with(
        &mut self,
        world: &mut PhysicsWorld,
        rigid_step: impl FnOnce(&mut PhysicsWorld),
    ) {
        let dt = world.integration_parameters.dt;
        let joints = (&world.impulse_joints, &world.multibody_joints);
        self.take_coming_tools(&world.bodies, &mut world.colliders, joints, &(), dt);
        self.step_taken(world, rigid_step);
    }

    /// [`SurfaceSet::step_with`] after the coming tools were taken
    /// ([`SurfaceSet::take_coming_tools`], with the caller's user hooks).
    pub(crate) fn step_taken(
        &mut self,
        world: &mut PhysicsWorld,
        rigid_step: impl FnOnce(&mut PhysicsWorld),
    ) {
        self.begin_step(&mut world.bodies, &world.colliders);
        self.drive_haptic_tools(&mut world.bodies, &mut world.colliders);
        rigid_step(world);
        self.step_surfaces(world);
        self.publish_haptic_models(world);
    }

    /// Records the tools' poses at the start of a rigid step, and hands rapier the surfaces'
    /// support of the dynamic tools they touched in the last one as forces on their bodies,
    /// for this step only ([`Fed`]; the first half of [`SurfaceSet::step_with`], for engines
    /// that own the step).
    pub(crate) fn begin_step(&mut self, bodies: &mut RigidBodySet, colliders: &ColliderSet) {
        self.tools.retain(|h, _| colliders.contains(*h));
        // Supports a step left on (its surface part never ran) come off first, last on first
        // off (a body with several tool colliders gets one each: so its own force comes
        // back exactly).
        for f in std::mem::take(&mut self.fed).iter().rev() {
            f.remove(bodies);
        }
        for (h, t) in self.tools.iter_mut() {
            // Where the tool starts the step. A collider's own pose follows its body only at
            // rapier's step: a body the user moved since the last step (a teleport, a
            // respawn, put back by the replay) starts from its new pose. Otherwise the
            // collider's own pose, which is that same pose unless the user moved the
            // collider itself, with `set_position` in a rigid step of their own (rapier's
            // step puts an awake body's colliders back on it). Six kinematic cubes moved that
            // way in a bench started every step from their bodies' first pose, up to 10 mm
            // off: each step swept them through the plate, which rose from 5 mJ to 3 J.
            t.prev = colliders.get(*h).map(|c| match pose_on_body(c, bodies) {
                Some(on_body) if t.seen_on_body != Some(on_body) => on_body,
                _ => *c.position(),
            });
            let body = colliders.get(*h).and_then(|c| c.parent());
            if let Some(fed) = body.and_then(|b| Fed::add(bodies, b, t.feed)) {
                self.fed.push(fed);
            }
        }
    }

    /// The surface part of a step: substeps with the kinematic tools' poses interpolated from
    /// the recorded start poses to their current ones and the dynamic tools moving under the
    /// surfaces' impulses ([`crate::coupling::dynamic_tools`]), reactions, and collider
    /// updates.
    pub(crate) fn step_surfaces(&mut self, world: &mut PhysicsWorld) {
        let dt = world.integration_parameters.dt;
        for t in self.tools.values_mut() {
            t.reaction = ToolReaction::default();
            t.held.clear();
            t.feed = (Vector::ZERO, Vector::ZERO);
        }
        // The supports were for rapier's step: taken off the bodies, and out of the velocity
        // the replay starts from (the surfaces give it their impulses themselves).
        let fed = std::mem::take(&mut self.fed);
        for f in fed.iter().rev() {
            f.remove(&mut world.bodies);
        }
        let mut tool_list: Vec<ToolMotion> = self
            .tools
            .iter()
            .filter_map(|(h, t)| {
                let c = world.colliders.get(*h)?;
                let now = *c.position();
                Some(ToolMotion {
                    handle: *h,
                    start: t.prev.unwrap_or(now),
                    end: now,
                    shape: t.shape.clone(),
                    friction: t.friction,
                    grasp: t.grasp,
                    record: self.links.contains_key(h),
                    holder: None,
                })
            })
            .collect();
        // The dynamic tools at the start of the rigid step, with their velocities then and
        // what rapier's step changed of them.
        let dynamic: Vec<DynamicTool> = tool_list
            .iter()
            .filter_map(|t| DynamicTool::new(world, t.handle, t.start, &fed))
            .collect();
        for (j, d) in dynamic.iter().enumerate() {
            if let Some(t) = tool_list.iter_mut().find(|t| t.handle == d.collider) {
                t.holder = Some(j);
            }
        }
        let mut changes = vec![MotionChange::default(); dynamic.len()];
        let mut supports = vec![(Vector::ZERO, Vector::ZERO); dynamic.len()];
        let mut mean: HashMap<ColliderHandle, Vector> = HashMap::default();
        let mut touching = self.touch.take_spare();
        for (handle, s, body_pose) in attached_with_pose(&mut self.entries, world) {
            let n = s.substeps.max(1);
            let h = dt / n as Real;
            // The surface steps at the world's step over its substeps. A world whose step
            // changed since the surface was attached (a game's slow motion, a variable step)
            // changes the surface's, its filter refactored once per change: kept at the step
            // it was attached with, a plate attached at 60 Hz and stepped at 1 kHz moved its
            // tools a millisecond a step while it stepped 16.7 ms, and read their forces (its
            // impulses over the world's step) 16.7 times too large. A step rapier would not
            // take (zero, negative, not finite: a paused world) steps no surface either.
            if !(h > 0.0 && h.is_finite()) {
                continue;
            }
            if (s.surface.dt() - h).abs() > 1e-6 * h {
                if let Err(e) = s.surface.set_dt(h) {
                    log::warn!("rapier_touch: a surface kept its time step ({e}): not stepped");
                    continue;
                }
            }
            let mut states = dynamic.clone();
            for k in 1..=n {
                for d in states.iter_mut() {
                    d.fall(h);
                }
                let a = k as Real / n as Real;
                let a_prev = (k - 1) as Real / n as Real;
                let poses: Vec<ToolMotion> = tool_list
                    .iter()
                    .map(|t| {
                        let (start, end) = match t.holder.and_then(|j| states.get(j)) {
                            Some(d) => (d.collider_pose(), d.predicted(h)),
                            None => (
                                lerp_pose(&t.start, &t.end, a_prev),
                                lerp_pose(&t.start, &t.end, a),
                            ),
                        };
                        ToolMotion {
                            start,
                            end,
                            shape: t.shape.clone(),
                            ..*t
                        }
                    })
                    .collect();
                if k == 1 {
                    press_ahead(s, world, &body_pose, (&poses, &states), h);
                }
                let substep = surface_substep(s, world, &body_pose, (&poses, &mut states), h);
                for (th, r, contacts) in substep {
                    *mean.entry(th).or_insert(Vector::ZERO) += r.mean_force / n as Real;
                    if k == n {
                        if r.held_vertices > 0 || r.pressed_points > 0 {
                            touching.insert((th, handle));
                        }
                        if let Some(t) = self.tools.get_mut(&th) {
                            t.held.extend(contacts);
                            t.reaction.force += r.force;
                            t.reaction.torque += r.torque;
                            t.reaction.held_vertices += r.held_vertices;
                            t.reaction.sticking_vertices += r.sticking_vertices;
                            t.reaction.pressed_points += r.pressed_points;
                        }
                    }
                }
            }
            // What the surface changed of each dynamic tool's motion.
            for (((start, end), change), support) in dynamic
                .iter()
                .zip(&states)
                .zip(changes.iter_mut())
                .zip(supports.iter_mut())
            {
                if end.touched {
                    change.add(start, end, h, n);
                    let (force, torque) = end.support(dt);
                    support.0 += force;
                    support.1 += torque;
                }
            }
        }
        crate::coupling::events::update(&mut self.touch, touching);
        // The colliders follow the deformed surfaces (a BVH refit each, once per rigid step),
        // unless no vertex moved by a millionth of the surface's size since the last update: a
        // changed shape makes rapier wake every body whose collider touches it, and a body
        // resting on a surface at rest never slept.
        for (_, entry) in self.entries.iter_mut() {
            let Some(s) = entry.as_mut() else {
                continue;
            };
            if let Some(ch) = s.collider {
                s.surface.positions_into(&mut s.scratch);
                if let Some(c) = world.colliders.get_mut(ch) {
                    let moved = c.shape().as_trimesh().is_none_or(|m| {
                        let tol = 1e-6 * m.local_aabb().extents().max_element();
                        m.vertices().len() != s.scratch.len()
                            || m.vertices()
                                .iter()
                                .zip(&s.scratch)
                                .any(|(a, b)| (*a - *b).length_squared() > tol * tol)
                    });
                    if moved {
                        if let Some(m) = c.shape_mut().as_trimesh_mut() {
                            m.set_vertices(&s.scratch);
                        }
                    }
                }
            }
        }
        for (th, t) in self.tools.iter_mut() {
            t.reaction.mean_force = mean.get(th).copied().unwrap_or(Vector::ZERO);
        }
        // Two-way coupling: the dynamic tools the surfaces touched take the motion they left
        // (their free motion from the step's start, changed by what each surface changed),
        // their colliders with them. One rapier supported and no surface touched (it left
        // them) takes its free motion: rapier's, less the support (which would have thrown a
        // body lifting off a surface up with the surface's last push).
        let mut moved = Vec::new();
        let length_unit = world.integration_parameters.length_unit;
        let motions: Vec<Option<(Pose, Vector, Vector)>> =
            changes.iter().map(MotionChange::motion).collect();
        let touched: HashSet<RigidBodyHandle> = dynamic
            .iter()
            .zip(&motions)
            .filter(|(_, m)| m.is_some())
            .map(|(d, _)| d.body)
            .collect();
        let mut left = HashSet::default();
        let rapier_substeps = world.integration_parameters.num_solver_iterations.max(1) as u32;
        for ((d, motion), support) in dynamic.iter().zip(motions).zip(&supports) {
            if let Some(t) = self.tools.get_mut(&d.collider) {
                t.feed = *support;
            }
            let free = || {
                let f = d.free(dt / rapier_substeps as Real, rapier_substeps);
                (f.pose, f.linvel, f.angvel)
            };
            let motion = motion.or_else(|| {
                let unsupported = !d.supported || touched.contains(&d.body);
                (!unsupported && left.insert(d.body)).then(free)
            });
            let (Some((pose, v, w)), Some(b)) = (motion, world.bodies.get_mut(d.body)) else {
                continue;
            };
            if !(pose.is_finite() && v.is_finite() && w.is_finite()) {
                continue;
            }
            // rapier decides when the body sleeps: an awake one is not woken again (that
            // would restart its sleep timer at every step, and a body resting on a surface
            // never slept), and a sleeping one stays asleep, where it is, unless the
            // surfaces moved it faster than rapier's own thresholds for sleep.
            if b.is_sleeping() {
                let a = b.activation();
                let linear = a.normalized_linear_threshold * length_unit;
                let stirred = (v - b.linvel()).length() > linear
                    || (w - b.angvel()).length() > a.angular_threshold;
                if !stirred {
                    continue;
                }
                b.wake_up(true);
            }
            b.set_position(pose, false);
            b.set_linvel(v, false);
            b.set_angvel(w, false);
            moved.push(d.body);
        }
        crate::hooks::sync_moved_colliders(world, &mut moved);
        for (h, t) in self.tools.iter_mut() {
            t.seen_on_body = world
                .colliders
                .get(*h)
                .and_then(|c| pose_on_body(c, &world.bodies));
        }
    }
}

/// Collider `c`'s pose on its parent body as the body stands now (its body's pose times its
/// pose on the body), or `None` for a collider without a body.
fn pose_on_body(c: &rapier3d::geometry::Collider, bodies: &RigidBodySet) -> Option<Pose> {
    let b = bodies.get(c.parent()?)?;
    Some(*b.position() * *c.position_wrt_parent()?)
}
