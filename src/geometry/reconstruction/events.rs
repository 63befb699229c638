//! The exact event search of the reconstruction: the paper's eq. (1)-(3) (and the 3D
//! edge-edge case) applied to the triangle pairs that a simultaneous traversal of both meshes'
//! BVHs, with the moving boxes swept along the trajectory, cannot rule out; the first touch,
//! every touch of the step (for perforation), and the penetration test of a pose.

use super::boxes::{is_small, is_small_mesh, triangle_boxes, BoxTransform};
use super::primitives::*;
use super::*;

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
        // A small moving mesh (`boxes.rs`): its triangles' own boxes in the fixed frame
        // against the fixed BVH's leaves under their joint sweep; a large one by the two BVHs'
        // joint descent.
        if is_small(moving, s_min, s_max) {
            let mut boxes = std::mem::take(&mut ws.m_boxes);
            let swept = triangle_boxes(ws, moving, fr, 2.0 * margin, (s_min, s_max), &mut boxes);
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
        if is_small(moving, s_min, s_max) {
            // A small moving mesh (`boxes.rs`), as in `collect_first_touch`.
            let mut boxes = std::mem::take(&mut ws.m_boxes);
            let all = triangle_boxes(ws, moving, fr, margin, (s_min, s_max), &mut boxes);
            let (a, b) = (a.min(b), a.max(b));
            for tf in fbvh.intersect_aabb(&all) {
                let Some(nf) = fbvh.leaf_node(tf) else {
                    continue;
                };
                for (tm, &(c, h)) in boxes.iter().enumerate() {
                    if Aabb::new(c - h + a, c + h + b).intersects(&nf.aabb()) {
                        ws.pairs.push((tf, tm as u32));
                    }
                }
            }
            ws.m_boxes = boxes;
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
        if is_small_mesh(moving) {
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

    /// A sample point of each surface inside the other one, when that one is closed.
    pub(super) fn sample_inside_either(
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
