//! Contacts between a solid tool and a surface mesh, found at the tool's pose now (its
//! motion over the next substep only bounds how far to look): surface vertices inside the
//! tool or within its reach ([`vertex_contacts`], from the tool's boundary queries), and the
//! points of surface triangles nearest the tool or deepest in it ([`triangle_contacts`], from
//! parry's contact query). A point short of the tool is a speculative contact (negative
//! depth): it may close its gap over the substep, not pass the tool. The dynamic tools of
//! [`crate::coupling`] press the surface with these, besides their own vertices and edges
//! ([`super::tool_surface_contacts`]).

use super::tool_boundary::{distance_outside, nearest_on_boundary, outward_normal};
use super::{Feature, SurfaceContact};
use crate::math::{Pose, Real, Vector};

/// The surface vertices (`candidates`, positions `positions` and velocities `velocities`,
/// surface frame) a dynamic tool of `shape` at `pose` (surface frame) moving at `tool` (its
/// material point's velocity at a point, surface frame) holds or may reach within `h`: a
/// vertex inside it is pressed out to the nearest boundary point (its depth), one outside is
/// a speculative contact its gap away along the boundary's normal. Each is appended to
/// `contacts` as a one-vertex contact, with the tool's material velocity there.
#[allow(clippy::too_many_arguments)]
pub(crate) fn vertex_contacts(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    tool: impl Fn(Vector) -> Vector,
    h: Real,
    (candidates, positions, velocity): (&[u32], &[Vector], impl Fn(u32) -> Vector),
    margin: Real,
    contacts: &mut Vec<SurfaceContact>,
    tool_velocities: &mut Vec<Vector>,
) {
    for &i in candidates {
        let Some(&p) = positions.get(i as usize) else {
            continue;
        };
        let v = velocity(i);
        let gap = distance_outside(shape, pose, p);
        let q = nearest_on_boundary(shape, pose, p);
        let material = tool(q);
        // Within reach over the substep: the tool's point and the vertex closing at most at
        // their speeds (twice: a contact the tool reaches before the next look is pressed in,
        // which stores energy in the springs).
        let reach = 2.0 * h * (material.length() + v.length()) + margin;
        if gap > reach || !q.is_finite() || !material.is_finite() {
            continue;
        }
        let local = pose.inverse_transform_point(q);
        let n = if gap > margin {
            (p - q) / (p - q).length()
        } else {
            pose.rotation * outward_normal(shape, local, margin)
        };
        if !n.is_finite() || n == Vector::ZERO {
            continue;
        }
        let depth = if gap > 0.0 { -gap } else { (q - p).dot(n) };
        // A surface vertex against the tool's solid: no feature of a mesh of the tool.
        contacts.push(SurfaceContact {
            tool_feature: Feature::Face(u32::MAX),
            surface: [(i, 1.0), (i, 0.0), (i, 0.0)],
            count: 1,
            normal: n,
            depth,
            point: q,
        });
        tool_velocities.push(material);
    }
}

/// The weight below which a triangle contact's point is taken as on the edge opposite
/// ([`triangle_contacts`]).
const SNAP: Real = 1e-2;

/// A triangle contact's point with a weight above `1 - NEAR_VERTEX` on a vertex is left to
/// that vertex ([`triangle_contacts`]).
const NEAR_VERTEX: Real = 0.1;

