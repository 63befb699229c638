//! The exact event search of the reconstruction: the paper's eq. (1)-(3) (and the 3D
//! edge-edge case) applied to the triangle pairs that a simultaneous traversal of both meshes'
//! BVHs, with the moving boxes swept along the trajectory, cannot rule out; the first touch,
//! every touch of the step (for perforation), and the penetration test of a pose.

use super::primitives::*;
use super::*;

/// The most triangles a moving mesh has for [`Reconstructor::penetrating_at`] to test it
/// triangle by triangle against the fixed BVH's candidates rather than by the two BVHs' joint
/// descent.
const SMALL_MOVER_TRIANGLES: usize = 32;

impl Reconstructor {
    /// The largest touch `s` in `[s_min, s_max]` (`-inf` if none), with every event within the
    /// tolerance of it in `ws.events`. Branch and bound over both BVHs: a pair of boxes whose
    /// overlap along the ray ends below the best touch so far cannot hold the first touch.
    pub(super) fn collect_first_touch(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_min: f64,
        s_max: f64,
    ) -> f64 {
        let ws = &mut self.ws;
        ws.pairs.clear();
        ws.events.clear();
        let pos12 = fr.pose12();
        let u = fr.u.as_vec3();
        let tol = fr.tol;
        let margin = fr.box_margin(fixed, moving);
        // Seed the bound with a touch that surely exists: each object's vertex deepest along
        // the motion, cast back along the trajectory. Less a margin that covers f32 rounding,
        // it is a lower bound of the first touch.
        let seed = seed_first_touch(fixed, moving, fr, s_min, s_max)
            .map_or(f64::NEG_INFINITY, |s| s - 10.0 * tol);
        let best = Cell::new(seed);
        let boxer = BoxTransform::new(&pos12, u, margin);
        let reach = |nf: &BvhNode, nm: &BvhNode| -> Option<f64> {
            let (lo, hi) = boxer.overlap_interval(nm, nf)?;
            let (lo, hi) = ((lo as f64).max(s_min), (hi as f64).min(s_max));
            (lo <= hi + tol).then_some(hi)
        };
        let check = |nf: &BvhNode, nm: &BvhNode| {
            reach(nf, nm).is_some_and(|hi| hi >= best.get() - 2.0 * tol)
        };
        let (fbvh, mbvh) = (fixed.bvh(), moving.bvh());
        // A pair of triangles whose boxes overlap past the best touch so far: its events.
        let visit = |ws: &mut Workspace, tf: u32, tm: u32| {
            ws.pairs.push((tf, tm));
            let lo = s_min.max(best.get() - tol);
            // Exact bound from each triangle's plane: past it the other triangle has left the
            // plane, so no touch of this pair lies beyond (the boxes above are inflated by the
            // rotation).
            let pf = fixed_tri(fixed, tf);
            let pm = moving.indices()[tm as usize].map(|v| moving_pt(ws, moving, fr, v));
            if plane_bound(&pf, &pm, -fr.u).min(plane_bound(&pm, &pf, fr.u)) < lo - tol {
                return;
            }
            let found = pair_events(ws, fixed, moving, fr, tf, tm, lo, s_max);
            if found > best.get() {
                best.set(found);
            }
        };
        // A small moving mesh (`SMALL_MOVER_TRIANGLES`): its triangles' own boxes, in the fixed
        // frame, against the fixed BVH's leaves under their joint sweep, as in
        // `small_mover_crosses`; a large one by the two BVHs' joint descent.
        if moving.num_triangles() <= SMALL_MOVER_TRIANGLES && s_min.is_finite() && s_max.is_finite()
        {
            let mut boxes = std::mem::take(&mut ws.m_boxes);
            boxes.clear();
            let mut swept = Aabb::new_invalid();
            let (a, b) = ((-s_min * fr.u).as_vec3(), (-s_max * fr.u).as_vec3());
            for idx in moving.indices() {
                let p = idx.map(|v| moving_pt(ws, moving, fr, v).as_vec3());
                let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
                let h = (hi - lo) * 0.5 + Vector::splat(2.0 * margin);
                let c = (lo + hi) * 0.5;
                swept.merge(&Aabb::new(c - h + a.min(b), c + h + a.max(b)));
                boxes.push((c, h));
            }
            for tf in fbvh.intersect_aabb(&swept) {
                let Some(nf) = fbvh.leaf_node(tf) else {
                    continue;
                };
                for (tm, &(c, h)) in boxes.iter().enumerate() {
                    let near = boxer.interval_of(c, h, nf).is_some_and(|(lo, hi)| {
                        let (lo, hi) = ((lo as f64).max(s_min), (hi as f64).min(s_max));
                        lo <= hi + tol && hi >= best.get() - 2.0 * tol
                    });
                    if near {
                        visit(ws, tf, tm as u32);
                    }
                }
            }
            ws.m_boxes = boxes;
        } else {
            for (tf, tm) in fbvh.leaf_pairs(mbvh, check) {
                let (Some(nf), Some(nm)) = (fbvh.leaf_node(tf), mbvh.leaf_node(tm)) else {
                    continue;
                };
                if check(nf, nm) {
                    visit(ws, tf, tm);
                }
            }
        }
        let b = ws
            .events
            .iter()
            .map(|e| e.s)
            .fold(f64::NEG_INFINITY, f64::max);
        ws.events.retain(|e| e.s >= b - tol);
        b
    }

