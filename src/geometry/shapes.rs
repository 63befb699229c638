//! [`TouchMesh::from_shape`]: the triangle surface of every parry shape that has a finite one.

use super::generators::MeshBuffers;
use super::hull::convex_hull;
use super::touch_mesh::{TouchMesh, TouchMeshError};
use crate::math::{Real, Vector};
use parry3d::bounding_volume::Aabb;
use parry3d::shape::{Shape, TypedShape};
use parry3d::utils::hashmap::HashMap;

/// Subdivisions of the curved shapes (parry's `to_trimesh` arguments).
const BALL_SUBDIV: (u32, u32) = (16, 16);
const CAPSULE_SUBDIV: (u32, u32) = (16, 8);
const CIRCLE_SUBDIV: u32 = 24;
/// Grid steps per octant edge of the sphere sample that rounds the round shapes: `4 n² + 2`
/// directions (402), the axes among them.
const SPHERE_STEPS: i32 = 10;
/// `1 - min_d max_s s·d` of that sample: its hull reaches `1 - 0.0096` of the unit sphere in
/// every direction (checked by `sphere_sample_covers_the_sphere` below); rounded up.
const SPHERE_GAP: Real = 0.0125;

/// A border radius below this fraction of the inner shape's size is left out: the sampled
/// offsets would be closer than the weld tolerance of [`TouchMesh::new`].
const MIN_BORDER: Real = 1.0e-4;

const CURVE: &str = "a curve has no surface: thicken it (a capsule or a round shape per segment)";

impl TouchMesh {
    /// Builds a touch mesh from any parry shape with a finite surface (the shapes a rapier
    /// collider can have), welded as in [`TouchMesh::new`]:
    ///
    /// | shape | mesh | distance to the true surface |
    /// |---|---|---|
    /// | `TriMesh`, `Triangle` (open), `HeightField` (open), `Voxels` (free voxel faces) | their triangles | exact |
    /// | `Cuboid` | 12 triangles | exact |
    /// | `ConvexPolyhedron` | the convex hull of its points¹ (not parry's `to_trimesh`, whose merged faces are not planar) | exact² |
    /// | `Ball` | 16 × 16 UV sphere | vertices on it, faces up to `0.025 r` inside |
    /// | `Capsule` | 16 × 8 per cap | vertices on it, faces up to `0.04 r` inside |
    /// | `Cylinder`, `Cone` | 24-gon sections | vertices on it, faces up to `0.0086 r` inside |
    /// | `RoundCuboid`, `RoundTriangle`, `RoundConvexPolyhedron`, `RoundCylinder`, `RoundCone` | see below | inside, within `0.0125 b` (plus `0.0086 r` for the cylinder and the cone)² |
    /// | `Compound` | every part, moved by its pose, in one mesh | as its parts |
    ///
    /// (`r`: the radius, `b`: the border radius.) A round shape is the convex hull¹ of its
    /// inner shape's vertices (the 24-gon sections for a cylinder or a cone) each moved by `b`
    /// along 402 directions of the sphere (the axes among them). It lies inside the true
    /// rounded shape, and every point of either surface is within `0.0125 b` of the other (plus
    /// the `0.0086 r` of the inner 24-gons); flat faces of a rounded box stay exact. A border
    /// radius below `1e-4 ×` the inner shape's size is left out (an error of at most `b`):
    /// its offsets would be closer together than the weld tolerance.
    ///
    /// ¹ Computed with exact orientation predicates (parry's `f32` quickhull takes points within
    /// `1.2e-5 ×` the diagonal of a face as on it, and fails on the clustered points of round
    /// shapes). If it fails (a flat polyhedron), a `ConvexPolyhedron` falls back to its
    /// `to_trimesh`. ² A hull vertex within `1e-6 ×` the largest extent of the line through two
    /// others would make a flat triangle that [`TouchMesh::new`] drops; it is left out, moving
    /// the surface by at most that much.
    ///
    /// A compound's parts are simply merged: overlapping parts give a self-intersecting,
    /// non-manifold mesh (a *shell*, see [`TouchMesh`]), and a compound of several closed
    /// parts is not judged convex (it takes the general search).
    ///
    /// ```
    /// use rapier_touch::parry3d::shape::SharedShape;
    /// use rapier_touch::prelude::*;
    /// let rounded = SharedShape::round_cuboid(0.5, 0.2, 0.3, 0.05);
    /// let mesh = TouchMesh::from_shape(rounded.as_ref()).unwrap();
    /// assert!(mesh.is_convex());
    /// let aabb = mesh.local_aabb();
    /// assert!((aabb.maxs - Vector::new(0.55, 0.25, 0.35)).length() < 1e-6);
    /// ```
    ///
    /// # Errors
    /// [`TouchMeshError::UnsupportedShape`] for the shapes with no finite surface: `HalfSpace`
    /// (infinite), `Segment` and `Polyline` (curves) and `Custom` shapes (unknown to the crate:
    /// mesh them yourself and use [`TouchMesh::new`]);
    /// [`TouchMeshError::UnsupportedCompoundPart`] for a compound with such a part; and the
    /// errors of [`TouchMesh::new`] (an empty height field or voxel set is
    /// [`TouchMeshError::Empty`]).
    pub fn from_shape(shape: &dyn Shape) -> Result<Self, TouchMeshError> {
        let (v, i) = shape_buffers(shape)?;
        Self::new(v, i)
    }
}

