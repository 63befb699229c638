//! The convex fast path of the reconstruction: two convex meshes are walked back by parry's
//! GJK (conservative advancement on the pair's scaled coordinates), and their penetration is
//! decided by GJK and EPA, with the exact tests of [`super::primitives`] where those are too
//! close to call.

use super::*;

impl Reconstructor {
    /// The convex path (see [`ReconstructionOptions::convex_fast_path`]). For two convex
    /// objects the poses at which they overlap form one interval `[s_lo, s_hi]` of the line
    /// (the line crosses the convex Minkowski difference once), so two GJK ray casts, one from
    /// each end of the bounding-box range, decide the state, and `s_hi` is the first touch.
    /// `None` hands the query to the general search.
    pub(super) fn convex_touch(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_lo_box: f64,
        s_hi_box: f64,
    ) -> Option<ConvexTouch> {
        let tol = fr.tol;
        let scale = fixed.scale().max(moving.scale()) as f64;
        // parry's GJK runs in f32 and asserts finite bounds: keep its coordinates (and their
        // squares) far from overflow; huge scenes take the general search.
        let reach = |m: &TouchMesh| {
            let b = m.local_aabb();
            b.mins.abs().max(b.maxs.abs()).max_element() as f64
        };
        let extent =
            reach(fixed) + reach(moving) + fr.tra.length() + s_lo_box.abs() + s_hi_box.abs();
        // (The cast divides coordinates by the scale: what matters is the extent in scales.)
        if !extent.is_finite() || extent >= 1.0e6 * scale {
            return None;
        }
        // GJK runs in f32 on coordinates divided by `scale` (see `convex_cast`): its absolute
        // stopping distance, 1.2e-6, is then 1.2e-6 of the scale at every scale. Its cast
        // answers within about 1e-4 of the scale (-1.0e-4 to +1.1e-4 over 9,678 casts of the
        // property tests, where a window of 1e-4 of the scale missed a unit pair's first
        // touch by 2.2e-4): the exact events are searched over five times that.
        let window = (5.0e-4 * scale).max(100.0 * tol);
        let pad = 1.0e-3 * scale + window;
        let s_from = s_hi_box + pad;
        let (t, w1, w2, n) = self.convex_cast(fixed, moving, fr, s_from, fr.u)?;
        let s_hi = s_from - t;
        if s_hi < -tol - window {
            return Some(ConvexTouch::Apart);
        }
        let deep = if s_hi > tol + window {
            let s_to = s_lo_box - pad;
            let (t_lo, ..) = self.convex_cast(fixed, moving, fr, s_to, -fr.u)?;
            let s_lo = s_to + t_lo;
            if s_lo > s_hi + window {
                return None;
            }
            if s_lo >= -tol - window {
                // Apart or touching at the front end now: passed through, or about to.
                return None;
            }
            true
        } else {
            false
        };
        let b = self.convex_events(fixed, moving, fr, w1, w2, s_hi, window)?;
        if (b - s_hi).abs() > window {
            return None;
        }
        // parry's cast can stop past the first touch, outside the window searched for the
        // exact events: 5.3 mm past it on a 2.4 m pair of icospheres met head-on
        // (`PROPTEST_RNG_SEED=100` in `tests/it/reconstruction_properties.rs`), where the events
        // then found a touch 4.4 mm short of the first one. Walked back a little past the touch
        // found, the pair must be apart (along the cast's normal, or else by the
        // reconstruction's own penetration test); otherwise the general search decides. The
        // step is GJK's tolerance seen along the path, at least a quarter of the window and at
        // most the window: a first touch missed by more than the step goes to the general
        // search, one missed by less is not caught here.
        let cos = (n.dot(fr.u.as_vec3()).abs() as f64).max(1e-3);
        let step = (4.0 * gjk::eps_tol() as f64 * scale / cos).clamp(0.25 * window, window);
        if !apart_along(fixed, moving, fr, -(b + step) * fr.u, n.as_dvec3())
            && self.penetrating_at(fixed, moving, fr, b + step)
        {
            return None;
        }
        if deep {
            (b > tol).then_some(ConvexTouch::Penetrating(b))
        } else if b < -tol {
            Some(ConvexTouch::Apart)
        } else if b <= tol {
            Some(ConvexTouch::Touching)
        } else {
            None
        }
    }

