//! The convex hull of a point set with exact predicates: the surface of a `ConvexPolyhedron`
//! and of the rounded shapes (see [`TouchMesh::from_shape`](super::TouchMesh::from_shape)).
//!
//! parry's quickhull (`parry3d::transformation::convex_hull`) runs in `f32` and takes points
//! within `1.2e-5 ×` the diagonal of a face as on it. On clustered points (a rounded shape with
//! a border radius below a thousandth of its size) that tolerance is larger than the clusters
//! and it returns meshes with points a tenth of the diagonal outside; with any tolerance, a
//! point taken as on a long thin face can leave the hull non-convex by the tolerance times the
//! face's aspect ratio. Here every above/below decision is Shewchuk's exact `orient3d`, so the
//! result is the exact hull of the given points.

use crate::math::Vector;
use glamx::DVec3;
use parry3d::bounding_volume::Aabb;
// parry's hash map (foldhash, fixed state): deterministic, and the hull of a rounded hull's
// 540 points took 15-20 % less time than with std's SipHash (3.4-4.8 -> 2.7-3.9 ms,
// alternated runs).
use parry3d::utils::hashmap::HashMap;
use robust::{orient3d, Coord3D};

/// A triangle whose height over its longest edge is below this fraction of the largest extent
/// is flat: [`TouchMesh::new`](super::TouchMesh::new) would drop it (at `1e-7`) and leave a
/// hole, so its middle vertex (at most that far from the hull of the others) is left out and
/// the hull recomputed.
const FLAT: f64 = 1.0e-6;

/// Why no hull was found.
#[derive(Debug)]
pub(crate) enum HullError {
    /// All points lie on a plane (or a line, or a point).
    Flat,
    /// The result failed its check (closed, edge-manifold, convex): a bug.
    Inconsistent,
}

/// The triangles (counter-clockwise seen from outside, indices into `points`) of the convex
/// hull of `points`. Points inside or on a face, and the middle vertices of flat triangles,
/// are used by no triangle.
pub(crate) fn convex_hull(points: &[Vector]) -> Result<Vec<[u32; 3]>, HullError> {
    let p: Vec<DVec3> = points.iter().map(|v| v.as_dvec3()).collect();
    let extent = Aabb::from_points(points.iter().copied())
        .extents()
        .max_element() as f64;
    let mut skip = vec![false; p.len()];
    for _ in 0..16 {
        let tris = quickhull(&p, &skip)?;
        if !is_convex_surface(&p, &tris) {
            return Err(HullError::Inconsistent);
        }
        let mut flat = false;
        for t in &tris {
            let [a, b, c] = t.map(|k| p[k as usize]);
            let opposite = [(b - c).length(), (c - a).length(), (a - b).length()];
            let k = (0..3)
                .max_by(|&x, &y| opposite[x].total_cmp(&opposite[y]))
                .unwrap_or(0);
            let height = (b - a).cross(c - a).length() / opposite[k];
            // NaN (a triangle with three equal corners) counts as flat.
            if height.is_nan() || height <= FLAT * extent {
                skip[t[k] as usize] = true;
                flat = true;
            }
        }
        if !flat {
            return Ok(tris);
        }
    }
    Err(HullError::Inconsistent)
}

fn coord(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// Exactly: is `x` strictly above the plane of the counter-clockwise triangle `t`?
fn above(p: &[DVec3], t: [u32; 3], x: DVec3) -> bool {
    let [a, b, c] = t.map(|k| coord(p[k as usize]));
    orient3d(a, b, c, coord(x)) < 0.0
}

/// The check of a result: a closed, edge-manifold surface, convex at every edge (exactly: the
/// far vertex of each neighbouring face is not above the face). Such a surface bounds a convex
/// set; the points left out were below every face when they were dropped, and the hull only
/// grows, so it holds them all.
fn is_convex_surface(p: &[DVec3], tris: &[[u32; 3]]) -> bool {
    let mut edges = HashMap::with_capacity_and_hasher(tris.len() * 3, Default::default());
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            if edges.insert((t[k], t[(k + 1) % 3]), f).is_some() {
                return false;
            }
        }
    }
    tris.iter().all(|t| {
        (0..3).all(|k| {
            let Some(&g) = edges.get(&(t[(k + 1) % 3], t[k])) else {
                return false;
            };
            let far = tris[g].iter().find(|v| !t.contains(v));
            far.is_none_or(|&x| !above(p, *t, p[x as usize]))
        })
    })
}

