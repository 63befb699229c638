//! What the coupling needs of a tool's shape, built once when the tool is added: the shape
//! that answers the vertex holds' point queries, and the polyhedral parts whose vertices and
//! edges press the surface between its vertices.

use crate::geometry::TouchMesh;
use crate::math::{Pose, Real};
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
}

impl ToolShape {
    /// The coupling's view of `shape`. Curved and rounded shapes have no polyhedral part: the
    /// surface vertices they contain carry their contact.
    pub fn of(shape: &dyn Shape) -> Self {
        let mut parts = Vec::new();
        let query = match shape.as_compound() {
            Some(compound) => {
                let mut changed = false;
                let mut rebuilt = Vec::with_capacity(compound.shapes().len());
                for (pose, part) in compound.shapes() {
                    if let Some(mesh) = polyhedral(part.as_ref()) {
                        parts.push((*pose, mesh));
                    }
                    match oriented(part.as_ref()) {
                        Some(o) => {
                            changed = true;
                            rebuilt.push((*pose, o));
                        }
                        None => rebuilt.push((*pose, part.clone())),
                    }
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
        ToolShape { query, parts }
    }
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