    /// GJK ray cast of the moving mesh, walked back to `s_from`, travelling along unit `dir`
    /// (fixed frame): the distance to contact, the witness on the fixed mesh (fixed frame), on
    /// the moving mesh (its own frame), and the contact normal (fixed frame). `None` if GJK
    /// misses or does not converge.
    ///
    /// parry's GJK stops at an absolute distance (`gjk::eps_tol()`, 1.2e-6): at a centimetre
    /// that is 1e-4 of the object, at 0.1 mm it is 1 %. The cast therefore runs on coordinates
    /// divided by the pair's scale, so its tolerances are relative at every scale.
    pub(super) fn convex_cast(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_from: f64,
        dir: DVec3,
    ) -> Option<(f64, Vector, Vector, Vector)> {
        let (scale, pos12, g1, g2) = self.scaled_pair(fixed, moving, fr, -s_from * fr.u);
        let hit =
            gjk::directional_distance(&pos12, &g1, &g2, dir.as_vec3(), &mut VoronoiSimplex::new());
        self.ws.warm = [g1.warm.get(), g2.warm.get()];
        let (t, n, w1, w2) = hit?;
        // A zero distance means the cast started in contact: no witnesses.
        let (t, w1, w2) = (t as f64 * scale, w1 * scale as Real, w2);
        (t.is_finite() && t > 0.0 && w1.is_finite() && w2.is_finite() && n.is_finite())
            .then(|| (t, w1, pos12.inverse_transform_point(w2) * scale as Real, n))
    }

