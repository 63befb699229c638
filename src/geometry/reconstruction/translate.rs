//! The paper's method along a translation (eq. 1-3 applied along the moving object's own
//! path): the walk back to first touch, its states (penetrating, perforated, touching) and the
//! contact set found there.

use super::*;

impl Reconstructor {
    /// The paper's method along a translation (the orientation of `pos_moving` is kept).
    pub(in crate::geometry) fn translate_back(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        pos_moving: &Pose,
        prev_pos_moving: &Pose,
    ) -> Result<ContactConfiguration, ReconstructionError> {
        self.translate_back_within(
            fixed,
            pos_fixed,
            moving,
            pos_moving,
            prev_pos_moving,
            Walk::Whole,
        )
    }

    /// [`Self::translate_back`], walking as `walk` says.
    pub(in crate::geometry) fn translate_back_within(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        pos_moving: &Pose,
        prev_pos_moving: &Pose,
        walk: Walk,
    ) -> Result<ContactConfiguration, ReconstructionError> {
        let mut c =
            self.translate_back_inner(fixed, pos_fixed, moving, pos_moving, prev_pos_moving, walk)?;
        c.touch_pose = Pose::from_parts(
            pos_moving.translation + c.reversing_vector,
            pos_moving.rotation,
        );
        Ok(c)
    }

