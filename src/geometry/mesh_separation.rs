//! Whether a convex shape is apart from a TriMesh, triangle by triangle, by separating axes.
//!
//! parry answers this with its composite intersection test: it walks the mesh's BVH and runs
//! a full separating-axis search of the shape against each triangle the shape's box meets,
//! until one intersects. A shape found apart (the answer the step guard asks about when it
//! lifts a resting body off a TriMesh floor) costs a full search per triangle, each through
//! the shapes' generic support maps. Hand-written here because a bench shows it wins: on
//! rapier's TriMesh-floor stress scene (cuboids and balls on a height field) parry's test was
//! a sixth of the step guard's time, and this one takes the scene's touch step from 1.52-1.54×
//! vanilla rapier to 1.47-1.51× (alternated binaries, `stress_scenes 300 trimesh_floor`).
//!
//! Per triangle, cheapest first: one shared axis (the direction the caller cares about, so the
//! shape's extreme point along it is one support query for all triangles), the triangle's
//! normal, and for a cuboid the rest of the box-triangle axes (its three faces, then the nine
//! crossings of a box edge with a triangle edge: Akenine-Möller's test, in the box's frame).
//! A triangle none of them separates is handed to parry's own triangle test (other shapes),
//! or is intersecting (a cuboid: the thirteen axes are all a box and a triangle can be
//! separated along).

use crate::math::{Pose, Vector};
use parry3d::shape::{Cuboid, Shape, TriMesh, Triangle};

/// Whether `shape` (posed at `rel` in `mesh`'s frame; it must have a support map) is apart from
/// every triangle of `mesh`: no point in common, touching counts as meeting. `axis` (in
/// `mesh`'s frame, any length) is tried first on every triangle; the direction a shape was
/// moved apart along is a good one. `false` for a shape with no support map or a pose that is
/// not finite (the caller measures such pairs another way).
pub(crate) fn apart_from_mesh(mesh: &TriMesh, shape: &dyn Shape, rel: &Pose, axis: Vector) -> bool {
    let Some(sm) = shape.as_support_map() else {
        return false;
    };
    let aabb = shape.compute_aabb(rel);
    if !aabb.mins.is_finite() || !aabb.maxs.is_finite() {
        return false;
    }
    let up = axis.try_normalize();
    let lowest = up.map(|u| sm.support_point_toward(rel, -u).dot(u));
    let cuboid = shape.as_cuboid();
    let inv = rel.inverse();
    let apart = mesh.bvh().intersect_aabb(&aabb).all(|i| {
        let tri = mesh.triangle(i);
        if let (Some(u), Some(low)) = (up, lowest) {
            if tri.a.dot(u).max(tri.b.dot(u)).max(tri.c.dot(u)) < low {
                return true;
            }
        }
        if let Some(m) = tri.normal() {
            // The triangle's plane, on the side the shape lies (either side separates).
            let plane = tri.a.dot(m);
            if sm.support_point_toward(rel, -m).dot(m) > plane
                || sm.support_point_toward(rel, m).dot(m) < plane
            {
                return true;
            }
        }
        match cuboid {
            Some(c) => {
                box_apart_from_triangle(c, &Triangle::new(inv * tri.a, inv * tri.b, inv * tri.c))
            }
            None => parry3d::query::intersection_test(&Pose::IDENTITY, &tri, rel, shape)
                .is_ok_and(|r| !r.intersecting),
        }
    });
    apart
}