/// Unit normal and offset of the plane of triangle `t` (for ranking distances only).
fn plane(p: &[DVec3], t: [u32; 3]) -> (DVec3, f64) {
    let [a, b, c] = t.map(|k| p[k as usize]);
    let n = (b - a).cross(c - a).normalize_or_zero();
    (n, n.dot(a))
}

struct Face {
    v: [u32; 3],
    n: DVec3,
    d: f64,
    outside: Vec<u32>,
    alive: bool,
}

/// Quickhull (Barber, Dobkin and Huhdanpaa 1996) over the points not skipped: each face keeps
/// the points strictly above it; the farthest point of a face is added by replacing the faces
/// it sees (found by walking from that face) with a cone over their horizon.
fn quickhull(p: &[DVec3], skip: &[bool]) -> Result<Vec<[u32; 3]>, HullError> {
    let ids: Vec<u32> = (0..p.len() as u32).filter(|&i| !skip[i as usize]).collect();
    // Farthest by `metric`; among near ties (a face or an edge of the hull parallel to the
    // previous points), the lexicographic largest by `keys`: an extreme point, so that the
    // initial tetrahedron adds no vertex in the middle of an edge or a face.
    let far = |metric: &dyn Fn(DVec3) -> f64, keys: [DVec3; 2]| {
        let best = ids
            .iter()
            .map(|&i| metric(p[i as usize]))
            .fold(f64::MIN, f64::max);
        let near = (best.abs() * 1e-12).max(f64::MIN_POSITIVE);
        let key = |i: u32| keys.map(|k| k.dot(p[i as usize]));
        ids.iter()
            .copied()
            .filter(|&i| metric(p[i as usize]) >= best - near)
            .max_by(|&a, &b| {
                let (ka, kb) = (key(a), key(b));
                ka[0].total_cmp(&kb[0]).then(ka[1].total_cmp(&kb[1]))
            })
            .ok_or(HullError::Flat)
    };
    // The initial tetrahedron: extreme points, each as far as possible from the previous ones.
    let i0 = far(&|x| -x.x, [-DVec3::Y, -DVec3::Z])?;
    let a = p[i0 as usize];
    let i1 = far(&|x| (x - a).length(), [DVec3::X, DVec3::Y])?;
    let ab = p[i1 as usize] - a;
    let side = ab.any_orthonormal_vector();
    let i2 = far(&|x| (x - a).cross(ab).length(), [ab, side])?;
    let n = ab.cross(p[i2 as usize] - a);
    let i3 = far(&|x| n.dot(x - a).abs(), [ab, n.cross(ab)])?;
    let tet = [i0, i1, i2, i3];
    if orient3d(
        coord(p[i0 as usize]),
        coord(p[i1 as usize]),
        coord(p[i2 as usize]),
        coord(p[i3 as usize]),
    ) == 0.0
    {
        return Err(HullError::Flat);
    }
    let make = |v: [u32; 3]| {
        let (n, d) = plane(p, v);
        Face {
            v,
            n,
            d,
            outside: Vec::new(),
            alive: true,
        }
    };
    let mut faces: Vec<Face> = Vec::new();
    for opposite in 0..4 {
        let mut v = [0u32; 3];
        let mut m = 0;
        for (k, &i) in tet.iter().enumerate() {
            if k != opposite {
                v[m] = i;
                m += 1;
            }
        }
        if above(p, v, p[tet[opposite] as usize]) {
            v.swap(1, 2);
        }
        faces.push(make(v));
    }
    let mut edges: HashMap<(u32, u32), usize> = HashMap::default();
    for (f, face) in faces.iter().enumerate() {
        for k in 0..3 {
            edges.insert((face.v[k], face.v[(k + 1) % 3]), f);
        }
    }
    assign(p, &mut faces, 0, &ids);

    let mut pending: Vec<usize> = (0..4).collect();
    while let Some(f0) = pending.pop() {
        if !faces[f0].alive || faces[f0].outside.is_empty() {
            continue;
        }
        let face = &faces[f0];
        let height = |i: u32| face.n.dot(p[i as usize]) - face.d;
        let apex = face
            .outside
            .iter()
            .copied()
            .fold(face.outside[0], |best, i| {
                if height(i) > height(best) {
                    i
                } else {
                    best
                }
            });
        let q = p[apex as usize];
        // The faces `apex` sees, by walking from `f0`; the horizon is their border.
        let mut visible = vec![f0];
        let mut sees: HashMap<usize, bool> = HashMap::default();
        sees.insert(f0, true);
        let mut horizon = Vec::new();
        let mut k = 0;
        while k < visible.len() {
            let f = visible[k];
            k += 1;
            for e in 0..3 {
                let (u, w) = (faces[f].v[e], faces[f].v[(e + 1) % 3]);
                let g = *edges.get(&(w, u)).ok_or(HullError::Inconsistent)?;
                let seen = *sees.entry(g).or_insert_with(|| {
                    let s = above(p, faces[g].v, q);
                    if s {
                        visible.push(g);
                    }
                    s
                });
                if !seen {
                    horizon.push((u, w));
                }
            }
        }
        let mut orphans = Vec::new();
        for &f in &visible {
            faces[f].alive = false;
            orphans.append(&mut faces[f].outside);
            for e in 0..3 {
                edges.remove(&(faces[f].v[e], faces[f].v[(e + 1) % 3]));
            }
        }
        let first = faces.len();
        for (u, w) in horizon {
            let f = faces.len();
            faces.push(make([u, w, apex]));
            for key in [(u, w), (w, apex), (apex, u)] {
                if edges.insert(key, f).is_some() {
                    return Err(HullError::Inconsistent);
                }
            }
            pending.push(f);
        }
        orphans.retain(|&i| i != apex);
        assign(p, &mut faces, first, &orphans);
    }
    Ok(faces.iter().filter(|f| f.alive).map(|f| f.v).collect())
}