/// The surface triangles (`candidates` of `triangles`, positions `positions`, surface frame) a
/// dynamic tool of `shape` at `pose` (surface frame; its material velocity at a point `tool`)
/// touches or may reach within `h`: parry's contact query between the tool and each
/// triangle, with a prediction distance of the reach over the substep, gives the point of the
/// triangle nearest the tool or deepest in it, pressed by barycentric weights along the
/// query's normal (a speculative contact while apart). A point on or near a vertex is left
/// to that vertex's contact (its depth `vertex_depth`, if it has one) unless it is deeper by
/// more than the tool's `slop` (within it neither is pushed out, and the two nearly repeat
/// each other in the solve), and
/// a point on an edge is taken once, from the first triangle that gives it. Shapes parry's contact query does not support give none.
#[allow(clippy::too_many_arguments)]
pub(crate) fn triangle_contacts(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    tool: impl Fn(Vector) -> Vector,
    h: Real,
    (triangles, candidates, positions, velocity): (
        &[[u32; 3]],
        &[u32],
        &[Vector],
        impl Fn(u32) -> Vector,
    ),
    vertex_depth: impl Fn(u32) -> Option<Real>,
    (margin, slop): (Real, Real),
    contacts: &mut Vec<SurfaceContact>,
    tool_velocities: &mut Vec<Vector>,
) {
    use parry3d::query::PointQueryWithLocation;
    use parry3d::shape::{Triangle, TrianglePointLocation};
    let first = contacts.len();
    let mut edges: Vec<[u32; 2]> = Vec::new();
    for &t in candidates {
        let Some(&idx) = triangles.get(t as usize) else {
            continue;
        };
        let Some(p) = idx
            .map(|v| positions.get(v as usize).copied())
            .into_iter()
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        let tri = Triangle::new(p[0], p[1], p[2]);
        let centroid = (p[0] + p[1] + p[2]) / 3.0;
        let own = idx
            .iter()
            .map(|&v| velocity(v).length())
            .fold(0.0, Real::max);
        let reach = 2.0 * h * (tool(centroid).length() + own) + margin;
        let Ok(Some(c)) = parry3d::query::contact(pose, shape, &Pose::IDENTITY, &tri, reach) else {
            continue;
        };
        let (_, location) = tri.project_local_point_and_get_location(c.point2, false);
        let weights = match location {
            TrianglePointLocation::OnVertex(_) => continue,
            TrianglePointLocation::OnEdge(..) | TrianglePointLocation::OnFace(..) => {
                let Some(w) = location.barycentric_coordinates() else {
                    continue;
                };
                w
            }
            _ => continue,
        };
        // A point near a vertex is left to that vertex's own contact ([`vertex_contacts`])
        // unless it is deeper by more than the slop: the triangles round a vertex at the bottom of a dent each gave
        // a point a few hundredths of an edge from it, with normals a degree or two apart, and
        // a ball resting there chattered on those near repeats (0.8 cm/s after 10 s, against
        // rest with the vertex alone). A weight under [`SNAP`] is left to the other two (the
        // edge's contact).
        let near = idx
            .iter()
            .zip(weights)
            .find(|(_, w)| *w >= 1.0 - NEAR_VERTEX)
            .map(|(v, _)| *v);
        if near
            .and_then(&vertex_depth)
            .is_some_and(|d| -c.dist <= d + slop)
        {
            continue;
        }
        let mut surface = [(idx[0], 0.0); 3];
        let mut count = 0;
        let kept: Real = weights.iter().filter(|&&w| w > SNAP).sum();
        for (v, w) in idx.iter().zip(weights) {
            if w > SNAP {
                surface[count] = (*v, w / kept);
                count += 1;
            }
        }
        if count == 2 {
            let mut key = [surface[0].0, surface[1].0];
            key.sort_unstable();
            if edges.contains(&key) {
                continue;
            }
            edges.push(key);
        }
        // parry gives a zero normal where the two touch exactly (distance 0): no direction
        // to press along, so no contact (the vertices' own contacts carry it). Pressed, its
        // zero normal was an invalid press that cost every press of the substep: a 12 g U
        // resting on a plate lost all support for a step and fell 2.7 mm into it.
        let n = c.normal1;
        let unit = (n.length() - 1.0).abs() < 1e-3;
        if count == 0 || !unit || !c.dist.is_finite() {
            continue;
        }
        let material = tool(c.point1);
        if !material.is_finite() {
            continue;
        }
        contacts.push(SurfaceContact {
            tool_feature: Feature::Face(u32::MAX),
            surface,
            count,
            normal: n,
            depth: -c.dist,
            point: c.point1,
        });
        tool_velocities.push(material);
    }
    // A point on an edge that a triangle on that edge meets as deep or deeper inside is that
    // triangle's: the tool is nearest the triangle's face, and the edge's point (from the
    // triangle beyond) is on the face's rim. Kept, the two rows and the face's nearly repeat
    // each other in the solve, which leaves the face's out while it is pushed in (a ball
    // resting across two edges of a triangle sank 0.2 mm into its face, and the surface, moved
    // out of it at every substep past the slop, pumped energy into the ball).
    let mut k = first;
    for i in first..contacts.len() {
        let c = &contacts[i];
        let inside_deeper = c.count == 2
            && contacts[first..].iter().any(|f| {
                f.count == 3
                    && f.depth >= c.depth
                    && c.weights()
                        .iter()
                        .all(|(v, _)| f.weights().iter().any(|(u, _)| u == v))
            });
        if !inside_deeper {
            contacts.swap(k, i);
            tool_velocities.swap(k, i);
            k += 1;
        }
    }
    contacts.truncate(k);
    tool_velocities.truncate(k);
}
