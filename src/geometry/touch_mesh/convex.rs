//! Convexity of a [`TouchMesh`] and hill-climbing support queries on convex meshes.

use super::{TouchMesh, NONE};
use crate::math::{Real, Vector};

/// What a convex mesh keeps for fast support-point queries.
#[derive(Clone)]
pub(super) struct ConvexData {
    /// The support vertex for each of 26 fixed directions (the starting points of hill climbing).
    directory: Vec<u32>,
    /// Per vertex: the outward normal of its plane when every neighbour lies on one plane
    /// through it (a vertex inside a flat face), else zero.
    flat_normal: Vec<Vector>,
}

/// The most vertices a mesh may have for [`TouchMesh::hull_vertices`] (quickhull and the
/// pass that takes its points back to the vertices run once per mesh, on first use).
const HULL_MAX_VERTICES: usize = 4096;

impl TouchMesh {
    /// `true` if the mesh bounds a convex solid: closed, edge-manifold, connected, consistently
    /// oriented, and locally convex at every vertex (each neighbour lies on or below the plane
    /// of every triangle around the vertex, to `1e-6` of [`TouchMesh::scale`]). A closed
    /// surface that is locally convex everywhere bounds a convex set (Tietze-Nakajima), so the
    /// check is exact up to that tolerance; a self-intersecting mesh can fool it.
    ///
    /// Convex pairs take a faster path in [`Reconstructor`](crate::geometry::Reconstructor):
    /// parry's GJK ray cast on the Minkowski difference finds the first touch, with support
    /// points found by hill climbing over the vertex graph.
    ///
    /// ```
    /// use rapier_touch::prelude::*;
    /// let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.5))).unwrap();
    /// assert!(cube.is_convex());
    /// // An L-shaped prism is closed but not convex.
    /// let (v, i) = rapier_touch::geometry::generators::extruded_polygon(
    ///     &[[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]],
    ///     1.0,
    /// )
    /// .unwrap();
    /// let l = TouchMesh::new(v, i).unwrap();
    /// assert!(l.is_closed() && !l.is_convex());
    /// ```
    pub fn is_convex(&self) -> bool {
        self.convex.is_some()
    }

    /// The vertices on the convex hull of the mesh's vertices (parry's quickhull, each hull
    /// point taken back to the vertex it came from), found once, on first use, for a mesh of
    /// at most [`HULL_MAX_VERTICES`] vertices: a support point of the hull is then a pass over
    /// these alone (a flat mesh has its outline's corners). `None` for a larger mesh; all
    /// vertices where quickhull fails.
    pub(crate) fn hull_vertices(&self) -> Option<&[u32]> {
        let v = self.vertices();
        if v.len() > HULL_MAX_VERTICES {
            return None;
        }
        let hull = self.hull.get_or_init(|| {
            let all = || (0..v.len() as u32).collect::<Vec<u32>>();
            let Ok((points, _)) = parry3d::transformation::try_convex_hull(v) else {
                return all();
            };
            let mut out: Vec<u32> = points
                .iter()
                .filter_map(|p| {
                    v.iter()
                        .enumerate()
                        .min_by(|a, b| {
                            (*a.1 - *p)
                                .length_squared()
                                .total_cmp(&(*b.1 - *p).length_squared())
                        })
                        .map(|(i, _)| i as u32)
                })
                .collect();
            out.sort_unstable();
            out.dedup();
            if out.is_empty() {
                all()
            } else {
                out
            }
        });
        Some(hull)
    }

    /// Strict hill climbing over the vertex graph from `start`: moves to a neighbour farther
    /// along `dir` until none is. A local maximum of `dir · x`, the support vertex on a convex
    /// mesh (see [`TouchMesh::convex_support`] for the one exception).
    pub(crate) fn hill_climb(&self, start: u32, dir: Vector) -> u32 {
        let v = self.vertices();
        let mut best = start;
        let mut best_d = v[best as usize].dot(dir);
        loop {
            let mut improved = false;
            for &w in self.vertex_neighbours(best) {
                let d = v[w as usize].dot(dir);
                if d > best_d {
                    (best, best_d) = (w, d);
                    improved = true;
                }
            }
            if !improved {
                return best;
            }
        }
    }

