//! Surface meshes for the soft-surface model: planar constrained Delaunay meshes, regular
//! plates, closed boxes and spheres, and Wavefront OBJ import.
//!
//! - [`triangulate_planar`]: a [`PlanarOutline`] (outer polygon, holes, internal constraint
//!   polylines) meshed by constrained Delaunay refinement ([`spade`]) to a target edge length.
//!   The 2D point `(u, v)` becomes the 3D point `(u, 0, v)`: a horizontal plate, `y` up.
//! - [`plate`], [`box_surface`], [`sphere_surface`]: regular meshes, no error cases.
//! - [`load_obj`] / [`parse_obj`]: a triangle mesh from an OBJ file or string; [`load_glb`] /
//!   [`parse_glb`]: from a binary glTF asset (the meshes its scene places).
//! - [`paper_plate_outline`], [`paper_organ_outline`]: outlines the size of the paper's Fig. 6
//!   plate (about 517 nodes) and Fig. 7 organ with a constrained internal boundary (about 790
//!   nodes).
//!
//! Every [`SurfaceMesh`] made here is compact (no unused vertex). Planar meshes and plates are
//! wound counter-clockwise seen from `+y`; boxes and spheres counter-clockwise seen from
//! outside.

use crate::geometry::generators;
use crate::math::{Real, Vector};
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters};
use spade::{InsertionError, Triangulation};
use std::collections::{HashMap, HashSet};
use std::fmt;
use std::io::BufRead;
use std::path::{Path, PathBuf};

pub use super::gltf_mesh::{load_glb, parse_glb};
pub use obj::{load_obj, parse_obj};
pub use planar::triangulate_planar;

pub(super) use obj::compacted;

mod obj;
mod planar;

/// Grid subdivisions are clamped to this, so vertex indices always fit in `u32`.
const MAX_GRID_CELLS: u32 = 1 << 14;

/// A triangle mesh: vertex positions and counter-clockwise index triples.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SurfaceMesh {
    /// Vertex positions.
    pub vertices: Vec<Vector>,
    /// Triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

impl SurfaceMesh {
    /// The number of vertices (the model's nodes).
    pub fn num_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// The number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The total area of the triangles, in f64 then rounded. Triangles with an index out of
    /// range count as zero.
    pub fn area(&self) -> Real {
        let vertex = |i: u32| self.vertices.get(i as usize).map(|v| v.as_dvec3());
        self.triangles
            .iter()
            .filter_map(|&[a, b, c]| {
                let (a, b, c) = (vertex(a)?, vertex(b)?, vertex(c)?);
                Some(0.5 * (b - a).cross(c - a).length())
            })
            .sum::<f64>() as Real
    }
}

/// Which part of a [`PlanarOutline`] an error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutlinePart {
    /// [`PlanarOutline::outer`].
    Outer,
    /// `PlanarOutline::holes[i]`.
    Hole(usize),
    /// `PlanarOutline::constraints[i]`.
    Constraint(usize),
}

impl fmt::Display for OutlinePart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OutlinePart::Outer => write!(f, "outer boundary"),
            OutlinePart::Hole(i) => write!(f, "hole {i}"),
            OutlinePart::Constraint(i) => write!(f, "constraint polyline {i}"),
        }
    }
}

