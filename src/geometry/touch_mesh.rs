//! [`TouchMesh`]: a parry [`TriMesh`] plus the adjacency the reconstruction needs, built once.

use crate::math::{Real, Vector};
use parry3d::bounding_volume::Aabb;
use parry3d::partitioning::Bvh;
use parry3d::shape::{Shape, TriMesh, TriMeshFlags};
use std::collections::HashMap;

/// Why a [`TouchMesh`] could not be built. Each variant says how to fix the input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TouchMeshError {
    /// The mesh has no vertex or no triangle. Give at least one non-degenerate triangle.
    #[error("the mesh is empty (no vertices or no triangles)")]
    Empty,
    /// A vertex coordinate is NaN or infinite. Clean the vertex buffer first.
    #[error("vertex {0} is not finite")]
    NonFiniteVertex(u32),
    /// A triangle names a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {vertex}, but the mesh has only {num_vertices} vertices")]
    IndexOutOfBounds {
        /// The offending triangle.
        triangle: u32,
        /// The vertex index it names.
        vertex: u32,
        /// The number of vertices of the mesh.
        num_vertices: u32,
    },
    /// Every triangle is degenerate (zero area) or a duplicate: nothing is left to touch.
    #[error("all {0} triangles are degenerate or duplicated")]
    AllTrianglesDegenerate(u32),
    /// This parry shape has no triangle-mesh form the crate knows how to build.
    /// Convert it yourself (e.g. `to_trimesh`) and use [`TouchMesh::new`].
    #[error("this shape type cannot be converted to a triangle mesh")]
    UnsupportedShape,
    /// parry refused the mesh.
    #[error("parry could not build the TriMesh: {0}")]
    Parry(String),
}

/// A mesh feature: what touches, named by the indices of the mesh the user gave.
///
/// Triangle indices are those of the user's index buffer (dropped degenerate triangles keep
/// their numbering out of the way, see [`TouchMesh::dropped_triangles`]).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Feature {
    /// A vertex, by index into the vertex buffer.
    Vertex(u32),
    /// An edge, by its two vertex indices (smallest first).
    Edge([u32; 2]),
    /// A triangle, by index into the user's index buffer.
    Face(u32),
}

impl Feature {
    /// The dimension of the feature: 0 for a vertex, 1 for an edge, 2 for a face.
    pub fn dimension(&self) -> u8 {
        match self {
            Feature::Vertex(_) => 0,
            Feature::Edge(_) => 1,
            Feature::Face(_) => 2,
        }
    }
}

/// A triangle mesh prepared for contact reconstruction.
///
/// Holds a parry [`TriMesh`] (its BVH prunes candidates) and the adjacency the paper's
/// neighbour-based classification needs: unique edges, the triangles on each edge, the edges of
/// each triangle and the vertex neighbours. All of it is built once here and reused by every
/// query.
///
/// # Bad input
/// - Empty meshes, non-finite vertices and out-of-range indices are errors.
/// - Degenerate (zero-area) and duplicated triangles are dropped; their original indices are
///   listed by [`TouchMesh::dropped_triangles`] so nothing is lost silently.
/// - Open and non-manifold meshes are accepted and treated as *shells* (a thin TriMesh floor is
///   an open mesh): every touch between surfaces is found, but "one object is entirely inside
///   the other" can only be detected when both meshes are closed ([`TouchMesh::is_closed`]).
///
/// # Example
/// ```
/// use rapier_touch::prelude::*;
/// let mesh = TouchMesh::from_shape(&Cuboid::new(Vector::new(1.0, 0.5, 0.5))).unwrap();
/// assert_eq!(mesh.num_triangles(), 12);
/// assert_eq!(mesh.num_edges(), 18);
/// assert!(mesh.is_closed());
/// ```
#[derive(Clone)]
pub struct TouchMesh {
    trimesh: TriMesh,
    /// For each internal triangle, its index in the user's index buffer.
    tri_to_user: Vec<u32>,
    dropped: Vec<u32>,
    edges: Vec<[u32; 2]>,
    /// The (up to) two triangles on each edge; `u32::MAX` where missing.
    edge_tris: Vec<[u32; 2]>,
    tri_edges: Vec<[u32; 3]>,
    neighbour_offsets: Vec<u32>,
    neighbours: Vec<u32>,
    tri_normals: Vec<Vector>,
    closed: bool,
    non_manifold_edges: usize,
    min_extent: Real,
    scale: Real,
    /// Triangles around each vertex (CSR: `vertex_tri_offsets[v]..vertex_tri_offsets[v + 1]`).
    vertex_tri_offsets: Vec<u32>,
    vertex_tris: Vec<u32>,
    /// Present when the mesh bounds a convex solid.
    convex: Option<ConvexData>,
}