    /// The vertex farthest along `dir` of a convex mesh: strict hill climbing over the vertex
    /// graph from the best of `warm` (a previous answer) and a 26-direction directory. On a
    /// convex surface every vertex that is not a maximum has a strictly better neighbour,
    /// except a vertex inside the flat face opposite `dir` (the climb cannot end there unless
    /// it starts there); if it does, all vertices are scanned. `None` for a mesh that is not
    /// convex.
    pub(crate) fn convex_support(&self, dir: Vector, warm: u32) -> Option<u32> {
        let cd = self.convex.as_ref()?;
        let v = self.vertices();
        let climb = |start: u32| self.hill_climb(start, dir);
        // Stuck inside the face opposite `dir`?
        let stuck = |best: u32| cd.flat_normal[best as usize].dot(dir) < 0.0;
        let warm_ok = (warm as usize) < v.len() && !self.vertex_triangles(warm).is_empty();
        let mut start = cd.directory[0];
        let mut start_d = v[start as usize].dot(dir);
        for &c in cd.directory[1..].iter().chain(warm_ok.then_some(&warm)) {
            let d = v[c as usize].dot(dir);
            if d > start_d {
                (start, start_d) = (c, d);
            }
        }
        let best = climb(start);
        if !stuck(best) {
            return Some(best);
        }
        (0..v.len() as u32)
            .filter(|&i| !self.vertex_triangles(i).is_empty())
            .max_by(|&a, &b| v[a as usize].dot(dir).total_cmp(&v[b as usize].dot(dir)))
    }
}