    /// Exact events of the convex path: every touch within `window` of the GJK estimate `s_g`
    /// among the triangles near the witness points `w1` (fixed mesh, fixed frame) and `w2`
    /// (moving mesh, its frame), then the whole touching region, grown pair by pair through
    /// triangles sharing a vertex. Leaves the events at the largest touch in the workspace and
    /// returns it; `None` if no touch was found near the witnesses.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn convex_events(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        w1: Vector,
        w2: Vector,
        s_g: f64,
        window: f64,
    ) -> Option<f64> {
        let ws = &mut self.ws;
        ws.events.clear();
        ws.pairs.clear();
        ws.visited.clear();
        ws.grow.clear();
        let tol = fr.tol;
        // The triangles around the witnesses: within two GJK errors of them (the exact touch
        // may sit on a neighbouring feature, reached by growing the region below).
        let r = Vector::splat((2.0 * window) as Real);
        let (mut near_f, mut near_m) = (
            std::mem::take(&mut ws.near_f),
            std::mem::take(&mut ws.near_m),
        );
        near_f.clear();
        near_f.extend(fixed.bvh().intersect_aabb(&Aabb::new(w1 - r, w1 + r)));
        near_m.clear();
        near_m.extend(moving.bvh().intersect_aabb(&Aabb::new(w2 - r, w2 + r)));
        let (lo, hi) = (s_g - window, s_g + window);
        let mut found = std::mem::take(&mut ws.near_touches);
        found.clear();
        for &tf in &near_f {
            for &tm in &near_m {
                ws.visited.insert(pair_key(tf, tm));
                if !boxes_meet(ws, fixed, moving, fr, tf, tm, lo, hi) {
                    continue;
                }
                let s = pair_events(ws, fixed, moving, fr, tf, tm, lo, hi);
                if s.is_finite() {
                    found.push((tf, tm, s));
                }
            }
        }
        ws.near_f = near_f;
        ws.near_m = near_m;
        let mut b = found.iter().map(|f| f.2).fold(f64::NEG_INFINITY, f64::max);
        if !b.is_finite() {
            return None;
        }
        ws.grow
            .extend(found.iter().filter(|f| f.2 >= b - tol).map(|f| (f.0, f.1)));
        ws.near_touches = found;
        while let Some((tf, tm)) = ws.grow.pop() {
            for k in 0..6 {
                let (mesh, v) = if k < 3 {
                    (fixed, fixed.indices()[tf as usize][k])
                } else {
                    (moving, moving.indices()[tm as usize][k - 3])
                };
                for &t in mesh.vertex_triangles(v) {
                    let (a, c) = if k < 3 { (t, tm) } else { (tf, t) };
                    // Up to the window's end, not just `b`'s tolerance: the witnesses can sit
                    // on a support vertex nearly tied with the touching one, whose touch is
                    // later along the path (a 19 km pair: 48.07 found near the witnesses,
                    // 48.47 on the neighbouring vertex, which a search up to `b + tol` never
                    // reached).
                    let top = hi.max(b + tol);
                    if !ws.visited.insert(pair_key(a, c))
                        || !boxes_meet(ws, fixed, moving, fr, a, c, b - tol, top)
                    {
                        continue;
                    }
                    let s = pair_events(ws, fixed, moving, fr, a, c, b - tol, top);
                    if s >= b - tol {
                        b = b.max(s);
                        ws.grow.push((a, c));
                    }
                }
            }
        }
        ws.events.retain(|e| e.s >= b - tol);
        Some(b)
    }

    /// The pair as parry's GJK sees it, on coordinates divided by the pair's scale (see
    /// [`Reconstructor::convex_cast`]): the scale, the moving mesh's pose in the fixed one's
    /// frame with the moving mesh shifted by `shift`, and both meshes as support maps warm-started
    /// from the workspace (store their `warm` back after the query).
    pub(super) fn scaled_pair<'a>(
        &self,
        fixed: &'a TouchMesh,
        moving: &'a TouchMesh,
        fr: &Frame,
        shift: DVec3,
    ) -> (f64, Pose, HillClimb<'a>, HillClimb<'a>) {
        let scale = fixed.scale().max(moving.scale()) as f64;
        let k = 1.0 / scale;
        let pos12 = Pose::from_parts((k * (fr.tra + shift)).as_vec3(), fr.rot.as_quat());
        let climb = |mesh, warm| HillClimb {
            mesh,
            warm: Cell::new(warm),
            k: k as Real,
        };
        (
            scale,
            pos12,
            climb(fixed, self.ws.warm[0]),
            climb(moving, self.ws.warm[1]),
        )
    }

    /// [`Reconstructor::penetrating_at`] for two convex meshes by GJK (and EPA when they
    /// intersect), on coordinates divided by the pair's scale like [`Reconstructor::convex_cast`]:
    /// overlapping deeper than the tolerance. `None` (the exact test decides) when the answer
    /// lies within 1e-3 of the scale of the decision or EPA does not converge.
    pub(super) fn convex_penetrating(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        shift: DVec3,
    ) -> Option<bool> {
        let (scale, pos12, g1, g2) = self.scaled_pair(fixed, moving, fr, shift);
        let dir = pos12.translation.try_normalize().unwrap_or(Vector::X);
        let mut simplex = VoronoiSimplex::new();
        simplex.reset(gjk::CsoPoint::from_shapes(&pos12, &g1, &g2, dir));
        // GJK and EPA run in f32 and stop at their own tolerances (EPA depths off by 1.7e-4 of
        // the scale were seen): within `MARGIN` of the decision the exact test decides.
        const MARGIN: Real = 1.0e-3;
        let tol = (fr.tol / scale) as Real;
        let answer = match gjk::closest_points(&pos12, &g1, &g2, MARGIN, true, &mut simplex) {
            gjk::GJKResult::NoIntersection(_) => Some(false),
            gjk::GJKResult::Intersection => parry3d::query::epa::EPA::new()
                .closest_points(&pos12, &g1, &g2, &simplex)
                .and_then(|(p1, p2, n)| {
                    let depth = (p1 - p2).dot(n);
                    (depth > tol + MARGIN).then_some(true)
                }),
            _ => None,
        };
        self.ws.warm = [g1.warm.get(), g2.warm.get()];
        answer
    }
}

/// The most vertices the hull of a mesh that is not convex may have for
/// [`Reconstructor::hull_gap`], whose support points it then finds by a pass over them
/// ([`TouchMesh::hull_vertices`]).
const HULL_GAP_VERTICES: usize = 64;