/// Whether the box `c` (centred at the origin, axis-aligned) and the triangle `tri` (in the
/// box's frame) are separated along a box face's normal or along the crossing of a box edge
/// with a triangle edge (the triangle's own normal is the caller's). Strict: touching is not
/// apart.
fn box_apart_from_triangle(c: &Cuboid, tri: &Triangle) -> bool {
    let h = c.half_extents;
    let (lo, hi) = (tri.a.min(tri.b).min(tri.c), tri.a.max(tri.b).max(tri.c));
    if lo.cmpgt(h).any() || hi.cmplt(-h).any() {
        return true;
    }
    let edges = [tri.b - tri.a, tri.c - tri.b, tri.a - tri.c];
    let units = [Vector::X, Vector::Y, Vector::Z];
    edges.iter().any(|e| {
        units.iter().any(|u| {
            let axis = u.cross(*e);
            let r = h.dot(axis.abs());
            let (pa, pb, pc) = (tri.a.dot(axis), tri.b.dot(axis), tri.c.dot(axis));
            let (min, max) = (pa.min(pb).min(pc), pa.max(pb).max(pc));
            // A zero axis (an edge along a box axis, or a degenerate edge) separates nothing.
            r > 0.0 && (min > r || max < -r)
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Real, Rotation};

    /// The largest of `v`'s components' magnitudes (a scale for rounding).
    fn scale_of(v: Vector) -> Real {
        v.abs().max_element()
    }

    /// A small height field's triangles (3 × 3 cells, 1 m each, bumps of `bump` m).
    fn hills(bump: Real) -> TriMesh {
        let n = 3;
        let mut heights = parry3d::utils::Array2::repeat(n + 1, n + 1, 0.0);
        for i in 0..=n {
            for j in 0..=n {
                heights[(i, j)] = bump * ((1.7 * i as Real).sin() + (2.3 * j as Real).cos());
            }
        }
        let (v, idx) =
            parry3d::shape::HeightField::new(heights, Vector::new(3.0, 1.0, 3.0)).to_trimesh();
        TriMesh::new(v, idx).expect("a height field's triangles")
    }

    /// Against parry's distance and contact queries, on a bumpy mesh at 1 mm, 1 m and 1 km, for
    /// a cuboid, a ball, a capsule and a cone at poses from far above down into the mesh,
    /// turned every way: apart wherever parry's distance is more than a rounding, meeting
    /// wherever its contact depth is, and both answers given many times (a test that cannot
    /// fail either way proves nothing). (Not against parry's intersection test itself: its GJK
    /// tolerance is absolute, and at 1 mm it finds a capsule 0.5 mm above the mesh meeting it.)
    #[test]
    fn answers_as_parrys_distance_and_depth() {
        let shapes: [Box<dyn Shape>; 4] = [
            Box::new(parry3d::shape::Cuboid::new(Vector::new(0.4, 0.15, 0.3))),
            Box::new(parry3d::shape::Ball::new(0.3)),
            Box::new(parry3d::shape::Capsule::new_y(0.2, 0.1)),
            Box::new(parry3d::shape::Cone::new(0.2, 0.3)),
        ];
        let (mut apart, mut meeting) = (0, 0);
        for scale in [1e-3, 1.0, 1e3] {
            for bump in [0.0, 0.2, 0.6] {
                let mesh = hills(bump).scaled(Vector::splat(scale));
                for (s, shape) in shapes.iter().enumerate() {
                    let shape = shape.scale_dyn(Vector::splat(scale), 8).expect("scaled");
                    for k in 0..300 {
                        let t = k as Real;
                        let rot = Rotation::from_axis_angle(
                            Vector::new((0.7 * t).sin(), 1.0 + s as Real, (1.3 * t).cos())
                                .normalize(),
                            0.37 * t,
                        );
                        let at = Vector::new(
                            0.2 + 2.6 * ((0.31 * t).sin() * 0.5 + 0.5),
                            -0.6 + 1.1 * ((0.13 * t + s as Real).cos() * 0.5 + 0.5),
                            0.2 + 2.6 * ((0.53 * t).cos() * 0.5 + 0.5),
                        ) * scale;
                        let rel = Pose::from_parts(at, rot);
                        let axis = Vector::new((0.2 * t).sin(), 1.0, 0.3);
                        let ours = apart_from_mesh(&mesh, &*shape, &rel, axis);
                        let dist = parry3d::query::distance(&Pose::IDENTITY, &mesh, &rel, &*shape)
                            .unwrap()
                            .distance;
                        let depth =
                            parry3d::query::contact(&Pose::IDENTITY, &mesh, &rel, &*shape, 0.0)
                                .unwrap()
                                .map_or(0.0, |c| -c.dist);
                        let rounding = 1e-4 * scale.max(scale_of(at));
                        if dist > rounding || depth > rounding {
                            assert_eq!(
                                ours,
                                dist > rounding,
                                "shape {s} scale {scale} bump {bump} pose {k}: distance {dist}, \
                                 depth {depth}"
                            );
                        }
                        if ours {
                            apart += 1;
                        } else {
                            meeting += 1;
                        }
                    }
                }
            }
        }
        assert!(
            apart > 1000 && meeting > 1000,
            "{apart} apart, {meeting} meeting"
        );
    }

    /// The box-triangle axes alone, against parry's cuboid-triangle test, on triangles of every
    /// tilt and size around a box (so that the crossing axes decide many of them).
    #[test]
    fn the_box_axes_agree_with_parrys_box_triangle_test() {
        let c = Cuboid::new(Vector::new(0.5, 0.2, 0.3));
        let (mut separated, mut not) = (0, 0);
        for k in 0..4000 {
            let t = k as Real;
            let p = |f: Real| {
                Vector::new(
                    1.5 * (f * 1.1 * t).sin(),
                    1.0 * (f * 0.7 * t + 1.0).cos(),
                    1.5 * (f * 1.9 * t + 2.0).sin(),
                )
            };
            let tri = Triangle::new(p(0.013), p(0.029), p(0.041));
            let dist = parry3d::query::distance(&Pose::IDENTITY, &c, &Pose::IDENTITY, &tri)
                .unwrap()
                .distance;
            let parry_apart =
                !parry3d::query::intersection_test(&Pose::IDENTITY, &c, &Pose::IDENTITY, &tri)
                    .unwrap()
                    .intersecting;
            let normal_separates = tri.normal().is_some_and(|m| {
                let r = c.half_extents.dot(m.abs());
                (tri.a.dot(m)).abs() > r
            });
            let ours = normal_separates || box_apart_from_triangle(&c, &tri);
            if dist > 1e-5 || !parry_apart {
                assert_eq!(ours, parry_apart, "triangle {k}: distance {dist}");
            }
            if box_apart_from_triangle(&c, &tri) && !normal_separates {
                separated += 1;
            } else if !ours {
                not += 1;
            }
        }
        assert!(
            separated > 100 && not > 100,
            "{separated} by the box axes, {not} meeting"
        );
    }

    /// Bad input: a pose that is not finite, a shape with no support map (a TriMesh) and a ball
    /// of no size. The first two are never called apart (the caller measures them another
    /// way); a point is apart from the mesh exactly where it lies off every triangle.
    #[test]
    fn bad_input_is_not_called_apart() {
        let mesh = hills(0.2);
        let cube = parry3d::shape::Cuboid::new(Vector::splat(0.2));
        let above = Pose::from_translation(Vector::new(1.5, 5.0, 1.5));
        assert!(apart_from_mesh(&mesh, &cube, &above, Vector::Y));
        for bad in [
            Pose::from_translation(Vector::new(Real::NAN, 5.0, 1.5)),
            Pose::from_translation(Vector::new(1.5, Real::INFINITY, 1.5)),
        ] {
            assert!(!apart_from_mesh(&mesh, &cube, &bad, Vector::Y));
        }
        // A zero or non-finite axis only loses the shared axis: the answer stays right.
        assert!(apart_from_mesh(&mesh, &cube, &above, Vector::ZERO));
        assert!(apart_from_mesh(&mesh, &cube, &above, Vector::NAN));
        assert!(!apart_from_mesh(&mesh, &hills(0.1), &above, Vector::Y));
        let point = parry3d::shape::Ball::new(0.0);
        assert!(apart_from_mesh(&mesh, &point, &above, Vector::Y));
        let below = Pose::from_translation(Vector::new(1.5, -5.0, 1.5));
        assert!(apart_from_mesh(&mesh, &point, &below, Vector::Y));
        let on = Pose::from_translation(mesh.vertices()[5]);
        assert!(!apart_from_mesh(&mesh, &point, &on, Vector::Y));
    }
}
