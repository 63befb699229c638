//! [`TouchMesh`]: a parry [`TriMesh`] plus the adjacency the reconstruction needs, built once.

mod convex;
mod weld;

use crate::math::{Real, Vector};
use convex::{convex_data, ConvexData};
use parry3d::bounding_volume::Aabb;
use parry3d::partitioning::Bvh;
use parry3d::shape::{ShapeType, TriMesh, TriMeshFlags};
use parry3d::utils::hashmap::HashMap;
use weld::WELD_RELATIVE_TOLERANCE;

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
    /// This parry shape has no finite triangle surface ([`TouchMesh::from_shape`] lists the
    /// shapes that have one). `reason` says why and what to use instead.
    #[error("a {shape:?} has no finite triangle surface: {reason}")]
    UnsupportedShape {
        /// The shape's type.
        shape: ShapeType,
        /// Why it has no surface, and what to give instead.
        reason: &'static str,
    },
    /// Part `part` of a compound shape has no finite triangle surface (as for
    /// [`TouchMeshError::UnsupportedShape`]), so the compound has none either.
    #[error("part {part} of the compound is a {shape:?}, which has no finite triangle surface: {reason}")]
    UnsupportedCompoundPart {
        /// The part's index in `Compound::shapes`.
        part: u32,
        /// The part's shape type.
        shape: ShapeType,
        /// Why it has no surface, and what to give instead.
        reason: &'static str,
    },
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
    /// A vertex, by index into the vertex buffer (of copies welded together, the lowest index;
    /// see [`TouchMesh::new`]).
    Vertex(u32),
    /// An edge, by its two vertex indices (smallest first, welded as for `Vertex`).
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
/// - Duplicated vertices are welded: a triangle soup (every triangle with its own copies of its
///   vertices, as modelling tools export it) becomes one connected surface, so a face contact
///   is one patch, not one fragment per triangle. Vertices closer than `1e-6 ×` the
///   bounding-box diagonal are one; the triangles are renumbered to the lowest user index of
///   each group, the vertex buffer stays the user's ([`TouchMesh::welded_vertices`],
///   [`TouchMesh::welded_to`]).
/// - Degenerate triangles (zero area: height over the longest edge below `1e-7 ×` the largest
///   bounding-box extent) and duplicated triangles (after welding) are dropped; their original
///   indices are listed by [`TouchMesh::dropped_triangles`] so nothing is lost silently.
/// - Open and non-manifold meshes are accepted and treated as *shells* (a thin TriMesh floor is
///   an open mesh): every touch between surfaces is found, but "one object is entirely inside
///   the other" can only be detected when the outer one is closed ([`TouchMesh::is_closed`]):
///   an open mover (even one triangle) wholly inside a closed mesh penetrates it, and one that
///   crosses a closed mesh within a step is [`Perforated`](super::TouchState::Perforated).
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
    /// The vertices on the convex hull of the vertices, found on first use
    /// ([`TouchMesh::hull_vertices`]).
    hull: std::sync::OnceLock<Vec<u32>>,
    /// Per user vertex, the vertex that stands for it in the triangles (empty: none welded).
    weld: Vec<u32>,
    welded: usize,
}

impl std::fmt::Debug for TouchMesh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TouchMesh")
            .field("vertices", &self.num_vertices())
            .field("triangles", &self.num_triangles())
            .field("edges", &self.edges.len())
            .field("closed", &self.closed)
            .field("dropped_triangles", &self.dropped.len())
            .field("welded_vertices", &self.welded)
            .finish()
    }
}

const NONE: u32 = u32::MAX;

impl TouchMesh {
    /// Builds a touch mesh from a vertex and an index buffer (counter-clockwise triangles are
    /// conventional but not required: the reconstruction does not rely on orientation).
    ///
    /// # Welding
    /// Vertices used by the triangles that lie within `1e-6 ×` the diagonal of their bounding
    /// box of each other are welded into one: each triangle is renumbered to the lowest user
    /// index of the group (a grid hash, linear time). The vertex buffer is kept as given, so
    /// [`Feature::Vertex`] and [`Feature::Edge`] still name the user's vertices, always the
    /// group's lowest index; the other copies are used by no triangle. Triangles that welding
    /// makes degenerate or duplicate are dropped like any other
    /// ([`TouchMesh::dropped_triangles`]).
    ///
    /// ```
    /// use rapier_touch::prelude::*;
    /// // A unit square as a soup: two triangles, each with its own three vertices.
    /// let v = [[0., 0.], [1., 0.], [1., 1.], [0., 0.], [1., 1.], [0., 1.]]
    ///     .map(|[x, z]| Vector::new(x, 0.0, z))
    ///     .to_vec();
    /// let m = TouchMesh::new(v, vec![[0, 2, 1], [3, 5, 4]]).unwrap();
    /// assert_eq!(m.welded_vertices(), 2); // 3 -> 0 and 4 -> 2
    /// assert_eq!(m.indices()[1], [0, 5, 2]);
    /// assert_eq!(m.num_edges(), 5); // the diagonal is shared
    /// ```
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

        // Weld the vertices the triangles use.
        let mut used = vec![false; vertices.len()];
        for &v in indices.iter().flatten() {
            used[v as usize] = true;
        }
        let used_box = Aabb::from_points(
            (0..vertices.len())
                .filter(|&v| used[v])
                .map(|v| vertices[v]),
        );
        let weld_tol = WELD_RELATIVE_TOLERANCE * used_box.extents().length();
        let mut weld = weld::weld_map(&vertices, &used, weld_tol);
        let welded = weld
            .iter()
            .enumerate()
            .filter(|&(v, &r)| r != v as u32)
            .count();
        let indices: Vec<[u32; 3]> = if welded == 0 {
            weld = Vec::new();
            indices
        } else {
            indices
                .iter()
                .map(|t| t.map(|v| weld[v as usize]))
                .collect()
        };

