//! The feature tests the reconstruction is built from: a ray against a triangle (eq. 1-3), an
//! edge against an edge (the 3D case), snapping a point to the feature it lies on; and the
//! tests of a pose (two triangles crossing, a point inside a closed mesh).

use super::*;

pub(crate) fn tri_normal(t: &[DVec3; 3]) -> DVec3 {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero()
}

/// Ray `o + s d` (unit `d`) against triangle `t`: `(s, [α, β, γ])` when it hits with `s` in
/// range. Parallel rays (no single crossing) return `None`.
pub(crate) fn ray_triangle(
    o: DVec3,
    d: DVec3,
    t: &[DVec3; 3],
    s_min: f64,
    s_max: f64,
) -> Option<(f64, [f64; 3])> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let h = d.cross(e2);
    let det = e1.dot(h);
    // |det| ≤ 1e-10 |e1| |e2|, squared (no square roots).
    if det * det <= 1e-20 * e1.length_squared() * e2.length_squared() {
        return None;
    }
    let inv = 1.0 / det;
    let sv = o - t[0];
    let b = inv * sv.dot(h);
    if !(-BARY_EPS..=1.0 + BARY_EPS).contains(&b) {
        return None;
    }
    let q = sv.cross(e1);
    let c = inv * d.dot(q);
    if c < -BARY_EPS || b + c > 1.0 + BARY_EPS {
        return None;
    }
    let s = inv * e2.dot(q);
    (s >= s_min && s <= s_max).then_some((s, [1.0 - b - c, b, c]))
}

/// Edges `p0 p1` (moving, walked back by `s` along `-u`) and `q0 q1` (fixed): the `s` at
/// which they cross, with the parameters along each edge and the unit normal `e × f`.
pub(crate) fn edge_edge(
    p0: DVec3,
    p1: DVec3,
    q0: DVec3,
    q1: DVec3,
    u: DVec3,
    s_min: f64,
    s_max: f64,
) -> Option<(f64, f64, f64, DVec3)> {
    let e = p1 - p0;
    let f = q1 - q0;
    let n = e.cross(f);
    let det = n.dot(u);
    // Parallel to the motion (or to each other): no single crossing. Also rejects n = 0.
    if det * det <= 1e-20 * e.length_squared() * f.length_squared() {
        return None;
    }
    let w = q0 - p0;
    let inv = 1.0 / det;
    // The range of s is the most selective test: first. (e · (f × w) = w · n.)
    let s = -w.dot(n) * inv;
    if !(s >= s_min && s <= s_max) {
        return None;
    }
    let alpha = w.dot(f.cross(u)) * inv;
    if !(-BARY_EPS..=1.0 + BARY_EPS).contains(&alpha) {
        return None;
    }
    let beta = -e.dot(w.cross(u)) * inv;
    if !(-BARY_EPS..=1.0 + BARY_EPS).contains(&beta) {
        return None;
    }
    Some((
        s,
        alpha.clamp(0.0, 1.0),
        beta.clamp(0.0, 1.0),
        n.normalize(),
    ))
}

/// Snaps a point given by barycentric coordinates on internal triangle `t` to the feature it
/// lies on.
pub(crate) fn tri_feature(mesh: &TouchMesh, t: u32, bary: [f64; 3]) -> Feature {
    const SNAP: f64 = 1.0e-7;
    let idx = mesh.indices()[t as usize];
    let mut on = [0usize; 3];
    let mut n = 0;
    for (k, &b) in bary.iter().enumerate() {
        if b > SNAP {
            on[n] = k;
            n += 1;
        }
    }
    match n {
        1 => Feature::Vertex(idx[on[0]]),
        2 => {
            let (x, y) = (idx[on[0]], idx[on[1]]);
            Feature::Edge([x.min(y), x.max(y)])
        }
        _ => Feature::Face(t),
    }
}

pub(super) fn edge_feature(e: [u32; 2], t: f64) -> Feature {
    const SNAP: f64 = 1.0e-7;
    if t <= SNAP {
        Feature::Vertex(e[0])
    } else if t >= 1.0 - SNAP {
        Feature::Vertex(e[1])
    } else {
        Feature::Edge([e[0].min(e[1]), e[0].max(e[1])])
    }
}

/// Do two triangles cross transversally (deeper than `tol`)? Touching along a vertex, an edge
/// or a face is not a crossing. `flat_a`, `flat_b`: which sides of each triangle its mesh
/// continues across in the same plane ([`TouchMesh::flat_sides`]).
pub(super) fn triangles_cross(
    (a, flat_a): (&[DVec3; 3], [bool; 3]),
    (b, flat_b): (&[DVec3; 3], [bool; 3]),
    tol: f64,
) -> bool {
    edges_cross_triangle(a, flat_a, b, tol) || edges_cross_triangle(b, flat_b, a, tol)
}

