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

/// Meshes a planar region by constrained Delaunay refinement so that edges are about
/// `target_edge` long (shorter near small features).
///
/// Triangles are refined until their area is at most that of an equilateral triangle of side
/// `target_edge` (`√3/4 · target_edge²`) and their smallest angle is at least 25° (spade's
/// Ruppert/Chew refinement), so edges come out between about `0.5 · target_edge` and
/// `1.4 · target_edge`, median `0.8 · target_edge`; a unit square with `target_edge = 0.1` has
/// 183 vertices. Boundary and constraint segments are split as needed, never crossed. The
/// outline's points come first in the vertex list, in the order given (outer, holes,
/// constraints; a repeated point once), then the points refinement added.
///
/// With constraint polylines, spade cannot tell the outside from the inside while refining
/// (see the source), so the outside is refined too, inside a frame, and thrown away: the
/// boundary then comes out somewhat finer (about 1.4× as many boundary vertices).
///
/// Output: 2D `(u, v)` becomes 3D `(u, 0, v)` (a horizontal plate, `y` up as rapier's
/// default gravity expects), triangles counter-clockwise seen from `+y`, no unused vertex.
///
/// ```
/// use rapier_touch::surface::meshing::{triangulate_planar, PlanarOutline};
///
/// let square = PlanarOutline {
///     outer: vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
///     ..Default::default()
/// };
/// let planar = triangulate_planar(&square, 0.25).unwrap();
/// assert!((planar.mesh.area() - 1.0).abs() < 1e-5);
/// assert!(planar.mesh.vertices.iter().all(|v| v.y == 0.0));
/// ```
///
/// # Errors
/// See [`MeshingError`]: too few points, non-finite points or target edge, crossing segments,
/// constraints outside the region, an empty result, or a target edge so small that more than
/// four million vertices would be needed.
pub fn triangulate_planar(
    outline: &PlanarOutline,
    target_edge: Real,
) -> Result<PlanarMesh, MeshingError> {
    if !(target_edge.is_finite() && target_edge > 0.0) {
        return Err(MeshingError::InvalidTargetEdge(target_edge));
    }
    let h = target_edge as f64;

    // Validate and convert every part before touching spade.
    let mut parts: Vec<(OutlinePart, Vec<[f64; 2]>, bool)> =
        Vec::with_capacity(1 + outline.holes.len() + outline.constraints.len());
    parts.push((
        OutlinePart::Outer,
        to_f64(&outline.outer, OutlinePart::Outer)?,
        true,
    ));
    for (i, hole) in outline.holes.iter().enumerate() {
        let part = OutlinePart::Hole(i);
        parts.push((part, to_f64(hole, part)?, true));
    }
    for (i, line) in outline.constraints.iter().enumerate() {
        let part = OutlinePart::Constraint(i);
        parts.push((part, to_f64(line, part)?, false));
    }
    for (part, points, closed) in &parts {
        let distinct = count_distinct(points);
        if distinct < if *closed { 3 } else { 1 } {
            return Err(MeshingError::TooFewPoints {
                part: *part,
                distinct,
            });
        }
    }

    // Bound the refinement: an equilateral lattice of edge h has 2/(√3 h²) vertices per unit
    // area; the bounding box (which holds the convex hull) sets the scale.
    let (lo, hi) = parts.iter().flat_map(|(_, p, _)| p.iter()).fold(
        ([f64::MAX; 2], [f64::MIN; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    let box_area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    let perimeter: f64 = parts
        .iter()
        .map(|(_, p, closed)| polyline_length(p, *closed))
        .sum();
    let input_points: usize = parts.iter().map(|(_, p, _)| p.len()).sum();
    let estimated = 2.0 * box_area / (3f64.sqrt() * h * h) + perimeter / h + input_points as f64;
    if estimated.is_nan() || estimated > MAX_PLANAR_VERTICES as f64 {
        return Err(MeshingError::TooManyVertices {
            estimated: estimated.min(u64::MAX as f64) as u64,
            max: MAX_PLANAR_VERTICES,
        });
    }

    // Insert every point first, then the constraint segments one by one, refusing any that
    // would cross an earlier one (spade's `add_constraint` panics on crossings).
    let mut cdt = Cdt::new();
    let mut handles: Vec<Vec<FixedVertexHandle>> = Vec::with_capacity(parts.len());
    for (part, points, _) in &parts {
        let mut hs = Vec::with_capacity(points.len());
        for (index, p) in points.iter().enumerate() {
            let handle =
                cdt.insert(Point2::new(p[0], p[1]))
                    .map_err(|source| MeshingError::Insertion {
                        part: *part,
                        index,
                        source,
                    })?;
            hs.push(handle);
        }
        handles.push(hs);
    }
    for ((part, _, closed), hs) in parts.iter().zip(&handles) {
        let n = hs.len();
        let segments = if *closed { n } else { n.saturating_sub(1) };
        for segment in 0..segments {
            let (a, b) = (hs[segment], hs[(segment + 1) % n]);
            if a == b {
                continue;
            }
            if !cdt.can_add_constraint(a, b) {
                return Err(MeshingError::Intersecting {
                    part: *part,
                    segment,
                });
            }
            cdt.add_constraint(a, b);
        }
    }

    // spade 2.15 classifies outer faces by peeling layers of constraint crossings; an open
    // polyline inside the region makes it mark the whole interior as outer. With internal
    // constraints, everything is refined instead, inside a rectangular frame a little larger
    // than the outline: without it, convex hull edges meet concave parts of the outline at
    // sharp angles and over-refine them. Vertices outside are dropped below.
    let exclude_outer = outline.constraints.is_empty();
    let mut frame_area = box_area;
    if !exclude_outer {
        let margin = (2.0 * h).min(0.5 * (hi[0] - lo[0]).hypot(hi[1] - lo[1]));
        let (x0, y0, x1, y1) = (
            lo[0] - margin,
            lo[1] - margin,
            hi[0] + margin,
            hi[1] + margin,
        );
        // Skipped (never needed in practice) if rounding put it on the outline.
        if x0 < lo[0] && y0 < lo[1] && x1 > hi[0] && y1 > hi[1] {
            let corners = [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
                .map(|[x, y]| cdt.insert(Point2::new(x, y)));
            if let [Ok(a), Ok(b), Ok(c), Ok(d)] = corners {
                for (p, q) in [(a, b), (b, c), (c, d), (d, a)] {
                    if cdt.can_add_constraint(p, q) {
                        cdt.add_constraint(p, q);
                    }
                }
                frame_area = (x1 - x0) * (y1 - y0);
            }
        }
    }
    let max_area = 3f64.sqrt() / 4.0 * h * h;
    let frame_ratio = if box_area > 0.0 {
        frame_area / box_area
    } else {
        1.0
    };
    let budget = (4.0 * estimated * frame_ratio) as usize + 1000;
    let params = RefinementParameters::<f64>::new()
        .exclude_outer_faces(exclude_outer)
        .with_max_allowed_area(max_area)
        .with_min_required_area(max_area * 1e-4)
        .with_angle_limit(AngleLimit::from_deg(MIN_ANGLE_DEG))
        .with_max_additional_vertices(budget);
    let refinement = cdt.refine(params);

    // Keep the faces inside the region: flood-fill the regions bounded by constraint edges and
    // classify each by one interior point.
    let polygons: Vec<&[[f64; 2]]> = parts
        .iter()
        .filter(|(_, _, closed)| *closed)
        .map(|(_, p, _)| p.as_slice())
        .collect();
    let kept = inside_faces(&cdt, &polygons);
    if kept.is_empty() {
        return Err(MeshingError::EmptyMesh);
    }

    // Compact the vertices (spade's order: outline points first, then refinement points).
    let mut new_index = vec![u32::MAX; cdt.num_vertices()];
    for &f in &kept {
        for v in cdt.face(f).vertices() {
            new_index[v.fix().index()] = 0;
        }
    }
    let mut vertices = Vec::new();
    for v in cdt.vertices() {
        let slot = &mut new_index[v.fix().index()];
        if *slot == 0 {
            *slot = vertices.len() as u32;
            let p = v.position();
            vertices.push(Vector::new(p.x as Real, 0.0, p.y as Real));
        }
    }
    let mut triangles = Vec::with_capacity(kept.len());
    let mut edge_uses: HashMap<(u32, u32), u32> = HashMap::with_capacity(kept.len() * 2);
    for &f in &kept {
        let [a, b, c] = cdt.face(f).vertices();
        let (pa, pb, pc) = (a.position(), b.position(), c.position());
        let ccw_uv = (pb.x - pa.x) * (pc.y - pa.y) - (pb.y - pa.y) * (pc.x - pa.x) > 0.0;
        let [a, b, c] = [a, b, c].map(|v| new_index[v.fix().index()]);
        // (u, v) -> (u, 0, v) mirrors the orientation: counter-clockwise in (u, v) is
        // clockwise seen from +y.
        let t = if ccw_uv { [a, c, b] } else { [a, b, c] };
        for k in 0..3 {
            let (i, j) = (t[k], t[(k + 1) % 3]);
            *edge_uses.entry((i.min(j), i.max(j))).or_insert(0) += 1;
        }
        triangles.push(t);
    }
    let mut boundary: Vec<u32> = edge_uses
        .iter()
        .filter(|(_, &uses)| uses == 1)
        .flat_map(|(&(i, j), _)| [i, j])
        .collect::<HashSet<u32>>()
        .into_iter()
        .collect();
    boundary.sort_unstable();

    // Trace each constraint polyline through its (possibly split) constraint edges.
    let mut constrained = Vec::with_capacity(outline.constraints.len());
    let first_constraint = 1 + outline.holes.len();
    for (c, hs) in handles[first_constraint..].iter().enumerate() {
        let mut chain: Vec<FixedVertexHandle> = vec![hs[0]];
        for w in hs.windows(2) {
            if w[0] != w[1] && !follow_constraint(&cdt, w[0], w[1], &mut chain) {
                return Err(MeshingError::ConstraintNotRecovered { constraint: c });
            }
        }
        let mut line = Vec::with_capacity(chain.len());
        for v in chain {
            let i = new_index[v.index()];
            if i == u32::MAX {
                return Err(MeshingError::ConstraintOutsideDomain { constraint: c });
            }
            line.push(i);
        }
        let in_mesh = line
            .windows(2)
            .all(|w| edge_uses.contains_key(&(w[0].min(w[1]), w[0].max(w[1]))));
        if !in_mesh {
            return Err(MeshingError::ConstraintOutsideDomain { constraint: c });
        }
        constrained.push(line);
    }

    Ok(PlanarMesh {
        mesh: SurfaceMesh {
            vertices,
            triangles,
        },
        boundary,
        constrained,
        refinement_complete: refinement.refinement_complete,
    })
}

fn to_f64(points: &[[Real; 2]], part: OutlinePart) -> Result<Vec<[f64; 2]>, MeshingError> {
    points
        .iter()
        .enumerate()
        .map(|(index, p)| {
            if p[0].is_finite() && p[1].is_finite() {
                Ok([p[0] as f64, p[1] as f64])
            } else {
                Err(MeshingError::NonFinitePoint { part, index })
            }
        })
        .collect()
}

/// The number of distinct points (`-0.0` and `0.0` count as one).
fn count_distinct(points: &[[f64; 2]]) -> usize {
    let mut seen: Vec<[u64; 2]> = points
        .iter()
        .map(|p| [(p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()])
        .collect();
    seen.sort_unstable();
    seen.dedup();
    seen.len()
}

fn polyline_length(points: &[[f64; 2]], closed: bool) -> f64 {
    let n = points.len();
    let segments = if closed { n } else { n.saturating_sub(1) };
    (0..segments)
        .map(|i| {
            let (a, b) = (points[i], points[(i + 1) % n]);
            (b[0] - a[0]).hypot(b[1] - a[1])
        })
        .sum()
}

/// Even-odd point-in-polygon test.
fn point_in_polygon(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut inside = false;
    let n = poly.len();
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// The inner faces of `cdt` inside `polygons[0]` and outside `polygons[1..]`, in spade's face
/// order. Faces are grouped into regions connected across non-constraint edges; no region
/// straddles a polygon edge, so one centroid per region decides.
fn inside_faces(cdt: &Cdt, polygons: &[&[[f64; 2]]]) -> Vec<FixedFaceHandle<InnerTag>> {
    const UNSEEN: u32 = u32::MAX;
    let mut region = vec![UNSEEN; cdt.num_all_faces()];
    let mut region_inside: Vec<bool> = Vec::new();
    let mut stack = Vec::new();
    for face in cdt.inner_faces() {
        if region[face.fix().index()] != UNSEEN {
            continue;
        }
        let id = region_inside.len() as u32;
        let [a, b, c] = face.vertices().map(|v| v.position());
        let centroid = [(a.x + b.x + c.x) / 3.0, (a.y + b.y + c.y) / 3.0];
        let inside = point_in_polygon(polygons[0], centroid)
            && !polygons[1..].iter().any(|h| point_in_polygon(h, centroid));
        region_inside.push(inside);
        region[face.fix().index()] = id;
        stack.push(face.fix());
        while let Some(f) = stack.pop() {
            for edge in cdt.face(f).adjacent_edges() {
                if edge.is_constraint_edge() {
                    continue;
                }
                if let Some(next) = edge.rev().face().as_inner() {
                    let slot = &mut region[next.fix().index()];
                    if *slot == UNSEEN {
                        *slot = id;
                        stack.push(next.fix());
                    }
                }
            }
        }
    }
    cdt.inner_faces()
        .filter(|f| region_inside[region[f.fix().index()] as usize])
        .map(|f| f.fix())
        .collect()
}

/// Walks constraint edges from `from` to `to` along the straight segment between them,
/// appending every vertex after `from` to `chain`. Refinement splits constraint edges at
/// points on the segment, so the walk always takes the constraint edge best aligned with the
/// remaining segment.
fn follow_constraint(
    cdt: &Cdt,
    from: FixedVertexHandle,
    to: FixedVertexHandle,
    chain: &mut Vec<FixedVertexHandle>,
) -> bool {
    let target = cdt.vertex(to).position();
    let mut current = from;
    for _ in 0..cdt.num_vertices() {
        if current == to {
            return true;
        }
        let p = cdt.vertex(current).position();
        let d = [target.x - p.x, target.y - p.y];
        let d_len = d[0].hypot(d[1]);
        let mut best: Option<(f64, FixedVertexHandle)> = None;
        for edge in cdt.vertex(current).out_edges() {
            if !edge.is_constraint_edge() {
                continue;
            }
            let q = edge.to().position();
            let w = [q.x - p.x, q.y - p.y];
            let w_len = w[0].hypot(w[1]);
            if w_len == 0.0 || w_len > d_len * (1.0 + 1e-9) {
                continue;
            }
            let cos = (w[0] * d[0] + w[1] * d[1]) / (w_len * d_len);
            if cos > 1.0 - 1e-9 && best.is_none_or(|(c, _)| cos > c) {
                best = Some((cos, edge.to().fix()));
            }
        }
        match best {
            Some((_, next)) => {
                chain.push(next);
                current = next;
            }
            None => return false,
        }
    }
    current == to
}

/// Grid subdivisions are clamped to this, so vertex indices always fit in `u32`.
const MAX_GRID_CELLS: u32 = 1 << 14;

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

/// Loads every object of a Wavefront OBJ file into one [`SurfaceMesh`] (see [`parse_obj`]).
/// Material libraries are not read.
///
/// # Errors
/// [`MeshingError::Io`] if the file cannot be opened, and the errors of [`parse_obj`].
pub fn load_obj(path: impl AsRef<Path>) -> Result<SurfaceMesh, MeshingError> {
    let path = path.as_ref();
    let file = std::fs::File::open(path).map_err(|source| MeshingError::Io {
        path: path.to_owned(),
        source,
    })?;
    read_obj(&mut std::io::BufReader::new(file))
}

/// Parses Wavefront OBJ text into one [`SurfaceMesh`].
///
/// All objects and groups are merged (their indices offset). Polygons are split into
/// triangle fans; points and lines are ignored, and so are faces that repeat a vertex.
/// Vertices are welded by OBJ position index: a position shared by faces with different
/// normals or texture coordinates stays one vertex, so the surface stays connected. Vertices
/// no face uses are dropped. The winding is the file's.
///
/// ```
/// let mesh = rapier_touch::surface::meshing::parse_obj(
///     "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n",
/// ).unwrap();
/// assert_eq!((mesh.num_vertices(), mesh.num_triangles()), (3, 1));
/// ```
///
/// # Errors
/// [`MeshingError::Obj`] for malformed text, [`MeshingError::NonFinitePosition`] for a NaN or
/// infinite position, [`MeshingError::EmptyMesh`] if no triangle is left.
pub fn parse_obj(text: &str) -> Result<SurfaceMesh, MeshingError> {
    read_obj(&mut text.as_bytes())
}

fn read_obj(reader: &mut impl BufRead) -> Result<SurfaceMesh, MeshingError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) =
        tobj::load_obj_buf(reader, &options, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(MeshingError::Obj)?;

    let mut positions: Vec<Vector> = Vec::new();
    let mut triangles: Vec<[usize; 3]> = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let offset = positions.len();
        for p in mesh.positions.chunks_exact(3) {
            let v = Vector::new(p[0], p[1], p[2]);
            if !v.is_finite() {
                return Err(MeshingError::NonFinitePosition {
                    vertex: positions.len(),
                });
            }
            positions.push(v);
        }
        let count = positions.len() - offset;
        for t in mesh.indices.chunks_exact(3) {
            let t = [t[0], t[1], t[2]].map(|i| i as usize);
            if t.iter().any(|&i| i >= count) {
                return Err(MeshingError::Obj(tobj::LoadError::FaceVertexOutOfBounds));
            }
            if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                continue;
            }
            triangles.push(t.map(|i| i + offset));
        }
    }
    compacted(positions, triangles)
}

/// A surface from a triangle soup read from a file: degenerate triangles already dropped, the
/// vertices no triangle uses removed (the others keep their file order).
pub(super) fn compacted(
    positions: Vec<Vector>,
    triangles: Vec<[usize; 3]>,
) -> Result<SurfaceMesh, MeshingError> {
    if triangles.is_empty() {
        return Err(MeshingError::EmptyMesh);
    }

    // Compact: keep the vertices some triangle uses, in file order.
    let mut new_index = vec![usize::MAX; positions.len()];
    for t in &triangles {
        for &i in t {
            new_index[i] = 0;
        }
    }
    let mut vertices = Vec::new();
    for (i, p) in positions.iter().enumerate() {
        if new_index[i] == 0 {
            new_index[i] = vertices.len();
            vertices.push(*p);
        }
    }
    if vertices.len() as u64 > u32::MAX as u64 {
        return Err(MeshingError::TooManyVertices {
            estimated: vertices.len() as u64,
            max: u32::MAX as u64,
        });
    }
    let triangles = triangles
        .iter()
        .map(|t| t.map(|i| new_index[i] as u32))
        .collect();
    Ok(SurfaceMesh {
        vertices,
        triangles,
    })
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
mod tests {
    use super::*;

    fn square(lo: Real, hi: Real) -> Vec<[Real; 2]> {
        vec![[lo, lo], [hi, lo], [hi, hi], [lo, hi]]
    }

    /// Every triangle's normal points to +y (counter-clockwise seen from above).
    fn all_ccw_from_up(mesh: &SurfaceMesh) -> bool {
        mesh.triangles.iter().all(|&[a, b, c]| {
            let [a, b, c] = [a, b, c].map(|i| mesh.vertices[i as usize]);
            (b - a).cross(c - a).y > 0.0
        })
    }

    fn edges(mesh: &SurfaceMesh) -> HashSet<(u32, u32)> {
        mesh.triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
            .collect()
    }

    fn compact(mesh: &SurfaceMesh) -> bool {
        let used: HashSet<u32> = mesh.triangles.iter().flatten().copied().collect();
        used.len() == mesh.vertices.len()
    }

    #[test]
    fn unit_square_meshes_to_target_size() {
        let outline = PlanarOutline {
            outer: square(0.0, 1.0),
            ..Default::default()
        };
        let planar = triangulate_planar(&outline, 0.1).unwrap();
        let mesh = &planar.mesh;
        let n = mesh.num_vertices();
        assert!((100..=300).contains(&n), "{n} vertices");
        assert!(all_ccw_from_up(mesh));
        assert!((mesh.area() - 1.0).abs() < 1e-4, "area {}", mesh.area());
        assert!(compact(mesh));
        assert!(planar.refinement_complete);
        assert!(mesh.vertices.iter().all(|v| v.y == 0.0));
        // The outline's own points come first, in order.
        assert_eq!(mesh.vertices[2], Vector::new(1.0, 0.0, 1.0));
        // Boundary vertices are exactly those on the square's sides.
        let on_side = |v: Vector| v.x.min(v.z).min(1.0 - v.x).min(1.0 - v.z) < 1e-6;
        for (i, v) in mesh.vertices.iter().enumerate() {
            assert_eq!(
                planar.boundary.binary_search(&(i as u32)).is_ok(),
                on_side(*v)
            );
        }
        // Edges are at most about the target length.
        let longest = edges(mesh)
            .iter()
            .map(|&(i, j)| (mesh.vertices[i as usize] - mesh.vertices[j as usize]).length())
            .fold(0.0, Real::max);
        assert!(longest < 0.16, "longest edge {longest}");
    }

    #[test]
    fn hole_is_left_out() {
        let outline = PlanarOutline {
            outer: square(0.0, 1.0),
            // Clockwise on purpose: orientation does not matter.
            holes: vec![square(0.3, 0.6).into_iter().rev().collect()],
            constraints: Vec::new(),
        };
        let planar = triangulate_planar(&outline, 0.1).unwrap();
        let mesh = &planar.mesh;
        assert!(
            (mesh.area() - (1.0 - 0.09)).abs() < 1e-4,
            "area {}",
            mesh.area()
        );
        assert!(all_ccw_from_up(mesh));
        assert!(compact(mesh));
        for &[a, b, c] in &mesh.triangles {
            let g =
                (mesh.vertices[a as usize] + mesh.vertices[b as usize] + mesh.vertices[c as usize])
                    / 3.0;
            assert!(!(g.x > 0.3 && g.x < 0.6 && g.z > 0.3 && g.z < 0.6), "{g}");
        }
        // The hole's corners are boundary vertices.
        let corner = mesh
            .vertices
            .iter()
            .position(|v| (*v - Vector::new(0.3, 0.0, 0.6)).length() < 1e-6)
            .unwrap();
        assert!(planar.boundary.contains(&(corner as u32)));
    }

    #[test]
    fn constraint_polyline_is_traced_in_order() {
        let line = vec![[0.2, 0.3], [0.5, 0.6], [0.8, 0.35]];
        let outline = PlanarOutline {
            outer: square(0.0, 1.0),
            holes: Vec::new(),
            constraints: vec![line.clone()],
        };
        let planar = triangulate_planar(&outline, 0.1).unwrap();
        let mesh = &planar.mesh;
        assert!((mesh.area() - 1.0).abs() < 1e-4);
        assert!(all_ccw_from_up(mesh));
        let chain = &planar.constrained[0];
        // Refinement split the 0.42 m and 0.39 m segments.
        assert!(chain.len() >= 7, "{chain:?}");
        let at = |i: u32| {
            let v = mesh.vertices[i as usize];
            [v.x, v.z]
        };
        assert_eq!(at(chain[0]), line[0]);
        assert_eq!(at(*chain.last().unwrap()), line[2]);
        assert!(chain.iter().any(|&i| at(i) == line[1]));
        // In order along the polyline: arc length strictly increases, every point lies on it.
        let mesh_edges = edges(mesh);
        let mut travelled = 0.0;
        for w in chain.windows(2) {
            assert!(mesh_edges.contains(&(w[0].min(w[1]), w[0].max(w[1]))));
            let (p, q) = (at(w[0]), at(w[1]));
            let step = (q[0] - p[0]).hypot(q[1] - p[1]);
            assert!(step > 1e-4);
            travelled += step;
        }
        let length = (0.3f32.hypot(0.3)) + (0.3f32.hypot(0.25));
        assert!((travelled - length).abs() < 1e-4, "{travelled} vs {length}");
        // No constraint vertex is on the outer boundary.
        assert!(chain.iter().all(|i| !planar.boundary.contains(i)));
    }

    #[test]
    fn constraint_touching_boundary_and_single_point() {
        let outline = PlanarOutline {
            outer: square(0.0, 1.0),
            holes: Vec::new(),
            constraints: vec![vec![[0.0, 0.5], [1.0, 0.5]], vec![[0.25, 0.75]]],
        };
        let planar = triangulate_planar(&outline, 0.2).unwrap();
        let chain = &planar.constrained[0];
        assert!(planar.boundary.contains(&chain[0]));
        assert!(planar.boundary.contains(chain.last().unwrap()));
        assert!(chain
            .iter()
            .all(|&i| planar.mesh.vertices[i as usize].z == 0.5));
        assert_eq!(planar.constrained[1].len(), 1);
        let p = planar.mesh.vertices[planar.constrained[1][0] as usize];
        assert_eq!(p, Vector::new(0.25, 0.0, 0.75));
    }

    #[test]
    fn bad_outlines_are_errors() {
        let empty = PlanarOutline::default();
        assert!(matches!(
            triangulate_planar(&empty, 0.1),
            Err(MeshingError::TooFewPoints {
                part: OutlinePart::Outer,
                distinct: 0
            })
        ));
        let mut nan = PlanarOutline {
            outer: square(0.0, 1.0),
            ..Default::default()
        };
        nan.outer[2][1] = Real::NAN;
        assert!(matches!(
            triangulate_planar(&nan, 0.1),
            Err(MeshingError::NonFinitePoint {
                part: OutlinePart::Outer,
                index: 2
            })
        ));
        let ok = PlanarOutline {
            outer: square(0.0, 1.0),
            ..Default::default()
        };
        for h in [0.0, -1.0, Real::NAN, Real::INFINITY] {
            assert!(matches!(
                triangulate_planar(&ok, h),
                Err(MeshingError::InvalidTargetEdge(_))
            ));
        }
        assert!(matches!(
            triangulate_planar(&ok, 1e-6),
            Err(MeshingError::TooManyVertices { .. })
        ));
        // Repeated closing point is fine; two distinct points are not a polygon.
        let line = PlanarOutline {
            outer: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]],
            ..Default::default()
        };
        assert!(matches!(
            triangulate_planar(&line, 0.1),
            Err(MeshingError::TooFewPoints { distinct: 2, .. })
        ));
        // Collinear points: no area.
        let flat = PlanarOutline {
            outer: vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
            ..Default::default()
        };
        assert!(matches!(
            triangulate_planar(&flat, 0.1),
            Err(MeshingError::EmptyMesh)
        ));
        // A bow tie crosses itself.
        let bow_tie = PlanarOutline {
            outer: vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]],
            ..Default::default()
        };
        assert!(matches!(
            triangulate_planar(&bow_tie, 0.1),
            Err(MeshingError::Intersecting {
                part: OutlinePart::Outer,
                ..
            })
        ));
        // A constraint crossing the boundary, one crossing another, one outside, one in a hole.
        let crossing = |constraints: Vec<Vec<[Real; 2]>>| PlanarOutline {
            outer: square(0.0, 1.0),
            holes: vec![square(0.6, 0.9)],
            constraints,
        };
        assert!(matches!(
            triangulate_planar(&crossing(vec![vec![[0.5, 0.5], [1.5, 0.5]]]), 0.1),
            Err(MeshingError::Intersecting {
                part: OutlinePart::Constraint(0),
                segment: 0
            })
        ));
        assert!(matches!(
            triangulate_planar(
                &crossing(vec![
                    vec![[0.1, 0.1], [0.5, 0.5]],
                    vec![[0.1, 0.5], [0.2, 0.4], [0.5, 0.1]]
                ]),
                0.1
            ),
            Err(MeshingError::Intersecting {
                part: OutlinePart::Constraint(1),
                segment: 1
            })
        ));
        assert!(matches!(
            triangulate_planar(&crossing(vec![vec![[1.5, 0.5], [2.0, 0.5]]]), 0.1),
            Err(MeshingError::ConstraintOutsideDomain { constraint: 0 })
        ));
        assert!(matches!(
            triangulate_planar(&crossing(vec![vec![[0.7, 0.7], [0.8, 0.8]]]), 0.1),
            Err(MeshingError::ConstraintOutsideDomain { constraint: 0 })
        ));
        // A chord across the hole between two of its corners.
        assert!(matches!(
            triangulate_planar(&crossing(vec![vec![[0.6, 0.6], [0.9, 0.9]]]), 0.1),
            Err(MeshingError::ConstraintOutsideDomain { constraint: 0 })
        ));
        let empty_line = crossing(vec![vec![]]);
        assert!(matches!(
            triangulate_planar(&empty_line, 0.1),
            Err(MeshingError::TooFewPoints {
                part: OutlinePart::Constraint(0),
                distinct: 0
            })
        ));
        let tiny = PlanarOutline {
            outer: vec![[0.0, 0.0], [1e-44, 0.0], [0.0, 1.0]],
            ..Default::default()
        };
        assert!(matches!(
            triangulate_planar(&tiny, 0.1),
            Err(MeshingError::Insertion { index: 1, .. })
        ));
    }

    #[test]
    fn plate_grid() {
        let p = plate(2.0, 1.0, 4, 2);
        assert_eq!(p.num_vertices(), 15);
        assert_eq!(p.num_triangles(), 16);
        assert!(all_ccw_from_up(&p));
        assert!(compact(&p));
        assert!((p.area() - 2.0).abs() < 1e-6);
        assert_eq!(p.vertices[0], Vector::new(-1.0, 0.0, -0.5));
        assert_eq!(p.vertices[14], Vector::new(1.0, 0.0, 0.5));
        // Edge-manifold: 4·2 cells have 4·3 + 5·2 + 8 = 30 edges.
        assert_eq!(edges(&p).len(), 30);
        let degenerate = plate(1.0, 1.0, 0, 0);
        assert_eq!(degenerate.num_triangles(), 2);
    }

    #[test]
    fn plate_rim_is_the_outer_boundary() {
        for (size, n) in [(0.3, 15), (0.3, 27), (0.3, 99), (0.3, 54), (2.0, 1)] {
            let p = plate(size, size, n, n);
            let edge = 0.5 * size - 1e-4;
            let by_position: Vec<u32> = (0..p.num_vertices() as u32)
                .filter(|&i| {
                    let v = p.vertices[i as usize];
                    v.x.abs() > edge || v.z.abs() > edge
                })
                .collect();
            assert_eq!(plate_rim(n, n), by_position, "{n} cells");
        }
        assert_eq!(plate_rim(0, 0), [0, 1, 2, 3]);
    }

    #[test]
    fn closed_generators() {
        let b = box_surface(Vector::new(1.0, 0.5, 0.25), 3);
        assert_eq!(b.num_triangles(), 6 * 9 * 2);
        assert!((b.area() - 7.0).abs() < 1e-5);
        let s = sphere_surface(2.0, 3);
        assert_eq!(s.num_triangles(), 20 * 64);
        assert!(s.vertices.iter().all(|v| (v.length() - 2.0).abs() < 1e-5));
        // Outward winding: the signed volume is positive.
        let volume: Real = s
            .triangles
            .iter()
            .map(|&[a, b, c]| {
                let [a, b, c] = [a, b, c].map(|i| s.vertices[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        assert!(volume > 0.9 * 4.0 / 3.0 * std::f32::consts::PI * 8.0);
    }

    const CUBE_OBJ: &str = "\
# unit cube, quads, with normals (which must not split the vertices)
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vn 0 0 -1
vn 0 0 1
vn 0 -1 0
vn 0 1 0
vn -1 0 0
vn 1 0 0
f 1//1 4//1 3//1 2//1
f 5//2 6//2 7//2 8//2
f 1//3 2//3 6//3 5//3
f 4//4 8//4 7//4 3//4
f 1//5 5//5 8//5 4//5
f 2//6 3//6 7//6 6//6
";

    #[test]
    fn obj_cube() {
        let mesh = parse_obj(CUBE_OBJ).unwrap();
        assert_eq!(mesh.num_vertices(), 8);
        assert_eq!(mesh.num_triangles(), 12);
        assert!((mesh.area() - 6.0).abs() < 1e-6);
        assert!(compact(&mesh));
        // Two objects merge with offset indices.
        let two = format!("{CUBE_OBJ}o second\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf 9 10 11\n");
        let mesh = parse_obj(&two).unwrap();
        assert_eq!((mesh.num_vertices(), mesh.num_triangles()), (11, 13));
        assert_eq!(mesh.triangles[12], [8, 9, 10]);
        assert_eq!(mesh.vertices[10], Vector::new(5.0, 1.0, 0.0));
    }

    #[test]
    fn obj_errors() {
        assert!(matches!(parse_obj(""), Err(MeshingError::EmptyMesh)));
        assert!(matches!(
            parse_obj("v 0 0 0\nv 1 0 0\nl 1 2\n"),
            Err(MeshingError::EmptyMesh)
        ));
        assert!(matches!(
            parse_obj("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"),
            Err(MeshingError::NonFinitePosition { vertex: 1 })
        ));
        assert!(matches!(
            parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"),
            Err(MeshingError::Obj(_))
        ));
        assert!(matches!(
            parse_obj("v 0 x 0\nf 1 1 1\n"),
            Err(MeshingError::Obj(_))
        ));
        assert!(matches!(
            load_obj("/nonexistent/definitely/missing.obj"),
            Err(MeshingError::Io { .. })
        ));
    }

    #[test]
    fn obj_file_round_trip() {
        let path =
            std::env::temp_dir().join(format!("rapier_touch_cube_{}.obj", std::process::id()));
        std::fs::write(&path, CUBE_OBJ).unwrap();
        let mesh = load_obj(&path);
        let _ = std::fs::remove_file(&path);
        assert_eq!(mesh.unwrap().num_triangles(), 12);
    }

    #[test]
    fn paper_plate_size() {
        let planar = triangulate_planar(&paper_plate_outline(), PAPER_PLATE_TARGET_EDGE).unwrap();
        let n = planar.mesh.num_vertices() as i64;
        assert!((n - 517).abs() <= 40, "{n} nodes");
        assert!(all_ccw_from_up(&planar.mesh));
        // The notch is half a regular 24-gon: 12 triangles of apex angle π/12.
        let notch = 12.0 * 0.5 * 0.04f32.powi(2) * (std::f32::consts::PI / 12.0).sin();
        let area = 0.3 * 0.2 - notch;
        assert!(
            (planar.mesh.area() - area).abs() < 1e-6,
            "{}",
            planar.mesh.area()
        );
        assert!(planar.refinement_complete);
    }

    #[test]
    fn paper_organ_size() {
        let (outline, h) = paper_organ_outline();
        let planar = triangulate_planar(&outline, h).unwrap();
        let n = planar.mesh.num_vertices() as i64;
        assert!((n - 790).abs() <= 50, "{n} nodes");
        assert!(all_ccw_from_up(&planar.mesh));
        assert!(compact(&planar.mesh));
        assert!(planar.refinement_complete);
        let chain = &planar.constrained[0];
        assert!(chain.len() > outline.constraints[0].len());
        let mesh_edges = edges(&planar.mesh);
        assert!(chain
            .windows(2)
            .all(|w| mesh_edges.contains(&(w[0].min(w[1]), w[0].max(w[1])))));
    }
}
