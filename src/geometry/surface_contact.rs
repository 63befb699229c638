//! Contacts between a rigid polyhedral tool and a deformable surface mesh: where the tool's
//! sharp features (its vertices and edges) press into the surface between the surface's
//! vertices.
//!
//! The surface vertex inside the tool (eq. 1-2 with the surface vertex as the moving point) is
//! handled by the coupling, which walks each such vertex back to the tool's boundary. This file
//! gives the other two kinds of section 2, with the surface taken as fixed at its current shape
//! over a substep and the tool as the moving object:
//!
//! - **a tool vertex inside a surface triangle** (eq. 3, the paper's special situation: a vertex
//!   of one object on a face of the other). The line through the tool vertex along the
//!   triangle's normal cuts the triangle at `P` ([`super::reconstruction::ray_triangle`], the
//!   same test the rigid reconstruction uses); the surface point `P` is pushed to the vertex's
//!   plane along the normal and loads the triangle's three vertices by their barycentric
//!   weights;
//! - **a tool edge across a surface edge**, the 3D kind the paper's 2D argument misses
//!   ([`super::reconstruction::edge_edge`], shared with the rigid reconstruction); the surface
//!   point loads the surface edge's two vertices. The push is along the surface's normal less
//!   its part along the tool's edge, not along the rigid case's `e × f`: a deformable surface
//!   has many edges nearly parallel to a tool edge lying in it, and `e × f` swings wildly
//!   between them (tangential pushes a frictionless contact must not give).
//!
//! A feature is in contact when it lies below the surface at the end of the substep by no more
//! than it and the surface around it moved over the substep (a feature farther below did not
//! get there in this substep: it is on the far side of a surface the tool does not press
//! there), or above it by no more than `margin` plus that motion: a *speculative* contact
//! (negative depth), which the next substep may close but not pass (the surface springing back
//! into a tool that stopped, a flat face resting on it). Below means on the side away from the
//! tool's centre at the start of the substep. Flat tool edges (the diagonals of a triangulated
//! face) are skipped: a face is held through its vertices and its real edges.

mod snapshot;

pub use snapshot::{triangles_in, SurfaceSnapshot};

use super::reconstruction::{edge_edge, ray_triangle};
use super::touch_mesh::{Feature, TouchMesh};
use crate::math::{Pose, Real, Vector};
use glamx::DVec3;

/// One contact of a tool feature with a surface point (everything in the surface's frame).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SurfaceContact {
    /// The tool's vertex or edge in contact ([`TouchMesh`] indices of the tool).
    pub tool_feature: Feature,
    /// The surface vertices carrying the contact point and their weights (summing to one):
    /// three for a point inside a triangle, two for a point on an edge.
    pub surface: [(u32, Real); 3],
    /// How many entries of `surface` are used (2 or 3).
    pub count: usize,
    /// Unit direction from the tool into the surface: where the surface point is pushed.
    pub normal: Vector,
    /// How far the surface point must move along `normal` to reach the tool's feature
    /// (positive: the feature is below the surface; negative: a speculative contact that far
    /// above it).
    pub depth: Real,
    /// The contact point on the tool.
    pub point: Vector,
}

impl SurfaceContact {
    /// The `(vertex, weight)` pairs used.
    pub fn weights(&self) -> &[(u32, Real)] {
        &self.surface[..self.count]
    }
}

/// The triangle a tool vertex is most inside: how far inside (its least barycentric
/// coordinate), its vertices, the vertex's weights on them, its normal toward the tool, and the
/// vertex's height over it.
type Inside = (f64, [u32; 3], [f64; 3], DVec3, f64);

/// A surface triangle's area normal now (vertices `now`), turned toward the side of `centre`
/// the triangle had at the start of the substep (`before`), and the reciprocal of its length;
/// `None` for a triangle with zero or non-finite area now or before (no side to turn to). The
/// two cross products once each: the side only needs the sign along the normal before.
fn area_toward(centre: DVec3, now: &[DVec3; 3], before: &[DVec3; 3]) -> Option<(DVec3, f64)> {
    let area = (now[1] - now[0]).cross(now[2] - now[0]);
    let area_before = (before[1] - before[0]).cross(before[2] - before[0]);
    // The area before is only asked for a side: its length squared says whether it has one
    // (no second square root and division per candidate triangle).
    let rcp = area.length_recip();
    let before2 = area_before.length_squared();
    if !(rcp.is_finite() && rcp > 0.0 && before2.is_finite() && before2 > 0.0) {
        return None;
    }
    let toward = (centre - before[0]).dot(area_before) >= 0.0;
    Some((if toward { area } else { -area }, rcp))
}

