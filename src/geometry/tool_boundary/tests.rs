//! Tests of the tool-boundary queries against independent answers (support functions,
//! parry's exact projections, the rounded shapes' definition).

use super::*;
use parry3d::shape::{Ball, Capsule, Cone, Cylinder, Shape};

/// The exact normals of balls, capsules, cylinders and cones against the support function (the boundary
/// point is the farthest point of the shape along its normal) and parry's projection (a
/// point just outside along the normal comes back to it), at points spread over their
/// faces away from the rims.
#[test]
fn round_shape_normals_match_the_support_function_and_parrys_projection() {
    let mut checked = 0;
    for (h, r) in [(0.5f32, 0.3f32), (0.1, 0.6), (2e-4, 1e-4), (300.0, 50.0)] {
        let cylinder = Cylinder::new(h, r);
        let cone = Cone::new(h, r);
        let ball = Ball::new(r);
        let capsule = Capsule::new_y(h, r);
        for k in 0..200 {
            let t = k as f32;
            let (angle, a, b) = (
                t * 2.4,
                (t * 0.37).sin() * 0.8,
                (t * 0.61).cos().abs() * 0.8,
            );
            let around = Vector::new(angle.cos(), 0.0, angle.sin());
            // A cylinder's side and caps; a cone's side (radius r (h - y) / 2h) and base.
            let dir = Vector::new(angle.cos() * b, a, angle.sin() * b)
                .try_normalize()
                .unwrap_or(Vector::Y);
            let points: [(&dyn Shape, Vector); 6] = [
                (&ball, dir * r),
                // A capsule's side, or a cap (the sphere around the segment's end).
                if k % 2 == 0 {
                    (&capsule, around * r + Vector::Y * (a * h))
                } else {
                    (&capsule, Vector::Y * (h * dir.y.signum()) + dir * r)
                },
                (&cylinder, around * r + Vector::Y * (a * h)),
                (
                    &cylinder,
                    around * (b * r) + Vector::Y * (if k % 2 == 0 { h } else { -h }),
                ),
                (
                    &cone,
                    around * (r * (h - a * h) / (2.0 * h)) + Vector::Y * (a * h),
                ),
                (&cone, around * (b * r) - Vector::Y * h),
            ];
            for (shape, p) in points {
                let n = round_normal(shape, p).unwrap();
                let support = shape.as_support_map().unwrap().local_support_point(n);
                assert!(
                    n.dot(support - p).abs() < 1e-5 * h.max(r),
                    "{:?} {h} {r}: at {p} normal {n}, support {support}",
                    shape.shape_type()
                );
                // A point just outside along the normal projects back onto `p` (parry's
                // exact projections; its ray cast's normals are off by up to 2e-3 rad on
                // a side).
                let out = shape.project_local_point(p + n * (0.01 * h.min(r)), false);
                assert!(
                    !out.is_inside && (out.point - p).length() < 1e-4 * h.max(r),
                    "{:?} {h} {r}: at {p} normal {n} leads to {:?}",
                    shape.shape_type(),
                    out
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 4800);
}

/// Rays from inside cylinders, cones and capsules of 1 mm to 1 km leave them on their
/// boundary: parry's exact projection of the exit point is within 1e-5 of the size (parry's
/// own cast from inside found no exit on the millimetre cylinder and left up to 4 % off on
/// the others).
#[test]
fn exits_from_round_shapes_are_on_their_boundary_at_any_size() {
    for size in [1e-3f32, 0.2, 30.0, 1e3] {
        let (h, r) = (0.3 * size, 0.2 * size);
        let shapes: [Box<dyn Shape>; 3] = [
            Box::new(Cylinder::new(h, r)),
            Box::new(Cone::new(h, r)),
            Box::new(Capsule::new_y(h, r)),
        ];
        for shape in &shapes {
            for k in 0..50 {
                let t = k as f32;
                let p =
                    Vector::new((t * 0.7).sin(), (t * 0.3).cos(), (t * 1.1).sin()) * (0.05 * size);
                let d = Vector::new((t * 1.9).sin(), (t * 2.3).cos(), (t * 0.9).cos()).normalize();
                let pose = Pose::from_translation(Vector::new(size, -2.0 * size, 0.5 * size));
                let q = exit_along(shape.as_ref(), &pose, pose.transform_point(p), d)
                    .unwrap_or_else(|| panic!("{:?} {size}: no exit", shape.shape_type()));
                let local = pose.inverse_transform_point(q);
                let on = shape.project_local_point(local, false);
                assert!(
                    (on.point - local).length() <= 1e-5 * size,
                    "{:?} {size}: exit {local} is {} off the boundary",
                    shape.shape_type(),
                    (on.point - local).length()
                );
                assert!((q - pose.transform_point(p)).normalize().dot(d) > 0.999);
            }
        }
    }
}

/// The nearest boundary point of rounded shapes (inner shape plus border) to points inside
/// and outside them, at 1 mm, 20 cm and 100 m: it lies on the boundary with its normal
/// (the support point along the normal is as far along it), and the point lies on that
/// normal's line (the nearest-point condition of a convex shape).
#[test]
fn rounded_shapes_nearest_points_and_normals_are_exact() {
    use parry3d::shape::SharedShape;
    for size in [1e-3f32, 0.2, 100.0] {
        let (h, b) = (0.4 * size, 0.1 * size);
        let corners: Vec<Vector> = (0..8)
            .map(|c| {
                let s = |bit: u8| if c & bit == 0 { -h } else { h };
                Vector::new(s(1), s(2), s(4))
            })
            .collect();
        let shapes = [
            SharedShape::round_cuboid(h, h, 0.5 * h, b),
            SharedShape::round_cylinder(h, 0.7 * h, b),
            SharedShape::round_cone(h, 0.7 * h, b),
            SharedShape::round_convex_hull(&corners, b).unwrap(),
        ];
        for shape in &shapes {
            let support = shape.as_support_map().unwrap();
            for k in 0..60 {
                let t = k as f32;
                let p = Vector::new((t * 0.7).sin(), (t * 1.3).cos(), (t * 2.1).sin())
                    * (size * if k % 2 == 0 { 0.3 } else { 0.9 });
                let r = nearest_on_boundary(shape.as_ref(), &Pose::IDENTITY, p);
                let n = outward_normal(shape.as_ref(), r, 0.0);
                let far = support.local_support_point(n);
                assert!(
                    n.dot(far - r).abs() <= 1e-5 * size,
                    "{:?} {size}: {r} with normal {n} is not on the boundary ({far})",
                    shape.shape_type()
                );
                assert!(
                    (p - r).cross(n).length() <= 1e-4 * size,
                    "{:?} {size}: {p} is not on the normal line of {r} ({n})",
                    shape.shape_type()
                );
            }
        }
    }
}

/// A point or direction that is not a number, or a point on a shape's axis or centre,
/// gets a finite normal, a finite boundary point or none, and no exit that is not finite:
/// nothing not a number reaches the coupling.
#[test]
fn bad_points_give_finite_answers_or_none() {
    use parry3d::shape::SharedShape;
    let shapes = [
        SharedShape::ball(0.1),
        SharedShape::capsule_y(0.1, 0.05),
        SharedShape::cylinder(0.1, 0.05),
        SharedShape::cone(0.1, 0.05),
        SharedShape::round_cuboid(0.1, 0.1, 0.1, 0.02),
        SharedShape::cuboid(0.1, 0.1, 0.1),
    ];
    let points = [Vector::NAN, Vector::ZERO, Vector::Y * 0.1, Vector::INFINITY];
    for shape in &shapes {
        for p in points {
            let n = outward_normal(shape.as_ref(), p, 0.0);
            assert!(
                n.is_finite() || !p.is_finite(),
                "{:?}: normal {n} at {p}",
                shape.shape_type()
            );
            if p.is_finite() {
                assert!(n.is_finite(), "{:?}: normal {n} at {p}", shape.shape_type());
                // A ball's centre has no one nearest boundary point: parry answers NaN,
                // which the vertex holds and the servo model skip (they check).
                let (q, inside) = boundary_point(shape.as_ref(), &Pose::IDENTITY, p);
                let centre = shape.as_ball().is_some() && p == Vector::ZERO;
                assert!(
                    inside && (q.is_finite() || centre),
                    "{:?}: {q} from {p}",
                    shape.shape_type()
                );
            }
            for d in [Vector::NAN, Vector::X] {
                if let Some(e) = exit_along(shape.as_ref(), &Pose::IDENTITY, p, d) {
                    assert!(
                        e.is_finite() || !(p.is_finite() && d.is_finite()),
                        "{:?}: exit {e} from {p} along {d}",
                        shape.shape_type()
                    );
                }
            }
        }
    }
}

/// On an edge or a corner of a cuboid, of the same box as a convex hull, as a triangle mesh
/// and of a compound's box part, the normal is the face most along the preferred direction,
/// and away from them the nearest face's whatever the preference. Checked on the box's own
/// face normals, at scales from 0.1 mm to 1 km.
#[test]
fn an_edge_point_takes_the_face_it_pushes_against() {
    use parry3d::shape::{Cuboid, SharedShape};
    for scale in [1e-4f32, 0.03, 1.0, 1e3] {
        let h = Vector::new(0.015, 0.03, 0.02) * scale;
        let corners: Vec<Vector> = (0..8)
            .map(|c| {
                let s = |bit: u32, v: f32| if c & bit == 0 { -v } else { v };
                Vector::new(s(1, h.x), s(2, h.y), s(4, h.z))
            })
            .collect();
        let offset = Pose::from_translation(Vector::new(0.1, 0.2, -0.1) * scale);
        let shapes: Vec<(SharedShape, Pose)> = vec![
            (SharedShape::new(Cuboid::new(h)), Pose::IDENTITY),
            (SharedShape::convex_hull(&corners).unwrap(), Pose::IDENTITY),
            // A triangle mesh: at an edge the nearest triangle is a tie that rounding breaks,
            // and each face of the box is two triangles.
            (
                {
                    let (v, i) = Cuboid::new(h).to_trimesh();
                    SharedShape::trimesh(v, i).unwrap()
                },
                Pose::IDENTITY,
            ),
            (
                SharedShape::compound(vec![(offset, SharedShape::new(Cuboid::new(h)))]),
                offset,
            ),
        ];
        let margin = 1e-4 * scale;
        for (shape, at) in &shapes {
            // The bottom edge along z at +x: the bottom face for a push down, the +x side for
            // a push along +x; a corner takes the third face for a push along it.
            let edge = at.transform_point(Vector::new(h.x, -h.y, 0.3 * h.z));
            let corner = at.transform_point(Vector::new(h.x, -h.y, h.z));
            let cases = [
                (edge, -Vector::Y, -Vector::Y),
                (edge, Vector::new(1.0, -0.2, 0.0), Vector::X),
                (corner, Vector::new(0.1, 0.2, 1.0), Vector::Z),
                // Mid-face: the face's own normal, whatever the preference.
                (
                    at.transform_point(Vector::new(0.2 * h.x, -h.y, 0.1 * h.z)),
                    Vector::X,
                    -Vector::Y,
                ),
            ];
            for (p, prefer, want) in cases {
                let n = outward_normal_toward(shape.as_ref(), p, margin, prefer);
                assert!(
                    (n - want).length() < 1e-5,
                    "{:?} at scale {scale}: {n} at {p} for {prefer}",
                    shape.shape_type()
                );
            }
        }
    }
}

/// Bad input to the edge rule: a NaN, infinite or zero preference, or a NaN point, answers as
/// `outward_normal` does (the preference is not used), on a cuboid, a convex hull and a ball.
#[test]
fn an_unusable_preference_falls_back_to_the_nearest_face() {
    use parry3d::shape::{Cuboid, SharedShape};
    let h = Vector::new(0.015, 0.03, 0.02);
    let shapes = [
        SharedShape::new(Cuboid::new(h)),
        SharedShape::convex_hull(&[
            Vector::new(-h.x, -h.y, -h.z),
            Vector::new(h.x, -h.y, -h.z),
            Vector::new(-h.x, h.y, -h.z),
            Vector::new(h.x, h.y, -h.z),
            Vector::new(-h.x, -h.y, h.z),
            Vector::new(h.x, -h.y, h.z),
            Vector::new(-h.x, h.y, h.z),
            Vector::new(h.x, h.y, h.z),
        ])
        .unwrap(),
        SharedShape::ball(0.02),
    ];
    let edge = Vector::new(h.x, -h.y, 0.0);
    for shape in &shapes {
        for prefer in [Vector::ZERO, Vector::NAN, Vector::splat(Real::INFINITY)] {
            let n = outward_normal_toward(shape.as_ref(), edge, 1e-6, prefer);
            let plain = outward_normal(shape.as_ref(), edge, 1e-6);
            assert_eq!(
                n.to_array().map(Real::to_bits),
                plain.to_array().map(Real::to_bits)
            );
        }
        // A NaN point: whatever `outward_normal` answers, and no panic.
        let p = Vector::NAN;
        let n = outward_normal_toward(shape.as_ref(), p, 1e-6, -Vector::Y);
        let plain = outward_normal(shape.as_ref(), p, 1e-6);
        assert_eq!(n.is_finite(), plain.is_finite(), "{n} against {plain}");
    }
}

/// A triangle mesh's normal at a point on one of its faces is that face's, whichever of its
/// triangles is nearest: the box as a mesh, every face, at scales from 0.1 mm to 1 km, with
/// and without a preference. (It read the normal of the mesh's first triangle wherever the
/// point was: parry's `feature_normal_at_point` takes the triangle the projection reports.)
#[test]
fn a_mesh_point_takes_its_own_faces_normal() {
    use parry3d::shape::{Cuboid, SharedShape};
    for scale in [1e-4f32, 0.03, 1.0, 1e3] {
        let h = Vector::new(0.015, 0.03, 0.02) * scale;
        let (v, i) = Cuboid::new(h).to_trimesh();
        let mesh = SharedShape::trimesh(v, i).unwrap();
        for axis in [Vector::X, Vector::Y, Vector::Z] {
            for n in [axis, -axis] {
                // A point on the face, off its centre and off the diagonal its two triangles
                // share.
                let (u, w) = n.any_orthonormal_pair();
                let p = n * n.dot(h).abs() + (u * 0.3 + w * 0.1) * h.abs().min_element();
                for prefer in [Vector::ZERO, n, -n, u] {
                    let got = outward_normal_toward(mesh.as_ref(), p, 1e-4 * scale, prefer);
                    assert!(
                        (got - n).length() < 1e-5,
                        "scale {scale}: {got} at {p} on the face {n}, preferring {prefer}"
                    );
                }
                let got = outward_normal(mesh.as_ref(), p, 1e-4 * scale);
                assert!((got - n).length() < 1e-5, "scale {scale}: {got} for {n}");
            }
        }
    }
}

/// A point inside a closed triangle mesh (oriented, as the coupling's query shape is) is no
/// distance outside it, and one outside is its distance from the mesh: a U, at scales from
/// 0.1 mm to 1 km, against the distances written here. (Inside a mesh it read the distance
/// to the nearest face: parry's solid distance for a mesh is the distance to its projection,
/// the boundary.)
#[test]
fn a_point_inside_a_closed_mesh_is_no_distance_outside() {
    use parry3d::shape::{SharedShape, TriMeshFlags};
    // A U in the xy plane (legs down), extruded 2 in z: legs 1 wide and 2 tall, 1 apart,
    // under a bridge 1 thick.
    let outline = [
        [-1.5f32, -2.0],
        [-0.5, -2.0],
        [-0.5, 0.0],
        [0.5, 0.0],
        [0.5, -2.0],
        [1.5, -2.0],
        [1.5, 1.0],
        [-1.5, 1.0],
    ];
    for scale in [1e-4f32, 0.03, 1.0, 1e3] {
        let scaled: Vec<[Real; 2]> = outline
            .iter()
            .map(|[x, y]| [x * scale, y * scale])
            .collect();
        let (v, i) = crate::geometry::generators::extruded_polygon(&scaled, 2.0 * scale).unwrap();
        let mesh = SharedShape::trimesh_with_flags(v, i, TriMeshFlags::ORIENTED).unwrap();
        // (point, its distance outside): in a leg near its outer bottom edge, in the middle
        // of a leg, in the bridge, between the legs under the bridge, beside a leg.
        let cases = [
            (Vector::new(1.45, -1.95, 0.3), 0.0),
            (Vector::new(1.0, -1.0, 0.0), 0.0),
            (Vector::new(0.0, 0.5, -0.9), 0.0),
            (Vector::new(0.0, -1.0, 0.0), 0.5),
            (Vector::new(1.8, -1.0, 0.2), 0.3),
        ];
        let pose = Pose::new(
            Vector::new(3.0, -1.0, 2.0) * scale,
            Vector::new(0.3, -0.7, 0.2),
        );
        for (p, want) in cases {
            let at = pose.transform_point(p * scale);
            let got = distance_outside(mesh.as_ref(), &pose, at);
            assert!(
                (got - want * scale).abs() <= 1e-4 * scale,
                "scale {scale}: {got} outside at {p}, not {}",
                want * scale
            );
        }
    }
}
