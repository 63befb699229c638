//! Planar constrained Delaunay meshes ([`triangulate_planar`]): an outline's polygons and
//! constraint polylines, refined by spade to a target edge length.

use super::*;
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