/// Smallest cosine between an edge-edge contact normal and the surface triangle's normal (a
/// tool edge standing nearly straight into the surface is pressed by its lowest vertex).
const MIN_EDGE_NORMAL_COS: f64 = 0.2;
/// Within this barycentric distance of a triangle's edge, a tool vertex's push blends from the
/// triangle's normal into the smooth (vertex-interpolated) normal: a tool corner over a dent's
/// apex otherwise flips between the apex's triangles' normals from one substep to the next and
/// chatters (measured: a tilted U's corner, its force's x swinging 0.75 to 1.38 N).
const SMOOTH_NEAR_EDGE: f64 = 0.1;
/// Smallest sine of the angle between a tool edge and a surface edge for an edge-edge contact.
const MIN_EDGE_SINE: f64 = 0.1;

/// The contacts of `tool` (moving from `start` to `end`, poses in the surface's frame) with the
/// candidate triangles of `surface` (see the module docs), appended to `out`. Each tool vertex
/// gets at most one contact (the triangle it is most inside); each tool edge one per surface
/// edge it crosses.
///
/// # Example
/// A cube turned corner-down, its lowest corner 1 cm under a flat two-triangle square:
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::geometry::{tool_surface_contacts, Feature, SurfaceSnapshot};
///
/// let square = [
///     Vector::new(-1.0, 0.0, -1.0), Vector::new(1.0, 0.0, -1.0),
///     Vector::new(1.0, 0.0, 1.0), Vector::new(-1.0, 0.0, 1.0),
/// ];
/// let triangles = [[0, 2, 1], [0, 3, 2]];
/// let surface = SurfaceSnapshot { before: &square, now: &square, triangles: &triangles };
/// let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.1))).unwrap();
/// // Body diagonal (1, 1, 1) turned onto +y: one corner points straight down.
/// let tilt = Rotation::from_rotation_arc(Vector::ONE.normalize(), Vector::Y);
/// let corner = 0.1 * 3f32.sqrt();
/// let start = Pose::from_parts(Vector::new(0.3, corner + 0.01, 0.1), tilt);
/// let end = Pose::from_parts(Vector::new(0.3, corner - 0.01, 0.1), tilt);
/// let mut out = Vec::new();
/// tool_surface_contacts(&surface, &[0, 1], &cube, &start, &end, 1e-6, &mut out);
/// assert_eq!(out.len(), 1);
/// let c = &out[0];
/// assert!(matches!(c.tool_feature, Feature::Vertex(_)));
/// assert!((c.depth - 0.01).abs() < 1e-5);
/// assert!((c.normal - Vector::new(0.0, -1.0, 0.0)).length() < 1e-5);
/// assert!((c.point - Vector::new(0.3, -0.01, 0.1)).length() < 1e-5);
/// ```
#[allow(clippy::too_many_arguments)]
pub fn tool_surface_contacts(
    surface: &SurfaceSnapshot<'_>,
    candidates: &[u32],
    tool: &TouchMesh,
    start: &Pose,
    end: &Pose,
    margin: Real,
    out: &mut Vec<SurfaceContact>,
) {
    contacts_with_rings(surface, candidates, None, tool, start, end, margin, out);
}

/// The triangles round a surface vertex: appends to its second argument every triangle that
/// uses the vertex (as [`super::SurfaceBvh::triangles_of`] lists them).
pub type TrianglesRound<'a> = &'a dyn Fn(u32, &mut Vec<u32>);