impl Reconstructor {
    /// The distance between the convex hulls of the two meshes' vertices in frame `fr`: a
    /// lower bound of the meshes' own distance (zero where the hulls overlap), by parry's GJK
    /// on coordinates divided by the pair's scale, as [`Reconstructor::convex_cast`]. `None`
    /// for a mesh that is neither convex nor of a small hull (more than 64 of its vertices on
    /// it, or more than 4096 vertices), or an answer that is not finite.
    pub(in crate::geometry) fn hull_gap(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
    ) -> Option<f64> {
        let small = |m: &TouchMesh| {
            m.is_convex()
                || m.hull_vertices()
                    .is_some_and(|h| h.len() <= HULL_GAP_VERTICES)
        };
        if !(small(fixed) && small(moving)) {
            return None;
        }
        let (scale, pos12, g1, g2) = self.scaled_pair(fixed, moving, fr, DVec3::ZERO);
        let dir = (-pos12.translation).try_normalize().unwrap_or(Vector::X);
        let mut simplex = VoronoiSimplex::new();
        simplex.reset(gjk::CsoPoint::from_shapes(&pos12, &g1, &g2, dir));
        let gap = match gjk::closest_points(&pos12, &g1, &g2, Real::MAX, true, &mut simplex) {
            // GJK's distance comes down to the true one from above and may stop short of it
            // in f32 (8.7 mm read for an L-shaped prism 0.5 mm over a 100 m floor): the gap
            // along its direction between the two support points is a lower bound whatever
            // GJK's precision (a separating axis).
            gjk::GJKResult::ClosestPoints(p1, p2, _) => match (p2 - p1).try_normalize() {
                Some(n) => {
                    let top = g1.local_support_point(n).dot(n);
                    let bottom = g2.support_point(&pos12, -n).dot(n);
                    (bottom - top).max(0.0)
                }
                None => 0.0,
            },
            _ => 0.0,
        };
        self.ws.warm = [g1.warm.get(), g2.warm.get()];
        let d = gap as f64 * scale;
        d.is_finite().then_some(d)
    }
}

/// Whether the two convex meshes, the moving one shifted by `shift` (fixed frame), are apart
/// along `n` or `-n` (fixed frame), from one support vertex of each, exactly: a separating axis.
/// The cheap half of the convex path's check of its first touch.
fn apart_along(fixed: &TouchMesh, moving: &TouchMesh, fr: &Frame, shift: DVec3, n: DVec3) -> bool {
    let Some(n) = n.try_normalize() else {
        return false;
    };
    [n, -n].into_iter().any(|a| {
        let top = fixed
            .convex_support(a.as_vec3(), 0)
            .map(|i| a.dot(fixed.vertices()[i as usize].as_dvec3()));
        let bottom = moving
            .convex_support((fr.rot.inverse() * -a).as_vec3(), 0)
            .map(|i| a.dot(fr.moving_point(moving.vertices()[i as usize]) + shift));
        matches!((top, bottom), (Some(t), Some(b)) if b > t)
    })
}

/// The vertex of `mesh` farthest along `dir` (mesh frame) reached by hill climbing over the
/// vertex graph from vertex 0: the support point on a convex mesh, a local maximum otherwise.
pub(super) fn support_vertex(mesh: &TouchMesh, dir: Vector) -> u32 {
    mesh.hill_climb(0, dir)
}

/// What the convex path decided.
pub(super) enum ConvexTouch {
    /// No touch at or behind the current pose.
    Apart,
    /// Penetrating now; the first touch is this far back (events in the workspace).
    Penetrating(f64),
    /// Touching now (events in the workspace).
    Touching,
}

/// A convex mesh scaled by `k` as a parry support map: support points by hill climbing
/// ([`TouchMesh::convex_support`]) from the previous answer.
pub(super) struct HillClimb<'a> {
    mesh: &'a TouchMesh,
    warm: Cell<u32>,
    k: Real,
}

impl SupportMap for HillClimb<'_> {
    fn local_support_point(&self, dir: Vector) -> Vector {
        let v = if self.mesh.is_convex() {
            self.mesh.convex_support(dir, self.warm.get()).unwrap_or(0)
        } else {
            // The hull of a mesh that is not convex (`Reconstructor::hull_gap`): a pass over
            // its hull's vertices.
            let v = self.mesh.vertices();
            let hull = self.mesh.hull_vertices().unwrap_or(&[]);
            hull.iter()
                .copied()
                .max_by(|a, b| v[*a as usize].dot(dir).total_cmp(&v[*b as usize].dot(dir)))
                .unwrap_or(0)
        };
        self.warm.set(v);
        self.mesh.vertices()[v as usize] * self.k
    }
}