/// The vertex and index buffers of `shape`'s surface (see [`TouchMesh::from_shape`]).
fn shape_buffers(shape: &dyn Shape) -> Result<MeshBuffers, TouchMeshError> {
    let unsupported = |reason| {
        Err(TouchMeshError::UnsupportedShape {
            shape: shape.shape_type(),
            reason,
        })
    };
    Ok(match shape.as_typed_shape() {
        TypedShape::TriMesh(m) => (m.vertices().to_vec(), m.indices().to_vec()),
        TypedShape::Triangle(t) => (t.vertices().to_vec(), vec![[0, 1, 2]]),
        TypedShape::HeightField(h) => h.to_trimesh(),
        TypedShape::Voxels(v) => v.to_trimesh(),
        TypedShape::Cuboid(c) => c.to_trimesh(),
        TypedShape::ConvexPolyhedron(c) => match convex_hull(c.points()) {
            // Indices into the polyhedron's points: `Feature::Vertex(i)` names `c.points()[i]`.
            Ok(tris) => (c.points().to_vec(), tris),
            Err(_) => c.to_trimesh(),
        },
        TypedShape::Ball(b) => b.to_trimesh(BALL_SUBDIV.0, BALL_SUBDIV.1),
        TypedShape::Capsule(c) => c.to_trimesh(CAPSULE_SUBDIV.0, CAPSULE_SUBDIV.1),
        TypedShape::Cylinder(c) => c.to_trimesh(CIRCLE_SUBDIV),
        TypedShape::Cone(c) => c.to_trimesh(CIRCLE_SUBDIV),
        TypedShape::RoundCuboid(r) => rounded(r.inner_shape.to_trimesh(), r.border_radius)?,
        TypedShape::RoundTriangle(r) => {
            let inner = (r.inner_shape.vertices().to_vec(), vec![[0, 1, 2]]);
            rounded(inner, r.border_radius)?
        }
        TypedShape::RoundConvexPolyhedron(r) => {
            let inner = hull(r.inner_shape.points()).unwrap_or_else(|_| r.inner_shape.to_trimesh());
            rounded(inner, r.border_radius)?
        }
        TypedShape::RoundCylinder(r) => {
            rounded(r.inner_shape.to_trimesh(CIRCLE_SUBDIV), r.border_radius)?
        }
        TypedShape::RoundCone(r) => {
            rounded(r.inner_shape.to_trimesh(CIRCLE_SUBDIV), r.border_radius)?
        }
        TypedShape::Compound(c) => {
            let (mut v, mut idx) = (Vec::new(), Vec::new());
            for (k, (pose, part)) in c.shapes().iter().enumerate() {
                let (pv, pi) = shape_buffers(part.as_ref()).map_err(|e| match e {
                    TouchMeshError::UnsupportedShape { shape, reason } => {
                        TouchMeshError::UnsupportedCompoundPart {
                            part: k as u32,
                            shape,
                            reason,
                        }
                    }
                    e => e,
                })?;
                let base = v.len() as u32;
                v.extend(pv.into_iter().map(|p| pose.transform_point(p)));
                idx.extend(pi.into_iter().map(|t| t.map(|i| i + base)));
            }
            (v, idx)
        }
        TypedShape::HalfSpace(_) => {
            return unsupported("a half-space is infinite: use a large cuboid or a TriMesh floor")
        }
        TypedShape::Segment(_) | TypedShape::Polyline(_) => return unsupported(CURVE),
        TypedShape::Custom(_) => {
            return unsupported(
                "a custom shape is unknown to the crate: mesh it yourself and use TouchMesh::new",
            )
        }
    })
}

