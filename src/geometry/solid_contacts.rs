//! Contacts between a solid tool and a surface mesh, found at the tool's pose now (its
//! motion over the next substep only bounds how far to look): surface vertices inside the
//! tool or within its reach ([`vertex_contacts`], from the tool's boundary queries), and the
//! points of surface triangles nearest the tool or deepest in it ([`triangle_contacts`], from
//! parry's contact query). A point short of the tool is a speculative contact (negative
//! depth): it may close its gap over the substep, not pass the tool. The dynamic tools of
//! [`crate::coupling`] press the surface with these, besides their own vertices and edges
//! ([`super::tool_surface_contacts`]).

use super::tool_boundary::{distance_outside, faces_at, nearest_on_boundary, outward_normal};
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

/// A triangle contact whose normal's cosine with its triangle's normal is under this (its
/// normal within about 6° of the triangle's plane) pushes the triangle along that plane
/// ([`triangle_contacts`]).
const ALONG_PLANE: Real = 0.1;

/// The surface triangles (`candidates` of `triangles`, positions `positions`, surface frame) a
/// dynamic tool of `shape` at `pose` (surface frame; its material velocity at a point `tool`)
/// touches or may reach within `h`: parry's contact query between the tool and each
/// triangle, with a prediction distance of the reach over the substep, gives the point of the
/// triangle nearest the tool or deepest in it, pressed by barycentric weights along the
/// query's normal (a speculative contact while apart). A point on or near a vertex is left
/// to that vertex's contact (its depth `vertex_depth`, if it has one) unless it is deeper by
/// more than the tool's `slop` (within it neither is pushed out, and the two nearly repeat
/// each other in the solve), and
/// a point on an edge is taken once, from the triangle that gives it deepest (a point just
/// inside one triangle, snapped onto its edge, and the shallower point the triangle beyond
/// gives on that edge alternated from substep to substep as the first found, the normal
/// turning 0.7° each time: a dumbbell resting across two edges gained energy and slid off).
/// Shapes parry's contact query does not support give none. `unit_copy`: the tool's shape
/// scaled to unit size and the factor, where parry's query is asked ([`contact`]).
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
    unit_copy: Option<(Real, &dyn parry3d::shape::Shape)>,
    contacts: &mut Vec<SurfaceContact>,
    tool_velocities: &mut Vec<Vector>,
) {
    use parry3d::query::PointQueryWithLocation;
    use parry3d::shape::{Triangle, TrianglePointLocation};
    let first = contacts.len();
    let mut edges: Vec<([u32; 2], usize)> = Vec::new();
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
        let Some(c) = contact(shape, pose, &tri, reach, unit_copy) else {
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
        // An edge's point already taken from the triangle beyond: the deeper of the two is
        // kept (below), not the first found.
        let (mut key, mut replaces) = (None, None);
        if count == 2 {
            let mut k = [surface[0].0, surface[1].0];
            k.sort_unstable();
            if let Some(&(_, at)) = edges.iter().find(|(e, _)| *e == k) {
                if contacts[at].depth >= -c.dist {
                    continue;
                }
                replaces = Some(at);
            } else {
                key = Some(k);
            }
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
        // A penetration's normal must be the tool's where it touches it: a face's own normal
        // (within 10°) on a face or a curved boundary, a normal leaning the way of one of the
        // faces at an edge or a corner. parry's contact between a triangle mesh and a
        // triangle crossing one of its triangles is their deepest pair's, and two flat
        // triangles crossing each other can give any depth along any normal: a 34 g U resting
        // on its legs on a plate met a plate triangle 5.1 cm "deep" at a leg's inner wall
        // along a normal 33° off the vertical, into the leg, and was thrown off at 3.4 m/s;
        // an 86 g U met one 2.3 mm deep beside a leg's wall along a normal 53° up from the
        // horizontal, and was set turning at 0.4 rad/s.
        if -c.dist > margin + slop {
            let local = pose.inverse_transform_point(c.point1);
            let along = pose.rotation.inverse() * n;
            let faces = faces_at(shape, local, margin);
            let toward_tool = if faces.len() > 1 {
                faces.iter().any(|f| f.dot(along) > 0.0)
            } else {
                outward_normal(shape, local, margin).dot(along) > 0.985
            };
            // A triangle's point outside the tool that reads deeper than twice its distance
            // from it (and the tolerances) is left out: parry's deepest pair between a
            // triangle mesh and a triangle lying along one of its faces can be two crossing
            // flat triangles, and their depth any length. A 100 g U at rest on its legs met a
            // plate triangle whose edge lay along a leg's bottom face, read 5.6 cm deep (more
            // than the leg is wide) along the diagonal of the leg's vertical edge (in that
            // edge's cone, so the normal check lets it through), its point 1.2 cm outside the
            // U, between the legs; it was kicked to 0.5 m/s and 6.3 rad/s. A plate wrapped
            // round a leg's edge gives points outside about as far as they are deep, which
            // hold the U (asked to be inside the tool, a 3.2 kg U sunk in a 12.6 N/m plate
            // went through).
            let tolerance = margin + slop;
            let outside = distance_outside(shape, pose, c.point2);
            if outside > tolerance && -c.dist > 2.0 * outside + tolerance {
                continue;
            }
            // Nor, for a triangle mesh, a point pushed along its triangle's own plane (its
            // normal within 6° of the plane) deeper than twice its distance from the tool's
            // boundary: two nearly flat triangles crossing read as deep as the one reaches
            // along the other, while the triangle leaves the tool along its own normal at
            // about that distance. A plate triangle under a resting 11.8 g U, 2 um from the
            // boundary across the bottom edge of a leg, read 17.5 mm deep along the leg's side
            // face, in the plate's plane (the edge's cone lets the normal through); the U was
            // moved 6.9 mm sideways and 3 mm up and kept moving at 16 cm/s. (A plate wrapped
            // round a heavy U's leg in a funnel gives points deeper than twice that distance
            // too, along normals across their triangles, which hold the U.)
            if shape.as_trimesh().is_some()
                && tri.normal().is_some_and(|m| m.dot(n).abs() < ALONG_PLANE)
            {
                let boundary = shape.project_point(pose, c.point2, false).point;
                if -c.dist > 2.0 * (boundary - c.point2).length() + tolerance {
                    continue;
                }
            }
            if !toward_tool {
                continue;
            }
        }
        let material = tool(c.point1);
        if !material.is_finite() {
            continue;
        }
        let contact = SurfaceContact {
            tool_feature: Feature::Face(u32::MAX),
            surface,
            count,
            normal: n,
            depth: -c.dist,
            point: c.point1,
        };
        match replaces {
            Some(at) => {
                contacts[at] = contact;
                tool_velocities[at] = material;
            }
            None => {
                if let Some(k) = key {
                    edges.push((k, contacts.len()));
                }
                contacts.push(contact);
                tool_velocities.push(material);
            }
        }
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

/// parry's contact between the tool (`shape` at `pose`) and `tri` within `reach`, asked of
/// `unit` (the shape scaled by its factor) where there is one: in the tool's frame scaled by
/// the factor, its translation taken out (the answer is brought back to `pose`'s frame).
fn contact(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    tri: &parry3d::shape::Triangle,
    reach: Real,
    unit: Option<(Real, &dyn parry3d::shape::Shape)>,
) -> Option<parry3d::query::Contact> {
    use parry3d::shape::Triangle;
    let Some((k, scaled)) = unit else {
        return parry3d::query::contact(pose, shape, &Pose::IDENTITY, tri, reach).ok()?;
    };
    let o = pose.translation;
    let turned = Pose::from_parts(Vector::ZERO, pose.rotation);
    let near = Triangle::new((tri.a - o) * k, (tri.b - o) * k, (tri.c - o) * k);
    let mut c =
        parry3d::query::contact(&turned, scaled, &Pose::IDENTITY, &near, reach * k).ok()??;
    c.point1 = c.point1 / k + o;
    c.point2 = c.point2 / k + o;
    c.dist /= k;
    Some(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::shape::{Ball, Shape, Triangle};

    /// Two triangles sharing an edge, a ball whose nearest surface point lies just inside the
    /// second one (a weight under `SNAP` on its third vertex, so taken onto the edge), the
    /// triangle beyond listed first. The edge's contact is the deeper of the two triangles'
    /// points, whatever their order: its depth is the largest of parry's depths of the ball
    /// against each triangle (asked here directly), at scales from 0.1 mm to 1 km.
    #[test]
    fn an_edge_point_given_by_both_triangles_is_the_deeper_one() {
        for scale in [1e-4f32, 1.0, 1e3] {
            let positions = [
                Vector::new(0.0, 0.0, 0.0),
                Vector::new(1.0, 0.0, 0.0),
                Vector::new(0.0, 0.0, 1.0),
                Vector::new(0.0, 0.0, -1.0),
            ]
            .map(|p| p * scale);
            // (0, 1) is the shared edge; the ball's nearest point lies at z = 0.005 inside
            // triangle (0, 1, 2) (weight 0.005 on vertex 2), beyond triangle (0, 3, 1).
            let triangles = [[0, 3, 1], [0, 1, 2]];
            let radius = 0.2 * scale;
            let centre = Vector::new(0.3 * scale, radius - 1e-3 * scale, 0.005 * scale);
            let pose = Pose::from_translation(centre);
            let ball = Ball::new(radius);
            // Asked as it is, and of a unit ball scaled back (the path a small tool's unit
            // copy takes).
            let unit_ball = Ball::new(1.0);
            for (order, unit) in [[0u32, 1], [1, 0]].into_iter().flat_map(|o| {
                [
                    (o, None),
                    (o, Some((1.0 / radius, &unit_ball as &dyn Shape))),
                ]
            }) {
                let (mut contacts, mut velocities) = (Vec::new(), Vec::new());
                triangle_contacts(
                    &ball,
                    &pose,
                    |_| Vector::ZERO,
                    1e-3,
                    (&triangles, &order, &positions, |_| Vector::ZERO),
                    |_| None,
                    (1e-4 * scale, 1e-3 * scale),
                    unit,
                    &mut contacts,
                    &mut velocities,
                );
                let deepest = triangles
                    .iter()
                    .filter_map(|t| {
                        let tri = Triangle::new(
                            positions[t[0] as usize],
                            positions[t[1] as usize],
                            positions[t[2] as usize],
                        );
                        parry3d::query::contact(&pose, &ball, &Pose::IDENTITY, &tri, 0.0)
                            .ok()
                            .flatten()
                            .map(|c| -c.dist)
                    })
                    .fold(Real::NEG_INFINITY, Real::max);
                assert_eq!(
                    contacts.len(),
                    1,
                    "scale {scale}, order {order:?}: {contacts:?}"
                );
                let c = &contacts[0];
                assert_eq!(c.count, 2, "{c:?}");
                assert!(
                    (c.depth - deepest).abs() <= 1e-4 * deepest,
                    "scale {scale}, order {order:?}: {} against parry's {deepest}",
                    c.depth
                );
            }
        }
    }
}
