//! What the coupling needs of a tool's shape, built once when the tool is added: the shape
//! that answers the vertex holds' point queries, and the polyhedral parts whose vertices and
//! edges press the surface between its vertices.

use crate::geometry::TouchMesh;
use crate::math::{Pose, Real, Vector};
use parry3d::shape::{Shape, SharedShape, TriMeshFlags};

/// A tool's shape as the coupling uses it.
#[derive(Debug, Default)]
pub(super) struct ToolShape {
    /// Answers "is this surface vertex inside, and where is the nearest boundary point" when
    /// the collider's own shape cannot: an oriented copy of a triangle mesh (parry tells inside
    /// from outside only for an oriented mesh), the same for a compound's triangle-mesh parts.
    /// `None`: the collider's shape answers.
    pub query: Option<SharedShape>,
    /// The polyhedral parts (cuboids, convex polyhedra, triangle meshes; a compound's parts
    /// each), with their pose in the tool's frame.
    pub parts: Vec<(Pose, TouchMesh)>,
    /// A compound's parts (oriented copies of its triangle meshes), with their pose in the
    /// tool's frame, and for each of `parts` its place among them: a polyhedral part's vertex
    /// or edge inside another part is not on the tool's boundary ([`ToolShape::covered`]).
    /// Empty for a shape that is not a compound of two parts or more.
    cover: Vec<(Pose, SharedShape)>,
    part_of: Vec<usize>,
    /// The query shape scaled to a unit bounding radius, and the factor, for a tool under a
    /// metre across (`None` otherwise, for a ball, or where parry cannot scale the shape):
    /// parry's contact queries are asked of it
    /// ([`crate::geometry::solid_contacts::triangle_contacts`]).
    pub unit: Option<(Real, SharedShape)>,
}

impl ToolShape {
    /// The coupling's view of `shape`. Curved and rounded shapes have no polyhedral part: the
    /// surface vertices they contain carry their contact.
    pub fn of(shape: &dyn Shape) -> Self {
        let mut parts = Vec::new();
        let (mut cover, mut part_of) = (Vec::new(), Vec::new());
        let query = match shape.as_compound() {
            Some(compound) => {
                let mut changed = false;
                let mut rebuilt = Vec::with_capacity(compound.shapes().len());
                for (k, (pose, part)) in compound.shapes().iter().enumerate() {
                    if let Some(mesh) = polyhedral(part.as_ref()) {
                        parts.push((*pose, mesh));
                        part_of.push(k);
                    }
                    match oriented(part.as_ref()) {
                        Some(o) => {
                            changed = true;
                            rebuilt.push((*pose, o));
                        }
                        None => rebuilt.push((*pose, part.clone())),
                    }
                }
                if rebuilt.len() > 1 {
                    cover.clone_from(&rebuilt);
                } else {
                    part_of.clear();
                }
                changed.then(|| SharedShape::compound(rebuilt))
            }
            None => {
                if let Some(mesh) = polyhedral(shape) {
                    parts.push((Pose::IDENTITY, mesh));
                }
                oriented(shape)
            }
        };
        let unit = unit_sized(query.as_deref().unwrap_or(shape));
        ToolShape {
            query,
            parts,
            cover,
            part_of,
            unit,
        }
    }

    /// Whether the tool is a compound of two parts or more ([`ToolShape::covered`]).
    pub fn is_compound(&self) -> bool {
        !self.cover.is_empty()
    }

    /// Whether `point` (the tool's frame) lies inside a part of the compound other than
    /// polyhedral part `part`'s, more than `margin` from that part's boundary: a vertex or edge
    /// of `part` there is inside the tool, not on its boundary, and makes no contact. A
    /// dumbbell's bar ends inside its balls: a 4.2 kg dumbbell landing at 6.2 m/s on a stiff
    /// plate had the plate pass a bar's end edges inside a ball within the substep, their
    /// contacts' normals across the bar, and was pushed out of them by a turn about its long
    /// axis, its cheapest (0.22 rad in a substep): it spun at 24 rad/s for good.
    pub fn covered(&self, part: usize, point: Vector, margin: Real) -> bool {
        let own = self.part_of.get(part).copied();
        self.cover.iter().enumerate().any(|(k, (pose, shape))| {
            if Some(k) == own {
                return false;
            }
            let local = pose.inverse_transform_point(point);
            let projection = shape.project_local_point(local, false);
            projection.is_inside && (projection.point - local).length() > margin
        })
    }
}

