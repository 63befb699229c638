//! Contact localisation (the paper's neighbour-based classification, section 2.1): the touching
//! feature pairs at first touch are grouped into connected regions through mesh adjacency, and
//! each region is classified as a vertex, edge (line) or face (polygon) contact.

use super::contact::{ContactKind, ContactPatch, ContactPoint};
use super::reconstruction::Frame;
use super::touch_mesh::{Feature, TouchMesh};
use crate::math::{Real, Vector};
use glamx::{DQuat, DVec3};
use parry3d::query::PointQuery;

/// A touching feature pair found along the trajectory.
#[derive(Clone, Debug)]
pub(crate) struct Event {
    /// Distance walked back along `-D` at which the pair touches.
    pub s: f64,
    /// The touching point, fixed frame, with the moving object walked back by `s`.
    pub point: DVec3,
    /// Unit normal of the touch (unoriented), fixed frame.
    pub normal: DVec3,
    /// Feature of the fixed mesh (internal triangle numbering).
    pub fixed: Feature,
    /// Feature of the moving mesh (internal triangle numbering).
    pub moving: Feature,
}

fn vertex_set(mesh: &TouchMesh, f: Feature) -> ([u32; 3], usize) {
    match f {
        Feature::Vertex(v) => ([v, 0, 0], 1),
        Feature::Edge([a, b]) => ([a, b, 0], 2),
        Feature::Face(t) => (mesh.indices()[t as usize], 3),
    }
}

fn features_adjacent(mesh: &TouchMesh, a: Feature, b: Feature) -> bool {
    let (va, na) = vertex_set(mesh, a);
    let (vb, nb) = vertex_set(mesh, b);
    va[..na]
        .iter()
        .any(|&x| vb[..nb].iter().any(|&y| mesh.vertices_adjacent(x, y)))
}