    /// Candidate pairs over `s ∈ [s_min, s_max]` and all three kinds of events in that range.
    pub(super) fn collect_events(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s_min: f64,
        s_max: f64,
    ) {
        let ws = &mut self.ws;
        ws.pairs.clear();
        ws.events.clear();
        let pos12 = fr.pose12();
        let u = fr.u.as_vec3();
        let margin = fr.box_margin(fixed, moving);
        let (a, b) = (-(s_min as Real) * u, -(s_max as Real) * u);
        let swept = |aabb: Aabb| -> Aabb {
            let m = aabb.transform_by(&pos12);
            Aabb::new(
                (m.mins + a).min(m.mins + b) - Vector::splat(margin),
                (m.maxs + a).max(m.maxs + b) + Vector::splat(margin),
            )
        };
        let fbvh = fixed.bvh();
        let mbvh = moving.bvh();
        if moving.num_triangles() <= SMALL_MOVER_TRIANGLES && s_min.is_finite() && s_max.is_finite()
        {
            // A small moving mesh: its triangles' own boxes in the fixed frame, swept, against
            // the fixed BVH's leaves under their joint sweep (as `collect_first_touch`).
            let mut boxes = std::mem::take(&mut ws.m_tris);
            boxes.clear();
            let mut all = Aabb::new_invalid();
            for idx in moving.indices() {
                let p = idx.map(|v| moving_pt(ws, moving, fr, v));
                let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
                let (lo, hi) = (lo.as_vec3(), hi.as_vec3());
                let bx = Aabb::new(
                    (lo + a).min(lo + b) - Vector::splat(margin),
                    (hi + a).max(hi + b) + Vector::splat(margin),
                );
                all.merge(&bx);
                boxes.push((p, bx));
            }
            for tf in fbvh.intersect_aabb(&all) {
                let Some(nf) = fbvh.leaf_node(tf) else {
                    continue;
                };
                for (tm, (_, bx)) in boxes.iter().enumerate() {
                    if bx.intersects(&nf.aabb()) {
                        ws.pairs.push((tf, tm as u32));
                    }
                }
            }
            ws.m_tris = boxes;
        } else {
            for (tf, tm) in fbvh.leaf_pairs(mbvh, |nf, nm| swept(nm.aabb()).intersects(&nf.aabb()))
            {
                let (Some(nf), Some(nm)) = (fbvh.leaf_node(tf), mbvh.leaf_node(tm)) else {
                    continue;
                };
                if swept(nm.aabb()).intersects(&nf.aabb()) {
                    ws.pairs.push((tf, tm));
                }
            }
        }
        if ws.pairs.is_empty() {
            return;
        }

        // Vertex (moving) against triangle (fixed): eq. (1)-(2).
        ws.pairs.sort_unstable();
        let mut i = 0;
        while i < ws.pairs.len() {
            let tf = ws.pairs[i].0;
            let st = ws.stamp();
            let tri = fixed_tri(fixed, tf);
            let n = tri_normal(&tri);
            while i < ws.pairs.len() && ws.pairs[i].0 == tf {
                let tm = ws.pairs[i].1;
                for &v in &moving.indices()[tm as usize] {
                    if ws.v_stamp_m[v as usize] != st {
                        ws.v_stamp_m[v as usize] = st;
                        let p = moving_pt(ws, moving, fr, v);
                        if let Some((s, bary)) = ray_triangle(p, -fr.u, &tri, s_min, s_max) {
                            ws.events.push(Event {
                                s,
                                point: p - s * fr.u,
                                normal: n,
                                fixed: tri_feature(fixed, tf, bary),
                                moving: Feature::Vertex(v),
                            });
                        }
                    }
                }
                i += 1;
            }
        }

        // Vertex (fixed) against triangle (moving): the special situation, eq. (3).
        ws.pairs.sort_unstable_by_key(|&(tf, tm)| (tm, tf));
        let qstamp = ws.stamp();
        let mut i = 0;
        while i < ws.pairs.len() {
            let tm = ws.pairs[i].1;
            let start = i;
            let st = ws.stamp();
            let idx = moving.indices()[tm as usize];
            let tri = idx.map(|v| moving_pt(ws, moving, fr, v));
            let n = tri_normal(&tri);
            while i < ws.pairs.len() && ws.pairs[i].1 == tm {
                let tf = ws.pairs[i].0;
                for &w in &fixed.indices()[tf as usize] {
                    if ws.v_stamp_f[w as usize] != st {
                        ws.v_stamp_f[w as usize] = st;
                        let q = fixed.vertices()[w as usize].as_dvec3();
                        if let Some((s, bary)) = ray_triangle(q, fr.u, &tri, s_min, s_max) {
                            ws.events.push(Event {
                                s,
                                point: q,
                                normal: n,
                                fixed: Feature::Vertex(w),
                                moving: tri_feature(moving, tm, bary),
                            });
                        }
                    }
                }
                i += 1;
            }
            ws.tm_range[tm as usize] = (start as u32, i as u32);
            ws.tm_range_stamp[tm as usize] = qstamp;
        }

        // Edge against edge: the 3D case the paper's 2D argument misses.
        for k in 0..ws.pairs.len() {
            let tm = ws.pairs[k].1;
            if k > 0 && ws.pairs[k - 1].1 == tm {
                continue;
            }
            for em in moving.triangle_edges(tm) {
                if ws.e_stamp_m[em as usize] == qstamp {
                    continue;
                }
                ws.e_stamp_m[em as usize] = qstamp;
                let st = ws.stamp();
                let [ma, mb] = moving.edges()[em as usize];
                let (p0, p1) = (moving_pt(ws, moving, fr, ma), moving_pt(ws, moving, fr, mb));
                let [t1, t2] = moving.edge_triangles(em);
                let mut tris = [tm, u32::MAX, u32::MAX];
                if t1 != tm {
                    tris[1] = t1;
                }
                if t2 != tm && t2 != t1 {
                    tris[2] = t2;
                }
                for t in tris {
                    if t == u32::MAX || ws.tm_range_stamp[t as usize] != qstamp {
                        continue;
                    }
                    let (r0, r1) = ws.tm_range[t as usize];
                    for r in r0..r1 {
                        let tf = ws.pairs[r as usize].0;
                        for ef in fixed.triangle_edges(tf) {
                            if ws.e_stamp_f[ef as usize] == st {
                                continue;
                            }
                            ws.e_stamp_f[ef as usize] = st;
                            let [fa, fb] = fixed.edges()[ef as usize];
                            let q0 = fixed.vertices()[fa as usize].as_dvec3();
                            let q1 = fixed.vertices()[fb as usize].as_dvec3();
                            if let Some((s, alpha, beta, n)) =
                                edge_edge(p0, p1, q0, q1, fr.u, s_min, s_max)
                            {
                                ws.events.push(Event {
                                    s,
                                    point: q0 + beta * (q1 - q0),
                                    normal: n,
                                    fixed: edge_feature([fa, fb], beta),
                                    moving: edge_feature([ma, mb], alpha),
                                });
                            }
                        }
                    }
                }
            }
        }
    }