/// [`tool_surface_contacts`], with the surface's smooth normal near a triangle's edge summed
/// over every triangle round each vertex (`rings`) rather than over the candidates that use
/// it. The candidates change with the tool's box as the surface moves, and a normal summed
/// over them with it: jaws tilted 0.30 rad, their corner on a triangle's edge, read a normal
/// 5° off at every other substep and slid the plate sideways and back at rest.
///
/// # Example
/// A cube corner 1 cm into a flat square of two triangles, the rings from a scan:
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::geometry::{tool_surface_contacts_with_rings, Feature, SurfaceSnapshot};
///
/// let square = [
///     Vector::new(-1.0, 0.0, -1.0), Vector::new(1.0, 0.0, -1.0),
///     Vector::new(1.0, 0.0, 1.0), Vector::new(-1.0, 0.0, 1.0),
/// ];
/// let triangles = [[0, 2, 1], [0, 3, 2]];
/// let rings = |v: u32, out: &mut Vec<u32>| {
///     out.extend((0..2u32).filter(|&t| triangles[t as usize].contains(&v)));
/// };
/// let surface = SurfaceSnapshot { before: &square, now: &square, triangles: &triangles };
/// let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.1))).unwrap();
/// let tilt = Rotation::from_rotation_arc(Vector::ONE.normalize(), Vector::Y);
/// let corner = 0.1 * 3f32.sqrt();
/// // Over the diagonal the two triangles share: the smooth normal there is theirs, -y.
/// let start = Pose::from_parts(Vector::new(0.2, corner + 0.01, 0.2), tilt);
/// let end = Pose::from_parts(Vector::new(0.2, corner - 0.01, 0.2), tilt);
/// let mut out = Vec::new();
/// tool_surface_contacts_with_rings(&surface, &[0, 1], &rings, &cube, &start, &end, 1e-6, &mut out);
/// // The corner's own contact (the cube's edges through it cross the diagonal too).
/// let c = out.iter().find(|c| matches!(c.tool_feature, Feature::Vertex(_))).unwrap();
/// assert!((c.depth - 0.01).abs() < 1e-5);
/// assert!((c.normal - Vector::new(0.0, -1.0, 0.0)).length() < 1e-5);
/// ```
#[allow(clippy::too_many_arguments)]
pub fn tool_surface_contacts_with_rings(
    surface: &SurfaceSnapshot<'_>,
    candidates: &[u32],
    rings: TrianglesRound<'_>,
    tool: &TouchMesh,
    start: &Pose,
    end: &Pose,
    margin: Real,
    out: &mut Vec<SurfaceContact>,
) {
    contacts_with_rings(
        surface,
        candidates,
        Some(rings),
        tool,
        start,
        end,
        margin,
        out,
    );
}