/// What a convex mesh keeps for fast support-point queries.
#[derive(Clone)]
struct ConvexData {
    /// The support vertex for each of 26 fixed directions (the starting points of hill climbing).
    directory: Vec<u32>,
    /// Per vertex: the outward normal of its plane when every neighbour lies on one plane
    /// through it (a vertex inside a flat face), else zero.
    flat_normal: Vec<Vector>,
}

impl std::fmt::Debug for TouchMesh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TouchMesh")
            .field("vertices", &self.num_vertices())
            .field("triangles", &self.num_triangles())
            .field("edges", &self.edges.len())
            .field("closed", &self.closed)
            .field("dropped_triangles", &self.dropped.len())
            .finish()
    }
}

const NONE: u32 = u32::MAX;

impl TouchMesh {
    /// Builds a touch mesh from a vertex and an index buffer (counter-clockwise triangles are
    /// conventional but not required: the reconstruction does not rely on orientation).
    ///
    /// # Errors
    /// See [`TouchMeshError`].
    pub fn new(vertices: Vec<Vector>, indices: Vec<[u32; 3]>) -> Result<Self, TouchMeshError> {
        if vertices.is_empty() || indices.is_empty() {
            return Err(TouchMeshError::Empty);
        }
        if let Some(i) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(TouchMeshError::NonFiniteVertex(i as u32));
        }
        let nv = vertices.len() as u32;
        for (t, tri) in indices.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v >= nv) {
                return Err(TouchMeshError::IndexOutOfBounds {
                    triangle: t as u32,
                    vertex: v,
                    num_vertices: nv,
                });
            }
        }

        // Drop degenerate and duplicate triangles, remembering the user's numbering.
        let extent = Aabb::from_points(vertices.iter().copied())
            .extents()
            .max_element();
        let area_eps = (extent * 1.0e-7).powi(2);
        let mut seen: HashMap<[u32; 3], ()> = HashMap::with_capacity(indices.len());
        let mut kept = Vec::with_capacity(indices.len());
        let mut tri_to_user = Vec::with_capacity(indices.len());
        let mut dropped = Vec::new();
        for (t, tri) in indices.iter().enumerate() {
            let [a, b, c] = tri.map(|i| vertices[i as usize]);
            let degenerate = tri[0] == tri[1]
                || tri[1] == tri[2]
                || tri[0] == tri[2]
                || (b - a).cross(c - a).length_squared() <= area_eps;
            let mut key = *tri;
            key.sort_unstable();
            if degenerate || seen.insert(key, ()).is_some() {
                dropped.push(t as u32);
            } else {
                kept.push(*tri);
                tri_to_user.push(t as u32);
            }
        }
        if kept.is_empty() {
            return Err(TouchMeshError::AllTrianglesDegenerate(indices.len() as u32));
        }

        let trimesh = TriMesh::with_flags(vertices, kept, TriMeshFlags::empty())
            .map_err(|e| TouchMeshError::Parry(format!("{e:?}")))?;
        Ok(Self::with_adjacency(trimesh, tri_to_user, dropped))
    }

    /// Builds a touch mesh from any parry shape that has a triangle-mesh form: `TriMesh`,
    /// `Cuboid`, `ConvexPolyhedron`, and round shapes (`Ball`, `Cylinder`, `Cone`, `Capsule`)
    /// tessellated with parry's default subdivisions.
    ///
    /// # Errors
    /// [`TouchMeshError::UnsupportedShape`] for other shapes (compounds, height fields,
    /// voxels...), plus the errors of [`TouchMesh::new`].
    pub fn from_shape(shape: &dyn Shape) -> Result<Self, TouchMeshError> {
        let (v, i) = if let Some(m) = shape.as_trimesh() {
            (m.vertices().to_vec(), m.indices().to_vec())
        } else if let Some(c) = shape.as_cuboid() {
            c.to_trimesh()
        } else if let Some(c) = shape.as_convex_polyhedron() {
            c.to_trimesh()
        } else if let Some(b) = shape.as_ball() {
            b.to_trimesh(16, 16)
        } else if let Some(c) = shape.as_cylinder() {
            c.to_trimesh(24)
        } else if let Some(c) = shape.as_cone() {
            c.to_trimesh(24)
        } else if let Some(c) = shape.as_capsule() {
            c.to_trimesh(16, 8)
        } else {
            return Err(TouchMeshError::UnsupportedShape);
        };
        Self::new(v, i)
    }

    fn with_adjacency(trimesh: TriMesh, tri_to_user: Vec<u32>, dropped: Vec<u32>) -> Self {
        let idx = trimesh.indices();
        let nv = trimesh.vertices().len();
        let mut edge_map: HashMap<[u32; 2], u32> = HashMap::with_capacity(idx.len() * 2);
        let mut edges = Vec::with_capacity(idx.len() * 3 / 2 + 1);
        let mut edge_tris: Vec<[u32; 2]> = Vec::with_capacity(edges.capacity());
        let mut edge_count: Vec<u32> = Vec::with_capacity(edges.capacity());
        let mut tri_edges = Vec::with_capacity(idx.len());
        for (t, tri) in idx.iter().enumerate() {
            let mut te = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = [a.min(b), a.max(b)];
                let e = *edge_map.entry(key).or_insert_with(|| {
                    edges.push(key);
                    edge_tris.push([NONE, NONE]);
                    edge_count.push(0);
                    (edges.len() - 1) as u32
                });
                let slot = &mut edge_tris[e as usize];
                if slot[0] == NONE {
                    slot[0] = t as u32;
                } else if slot[1] == NONE {
                    slot[1] = t as u32;
                }
                edge_count[e as usize] += 1;
                te[k] = e;
            }
            tri_edges.push(te);
        }
        let closed = edge_count.iter().all(|&c| c == 2);
        let non_manifold_edges = edge_count.iter().filter(|&&c| c > 2).count();

        // Vertex neighbours (CSR).
        let mut degree = vec![0u32; nv + 1];
        for e in &edges {
            degree[e[0] as usize + 1] += 1;
            degree[e[1] as usize + 1] += 1;
        }
        for i in 0..nv {
            degree[i + 1] += degree[i];
        }
        let neighbour_offsets = degree.clone();
        let mut fill = degree;
        let mut neighbours = vec![0u32; edges.len() * 2];
        for e in &edges {
            neighbours[fill[e[0] as usize] as usize] = e[1];
            fill[e[0] as usize] += 1;
            neighbours[fill[e[1] as usize] as usize] = e[0];
            fill[e[1] as usize] += 1;
        }

        let tri_normals = (0..idx.len() as u32)
            .map(|t| trimesh.triangle(t).normal().unwrap_or(Vector::Y))
            .collect();

        // Triangles around each vertex (CSR).
        let mut vertex_tri_offsets = vec![0u32; nv + 1];
        for tri in idx {
            for &v in tri {
                vertex_tri_offsets[v as usize + 1] += 1;
            }
        }
        for i in 0..nv {
            vertex_tri_offsets[i + 1] += vertex_tri_offsets[i];
        }
        let mut fill = vertex_tri_offsets.clone();
        let mut vertex_tris = vec![0u32; idx.len() * 3];
        for (t, tri) in idx.iter().enumerate() {
            for &v in tri {
                vertex_tris[fill[v as usize] as usize] = t as u32;
                fill[v as usize] += 1;
            }
        }

        let ext = trimesh.local_aabb().extents();
        let scale = ext.length().max(Real::MIN_POSITIVE);
        let convex = if closed {
            convex_data(
                trimesh.vertices(),
                idx,
                &edges,
                &edge_tris,
                &neighbour_offsets,
                &neighbours,
                &vertex_tri_offsets,
                &vertex_tris,
                scale,
            )
        } else {
            None
        };
        Self {
            vertex_tri_offsets,
            vertex_tris,
            convex,
            min_extent: ext.min_element(),
            scale,
            trimesh,
            tri_to_user,
            dropped,
            edges,
            edge_tris,
            tri_edges,
            neighbour_offsets,
            neighbours,
            tri_normals,
            closed,
            non_manifold_edges,
        }
    }

    /// The parry triangle mesh (degenerate triangles removed).
    pub fn trimesh(&self) -> &TriMesh {
        &self.trimesh
    }
    /// The BVH over the triangles (parry's own).
    pub fn bvh(&self) -> &Bvh {
        self.trimesh.bvh()
    }
    /// The vertex buffer (the user's, unchanged).
    pub fn vertices(&self) -> &[Vector] {
        self.trimesh.vertices()
    }
    /// The kept triangles, in internal order (see [`TouchMesh::user_triangle`]).
    pub fn indices(&self) -> &[[u32; 3]] {
        self.trimesh.indices()
    }
    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.trimesh.vertices().len()
    }
    /// Number of kept triangles.
    pub fn num_triangles(&self) -> usize {
        self.trimesh.indices().len()
    }
    /// Number of unique edges.
    pub fn num_edges(&self) -> usize {
        self.edges.len()
    }
    /// The unique edges, as vertex pairs (smallest index first).
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }
    /// The (up to two) internal triangles on edge `e`; `u32::MAX` marks a missing one.
    pub fn edge_triangles(&self, e: u32) -> [u32; 2] {
        self.edge_tris[e as usize]
    }
    /// The three edges of internal triangle `t`, in the order (a,b), (b,c), (c,a).
    pub fn triangle_edges(&self, t: u32) -> [u32; 3] {
        self.tri_edges[t as usize]
    }
    /// The vertices joined to `v` by an edge.
    pub fn vertex_neighbours(&self, v: u32) -> &[u32] {
        let (a, b) = (
            self.neighbour_offsets[v as usize] as usize,
            self.neighbour_offsets[v as usize + 1] as usize,
        );
        &self.neighbours[a..b]
    }
    /// `true` if `a == b` or an edge joins them.
    pub fn vertices_adjacent(&self, a: u32, b: u32) -> bool {
        a == b || self.vertex_neighbours(a).contains(&b)
    }
    /// Index in the user's index buffer of internal triangle `t`.
    pub fn user_triangle(&self, t: u32) -> u32 {
        self.tri_to_user[t as usize]
    }
    /// The user's triangles that were dropped as degenerate (zero area) or duplicated.
    pub fn dropped_triangles(&self) -> &[u32] {
        &self.dropped
    }
    /// Unit normal of internal triangle `t` (counter-clockwise winding), in the mesh frame.
    pub fn triangle_normal(&self, t: u32) -> Vector {
        self.tri_normals[t as usize]
    }
    /// The triangles (internal numbering) that have vertex `v`.
    pub fn vertex_triangles(&self, v: u32) -> &[u32] {
        let (a, b) = (
            self.vertex_tri_offsets[v as usize] as usize,
            self.vertex_tri_offsets[v as usize + 1] as usize,
        );
        &self.vertex_tris[a..b]
    }

    /// `true` if the mesh bounds a convex solid: closed, edge-manifold, connected, consistently
    /// oriented, and locally convex at every vertex (each neighbour lies on or below the plane
    /// of every triangle around the vertex, to `1e-6` of [`TouchMesh::scale`]). A closed
    /// surface that is locally convex everywhere bounds a convex set (Tietze-Nakajima), so the
    /// check is exact up to that tolerance; a self-intersecting mesh can fool it.
    ///
    /// Convex pairs take a faster path in [`Reconstructor`](super::Reconstructor): parry's GJK
    /// ray cast on the Minkowski difference finds the first touch, with support points found
    /// by hill climbing over the vertex graph.
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

    /// `true` if every edge has exactly two triangles (a closed, edge-manifold surface).
    pub fn is_closed(&self) -> bool {
        self.closed
    }
    /// Number of edges shared by more than two triangles.
    pub fn non_manifold_edges(&self) -> usize {
        self.non_manifold_edges
    }
    /// The mesh's local bounding box.
    pub fn local_aabb(&self) -> Aabb {
        self.trimesh.local_aabb()
    }
    /// The smallest edge of the local bounding box: the paper's safe step length for this
    /// object (a step shorter than it cannot carry the object through another, section 2).
    ///
    /// It is zero for a flat mesh (a floor of zero thickness): the reconstruction still sees
    /// every touch along the whole trajectory, so use [`crate::geometry::safe_step_length`] only
    /// to split steps of solid objects.
    pub fn min_extent(&self) -> Real {
        self.min_extent
    }
    /// The length of the bounding-box diagonal, used to scale tolerances.
    pub fn scale(&self) -> Real {
        self.scale
    }
}

/// Convexity check and support directory of a closed mesh (see [`TouchMesh::is_convex`]).
#[allow(clippy::too_many_arguments)]
fn convex_data(
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

/// The paper's safe step length for a pair (section 2, case c): a translation shorter than the
/// smallest bounding-box edge of both objects cannot carry one through the other.
///
/// Zero when one of the meshes is flat; see [`TouchMesh::min_extent`].
pub fn safe_step_length(a: &TouchMesh, b: &TouchMesh) -> Real {
    a.min_extent().min(b.min_extent())
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
}