/// `shape` scaled to a unit bounding radius, and the factor, if it is under a metre across
/// and parry scales it to the size asked (its round shapes' borders included).
///
/// parry's GJK takes two shapes closer than an absolute 10 `f32::EPSILON` (1.2e-6) for
/// touching and hands them to EPA, whose normal there is any: for a tool a millimetre across
/// that is twelve times its contact margin (a ten-thousandth of its size). Dropped onto a
/// plate scaled with them (gravity, masses and stiffnesses too), a U of triangles 1.6 mm
/// across (17 substeps) and 0.16 mm across (1 substep), and a cube 16 µm across, went through
/// it where the same scene at 1 m comes to rest (`tests/it/dynamic_scales.rs`).
///
/// A ball is left as it is: parry answers a ball against a triangle in closed form.
fn unit_sized(shape: &dyn Shape) -> Option<(Real, SharedShape)> {
    if shape.as_ball().is_some() {
        return None;
    }
    let radius = shape.compute_local_bounding_sphere().radius;
    if !(radius > 0.0 && radius < 0.5) {
        return None;
    }
    let k = 1.0 / radius;
    let scaled = shape.scale_dyn(crate::math::Vector::splat(k), 16)?;
    let got = scaled.compute_local_bounding_sphere().radius;
    ((got - 1.0).abs() < 1e-3 && k.is_finite()).then(|| (k, SharedShape(scaled.into())))
}

/// The touch mesh of a polyhedral shape (cuboid, convex polyhedron, triangle mesh).
fn polyhedral(shape: &dyn Shape) -> Option<TouchMesh> {
    let polyhedral = shape.as_cuboid().is_some()
        || shape.as_convex_polyhedron().is_some()
        || shape.as_trimesh().is_some();
    if !polyhedral {
        return None;
    }
    TouchMesh::from_shape(shape).ok()
}

/// An oriented copy of a triangle mesh that is not oriented (`None` for any other shape, an
/// oriented mesh, or one parry cannot orient: it then answers as the collider's shape does).
fn oriented(shape: &dyn Shape) -> Option<SharedShape> {
    let mesh = shape.as_trimesh()?;
    if mesh.flags().contains(TriMeshFlags::ORIENTED) {
        return None;
    }
    SharedShape::trimesh_with_flags(
        mesh.vertices().to_vec(),
        mesh.indices().to_vec(),
        mesh.flags() | TriMeshFlags::ORIENTED,
    )
    .ok()
}

/// The contact tolerance for a tool whose bounds are `aabb`: `fraction` of its size, plus a
/// few f32 steps of its coordinates (a tool far from the origin cannot place points closer
/// than that). Relative, with no absolute floor: the tolerances were `f × (1 m + size)` with a
/// hundredth of today's fractions, the same on a centimetre tool, but a micrometre on a
/// 0.1 mm one (a tenth of a typical press there).
pub(super) fn contact_margin(aabb: &parry3d::bounding_volume::Aabb, fraction: Real) -> Real {
    let size = aabb.extents().max_element();
    let reach = aabb.mins.abs().max(aabb.maxs.abs()).max_element();
    let margin = fraction * size + 8.0 * Real::EPSILON * reach;
    if margin.is_finite() && margin > 0.0 {
        margin
    } else {
        Real::MIN_POSITIVE
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dumbbell's bar (a cuboid from one ball's centre to the other's): its end corners lie
    /// inside the balls, its middle edges outside them (by the distance to the balls' centres).
    #[test]
    fn a_bar_is_covered_where_it_lies_inside_a_ball() {
        let (r, rb) = (0.08, 0.05);
        let ball = SharedShape::ball(rb);
        let bar = SharedShape::cuboid(r, 0.01, 0.01);
        let parts = vec![
            (Pose::translation(-r, 0.0, 0.0), ball.clone()),
            (Pose::translation(r, 0.0, 0.0), ball),
            (Pose::IDENTITY, bar),
        ];
        let shape = ToolShape::of(&*SharedShape::compound(parts));
        assert!(shape.is_compound());
        assert_eq!(shape.parts.len(), 1, "only the bar is polyhedral");
        let margin = 1e-4;
        for x in [-r, -0.5 * r, 0.0, 0.5 * r, r] {
            for (y, z) in [(-0.01, -0.01), (0.01, -0.01), (-0.01, 0.01), (0.01, 0.01)] {
                let p = Vector::new(x, y, z);
                let deep_in_a_ball = [-r, r]
                    .iter()
                    .any(|&c| (p - Vector::new(c, 0.0, 0.0)).length() < rb - margin);
                assert_eq!(shape.covered(0, p, margin), deep_in_a_ball, "{p:?}");
            }
        }
        // A single shape covers nothing.
        let single = ToolShape::of(&*SharedShape::cuboid(r, 0.01, 0.01));
        assert!(!single.is_compound());
        assert!(!single.covered(0, Vector::ZERO, margin));
    }
}