#[allow(clippy::too_many_arguments)]
fn contacts_with_rings(
    surface: &SurfaceSnapshot<'_>,
    candidates: &[u32],
    rings: Option<TrianglesRound<'_>>,
    tool: &TouchMesh,
    start: &Pose,
    end: &Pose,
    margin: Real,
    out: &mut Vec<SurfaceContact>,
) {
    let margin = margin.max(0.0) as f64;
    let centre = start.transform_point(tool.local_aabb().center()).as_dvec3();
    // The tool's vertices at the end and at the start of the substep.
    let (tool_end, tool_start): (Vec<DVec3>, Vec<DVec3>) = tool
        .vertices()
        .iter()
        .map(|v| {
            (
                end.transform_point(*v).as_dvec3(),
                start.transform_point(*v).as_dvec3(),
            )
        })
        .unzip();
    // Per candidate triangle: its vertices and corners now, the unit normal toward the tool,
    // how far its points moved over the substep, its area normal toward the tool, and its
    // bounds now. Also the bounds of them all, grown by the farthest any moved.
    let mut tris = Vec::with_capacity(candidates.len());
    let mut all_tris = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    let mut max_moved: f64 = 0.0;
    for &t in candidates {
        let (Some(now), Some(before), Some(&idx)) = (
            surface.tri(surface.now, t),
            surface.tri(surface.before, t),
            surface.triangles.get(t as usize),
        ) else {
            continue;
        };
        let Some((area, rcp)) = area_toward(centre, &now, &before) else {
            continue;
        };
        // The largest of the three displacements (one square root).
        let moved = (0..3)
            .map(|k| (now[k] - before[k]).length_squared())
            .fold(0.0, f64::max)
            .sqrt();
        let bounds = (
            now[0].min(now[1]).min(now[2]),
            now[0].max(now[1]).max(now[2]),
        );
        all_tris = (all_tris.0.min(bounds.0), all_tris.1.max(bounds.1));
        max_moved = max_moved.max(moved);
        tris.push((idx, now, area * rcp, moved, area, bounds));
    }
    if tris.is_empty() {
        return;
    }
    // The area-weighted normal of the candidate region at vertex `v`, toward the tool (asked
    // for a few vertices per call: summed where asked rather than kept for every vertex).
    // With `rings`, over every triangle round the vertex, each turned toward the tool as the
    // candidates are.
    let vertex_normal = |v: u32| -> DVec3 {
        if let Some(rings) = rings {
            let mut ring = Vec::new();
            rings(v, &mut ring);
            let sum = ring
                .iter()
                .filter_map(|&t| {
                    let (now, before) = (
                        surface.tri(surface.now, t)?,
                        surface.tri(surface.before, t)?,
                    );
                    area_toward(centre, &now, &before).map(|(area, _)| area)
                })
                .sum::<DVec3>();
            if !ring.is_empty() {
                return sum;
            }
        }
        tris.iter()
            .filter(|t| t.0.contains(&v))
            .map(|t| t.4)
            .sum::<DVec3>()
    };
    // The surface's normal at a point of weights `w` on vertices `idx`, interpolated from the
    // vertex normals (smooth across triangles); the triangle's own where that is degenerate or
    // turned more than 60° from it.
    let smooth = |idx: &[u32; 3], w: &[f64; 3], face: DVec3| -> DVec3 {
        idx.iter()
            .zip(w)
            .map(|(v, w)| vertex_normal(*v) * *w)
            .sum::<DVec3>()
            .try_normalize()
            .filter(|m| m.dot(face) > 0.5)
            .unwrap_or(face)
    };
    // Tool vertex inside a surface triangle.
    for (v, (&p1, &p0)) in tool_end.iter().zip(&tool_start).enumerate() {
        let feature = Feature::Vertex(v as u32);
        let mut best: Option<Inside> = None;
        let travel = (p1 - p0).length() + margin;
        // Farther from all the triangles' bounds than any of the tests below reaches: none.
        let reach_all =
            DVec3::splat(travel + max_moved + 1e-6 * (all_tris.1 - all_tris.0).max_element());
        if (all_tris.0 - reach_all).cmpgt(p1).any() || p1.cmpgt(all_tris.1 + reach_all).any() {
            continue;
        }
        for (idx, now, n, moved, _, (lo, hi)) in &tris {
            let h1 = (p1 - now[0]).dot(*n);
            if h1.abs() > travel + moved {
                continue;
            }
            // The line below meets the triangle within |h1| of the vertex (and a hair more:
            // `ray_triangle` takes points a billionth outside): not if the vertex is farther
            // from the triangle's bounds.
            let reach = DVec3::splat(h1.abs() + 1e-6 * (*hi - *lo).max_element());
            if (*lo - reach).cmpgt(p1).any() || p1.cmpgt(*hi + reach).any() {
                continue;
            }
            // The line through the vertex along the normal cuts the triangle (eq. 3).
            let Some((_, bary)) = ray_triangle(p1, *n, now, -f64::MAX, f64::MAX) else {
                continue;
            };
            let inside = bary[0].min(bary[1]).min(bary[2]);
            if best.as_ref().is_some_and(|b| b.0 >= inside) {
                continue;
            }
            let w = bary.map(|b| b.clamp(0.0, 1.0));
            let sum = w[0] + w[1] + w[2];
            if sum <= 0.0 {
                continue;
            }
            best = Some((inside, *idx, w.map(|x| x / sum), *n, h1));
        }
        // Pushed along the triangle's normal well inside it; near its edges, blended into the
        // smooth normal, by what puts the vertex on the triangle's plane (the smooth normal
        // for the chosen triangle only).
        out.extend(best.map(|(inside, idx, w, n, h1)| {
            let blend = (inside / SMOOTH_NEAR_EDGE).clamp(0.0, 1.0);
            let m = if blend < 1.0 {
                (n * blend + smooth(&idx, &w, n) * (1.0 - blend))
                    .try_normalize()
                    .unwrap_or(n)
            } else {
                n
            };
            SurfaceContact {
                tool_feature: feature,
                surface: [0, 1, 2].map(|k| (idx[k], w[k] as Real)),
                count: 3,
                normal: (-m).as_vec3(),
                depth: (-h1 / m.dot(n)) as Real,
                point: p1.as_vec3(),
            }
        }));
    }
    // Tool edge across a surface edge. Each surface edge once, with the first candidate
    // triangle that has it (its normal and motion).
    let mut seen = parry3d::utils::hashset::HashSet::with_capacity_and_hasher(
        3 * tris.len(),
        Default::default(),
    );
    let mut surface_edges = Vec::with_capacity(tris.len() * 2);
    // Each edge's bounds grown by how far it moved (the reach test below adds the tool edge's
    // travel), and the bounds of them all: most pairs fail the test (about 40 of 740 pass for
    // a cube on a plate).
    let mut edge_boxes = Vec::with_capacity(tris.len() * 2);
    let mut all_edges = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for (idx, now, n, moved, _, _) in &tris {
        for k in 0..3 {
            let (i, j) = (idx[k], idx[(k + 1) % 3]);
            if seen.insert((u64::from(i.min(j)) << 32) | u64::from(i.max(j))) {
                let (q0, q1) = (now[k], now[(k + 1) % 3]);
                let grown = DVec3::splat(*moved);
                let (q_lo, q_hi) = (q0.min(q1) - grown, q0.max(q1) + grown);
                all_edges = (all_edges.0.min(q_lo), all_edges.1.max(q_hi));
                edge_boxes.push((q_lo, q_hi));
                let f_dir = q1 - q0;
                surface_edges.push((i, j, q0, q1, f_dir, f_dir.length_squared(), *n, *moved));
            }
        }
    }
    for (e, &[a, b]) in tool.edges().iter().enumerate() {
        let [ta, tb] = tool.edge_triangles(e as u32);
        if tool.triangle_normal(ta).dot(tool.triangle_normal(tb)) > 1.0 - 1e-6 {
            continue; // a diagonal of a flat face
        }
        let feature = Feature::Edge([a.min(b), a.max(b)]);
        let (p0, p1) = (tool_end[a as usize], tool_end[b as usize]);
        let (s0, s1) = (tool_start[a as usize], tool_start[b as usize]);
        let travel = (p0 - s0).length().max((p1 - s1).length()) + margin;
        let reach = DVec3::splat(travel);
        let (lo, hi) = (p0.min(p1) - reach, p0.max(p1) + reach);
        // The walk below moves the tool edge at most `travel + moved`: a surface edge farther
        // from its box in any axis cannot cross it (nor can any, past all their bounds).
        if all_edges.0.cmpgt(hi).any() || lo.cmpgt(all_edges.1).any() {
            continue;
        }
        let e_dir = p1 - p0;
        let e_len2 = e_dir.length_squared();
        // Frictionless: a force along the tool's edge has no contact to act on.
        let Some(e_unit) = e_dir.try_normalize() else {
            continue;
        };
        for (&(q_lo, q_hi), &(i, j, q0, q1, f_dir, f_len2, n, moved)) in
            edge_boxes.iter().zip(&surface_edges)
        {
            if q_lo.cmpgt(hi).any() || lo.cmpgt(q_hi).any() {
                continue;
            }
            // Nearly parallel edges cross at no definite point: the tool's vertices and the
            // surface's own vertices carry such a contact. (|e × f| < sin |e| |f|, squared.)
            let sine2 = MIN_EDGE_SINE * MIN_EDGE_SINE;
            if e_dir.cross(f_dir).length_squared() < sine2 * e_len2 * f_len2 {
                continue;
            }
            // Along the triangle's normal less its part along the tool's edge.
            let Some(u) = (-(n - e_unit * e_unit.dot(n)))
                .try_normalize()
                .filter(|u| -u.dot(n) >= MIN_EDGE_NORMAL_COS)
            else {
                continue;
            };
            // Walking the tool edge back along -u by `depth` makes the edges cross.
            let Some((depth, alpha, beta, _)) =
                edge_edge(p0, p1, q0, q1, u, -(travel + moved), travel + moved)
            else {
                continue;
            };
            const INTERIOR: f64 = 1e-6;
            if !(INTERIOR..=1.0 - INTERIOR).contains(&alpha)
                || !(INTERIOR..=1.0 - INTERIOR).contains(&beta)
            {
                continue;
            }
            out.push(SurfaceContact {
                tool_feature: feature,
                surface: [(i, (1.0 - beta) as Real), (j, beta as Real), (0, 0.0)],
                count: 2,
                normal: u.as_vec3(),
                depth: depth as Real,
                point: (p0 + (p1 - p0) * alpha).as_vec3(),
            });
        }
    }
}