    /// Do the objects interpenetrate with the moving one walked back by `s`? A transversal
    /// crossing of the surfaces, or one inside the other (the outer one closed).
    pub(in crate::geometry) fn penetrating_at(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        s: f64,
    ) -> bool {
        let shift = -s * fr.u;
        // Two convex meshes: parry's GJK and EPA on the meshes' support maps decide in a few
        // support queries, where the triangle test below walks every pair of triangles within
        // the tolerance of each other (hundreds on a rounded shape resting on another; a bench
        // of the rotating path on rapier's rounded hulls spent 90 % of its time there).
        if fixed.is_convex() && moving.is_convex() {
            if let Some(p) = self.convex_penetrating(fixed, moving, fr, shift) {
                return p;
            }
        }
        // Quick sufficient test first: the vertex of each object deepest along the motion lies
        // inside the other (closed) one, farther than the tolerance from its surface.
        // (Containment needs only the container closed: an open mover, even a single
        // triangle, wholly inside a closed mesh penetrates it.)
        let inv = fr.rot.conjugate();
        if fixed.is_closed() {
            let v = support_vertex(moving, (inv * fr.u).as_vec3());
            let p = fr.moving_point(moving.vertices()[v as usize]) + shift;
            if deep_inside(fixed, p, fr.tol) {
                return true;
            }
        }
        if moving.is_closed() {
            let w = support_vertex(fixed, (-fr.u).as_vec3());
            let q = inv * (fixed.vertices()[w as usize].as_dvec3() - shift - fr.tra);
            if deep_inside(moving, q, fr.tol) {
                return true;
            }
        }
        let margin = fr.box_margin(fixed, moving);
        if moving.num_triangles() <= SMALL_MOVER_TRIANGLES {
            return self.small_mover_crosses(fixed, moving, fr, shift, margin)
                || self.sample_inside_either(fixed, moving, fr, shift);
        }
        let pos12 = Pose::from_parts((fr.tra + shift).as_vec3(), fr.rot.as_quat());
        let overlap = |nf: &BvhNode, nm: &BvhNode| {
            nm.aabb()
                .transform_by(&pos12)
                .loosened(margin)
                .intersects(&nf.aabb())
        };
        let (fbvh, mbvh) = (fixed.bvh(), moving.bvh());
        for (tf, tm) in fbvh.leaf_pairs(mbvh, overlap) {
            let a = fixed_tri(fixed, tf);
            let b = moving.indices()[tm as usize]
                .map(|v| moving_pt(&mut self.ws, moving, fr, v) + shift);
            if triangles_cross(
                (&a, fixed.flat_sides(tf)),
                (&b, moving.flat_sides(tm)),
                fr.tol,
            ) {
                return true;
            }
        }
        self.sample_inside_either(fixed, moving, fr, shift)
    }