/// Convexity check and support directory of a closed mesh (see [`TouchMesh::is_convex`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn convex_data(
    vertices: &[Vector],
    idx: &[[u32; 3]],
    edges: &[[u32; 2]],
    edge_tris: &[[u32; 2]],
    neighbour_offsets: &[u32],
    neighbours: &[u32],
    vertex_tri_offsets: &[u32],
    vertex_tris: &[u32],
    scale: Real,
) -> Option<ConvexData> {
    use glamx::DVec3;
    let nv = vertices.len();
    let used = |v: usize| vertex_tri_offsets[v + 1] > vertex_tri_offsets[v];
    // Consistent orientation: the two triangles of an edge run along it in opposite directions.
    let runs = |t: u32, a: u32, b: u32| {
        let tri = idx[t as usize];
        (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b)
    };
    for (e, &[a, b]) in edges.iter().enumerate() {
        let [t1, t2] = edge_tris[e];
        if t1 == NONE || t2 == NONE || runs(t1, a, b) == runs(t2, a, b) {
            return None;
        }
    }
    // Connected.
    let first = (0..nv).find(|&v| used(v))?;
    let mut seen = vec![false; nv];
    let mut stack = vec![first as u32];
    seen[first] = true;
    let mut reached = 1;
    while let Some(v) = stack.pop() {
        let (a, b) = (
            neighbour_offsets[v as usize] as usize,
            neighbour_offsets[v as usize + 1] as usize,
        );
        for &w in &neighbours[a..b] {
            if !seen[w as usize] {
                seen[w as usize] = true;
                reached += 1;
                stack.push(w);
            }
        }
    }
    if reached != (0..nv).filter(|&v| used(v)).count() {
        return None;
    }
    // Outward orientation from the sign of the enclosed volume.
    let p = |v: u32| vertices[v as usize].as_dvec3();
    let volume: f64 = idx
        .iter()
        .map(|t| p(t[0]).dot(p(t[1]).cross(p(t[2]))))
        .sum::<f64>()
        / 6.0;
    if volume == 0.0 || !volume.is_finite() {
        return None;
    }
    let sign = volume.signum();
    let normal = |t: u32| {
        let [a, b, c] = idx[t as usize].map(p);
        (b - a).cross(c - a).normalize_or_zero() * sign
    };
    // Local convexity at every vertex; flat vertices remember their plane.
    let eps = 1.0e-6 * scale as f64;
    let mut flat_normal = vec![Vector::ZERO; nv];
    for v in 0..nv {
        if !used(v) {
            continue;
        }
        let pv = p(v as u32);
        let nb = &neighbours[neighbour_offsets[v] as usize..neighbour_offsets[v + 1] as usize];
        let tris = &vertex_tris[vertex_tri_offsets[v] as usize..vertex_tri_offsets[v + 1] as usize];
        let mut flat = true;
        let n0 = normal(tris[0]);
        for &t in tris {
            let n = normal(t);
            if n == DVec3::ZERO {
                return None;
            }
            for &w in nb {
                if n.dot(p(w) - pv) > eps {
                    return None;
                }
            }
        }
        for &w in nb {
            if n0.dot(p(w) - pv).abs() > eps {
                flat = false;
            }
        }
        if flat {
            flat_normal[v] = n0.as_vec3();
        }
    }
    // Support vertices for the 26 directions of a 3x3x3 grid.
    let mut directory = Vec::with_capacity(26);
    for i in -1i32..=1 {
        for j in -1i32..=1 {
            for k in -1i32..=1 {
                if (i, j, k) == (0, 0, 0) {
                    continue;
                }
                let d = Vector::new(i as Real, j as Real, k as Real);
                let best = (0..nv)
                    .filter(|&v| used(v))
                    .max_by(|&a, &b| vertices[a].dot(d).total_cmp(&vertices[b].dot(d)))?;
                directory.push(best as u32);
            }
        }
    }
    Some(ConvexData {
        directory,
        flat_normal,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::generators::{extruded_polygon, icosphere, subdivided_box};
    use parry3d::shape::{Ball, Capsule, Cuboid};

    fn mesh((v, i): (Vec<Vector>, Vec<[u32; 3]>)) -> TouchMesh {
        TouchMesh::new(v, i).unwrap()
    }

    /// Directions on a Fibonacci sphere plus the exact axes and diagonals (which meet flat
    /// faces and edges head-on, the plateaus of hill climbing).
    fn directions() -> Vec<Vector> {
        let mut d: Vec<Vector> = (0..600)
            .map(|k| {
                let z = 1.0 - 2.0 * (k as Real + 0.5) / 600.0;
                let phi = k as Real * 2.399_963;
                let r = (1.0 - z * z).sqrt();
                Vector::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect();
        for i in -1i32..=1 {
            for j in -1i32..=1 {
                for k in -1i32..=1 {
                    if (i, j, k) != (0, 0, 0) {
                        d.push(Vector::new(i as Real, j as Real, k as Real).normalize());
                    }
                }
            }
        }
        d
    }

    #[test]
    fn convexity_is_recognised() {
        let convex = [
            mesh(subdivided_box(Vector::new(0.5, 0.25, 0.5), 8)),
            mesh(icosphere(0.3, 3)),
            TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.5))).unwrap(),
            TouchMesh::from_shape(&Ball::new(0.4)).unwrap(),
            TouchMesh::from_shape(&Capsule::new_y(0.5, 0.2)).unwrap(),
        ];
        for m in &convex {
            assert!(m.is_convex(), "{m:?}");
        }
        // Not convex: an L prism, an open box, two separate cubes, a dented sphere.
        let l = extruded_polygon(
            &[
                [0.0, 0.0],
                [2.0, 0.0],
                [2.0, 1.0],
                [1.0, 1.0],
                [1.0, 2.0],
                [0.0, 2.0],
            ],
            1.0,
        )
        .unwrap();
        assert!(!mesh(l).is_convex());
        let (v, mut i) = subdivided_box(Vector::splat(0.5), 2);
        i.pop();
        assert!(!mesh((v, i)).is_convex());
        let (mut v, mut i) = subdivided_box(Vector::splat(0.5), 1);
        let n = v.len() as u32;
        v.extend(v.clone().iter().map(|p| *p + Vector::X * 3.0));
        i.extend(i.clone().iter().map(|t| t.map(|k| k + n)));
        assert!(!mesh((v, i)).is_convex());
        let (mut v, i) = icosphere(1.0, 3);
        // The vertices of this sphere stand about 1 cm above the plane of their neighbours.
        let mut dented = v.clone();
        dented[7] *= 0.995;
        assert!(
            mesh((dented, i.clone())).is_convex(),
            "still locally convex"
        );
        v[7] *= 0.97;
        assert!(!mesh((v, i)).is_convex(), "a 3 cm dent in a 1 m sphere");
    }

    #[test]
    fn hill_climbing_finds_the_support_vertex() {
        let meshes = [
            mesh(subdivided_box(Vector::new(0.5, 0.25, 0.5), 16)),
            mesh(subdivided_box(Vector::new(0.05, 1.0, 0.3), 5)),
            mesh(icosphere(0.35, 4)),
            TouchMesh::from_shape(&Capsule::new_y(0.5, 0.2)).unwrap(),
        ];
        for m in &meshes {
            let v = m.vertices();
            let eps = 1e-6 * m.scale();
            let mut warm = 0;
            for d in directions() {
                let best = v.iter().map(|p| p.dot(d)).fold(Real::MIN, Real::max);
                // From a previous answer anywhere on the mesh, including the opposite face.
                for start in [warm, 0, (v.len() / 2) as u32] {
                    let s = m.convex_support(d, start).unwrap();
                    assert!(v[s as usize].dot(d) >= best - eps, "{m:?} {d}");
                    warm = s;
                }
            }
        }
        let l = mesh(
            extruded_polygon(
                &[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, 0.2], [0.0, 1.0]],
                1.0,
            )
            .unwrap(),
        );
        assert_eq!(l.convex_support(Vector::Y, 0), None);
    }

    /// A welded triangle soup keeps its copies in the vertex buffer, used by no triangle: the
    /// convexity check and the support queries must see only the vertices in use.
    #[test]
    fn welded_soup_is_convex_and_supports_name_used_vertices() {
        let (v, i) = icosphere(0.4, 2);
        let soup_v: Vec<Vector> = i.iter().flat_map(|t| t.map(|k| v[k as usize])).collect();
        let soup_i = (0..i.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        let m = TouchMesh::new(soup_v, soup_i).unwrap();
        assert_eq!(m.welded_vertices(), 3 * i.len() - v.len());
        assert!(m.is_closed() && m.is_convex(), "{m:?}");
        let best = |d: Vector| v.iter().map(|p| p.dot(d)).fold(Real::MIN, Real::max);
        let copy = (0..3 * i.len() as u32)
            .find(|&k| m.welded_to(k) != k)
            .unwrap();
        assert!(m.vertex_triangles(copy).is_empty());
        for d in directions() {
            // Warm starts on unused copies too.
            for warm in [0, copy, 3 * i.len() as u32 - 1] {
                let s = m.convex_support(d, warm).unwrap();
                assert!(!m.vertex_triangles(s).is_empty());
                assert!(m.vertices()[s as usize].dot(d) >= best(d) - 1e-6);
            }
        }
    }

    /// The hull of a mesh that is not convex: a subdivided box with the inner vertices of its
    /// top face pushed down (a notch; hundreds of vertices) has exactly the box's eight
    /// corners on its hull; the support point of those alone matches a pass over every vertex
    /// in any direction. A flat grid has its four corners.
    #[test]
    fn a_notched_box_of_many_vertices_has_its_corners_for_hull() {
        let h = Vector::new(1.0, 0.5, 0.5);
        let (mut v, idx) = subdivided_box(h, 8);
        for p in v.iter_mut() {
            if p.y == h.y && p.x.abs() < h.x && p.z.abs() < h.z {
                p.y -= 0.2;
            }
        }
        let notched = mesh((v, idx));
        assert!(!notched.is_convex());
        let verts = notched.vertices();
        let corners: Vec<Vector> = notched
            .hull_vertices()
            .unwrap()
            .iter()
            .map(|&i| verts[i as usize])
            .collect();
        assert_eq!(corners.len(), 8, "{corners:?}");
        for c in &corners {
            assert!((c.abs() - h).length() < 1e-6, "{c}");
        }
        for dir in directions() {
            let all = verts.iter().map(|p| p.dot(dir)).fold(Real::MIN, Real::max);
            let on_hull = corners
                .iter()
                .map(|p| p.dot(dir))
                .fold(Real::MIN, Real::max);
            assert!(
                (all - on_hull).abs() <= 1e-6 * (1.0 + all.abs()),
                "{dir}: {all} {on_hull}"
            );
        }
        // A flat grid: its four corners.
        let grid: Vec<Vector> = (0..25)
            .map(|k| Vector::new((k % 5) as Real * 0.25, 0.0, (k / 5) as Real * 0.25))
            .collect();
        let cells: Vec<[u32; 3]> = (0..16u32)
            .flat_map(|c| {
                let q = (c / 4) * 5 + c % 4;
                [[q, q + 5, q + 6], [q, q + 6, q + 1]]
            })
            .collect();
        let flat = mesh((grid, cells));
        let fv = flat.vertices();
        let mut on: Vec<Vector> = flat
            .hull_vertices()
            .unwrap()
            .iter()
            .map(|&i| fv[i as usize])
            .collect();
        on.sort_by(|a, b| (a.x, a.z).partial_cmp(&(b.x, b.z)).unwrap());
        assert_eq!(
            on,
            vec![
                Vector::new(0.0, 0.0, 0.0),
                Vector::new(0.0, 0.0, 1.0),
                Vector::new(1.0, 0.0, 0.0),
                Vector::new(1.0, 0.0, 1.0)
            ]
        );
    }
}