/// Does an edge of `b` cross triangle `a`, with both ends farther than `tol` from its plane?
/// The crossing point must lie inside `a` by more than `tol` from each side, except from a
/// side marked in `flat` (its mesh goes on in the same plane there), which it need only be
/// inside of (up to [`FLAT_SLACK`] of `tol` beyond, for rounding). A strict test on every side
/// missed a crossing within `tol` of a side shared by two triangles of a flat floor: both
/// triangles refused it. A cube turning from rest on a wide floor dipped its corner 9 mm in,
/// over such a side, and was found not penetrating there (though it was at smaller and larger
/// turns), so the rotating path's bisection ended there (`tests/it/rigid_motion.rs`, a random
/// case). Beyond a side where the mesh bends (or ends) the plane of `a` is not the surface,
/// and the test stays strict.
pub(super) fn edges_cross_triangle(
    a: &[DVec3; 3],
    flat: [bool; 3],
    b: &[DVec3; 3],
    tol: f64,
) -> bool {
    let n = (a[1] - a[0]).cross(a[2] - a[0]);
    let nl = n.length();
    if nl == 0.0 {
        return false;
    }
    let n = n / nl;
    let d = b.map(|p| n.dot(p - a[0]));
    if (d[0] > -tol && d[1] > -tol && d[2] > -tol) || (d[0] < tol && d[1] < tol && d[2] < tol) {
        return false;
    }
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        if (d[i] < -tol && d[j] > tol) || (d[i] > tol && d[j] < -tol) {
            let x = b[i] + (b[j] - b[i]) * (d[i] / (d[i] - d[j]));
            if point_in_triangle_within(x, a, n, flat, tol) {
                return true;
            }
        }
    }
    false
}

/// How far past a flat side (in `tol`s) a crossing point still counts as inside its triangle
/// ([`edges_cross_triangle`]): the triangle beyond it takes points farther out. A whole `tol`
/// let a triangle take a point its neighbour refuses: a cube resting on a grid floor had the
/// floor's diagonal edge meet the plane of its side face on its bottom edge, 0.19 mm past that
/// face triangle's own diagonal (tolerance 0.22 mm); the face's other triangle, on whose
/// bottom edge the point lay, refused it, this one took it, and the resting cube read as
/// crossing the floor (walked back 15 m, `tests/it/rigid_motion.rs`).
const FLAT_SLACK: f64 = 1e-2;

/// Is `x` (on the plane of `t`) inside `t` by more than `tol` from every edge, or no more than
/// [`FLAT_SLACK`] of `tol` beyond an edge marked in `flat` (edge `k` runs from `t[k]` to
/// `t[k + 1]`)?
fn point_in_triangle_within(x: DVec3, t: &[DVec3; 3], n: DVec3, flat: [bool; 3], tol: f64) -> bool {
    for k in 0..3 {
        let (p, q) = (t[k], t[(k + 1) % 3]);
        let edge = q - p;
        let len = edge.length();
        if len == 0.0 {
            return false;
        }
        // Signed distance from the edge, positive inside.
        let limit = if flat[k] { -FLAT_SLACK * tol } else { tol };
        if n.cross(edge).dot(x - p) / len <= limit {
            return false;
        }
    }
    true
}

/// Is a sample point of `sampled` (mapped by `to_other`) inside the closed mesh `other`?
/// Tries a few triangle centroids; `None` if every sample was ambiguous.
pub(super) fn sample_inside(
    sampled: &TouchMesh,
    other: &TouchMesh,
    to_other: impl Fn(Vector) -> DVec3,
) -> Option<bool> {
    let n = sampled.num_triangles();
    for k in 0..n.min(4) {
        let t = (k * n / n.clamp(1, 4)) as u32;
        let [a, b, c] = sampled.indices()[t as usize].map(|v| sampled.vertices()[v as usize]);
        let centroid = (a + b + c) / 3.0;
        if let Some(inside) = point_in_closed_mesh(other, to_other(centroid)) {
            return Some(inside);
        }
    }
    None
}

/// Is `p` (mesh frame) inside the closed mesh and farther than `tol` from its surface?
pub(super) fn deep_inside(mesh: &TouchMesh, p: DVec3, tol: f64) -> bool {
    point_in_closed_mesh(mesh, p) == Some(true)
        && mesh
            .trimesh()
            .project_local_point_with_max_dist(p.as_vec3(), false, tol as Real)
            .is_none_or(|q| q.point.as_dvec3().distance(p) > tol)
}

/// Parity test for a point in the local frame of a closed mesh. `None` if the ray grazes an
/// edge or the point is on the surface (ambiguous); the caller tries another point.
pub(crate) fn point_in_closed_mesh(mesh: &TouchMesh, p: DVec3) -> Option<bool> {
    const DIRS: [[f64; 3]; 3] = [
        [0.539_163, 0.617_213, 0.573_025],
        [-0.283_111, 0.911_711, -0.297_514],
        [0.712_345, -0.100_113, -0.694_610],
    ];
    let aabb = mesh.local_aabb();
    let pf = p.as_vec3();
    if !aabb.contains_local_point(pf) {
        return Some(false);
    }
    let reach = aabb.extents().length() as f64 * 2.0 + 1.0;
    let eps = 1e-9 * mesh.scale() as f64;
    'dirs: for d in DIRS {
        let d = DVec3::from(d).normalize();
        let ray = Ray::new(pf, d.as_vec3());
        let mut count = 0u32;
        let mut ambiguous = false;
        mesh.bvh().traverse(|node| {
            if ambiguous {
                return TraversalAction::EarlyExit;
            }
            let b = node.aabb().loosened(1e-4 * mesh.scale());
            if !b.intersects_local_ray(&ray, reach as Real) {
                return TraversalAction::Prune;
            }
            if let Some(t) = node.leaf_data() {
                let tri = fixed_tri(mesh, t);
                if let Some((s, bary)) = ray_triangle(p, d, &tri, -eps, reach) {
                    if s.abs() <= eps || bary.iter().any(|&x| x.abs() < 1e-7) {
                        ambiguous = true;
                    } else {
                        count += 1;
                    }
                }
            }
            TraversalAction::Continue
        });
        if ambiguous {
            continue 'dirs;
        }
        return Some(count % 2 == 1);
    }
    None
}