        // Drop degenerate and duplicate triangles, remembering the user's numbering.
        let extent = Aabb::from_points(vertices.iter().copied())
            .extents()
            .max_element();
        // Flat: the height over the longest edge is below `1e-7 ×` the extent (in `f64`, so
        // the test is the same at every scale).
        let flat = 1.0e-7 * extent as f64;
        let mut seen: HashMap<[u32; 3], ()> =
            HashMap::with_capacity_and_hasher(indices.len(), Default::default());
        let mut kept = Vec::with_capacity(indices.len());
        let mut tri_to_user = Vec::with_capacity(indices.len());
        let mut dropped = Vec::new();
        for (t, tri) in indices.iter().enumerate() {
            let [a, b, c] = tri.map(|i| vertices[i as usize].as_dvec3());
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            let degenerate = tri[0] == tri[1]
                || tri[1] == tri[2]
                || tri[0] == tri[2]
                || (b - a).cross(c - a).length() <= flat * longest;
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
        let mut mesh = Self::with_adjacency(trimesh, tri_to_user, dropped);
        mesh.weld = weld;
        mesh.welded = welded;
        Ok(mesh)
    }

    fn with_adjacency(trimesh: TriMesh, tri_to_user: Vec<u32>, dropped: Vec<u32>) -> Self {
        let idx = trimesh.indices();
        let nv = trimesh.vertices().len();
        let mut edge_map: HashMap<[u32; 2], u32> =
            HashMap::with_capacity_and_hasher(idx.len() * 2, Default::default());
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
            hull: std::sync::OnceLock::new(),
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
            weld: Vec::new(),
            welded: 0,
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
    /// The kept triangles, in internal order (see [`TouchMesh::user_triangle`]), with welded
    /// vertices renumbered (see [`TouchMesh::new`]).
    pub fn indices(&self) -> &[[u32; 3]] {
        self.trimesh.indices()
    }
    /// Number of vertices in the user's buffer (welded copies and vertices no triangle uses
    /// included).
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
    /// How many vertices were welded into a lower-numbered copy (see [`TouchMesh::new`]): the
    /// number of vertices the triangles no longer use because another stands for them.
    pub fn welded_vertices(&self) -> usize {
        self.welded
    }
    /// The vertex that stands for user vertex `v` in the triangles: `v` itself, or the lowest
    /// index of the copies it was welded with (see [`TouchMesh::new`]).
    pub fn welded_to(&self, v: u32) -> u32 {
        self.weld.get(v as usize).copied().unwrap_or(v)
    }
    /// Unit normal of internal triangle `t` (counter-clockwise winding), in the mesh frame.
    pub fn triangle_normal(&self, t: u32) -> Vector {
        self.tri_normals[t as usize]
    }
    /// Which sides of internal triangle `t` (in [`TouchMesh::triangle_edges`]' order) the
    /// mesh continues across in the same plane: the other triangle on that edge has the same
    /// normal to within `1e-6` of its cosine (1.4 mrad).
    pub(crate) fn flat_sides(&self, t: u32) -> [bool; 3] {
        self.triangle_edges(t).map(|e| {
            self.edge_triangles(e).iter().any(|&o| {
                o != t
                    && o != u32::MAX
                    && self.tri_normals[o as usize].dot(self.tri_normals[t as usize])
                        >= 1.0 - 1.0e-6
            })
        })
    }
    /// The triangles (internal numbering) that have vertex `v`.
    pub fn vertex_triangles(&self, v: u32) -> &[u32] {
        let (a, b) = (
            self.vertex_tri_offsets[v as usize] as usize,
            self.vertex_tri_offsets[v as usize + 1] as usize,
        );
        &self.vertex_tris[a..b]
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
/// The paper's safe step length for a pair (section 2, case c): a translation shorter than the
/// smallest bounding-box edge of both objects cannot carry one through the other.
///
/// Zero when one of the meshes is flat; see [`TouchMesh::min_extent`].
///
/// # Example
/// A 20 cm cube crossing a 10 cm slab: one 40 cm step goes through it, steps shorter than the
/// safe length end inside it first.
/// ```
/// use rapier_touch::prelude::*;
/// let slab = TouchMesh::from_shape(&Cuboid::new(Vector::new(1.0, 0.05, 1.0))).unwrap();
/// let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.1))).unwrap();
/// let step = safe_step_length(&slab, &cube);
/// assert!((step - 0.1).abs() < 1e-6); // the slab's thickness
///
/// let at = |y: f32| Pose::from_translation(Vector::new(0.0, y, 0.0));
/// let mut rec = Reconstructor::default();
/// let c = rec.reconstruct(&slab, &Pose::IDENTITY, &cube, &at(-0.2), &at(0.2)).unwrap();
/// assert_eq!(c.state, TouchState::Perforated);
///
/// let first_meeting = (0..10)
///     .map(|i| {
///         let (from, to) = (0.2 - i as f32 * 0.9 * step, 0.2 - (i + 1) as f32 * 0.9 * step);
///         rec.reconstruct(&slab, &Pose::IDENTITY, &cube, &at(to), &at(from)).unwrap().state
///     })
///     .find(|&s| s != TouchState::Separated);
/// assert_eq!(first_meeting, Some(TouchState::Penetrating));
/// ```
pub fn safe_step_length(a: &TouchMesh, b: &TouchMesh) -> Real {
    a.min_extent().min(b.min_extent())
}