    /// Whether a surface triangle of the small mesh `moving` (shifted by `shift`, fixed
    /// frame) crosses one of `fixed`'s. Its triangles are put in the fixed frame once, one
    /// query of the fixed BVH with their joint box gives the fixed candidates, and each
    /// candidate is tried against the moving triangles whose own (exact, loosened by
    /// `margin`) boxes it meets: the same pairs the two BVHs' joint descent lets through or
    /// fewer (a moving node's box turned into the fixed frame contains its triangles'), for
    /// a quarter of the node tests. (A cube turning against an 800-triangle TriMesh floor:
    /// 200-300 node boxes turned and tested for each pose apart, 8-10 us a test.)
    fn small_mover_crosses(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        shift: DVec3,
        margin: Real,
    ) -> bool {
        let mut tris = std::mem::take(&mut self.ws.m_tris);
        tris.clear();
        let mut all = Aabb::new_invalid();
        for idx in moving.indices() {
            let b = idx.map(|v| moving_pt(&mut self.ws, moving, fr, v) + shift);
            let (lo, hi) = (b[0].min(b[1]).min(b[2]), b[0].max(b[1]).max(b[2]));
            let bx = Aabb::new(lo.as_vec3(), hi.as_vec3()).loosened(margin);
            all.merge(&bx);
            tris.push((b, bx));
        }
        let fbvh = fixed.bvh();
        let crosses = fbvh.intersect_aabb(&all).any(|tf| {
            let Some(nf) = fbvh.leaf_node(tf) else {
                return false;
            };
            let a = fixed_tri(fixed, tf);
            tris.iter().enumerate().any(|(tm, (b, bx))| {
                bx.intersects(&nf.aabb())
                    && triangles_cross(
                        (&a, fixed.flat_sides(tf)),
                        (b, moving.flat_sides(tm as u32)),
                        fr.tol,
                    )
            })
        });
        self.ws.m_tris = tris;
        crosses
    }