/// Puts each point in the outside set of the face (from `first` on) it is strictly above,
/// the farthest one if several.
fn assign(p: &[DVec3], faces: &mut [Face], first: usize, points: &[u32]) {
    for &i in points {
        let x = p[i as usize];
        let best = (first..faces.len())
            .filter(|&f| above(p, faces[f].v, x))
            .max_by(|&f, &g| {
                (faces[f].n.dot(x) - faces[f].d).total_cmp(&(faces[g].n.dot(x) - faces[g].d))
            });
        if let Some(f) = best {
            faces[f].outside.push(i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Real;

    #[test]
    fn hull_of_a_cube_lattice_is_the_cube() {
        // 5×5×5 lattice: coplanar and collinear points everywhere, all but the 8 corners on or
        // inside the hull's faces and edges.
        let mut pts = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                for k in 0..5 {
                    pts.push(Vector::new(i as Real, j as Real, k as Real) * 0.25);
                }
            }
        }
        let tris = convex_hull(&pts).unwrap();
        let mut used: Vec<u32> = tris.iter().flatten().copied().collect();
        used.sort_unstable();
        used.dedup();
        assert_eq!(used.len(), 8, "{used:?}");
        assert_eq!(tris.len(), 12);
        assert!(matches!(
            convex_hull(&[Vector::ZERO, Vector::X, Vector::Y, Vector::X + Vector::Y]),
            Err(HullError::Flat)
        ));
    }
}