/// Why a mesh could not be made or loaded.
#[derive(Debug, thiserror::Error)]
pub enum MeshingError {
    /// A polygon has fewer than three distinct points, or a constraint polyline has none.
    /// Give the outer boundary and every hole at least three distinct points (without
    /// repeating the first one at the end), and every constraint polyline at least one point.
    #[error("{part} has {distinct} distinct point(s): polygons need 3, polylines 1")]
    TooFewPoints {
        /// The polygon or polyline.
        part: OutlinePart,
        /// Its number of distinct points.
        distinct: usize,
    },
    /// A coordinate is NaN or infinite. Give finite coordinates.
    #[error("point {index} of the {part} is not finite")]
    NonFinitePoint {
        /// The polygon or polyline.
        part: OutlinePart,
        /// The point's index in it.
        index: usize,
    },
    /// The target edge length is zero, negative or not finite. Give a positive length in the
    /// outline's units, e.g. a tenth of its width.
    #[error("target edge length {0} is not a positive finite number")]
    InvalidTargetEdge(Real),
    /// The mesh would have more vertices than this module makes. Give a larger target edge
    /// length, or a smaller outline.
    #[error("about {estimated} vertices needed, more than the {max} allowed")]
    TooManyVertices {
        /// The estimated (planar meshing) or actual (OBJ) vertex count.
        estimated: u64,
        /// The largest count allowed.
        max: u64,
    },
    /// spade refused a point: a coordinate must be 0 or at least [`spade::MIN_ALLOWED_VALUE`]
    /// (about 1.8e-43, so `f32` subnormals fail) in magnitude. Snap tiny coordinates to 0 or
    /// rescale the outline.
    #[error("point {index} of the {part} could not be inserted: {source}")]
    Insertion {
        /// The polygon or polyline.
        part: OutlinePart,
        /// The point's index in it.
        index: usize,
        /// spade's reason.
        source: InsertionError,
    },
    /// A segment crosses an earlier segment: the outer boundary or a hole intersects itself,
    /// two polygons cross, or a constraint polyline crosses a boundary or another constraint.
    /// Touching at a shared point and overlapping along a line are allowed; crossing is not.
    /// Split crossing polylines at their crossing point, or fix the polygon.
    #[error("segment {segment} of the {part} crosses an earlier segment")]
    Intersecting {
        /// The polygon or polyline whose segment crosses.
        part: OutlinePart,
        /// The segment's index (from point `segment` to point `segment + 1`, closing for
        /// polygons).
        segment: usize,
    },
    /// Part of a constraint polyline lies outside the meshed region (outside the outer
    /// boundary or inside a hole). Keep constraint polylines inside the outer boundary and out
    /// of the holes; touching the boundary is fine.
    #[error("constraint polyline {constraint} leaves the meshed region")]
    ConstraintOutsideDomain {
        /// The constraint polyline's index.
        constraint: usize,
    },
    /// The split constraint edges of a polyline could not be followed after refinement (a
    /// bug; please report it with the outline). Moving the polyline's points slightly
    /// usually avoids it.
    #[error("constraint polyline {constraint} could not be traced in the refined mesh")]
    ConstraintNotRecovered {
        /// The constraint polyline's index.
        constraint: usize,
    },
    /// No triangle is left: the outer polygon has zero area or the holes cover it all. Give
    /// an outer polygon with area, or an OBJ file with faces.
    #[error("the mesh has no triangle")]
    EmptyMesh,
    /// The OBJ file could not be opened or read. Check the path and permissions.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The `.glb` could not be parsed or failed glTF's validation (gltf's reason says why).
    #[error("invalid glTF: {0}")]
    Gltf(#[source] gltf::Error),
    /// A glTF mesh reads a buffer that is not the `.glb` file's own binary chunk (an external
    /// file or a data URI): pack the asset as a single `.glb`.
    #[error("glTF buffer {buffer} is not the .glb's binary chunk (external or data URI)")]
    GltfExternalBuffer {
        /// The buffer's index.
        buffer: usize,
    },
    /// A glTF primitive's index points past its vertices.
    #[error("glTF mesh {mesh}, primitive {primitive} has an index past its vertices")]
    GltfIndexOutOfRange {
        /// The mesh's index.
        mesh: usize,
        /// The primitive's index in the mesh.
        primitive: usize,
    },
    /// A triangle primitive of a glTF mesh has no positions.
    #[error("glTF mesh {mesh}, primitive {primitive} has no POSITION attribute")]
    GltfNoPositions {
        /// The mesh's index.
        mesh: usize,
        /// The primitive's index in the mesh.
        primitive: usize,
    },
    /// The OBJ text could not be parsed. Fix the OBJ text (tobj's reason says which element).
    #[error("invalid OBJ: {0}")]
    Obj(#[source] tobj::LoadError),
    /// A vertex position is NaN or infinite (OBJ: fix the `v` line; glTF: the POSITION data).
    #[error("vertex {vertex} (in file order, over all objects) is not finite")]
    NonFinitePosition {
        /// The vertex's index in the merged mesh, before compaction.
        vertex: usize,
    },
}

/// A planar region to mesh, in 2D coordinates `(u, v)` (mapped to `(u, 0, v)` in 3D).
///
/// Polygons are closed implicitly: do not repeat the first point at the end (a repeated point
/// is ignored). Either orientation is accepted. A point is meshed if it is inside `outer` and
/// inside none of the `holes`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlanarOutline {
    /// The outer boundary polygon.
    pub outer: Vec<[Real; 2]>,
    /// Hole polygons, each inside `outer`.
    pub holes: Vec<Vec<[Real; 2]>>,
    /// Open polylines inside the region that the mesh must contain as edges (internal
    /// boundaries, seams, lines of pinned nodes). A single point forces a mesh vertex there.
    pub constraints: Vec<Vec<[Real; 2]>>,
}

/// The result of [`triangulate_planar`].
#[derive(Debug, Clone, PartialEq)]
pub struct PlanarMesh {
    /// The mesh in the plane `y = 0`: `(u, v)` becomes `(u, 0, v)`, triangles counter-clockwise
    /// seen from `+y`.
    pub mesh: SurfaceMesh,
    /// Every vertex on the outer boundary or a hole boundary (an edge used by one triangle
    /// only), in increasing order.
    pub boundary: Vec<u32>,
    /// For each constraint polyline, the mesh vertices lying on it, in order from its first
    /// point to its last, including the points refinement added on it. Every consecutive pair
    /// is an edge of the mesh.
    pub constrained: Vec<Vec<u32>>,
    /// `false` if spade ran out of its budget of added vertices before every triangle met
    /// the size and angle limits (tiny input angles can cause this). The mesh is valid but
    /// may be coarser or less regular than asked in places.
    pub refinement_complete: bool,
}

/// The smallest angle refinement aims for, in degrees. Below spade's 30° default, so that
/// refinement stays well-behaved next to sharp input corners.
const MIN_ANGLE_DEG: f64 = 25.0;
/// The largest vertex count [`triangulate_planar`] will aim for.
const MAX_PLANAR_VERTICES: u64 = 4_000_000;

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// A regular `nx × nz` grid plate in the plane `y = 0`, centred on the origin:
/// `size_x × size_z`, `(nx + 1)(nz + 1)` vertices, `2 nx nz` triangles counter-clockwise seen
/// from `+y`.
///
/// Vertex `i + j (nx + 1)` is at `x = -size_x/2 + i size_x/nx`, `z = -size_z/2 + j size_z/nz`.
/// Each cell is split along alternating diagonals (a checkerboard), so the springs have no
/// preferred diagonal direction. `nx` and `nz` are clamped to `1..=16384`; negative sizes
/// are used as their absolute value.
///
/// ```
/// let p = rapier_touch::surface::meshing::plate(2.0, 1.0, 4, 2);
/// assert_eq!((p.num_vertices(), p.num_triangles()), (15, 16));
/// assert!((p.area() - 2.0).abs() < 1e-6);
/// ```
pub fn plate(size_x: Real, size_z: Real, nx: u32, nz: u32) -> SurfaceMesh {
    let (nx, nz) = (nx.clamp(1, MAX_GRID_CELLS), nz.clamp(1, MAX_GRID_CELLS));
    let (sx, sz) = (size_x.abs(), size_z.abs());
    let mut vertices = Vec::with_capacity(((nx + 1) * (nz + 1)) as usize);
    for j in 0..=nz {
        for i in 0..=nx {
            vertices.push(Vector::new(
                -0.5 * sx + sx * i as Real / nx as Real,
                0.0,
                -0.5 * sz + sz * j as Real / nz as Real,
            ));
        }
    }
    let id = |i: u32, j: u32| i + j * (nx + 1);
    let mut triangles = Vec::with_capacity((2 * nx * nz) as usize);
    for j in 0..nz {
        for i in 0..nx {
            let (p00, p10, p11, p01) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            // Counter-clockwise from +y is (x, z) -> clockwise in the (x, z) plane.
            if (i + j) % 2 == 0 {
                triangles.push([p00, p11, p10]);
                triangles.push([p00, p01, p11]);
            } else {
                triangles.push([p00, p01, p10]);
                triangles.push([p10, p01, p11]);
            }
        }
    }
    SurfaceMesh {
        vertices,
        triangles,
    }
}

/// The vertices on the outer rim of a [`plate`] of `nx × nz` cells (clamped as [`plate`] clamps
/// them), in increasing order: the ones to pin for a plate clamped on its edges.
///
/// ```
/// use rapier_touch::surface::meshing::{plate, plate_rim};
/// let rim = plate_rim(4, 2);
/// assert_eq!(rim, [0, 1, 2, 3, 4, 5, 9, 10, 11, 12, 13, 14]);
/// let p = plate(2.0, 1.0, 4, 2);
/// assert!(rim.iter().all(|&i| {
///     let v = p.vertices[i as usize];
///     v.x.abs() == 1.0 || v.z.abs() == 0.5
/// }));
/// ```
pub fn plate_rim(nx: u32, nz: u32) -> Vec<u32> {
    let (nx, nz) = (nx.clamp(1, MAX_GRID_CELLS), nz.clamp(1, MAX_GRID_CELLS));
    (0..=nz)
        .flat_map(|j| {
            (0..=nx)
                .filter(move |&i| i == 0 || i == nx || j == 0 || j == nz)
                .map(move |i| i + j * (nx + 1))
        })
        .collect()
}

/// Box faces are clamped to `n ≤ 1024` (12.6 million triangles).
const MAX_BOX_CELLS: u32 = 1024;
/// Spheres are clamped to 10 subdivisions (21 million triangles).
const MAX_SPHERE_SUBDIVISIONS: u32 = 10;

/// The closed surface of a box of half extents `half`, centred on the origin, each face split
/// into `n × n` quads ([`generators::subdivided_box`]): `6 n² + 2` vertices, `12 n²`
/// triangles, counter-clockwise seen from outside. `n` is clamped to `1..=1024`.
///
/// ```
/// let b = rapier_touch::surface::meshing::box_surface(rapier_touch::math::Vector::ONE, 2);
/// assert_eq!((b.num_vertices(), b.num_triangles()), (26, 48));
/// ```
pub fn box_surface(half: Vector, n: u32) -> SurfaceMesh {
    let (vertices, triangles) = generators::subdivided_box(half, n.clamp(1, MAX_BOX_CELLS));
    SurfaceMesh {
        vertices,
        triangles,
    }
}

/// The closed surface of a sphere of the given radius centred on the origin, an icosphere
/// ([`generators::icosphere`]): `10 · 4^s + 2` vertices and `20 · 4^s` triangles for
/// `s = subdivisions`, counter-clockwise seen from outside. `subdivisions` is clamped to 10.
///
/// ```
/// let s = rapier_touch::surface::meshing::sphere_surface(0.5, 2);
/// assert_eq!((s.num_vertices(), s.num_triangles()), (162, 320));
/// ```
pub fn sphere_surface(radius: Real, subdivisions: u32) -> SurfaceMesh {
    let (vertices, triangles) =
        generators::icosphere(radius, subdivisions.min(MAX_SPHERE_SUBDIVISIONS));
    SurfaceMesh {
        vertices,
        triangles,
    }
}

/// Target edge length for [`paper_plate_outline`] (14.7 mm): meshes it to 519 nodes with
/// spade 2.15.1, the paper's Fig. 6 plate has 517.
pub const PAPER_PLATE_TARGET_EDGE: Real = 0.0147;

/// A thin plate outline the size of the paper's Fig. 6 plate: a 0.3 m × 0.2 m rectangle
/// centred on the origin with a rounded notch (a half disc of radius 4 cm) cut into the middle
/// of its `v = +0.1` edge (a 12-segment arc). Meshed with [`PAPER_PLATE_TARGET_EDGE`] it has
/// 519 nodes with spade 2.15.1 (the paper's plate has 517; other spade releases may refine
/// slightly differently).
///
/// ```
/// use rapier_touch::surface::meshing::*;
/// let planar = triangulate_planar(&paper_plate_outline(), PAPER_PLATE_TARGET_EDGE).unwrap();
/// assert!((planar.mesh.num_vertices() as i64 - 517).abs() <= 40);
/// ```
pub fn paper_plate_outline() -> PlanarOutline {
    let (hx, hz, r): (f64, f64, f64) = (0.15, 0.1, 0.04);
    let p = |u: f64, v: f64| [u as Real, v as Real];
    let mut outer = vec![p(-hx, -hz), p(hx, -hz), p(hx, hz)];
    let arc = 12;
    for k in 0..=arc {
        // From angle 0 to -π: down and around the notch's bottom.
        let a = -std::f64::consts::PI * k as f64 / arc as f64;
        outer.push(p(r * a.cos(), hz + r * a.sin()));
    }
    outer.push(p(-hx, hz));
    PlanarOutline {
        outer,
        ..Default::default()
    }
}

/// An organ-like outline the size of the paper's Fig. 7 example, with one constrained
/// internal boundary, and the target edge length that meshes it to about 790 nodes (the
/// paper's count): 5.28 mm, giving 788 nodes with spade 2.15.1 (other spade releases may
/// refine slightly differently).
///
/// The outline is a kidney shape about 0.16 m × 0.10 m centred on the origin (a 64-gon),
/// indented on its `u < 0` side; the constraint is an open polyline through its interior (a vessel or an
/// internal boundary) whose mesh vertices [`PlanarMesh::constrained`] returns.
///
/// ```
/// use rapier_touch::surface::meshing::*;
/// let (outline, h) = paper_organ_outline();
/// let planar = triangulate_planar(&outline, h).unwrap();
/// assert!((planar.mesh.num_vertices() as i64 - 790).abs() <= 50);
/// assert_eq!(planar.constrained.len(), 1);
/// ```
pub fn paper_organ_outline() -> (PlanarOutline, Real) {
    let n = 64;
    let outer = (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            // An ellipse pushed in around t = π (the hilum).
            let dent = 0.35 * (-(t - std::f64::consts::PI).powi(2) / 0.3).exp();
            let r = 1.0 - dent;
            [(0.08 * r * t.cos()) as Real, (0.05 * r * t.sin()) as Real]
        })
        .collect();
    let constraint = vec![
        [-0.045, -0.012],
        [-0.02, 0.004],
        [0.005, 0.008],
        [0.03, 0.002],
        [0.055, -0.014],
    ];
    (
        PlanarOutline {
            outer,
            holes: Vec::new(),
            constraints: vec![constraint],
        },
        0.00528,
    )
}

#[cfg(test)]
mod tests;