/// The convex hull of `points` ([`super::hull`]), its vertices compacted.
fn hull(points: &[Vector]) -> Result<MeshBuffers, TouchMeshError> {
    let tris = convex_hull(points)
        .map_err(|e| TouchMeshError::Parry(format!("convex hull failed: {e:?}")))?;
    let mut new_index = HashMap::default();
    let mut v = Vec::new();
    let tris = tris
        .iter()
        .map(|t| {
            t.map(|k| {
                *new_index.entry(k).or_insert_with(|| {
                    v.push(points[k as usize]);
                    v.len() as u32 - 1
                })
            })
        })
        .collect();
    Ok((v, tris))
}

/// Directions `(i, j, k) / |(i, j, k)|` with `|i| + |j| + |k| = SPHERE_STEPS`: the vertices of
/// an octahedron whose faces are split into a grid, projected on the unit sphere.
fn sphere_sample() -> Vec<Vector> {
    let n = SPHERE_STEPS;
    let mut dirs = Vec::with_capacity((4 * n * n + 2) as usize);
    for i in -n..=n {
        for j in -(n - i.abs())..=(n - i.abs()) {
            let k = n - i.abs() - j.abs();
            for k in if k == 0 { vec![0] } else { vec![k, -k] } {
                dirs.push(Vector::new(i as Real, j as Real, k as Real).normalize());
            }
        }
    }
    dirs
}

/// The convex hull of `inner`'s vertices each moved by `radius` along every direction of
/// [`sphere_sample`]: a polytope inside the inner shape's Minkowski sum with the ball of that
/// radius (see [`TouchMesh::from_shape`] for the error).
///
/// Offsets that cannot be hull vertices are skipped: `p + r s` is one only if some `d` has `p`
/// as the inner support point and `s` as the sample's, so `d·(q - p) ≤ 0` for every inner
/// vertex `q`, and `|s - d| ≤ √(2 SPHERE_GAP)`, hence `s·(q - p) ≤ √(2 SPHERE_GAP) |q - p|`
/// (checked over the mesh neighbours `q` of `p`).
fn rounded(inner: MeshBuffers, radius: Real) -> Result<MeshBuffers, TouchMeshError> {
    let (iv, ii) = inner;
    let size = Aabb::from_points(iv.iter().copied()).extents().length();
    if radius.is_nan() || radius <= MIN_BORDER * size {
        return Ok((iv, ii));
    }
    let mut neighbours = vec![Vec::new(); iv.len()];
    for t in &ii {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            neighbours[a as usize].push(b);
            neighbours[b as usize].push(a);
        }
    }
    let slack = (2.0 * SPHERE_GAP).sqrt();
    let sample = sphere_sample();
    let mut points = Vec::new();
    for (p, nb) in iv.iter().zip(&neighbours) {
        if nb.is_empty() {
            continue;
        }
        for s in &sample {
            let may_be_vertex = nb.iter().all(|&q| {
                let e = iv[q as usize] - *p;
                s.dot(e) <= slack * e.length()
            });
            if may_be_vertex {
                points.push(*p + *s * radius);
            }
        }
    }
    hull(&points)
}

/// How far a point of `shape` can be from the shape's origin: the distance to its bounding
/// sphere's centre plus the sphere's radius (the centre of a convex hull's sphere is not its
/// origin).
pub(crate) fn shape_reach(shape: &dyn Shape) -> Real {
    let sphere = shape.compute_local_bounding_sphere();
    sphere.center.length() + sphere.radius
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent check of `SPHERE_GAP`: over a 201 × 201 grid of directions on one octant
    /// (the sample is symmetric under the octant reflections), the sample's support stays
    /// above `1 - SPHERE_GAP`, and the measured gap is the documented `0.0096`.
    #[test]
    fn sphere_sample_covers_the_sphere() {
        let s = sphere_sample();
        assert_eq!(s.len(), 402);
        let support = |d: Vector| s.iter().map(|p| p.dot(d)).fold(Real::MIN, Real::max);
        let mut worst = (Real::MAX, Vector::X);
        let m = 200;
        for a in 0..=m {
            for b in 0..=m {
                let (th, ph) = (
                    std::f32::consts::FRAC_PI_2 * a as Real / m as Real,
                    std::f32::consts::FRAC_PI_2 * b as Real / m as Real,
                );
                let d = Vector::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                let h = support(d);
                if h < worst.0 {
                    worst = (h, d);
                }
            }
        }
        assert!(worst.0 > 1.0 - 0.0097, "{worst:?}");
        assert!(
            worst.0 < 1.0 - 0.009,
            "{worst:?}: the gap is not overstated by much"
        );
        assert!(1.0 - worst.0 < SPHERE_GAP);
    }
}