    /// A sample point of each surface inside the other one, when that one is closed.
    fn sample_inside_either(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        shift: DVec3,
    ) -> bool {
        let inv = fr.rot.conjugate();
        if fixed.is_closed()
            && sample_inside(moving, fixed, |p| fr.moving_point(p) + shift) == Some(true)
        {
            return true;
        }
        moving.is_closed()
            && sample_inside(fixed, moving, |p| inv * (p.as_dvec3() - shift - fr.tra)) == Some(true)
    }

    /// Did the objects overlap somewhere strictly between the first touch and now?
    pub(super) fn perforated_between(
        &mut self,
        fixed: &TouchMesh,
        moving: &TouchMesh,
        fr: &Frame,
        first: f64,
    ) -> bool {
        let mut ss: Vec<f64> = self
            .ws
            .events
            .iter()
            .map(|e| e.s)
            .filter(|&s| s > fr.tol && s <= first + fr.tol)
            .collect();
        ss.push(0.0);
        ss.sort_unstable_by(|a, b| b.total_cmp(a));
        ss.dedup_by(|a, b| (*a - *b).abs() <= fr.tol);
        let mids: Vec<f64> = ss.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
        let n = mids.len();
        let budget = self.options.max_perforation_samples.max(1);
        let step = n.div_ceil(budget).max(1);
        (0..n)
            .step_by(step)
            .any(|k| self.penetrating_at(fixed, moving, fr, mids[k]))
    }
}

pub(super) fn pair_key(tf: u32, tm: u32) -> u64 {
    ((tf as u64) << 32) | tm as u64
}

/// Can triangles `tf` and `tm` (the latter walked back by some `s` in `[s0, s1]`) be within
/// the tolerance of each other? The fixed triangle's bounding box and the moving one's swept
/// over the range, loosened by two tolerances, overlap.
#[allow(clippy::too_many_arguments)]
pub(super) fn boxes_meet(
    ws: &mut Workspace,
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
    tf: u32,
    tm: u32,
    s0: f64,
    s1: f64,
) -> bool {
    let a = fixed_tri(fixed, tf);
    let b = moving.indices()[tm as usize].map(|v| moving_pt(ws, moving, fr, v));
    let m = DVec3::splat(2.0 * fr.tol);
    let (a_lo, a_hi) = (a[0].min(a[1]).min(a[2]), a[0].max(a[1]).max(a[2]));
    let (b_lo, b_hi) = (b[0].min(b[1]).min(b[2]), b[0].max(b[1]).max(b[2]));
    let (d0, d1) = (-s0 * fr.u, -s1 * fr.u);
    let (b_lo, b_hi) = (b_lo + d0.min(d1), b_hi + d0.max(d1));
    (a_lo - m).cmple(b_hi).all() && (b_lo - m).cmple(a_hi).all()
}