/// Is the midpoint of two touch points on both surfaces (within ten tolerances)? Two touches
/// joined by mesh edges can still be separate regions on a coarse mesh (the two legs of a U
/// standing on one floor polygon): the contact set between them is empty.
fn midpoint_on_both(
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
    s_star: f64,
    a: DVec3,
    b: DVec3,
) -> bool {
    let m = 0.5 * (a + b);
    let lim = 10.0 * fr.tol;
    if a.distance_squared(b) <= (4.0 * lim) * (4.0 * lim) {
        return true;
    }
    // A projection bounded by the limit: parry prunes every BVH node farther than it.
    let on = |mesh: &TouchMesh, p: DVec3| {
        mesh.trimesh()
            .project_local_point_with_max_dist(p.as_vec3(), false, lim as Real)
            .is_some_and(|q| q.point.as_dvec3().distance(p) <= lim)
    };
    // The moving surface at first touch: walked back by s_star, in its own frame.
    let m_local = fr.rot.conjugate() * (m + s_star * fr.u - fr.tra);
    on(fixed, m) && on(moving, m_local)
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

fn to_user(mesh: &TouchMesh, f: Feature) -> Feature {
    match f {
        Feature::Face(t) => Feature::Face(mesh.user_triangle(t)),
        other => other,
    }
}

/// Groups the events at first touch into patches (world space).
pub(crate) fn build_patches(
    fixed: &TouchMesh,
    moving: &TouchMesh,
    fr: &Frame,
    mut events: Vec<Event>,
    s_star: f64,
    to_world: &dyn Fn(DVec3) -> Vector,
    rf: DQuat,
) -> Vec<ContactPatch> {
    let tol = fr.tol;
    // One entry per feature pair, then one per location (keeping the lowest-dimensional
    // features: a vertex on a vertex is found by several triangles and edges).
    events.sort_by_key(|e| (e.fixed, e.moving));
    events.dedup_by(|a, b| a.fixed == b.fixed && a.moving == b.moving);
    events.sort_by_key(|e| e.fixed.dimension() + e.moving.dimension());
    let mut kept: Vec<Event> = Vec::with_capacity(events.len());
    for e in events {
        let dup = kept.len() < 4096
            && kept
                .iter()
                .any(|k| k.point.distance_squared(e.point) <= tol * tol);
        if !dup {
            kept.push(e);
        }
    }
    for e in &mut kept {
        if e.normal.dot(fr.u) > 0.0 {
            e.normal = -e.normal;
        }
    }

    // Regions: two touches belong together when their features are neighbours on both meshes.
    let n = kept.len();
    let mut parent: Vec<usize> = (0..n).collect();
    for i in 0..n {
        for j in i + 1..n {
            // Already in one region: the (costly) tests below cannot change anything.
            let (a, b) = (find(&mut parent, i), find(&mut parent, j));
            if a != b
                && features_adjacent(fixed, kept[i].fixed, kept[j].fixed)
                && features_adjacent(moving, kept[i].moving, kept[j].moving)
                && midpoint_on_both(fixed, moving, fr, s_star, kept[i].point, kept[j].point)
            {
                parent[a] = b;
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut root_group = vec![usize::MAX; n];
    for i in 0..n {
        let r = find(&mut parent, i);
        if root_group[r] == usize::MAX {
            root_group[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[root_group[r]].push(i);
    }

    groups
        .into_iter()
        .map(|g| {
            let pts: Vec<DVec3> = g.iter().map(|&i| kept[i].point).collect();
            let normal = g
                .iter()
                .map(|&i| kept[i].normal)
                .sum::<DVec3>()
                .try_normalize()
                .unwrap_or(-fr.u);
            let (kind, poly) = classify(&pts, normal, tol);
            let points: Vec<ContactPoint> = g
                .iter()
                .map(|&i| ContactPoint {
                    point: to_world(kept[i].point),
                    fixed_feature: to_user(fixed, kept[i].fixed),
                    moving_feature: to_user(moving, kept[i].moving),
                })
                .collect();
            let mut fixed_features: Vec<Feature> = points.iter().map(|p| p.fixed_feature).collect();
            fixed_features.sort_unstable();
            fixed_features.dedup();
            let mut moving_features: Vec<Feature> =
                points.iter().map(|p| p.moving_feature).collect();
            moving_features.sort_unstable();
            moving_features.dedup();
            ContactPatch {
                kind,
                normal: (rf * normal).as_vec3(),
                polygon: poly.into_iter().map(to_world).collect(),
                points,
                fixed_features,
                moving_features,
            }
        })
        .collect()
}

/// Vertex if the points coincide, edge if they are collinear, face otherwise; with the
/// region's shape (point, segment ends, or convex polygon counter-clockwise about `normal`).
fn classify(pts: &[DVec3], normal: DVec3, tol: f64) -> (ContactKind, Vec<DVec3>) {
    let p0 = pts[0];
    let (far_i, far_d) = pts
        .iter()
        .enumerate()
        .map(|(i, p)| (i, p.distance(p0)))
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    if far_d <= tol {
        let c = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
        return (ContactKind::Vertex, vec![c]);
    }
    let dir = (pts[far_i] - p0) / far_d;
    let off_line = pts
        .iter()
        .map(|p| (*p - p0).reject_from_normalized(dir).length())
        .fold(0.0, f64::max);
    if off_line <= tol {
        let (mut lo, mut hi) = (p0, p0);
        let (mut tlo, mut thi) = (0.0, 0.0);
        for p in pts {
            let t = (*p - p0).dot(dir);
            if t < tlo {
                tlo = t;
                lo = *p;
            }
            if t > thi {
                thi = t;
                hi = *p;
            }
        }
        return (ContactKind::Edge, vec![lo, hi]);
    }
    (ContactKind::Face, convex_hull_on_plane(pts, normal, tol))
}

/// Andrew's monotone chain on the plane orthogonal to `n`; counter-clockwise about `n`.
fn convex_hull_on_plane(pts: &[DVec3], n: DVec3, tol: f64) -> Vec<DVec3> {
    let t1 = n.any_orthonormal_vector();
    let t2 = n.cross(t1);
    let mut p: Vec<(f64, f64, usize)> = pts
        .iter()
        .enumerate()
        .map(|(i, q)| (q.dot(t1), q.dot(t2), i))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let turn = |o: (f64, f64, usize), a: (f64, f64, usize), b: (f64, f64, usize)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64, usize)> = Vec::with_capacity(p.len() * 2);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64, usize)>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    // Corners within `tol` of the line through their neighbours are not corners.
    let mut k = 0;
    while hull.len() > 3 && k < hull.len() {
        let m = hull.len();
        let (o, a, b) = (hull[(k + m - 1) % m], hull[k], hull[(k + 1) % m]);
        let len = (b.0 - o.0).hypot(b.1 - o.1);
        if len > 0.0 && turn(o, a, b).abs() / len <= tol {
            hull.remove(k);
        } else {
            k += 1;
        }
    }
    hull.into_iter().map(|(_, _, i)| pts[i]).collect()
}