    pub(super) fn translate_back_inner(
        &mut self,
        fixed: &TouchMesh,
        pos_fixed: &Pose,
        moving: &TouchMesh,
        pos_moving: &Pose,
        prev_pos_moving: &Pose,
        walk: Walk,
    ) -> Result<ContactConfiguration, ReconstructionError> {
        let (rf, tf) = dpose(pos_fixed);
        let (rm, tm) = dpose(pos_moving);
        let scale = fixed.scale().max(moving.scale()) as f64;
        let tol = (self.options.tolerance as f64).clamp(1e-9, 1e-3) * scale;

        let d_world = tm - prev_pos_moving.translation.as_dvec3();
        let len = d_world.length();
        let (u_world, source, traj_len) = if len > 1e-9 * scale {
            (d_world / len, DirectionSource::Trajectory, len)
        } else {
            let dir = match self.options.zero_motion_direction {
                Some(d) => {
                    let d = d.as_dvec3();
                    if !d.is_finite() || d.length_squared() == 0.0 {
                        return Err(ReconstructionError::InvalidFallbackDirection);
                    }
                    d.normalize()
                }
                None => {
                    let cf = rf * fixed.local_aabb().center().as_dvec3() + tf;
                    let cm = rm * moving.local_aabb().center().as_dvec3() + tm;
                    (cf - cm).try_normalize().unwrap_or(DVec3::NEG_Y)
                }
            };
            (dir, DirectionSource::ZeroMotionFallback, f64::INFINITY)
        };

        let fr = self.frame_at(fixed, pos_fixed, moving, pos_moving, u_world, tol);
        let mut result =
            ContactConfiguration::separated(u_world.as_vec3(), source, true, *pos_moving);

        // The range of `s` over which the bounding boxes overlap.
        let Some((s_lo_box, s_hi)) = aabb_overlap_range(fixed, moving, &fr) else {
            return Ok(result);
        };
        if s_hi < -tol {
            return Ok(result);
        }
        if self.options.convex_fast_path && fixed.is_convex() && moving.is_convex() {
            match self.convex_touch(fixed, moving, &fr, s_lo_box, s_hi) {
                // Apart by the casts, unless the pair overlaps now by the exact test: then the
                // general search decides. A 0.5 m box tumbling 1.08 mm deep in a 100 m floor,
                // moving nearly along the floor's face, was answered apart (parry's f32 casts
                // on coordinates divided by the floor's size, where the overlap is 1e-5) and
                // left in (`tests/it/rigid_motion.rs`, the recorded step).
                Some(ConvexTouch::Apart) if !self.penetrating_at(fixed, moving, &fr, 0.0) => {
                    return Ok(result)
                }
                Some(ConvexTouch::Apart) => {}
                Some(ConvexTouch::Penetrating(s)) => {
                    result.state = TouchState::Penetrating;
                    // The start pose penetrates too when the touch lies beyond it.
                    result.on_trajectory =
                        source == DirectionSource::Trajectory && s <= traj_len + tol;
                    result.candidate_pairs = self.ws.visited.len();
                    return Ok(self.finish(result, fixed, moving, &fr, s, traj_len, rf, tf));
                }
                Some(ConvexTouch::Touching) => {
                    result.state = TouchState::Touching;
                    result.candidate_pairs = self.ws.visited.len();
                    return Ok(self.finish(result, fixed, moving, &fr, 0.0, traj_len, rf, tf));
                }
                None => {}
            }
        }
        // A touch up to one tolerance before the start of the step still counts as on the step
        // (a start pose that overlaps by a rounding error).
        let s_max = s_hi.min(traj_len + tol);
        // Only the largest touch matters for the first touch: a bounded search.
        let first_touch = self.collect_first_touch(fixed, moving, &fr, -tol, s_max);
        result.candidate_pairs = self.ws.pairs.len();
        let pen0 = self.penetrating_at(fixed, moving, &fr, 0.0);

        let s_star;
        if pen0 {
            result.state = TouchState::Penetrating;
            // No surface meets the other between the first touch and the start of the step
            // (the first touch is the largest), so the configuration just before the first
            // touch is the start pose's: valid if the step started apart. The start pose is
            // the cheaper one to test (farther from contact), and needs no test at all when the
            // boxes were already apart there.
            let after = if walk == Walk::SubStep { 0.0 } else { tol };
            let valid = first_touch > after
                && (s_hi < traj_len || !self.penetrating_at(fixed, moving, &fr, traj_len));
            if valid && source == DirectionSource::Trajectory {
                s_star = first_touch;
            } else {
                // The first touch is not on this step: go back to the nearest separating pose,
                // the last touch on the whole backward ray.
                result.on_trajectory = false;
                if walk != Walk::Whole {
                    return Ok(result);
                }
                s_star = if s_max < s_hi {
                    let s = self.collect_first_touch(fixed, moving, &fr, -tol, s_hi);
                    result.candidate_pairs = self.ws.pairs.len();
                    s
                } else {
                    first_touch
                };
                if !s_star.is_finite() {
                    // Containment with no surface on the ray: cannot happen for finite
                    // meshes, but never hand back a NaN.
                    return Ok(result);
                }
            }
        } else if first_touch > tol {
            // Not penetrating now but the surfaces met during the step: a perforation if the
            // objects overlapped in between, otherwise a graze (or a touch now). Rare, so every
            // touch of the step is collected here.
            self.collect_events(fixed, moving, &fr, -tol, s_max);
            result.candidate_pairs = self.ws.pairs.len();
            if self.perforated_between(fixed, moving, &fr, first_touch) {
                result.state = TouchState::Perforated;
                s_star = first_touch;
            } else if self.ws.events.iter().any(|e| e.s.abs() <= tol) {
                result.state = TouchState::Touching;
                s_star = 0.0;
            } else {
                return Ok(result);
            }
        } else if first_touch >= -tol {
            result.state = TouchState::Touching;
            s_star = 0.0;
        } else {
            return Ok(result);
        }

        Ok(self.finish(result, fixed, moving, &fr, s_star, traj_len, rf, tf))
    }

    /// Fills in the reversing vector, time of impact and contact patches for a touch at
    /// `s_star`, from the events in the workspace.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn finish(
        &self,
        mut result: ContactConfiguration,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_star: f64,
        traj_len: f64,
        rf: DQuat,
        tf: DVec3,
    ) -> ContactConfiguration {
        let to_world = |p: DVec3| -> Vector { (rf * p + tf).as_vec3() };
        let u_world = rf * fr.u;
        let s_star = s_star.max(0.0);
        if s_star > 0.0 {
            result.reversing_vector = (-s_star * u_world).as_vec3();
            result.depth = s_star as Real;
            if result.on_trajectory && traj_len.is_finite() {
                result.time_of_impact = Some((1.0 - s_star / traj_len).clamp(0.0, 1.0) as Real);
            }
        } else if result.state == TouchState::Touching && traj_len.is_finite() {
            result.time_of_impact = Some(1.0);
        }
        // Contact set: every event at s_star (within tolerance).
        let selected: Vec<Event> = self
            .ws
            .events
            .iter()
            .filter(|e| (e.s - s_star).abs() <= fr.tol)
            .cloned()
            .collect();
        result.patches = build_patches(fixed, moving, fr, selected, s_star, &to_world, rf);
        result
    }
}