/// A touch `s` in `[s_min, s_max]` found cheaply (or `None`): the moving object's deepest
/// vertex against the fixed mesh, and the fixed object's deepest vertex against the moving
/// mesh, each by one parry ray cast from the far end of the range.
pub(super) fn seed_first_touch(
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
    s_min: f64,
    s_max: f64,
) -> Option<f64> {
    let span = s_max - s_min;
    if !(span.is_finite() && span >= 0.0) {
        return None;
    }
    let inv = fr.rot.conjugate();
    let mut best: Option<f64> = None;
    // Moving vertex p walked back by s sits at p - s u: from p - s_max u toward +u.
    let v = support_vertex(moving, (inv * fr.u).as_vec3());
    let p = fr.moving_point(moving.vertices()[v as usize]);
    let ray = Ray::new((p - s_max * fr.u).as_vec3(), fr.u.as_vec3());
    if let Some(t) = fixed.trimesh().cast_local_ray(&ray, span as Real, false) {
        best = Some(s_max - t as f64);
    }
    // Fixed vertex q against the moving mesh walked back by s: in the moving frame q sits at
    // q' + s u', from q' + s_max u' toward -u'.
    let w = support_vertex(fixed, (-fr.u).as_vec3());
    let q = inv * (fixed.vertices()[w as usize].as_dvec3() - fr.tra);
    let um = inv * fr.u;
    let ray = Ray::new((q + s_max * um).as_vec3(), (-um).as_vec3());
    if let Some(t) = moving.trimesh().cast_local_ray(&ray, span as Real, false) {
        let s = s_max - t as f64;
        best = Some(best.map_or(s, |b: f64| b.max(s)));
    }
    best
}

/// Largest `s` at which triangle `b`, moved by `s d` (unit `d`), can still meet the plane of
/// triangle `a`; `+inf` when `d` is parallel to the plane or `a` is degenerate.
pub(super) fn plane_bound(a: &[DVec3; 3], b: &[DVec3; 3], d: DVec3) -> f64 {
    let n = (a[1] - a[0]).cross(a[2] - a[0]);
    let nd = n.dot(d);
    if nd.abs() <= 1e-12 * n.length() {
        return f64::INFINITY;
    }
    // Signed distances, oriented so that moving along d decreases them.
    let sign = if nd > 0.0 { -1.0 } else { 1.0 };
    let dist = b.map(|p| sign * n.dot(p - a[0]));
    // b meets the plane while min(dist) - s |nd| <= 0 <= max(dist) - s |nd|.
    dist[0].max(dist[1]).max(dist[2]) / nd.abs()
}

/// All touches of one triangle pair with `s` in `[lo, hi]`, pushed to `ws.events`; returns the
/// largest (or `-inf`).
#[allow(clippy::too_many_arguments)]
pub(super) fn pair_events(
    ws: &mut Workspace,
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
    tf: u32,
    tm: u32,
    lo: f64,
    hi: f64,
) -> f64 {
    let fi = fixed.indices()[tf as usize];
    let mi = moving.indices()[tm as usize];
    let pf = fixed_tri(fixed, tf);
    let pm = mi.map(|v| moving_pt(ws, moving, fr, v));
    let mut best = f64::NEG_INFINITY;
    let mut push = |ws: &mut Workspace, e: Event| {
        best = best.max(e.s);
        ws.events.push(e);
    };
    for k in 0..3 {
        if let Some((s, bary)) = ray_triangle(pm[k], -fr.u, &pf, lo, hi) {
            let e = Event {
                s,
                point: pm[k] - s * fr.u,
                normal: tri_normal(&pf),
                fixed: tri_feature(fixed, tf, bary),
                moving: Feature::Vertex(mi[k]),
            };
            push(ws, e);
        }
        if let Some((s, bary)) = ray_triangle(pf[k], fr.u, &pm, lo, hi) {
            let e = Event {
                s,
                point: pf[k],
                normal: tri_normal(&pm),
                fixed: Feature::Vertex(fi[k]),
                moving: tri_feature(moving, tm, bary),
            };
            push(ws, e);
        }
    }
    for i in 0..3 {
        let (p0, p1) = (pm[i], pm[(i + 1) % 3]);
        for j in 0..3 {
            let (q0, q1) = (pf[j], pf[(j + 1) % 3]);
            if let Some((s, alpha, beta, n)) = edge_edge(p0, p1, q0, q1, fr.u, lo, hi) {
                let e = Event {
                    s,
                    point: q0 + beta * (q1 - q0),
                    normal: n,
                    fixed: edge_feature([fi[j], fi[(j + 1) % 3]], beta),
                    moving: edge_feature([mi[i], mi[(i + 1) % 3]], alpha),
                };
                push(ws, e);
            }
        }
    }
    best
}

/// Moves boxes of the moving tree into the fixed frame and intersects them with boxes of the
/// fixed tree along the ray, with the rotation matrices and `1/u` computed once per query.
pub(super) struct BoxTransform {
    rot: glamx::Mat3,
    abs_rot: glamx::Mat3,
    tra: Vector,
    inv_u: Vector,
    u: Vector,
    margin: Real,
}

impl BoxTransform {
    pub(super) fn new(pos12: &Pose, u: Vector, margin: Real) -> Self {
        let rot = glamx::Mat3::from_quat(pos12.rotation);
        let abs_rot = glamx::Mat3::from_cols(rot.x_axis.abs(), rot.y_axis.abs(), rot.z_axis.abs());
        Self {
            rot,
            abs_rot,
            tra: pos12.translation,
            inv_u: u.recip(),
            u,
            margin,
        }
    }

    /// The interval of `s` over which moving box `nm`, walked back by `s` along `-u`, overlaps
    /// fixed box `nf` (both loosened by the margin).
    #[inline]
    pub(super) fn overlap_interval(&self, nm: &BvhNode, nf: &BvhNode) -> Option<(Real, Real)> {
        let (mmin, mmax) = (nm.mins(), nm.maxs());
        let c = self.rot * ((mmin + mmax) * 0.5) + self.tra;
        let h = self.abs_rot * ((mmax - mmin) * 0.5) + Vector::splat(2.0 * self.margin);
        self.interval_of(c, h, nf)
    }

    /// [`BoxTransform::overlap_interval`] of a moving box already in the fixed frame: centre
    /// `c`, half extents `h` (loosened).
    #[inline]
    pub(super) fn interval_of(&self, c: Vector, h: Vector, nf: &BvhNode) -> Option<(Real, Real)> {
        let (fmin, fmax) = (nf.mins(), nf.maxs());
        // Need (c - h) - s u <= fmax and (c + h) - s u >= fmin, per axis.
        let a = (c - h - fmax) * self.inv_u;
        let b = (c + h - fmin) * self.inv_u;
        let (mut lo, mut hi) = (Real::NEG_INFINITY, Real::INFINITY);
        for k in 0..3 {
            if self.u[k].abs() < 1e-12 {
                if c[k] - h[k] > fmax[k] || c[k] + h[k] < fmin[k] {
                    return None;
                }
                continue;
            }
            let (l, r) = if self.u[k] > 0.0 {
                (a[k], b[k])
            } else {
                (b[k], a[k])
            };
            lo = lo.max(l);
            hi = hi.min(r);
        }
        (lo <= hi).then_some((lo, hi))
    }
}

/// The interval of `s` over which the moving mesh's box (walked back by `s`) overlaps the fixed
/// mesh's box.
pub(super) fn aabb_overlap_range(
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
) -> Option<(f64, f64)> {
    let f = fixed.local_aabb();
    let pos12 = fr.pose12();
    let m = moving.local_aabb().transform_by(&pos12);
    let pad = fr.tol * 4.0 + 1e-5 * (f.extents().length() as f64).max(1e-12);
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        let (fmn, fmx) = (f.mins[k] as f64 - pad, f.maxs[k] as f64 + pad);
        let (mmn, mmx) = (m.mins[k] as f64, m.maxs[k] as f64);
        let uk = fr.u[k];
        // Need mmn - s uk <= fmx and mmx - s uk >= fmn.
        if uk.abs() < 1e-15 {
            if mmn > fmx || mmx < fmn {
                return None;
            }
            continue;
        }
        let a = (mmn - fmx) / uk;
        let b = (mmx - fmn) / uk;
        let (l, h) = if uk > 0.0 { (a, b) } else { (b, a) };
        lo = lo.max(l);
        hi = hi.min(h);
    }
    (lo <= hi).then_some((lo, hi))
}

pub(super) fn moving_pt(ws: &mut Workspace, moving: &TouchMesh, fr: &Frame, v: u32) -> DVec3 {
    let i = v as usize;
    if ws.m_pt_stamp[i] != fr.stamp {
        ws.m_pt_stamp[i] = fr.stamp;
        ws.m_pts[i] = fr.moving_point(moving.vertices()[i]);
    }
    ws.m_pts[i]
}

pub(super) fn fixed_tri(fixed: &TouchMesh, t: u32) -> [DVec3; 3] {
    fixed.indices()[t as usize].map(|v| fixed.vertices()[v as usize].as_dvec3())
}
