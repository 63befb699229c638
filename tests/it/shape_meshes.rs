//! Every shape type a rapier collider can have gets a touch mesh or a refusal naming it
//! (`TouchMesh::from_shape`): the mesh's vertices lie on parry's own surface of the shape, and
//! for convex shapes the mesh's support in every direction falls short of parry's support map
//! by no more than `from_shape` documents (and never exceeds it); a compound's mesh has the
//! compound's box; half-spaces, segments and polylines (and compounds with one) are the only
//! refusals. References are parry's point queries and support maps, never the crate's own
//! output.

use crate::common::round_parts;
use crate::mesh_inputs::{directions, support, used_vertices};
use parry3d::math::IVector;
use parry3d::query::PointQuery;
use parry3d::shape::{Shape, ShapeType, SharedShape, Triangle};
use parry3d::utils::Array2;
use proptest::prelude::*;
use rapier_touch::prelude::*;

/// What `from_shape` promises for a shape: the bound on the distance between the mesh and
/// the true surface (`from_shape`'s table), or a refusal.
#[derive(Debug)]
enum Expect {
    Mesh {
        bound: Real,
        closed: bool,
        convex: bool,
    },
    Refused,
}

/// A heightfield over `[-1, 1]²` with bumps.
fn heights() -> Array2<Real> {
    let n = 6;
    let data = (0..n * n)
        .map(|k| ((k % n) as Real * 0.9).sin() * ((k / n) as Real * 0.7).cos() * 0.3)
        .collect();
    Array2::new(n, n, data)
}

/// One example of each shape type (an exhaustive match, so a new parry shape type breaks
/// the build here), with what `from_shape` must give. `None`: `Custom`, which needs a
/// user-defined shape.
fn example(t: ShapeType) -> Option<(SharedShape, Expect)> {
    use Expect::*;
    let v = Vector::new;
    let exact = |closed, convex| Mesh {
        bound: 0.0,
        closed,
        convex,
    };
    let curved = |bound| Mesh {
        bound,
        closed: true,
        convex: true,
    };
    let (r, b) = (0.4, 0.1);
    let cloud: Vec<Vector> = (0..30)
        .map(|k| {
            let k = k as Real;
            v(
                (k * 1.3).sin(),
                (k * 2.1).cos() * 0.7,
                (k * 0.37).sin() * 0.5,
            )
        })
        .collect();
    Some(match t {
        ShapeType::Ball => (SharedShape::ball(r), curved(0.025 * r)),
        ShapeType::Cuboid => (SharedShape::cuboid(0.5, 0.2, 0.3), exact(true, true)),
        ShapeType::Capsule => (SharedShape::capsule_y(0.3, r), curved(0.04 * r)),
        ShapeType::Segment => (SharedShape::segment(v(0., 0., 0.), v(1., 0., 0.)), Refused),
        ShapeType::Triangle => (
            SharedShape::triangle(v(0., 0., 0.), v(1., 0., 0.), v(0., 0.5, 1.)),
            exact(false, false),
        ),
        ShapeType::Voxels => {
            let cells = [
                [0, 0, 0],
                [1, 0, 0],
                [2, 0, 0],
                [2, 1, 0],
                [2, 1, 1],
                [0, 0, 1],
            ];
            let cells: Vec<IVector> = cells.iter().map(|c| IVector::from_array(*c)).collect();
            (
                SharedShape::voxels(v(0.2, 0.3, 0.25), &cells),
                exact(true, false),
            )
        }
        ShapeType::TriMesh => {
            let (v, i) = rapier_touch::geometry::generators::icosphere(0.5, 2);
            (SharedShape::trimesh(v, i).unwrap(), exact(true, true))
        }
        ShapeType::Polyline => (
            SharedShape::polyline(vec![v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.)], None),
            Refused,
        ),
        ShapeType::HalfSpace => (SharedShape::halfspace(Vector::Y), Refused),
        ShapeType::HeightField => (
            SharedShape::heightfield(heights(), v(2.0, 1.0, 2.0)),
            exact(false, false),
        ),
        ShapeType::Compound => (
            SharedShape::compound(vec![
                (
                    Pose::from_parts(
                        Vector::new(0.0, 0.2, 0.0),
                        Rotation::from_axis_angle(v(1., 2., 0.5).normalize(), 0.7),
                    ),
                    SharedShape::cuboid(0.5, 0.1, 0.2),
                ),
                (
                    Pose::from_translation(v(1.0, 0.0, 0.0)),
                    SharedShape::ball(0.3),
                ),
                (
                    Pose::from_translation(v(-1.0, 0.5, 0.2)),
                    SharedShape::cylinder(0.4, 0.25),
                ),
                (
                    Pose::from_translation(v(0.0, -1.0, 0.0)),
                    SharedShape::round_cuboid(0.2, 0.2, 0.2, 0.05),
                ),
                (
                    Pose::from_translation(v(0.0, 0.0, 1.5)),
                    SharedShape::triangle(v(0., 0., 0.), v(0.3, 0., 0.), v(0., 0.4, 0.)),
                ),
            ]),
            // The ball's faces are the worst part.
            Mesh {
                bound: 0.025 * 0.3,
                closed: false,
                convex: false,
            },
        ),
        ShapeType::ConvexPolyhedron => {
            (SharedShape::convex_hull(&cloud).unwrap(), exact(true, true))
        }
        ShapeType::Cylinder => (SharedShape::cylinder(0.3, r), curved(0.0086 * r)),
        ShapeType::Cone => (SharedShape::cone(0.3, r), curved(0.0086 * r)),
        ShapeType::RoundCuboid => (
            SharedShape::round_cuboid(0.5, 0.2, 0.3, b),
            curved(0.0125 * b),
        ),
        ShapeType::RoundTriangle => (
            SharedShape::round_triangle(v(0., 0., 0.), v(1., 0., 0.), v(0., 0.5, 1.), b),
            curved(0.0125 * b),
        ),
        ShapeType::RoundCylinder => (
            SharedShape::round_cylinder(0.3, r, b),
            curved(0.0125 * b + 0.0086 * r),
        ),
        ShapeType::RoundCone => (
            SharedShape::round_cone(0.3, r, b),
            curved(0.0125 * b + 0.0086 * r),
        ),
        ShapeType::RoundConvexPolyhedron => (
            SharedShape::round_convex_hull(&cloud, b).unwrap(),
            curved(0.0125 * b),
        ),
        ShapeType::Custom => return None,
    })
}

const ALL_TYPES: [ShapeType; 20] = [
    ShapeType::Ball,
    ShapeType::Cuboid,
    ShapeType::Capsule,
    ShapeType::Segment,
    ShapeType::Triangle,
    ShapeType::Voxels,
    ShapeType::TriMesh,
    ShapeType::Polyline,
    ShapeType::HalfSpace,
    ShapeType::HeightField,
    ShapeType::Compound,
    ShapeType::ConvexPolyhedron,
    ShapeType::Cylinder,
    ShapeType::Cone,
    ShapeType::RoundCuboid,
    ShapeType::RoundTriangle,
    ShapeType::RoundCylinder,
    ShapeType::RoundCone,
    ShapeType::RoundConvexPolyhedron,
    ShapeType::Custom,
];

/// The distance from `p` to the true surface of `shape`, from parry's point queries. For a
/// round shape, `|dist(p, inner shape) - border radius|`: parry's own projection on a round
/// shape goes through EPA for points inside, which is off by up to ~3 % of the border radius.
fn surface_distance(shape: &dyn Shape, p: Vector) -> Real {
    match round_parts(shape) {
        Some((inner, b)) => {
            (hull_distance(inner, p).unwrap_or_else(|| inner.distance_to_local_point(p, true)) - b)
                .abs()
        }
        None => hull_distance(shape, p)
            .map(Real::abs)
            .unwrap_or_else(|| (shape.project_local_point(p, false).point - p).length()),
    }
}

/// For a convex polyhedron, the signed distance (negative inside) from `p` to the boundary of
/// the hull of its points, which is what parry's support map (and so its collision detection)
/// takes as the shape: by brute force, from every triple of points whose plane has no point
/// above it, in `f64`, each such triangle projected exactly (parry's triangle projection, by
/// its Voronoi regions). parry's own point query on the polyhedron is an
/// iterative GJK: it read a point of the cloud, on the hull, 4.9e-5 outside a 1.9 m hull
/// (`PROPTEST_RNG_SEED=777`).
fn hull_distance(shape: &dyn Shape, p: Vector) -> Option<Real> {
    let pts: Vec<glamx::DVec3> = shape
        .as_convex_polyhedron()?
        .points()
        .iter()
        .map(|v| v.as_dvec3())
        .collect();
    let q = p.as_dvec3();
    let scale = pts
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs().max_element()))
        .max(1e-30);
    let (mut best, mut outside) = (f64::INFINITY, false);
    let n = pts.len();
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let (a, b, c) = (pts[i], pts[j], pts[k]);
                let Some(nrm) = (b - a).cross(c - a).try_normalize() else {
                    continue;
                };
                let heights = pts.iter().map(|v| nrm.dot(*v - a));
                let (lo, hi) = heights.fold((0.0f64, 0.0f64), |(l, h), x| (l.min(x), h.max(x)));
                let on = 1e-9 * scale;
                // A supporting plane: every point on one side.
                let nrm = if hi <= on {
                    nrm
                } else if lo >= -on {
                    -nrm
                } else {
                    continue;
                };
                outside |= nrm.dot(q - a) > on;
                let triangle = Triangle::new(a.as_vec3(), b.as_vec3(), c.as_vec3());
                best = best.min(triangle.distance_to_local_point(p, false) as f64);
            }
        }
    }
    best.is_finite()
        .then(|| (if outside { best } else { -best }) as Real)
}

/// The checks of claim (3) for one shape: vertices on parry's surface within `bound` (plus
/// `1e-5 ×` the size for rounding), and for a support-map shape, `0 ≤ h_shape - h_mesh ≤
/// bound` along every direction.
fn check_mesh(shape: &dyn Shape, m: &TouchMesh, bound: Real) -> Result<(), String> {
    let size = shape.compute_local_aabb().extents().length();
    let tol = bound + 1e-5 * size;
    for p in used_vertices(m) {
        let d = surface_distance(shape, p);
        if d > tol {
            return Err(format!("vertex {p} is {d} from the surface (bound {tol})"));
        }
    }
    if let Some(sm) = shape.as_support_map() {
        let verts = used_vertices(m);
        for d in directions(400) {
            let hs = sm.local_support_point(d).as_dvec3().dot(d.as_dvec3());
            let gap = hs - support(&verts, d);
            if gap < -1e-5 * size as f64 || gap > tol as f64 {
                return Err(format!("support gap {gap} along {d} (bound {tol})"));
            }
        }
    }
    Ok(())
}

#[test]
fn every_shape_type_gets_a_mesh_or_a_reason() {
    let mut refused = Vec::new();
    for t in ALL_TYPES {
        let Some((shape, expect)) = example(t) else {
            continue;
        };
        assert_eq!(shape.shape_type(), t);
        match (TouchMesh::from_shape(shape.as_ref()), expect) {
            (
                Ok(m),
                Expect::Mesh {
                    bound,
                    closed,
                    convex,
                },
            ) => {
                check_mesh(shape.as_ref(), &m, bound).unwrap_or_else(|e| panic!("{t:?}: {e}"));
                assert_eq!(m.is_closed(), closed, "{t:?}: {m:?}");
                assert_eq!(m.is_convex(), convex, "{t:?}: {m:?}");
            }
            (Err(TouchMeshError::UnsupportedShape { shape, reason }), Expect::Refused) => {
                assert_eq!(shape, t);
                assert!(!reason.is_empty());
                refused.push(t);
            }
            (got, expect) => panic!("{t:?}: expected {expect:?}, got {got:?}"),
        }
    }
    assert_eq!(
        refused,
        [
            ShapeType::Segment,
            ShapeType::Polyline,
            ShapeType::HalfSpace
        ]
    );
}

#[test]
fn compound_mesh_has_the_compound_box_and_names_a_bad_part() {
    let (shape, _) = example(ShapeType::Compound).unwrap();
    let m = TouchMesh::from_shape(shape.as_ref()).unwrap();
    let want = *shape.as_compound().unwrap().local_aabb();
    let got = m.local_aabb();
    assert!(
        (got.mins - want.mins).abs().max_element() < 1e-5
            && (got.maxs - want.maxs).abs().max_element() < 1e-5,
        "{got:?} vs {want:?}"
    );
    let bad = SharedShape::compound(vec![
        (Pose::IDENTITY, SharedShape::ball(0.5)),
        (
            Pose::from_translation(Vector::X),
            SharedShape::segment(Vector::ZERO, Vector::Y),
        ),
    ]);
    assert!(matches!(
        TouchMesh::from_shape(bad.as_ref()),
        Err(TouchMeshError::UnsupportedCompoundPart {
            part: 1,
            shape: ShapeType::Segment,
            ..
        })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Round shapes at random sizes and border radii (from `1e-6` to twice the inner size)
    /// keep the documented bound and stay convex and closed. (A border below `1e-4 ×` the inner
    /// size is left out: the bound is then the border itself, and a triangle stays flat.)
    #[test]
    fn round_shapes_keep_their_bound(
        h in (0.05f32..1.0, 0.05f32..1.0, 0.05f32..1.0),
        rel in -6.0f32..0.3,
        pts in prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), 6..20),
    ) {
        let b = h.0.max(h.1).max(h.2) * Real::powf(10.0, rel);
        let pts: Vec<Vector> = pts.into_iter().map(|(x, y, z)| Vector::new(x, y, z)).collect();
        let mut shapes = vec![
            (SharedShape::round_cuboid(h.0, h.1, h.2, b), 0.0125 * b),
            (SharedShape::round_cylinder(h.0, h.1, b), 0.0125 * b + 0.0086 * h.1),
            (SharedShape::round_cone(h.0, h.1, b), 0.0125 * b + 0.0086 * h.1),
            (
                SharedShape::round_triangle(
                    Vector::ZERO,
                    Vector::new(h.0, 0.0, 0.0),
                    Vector::new(0.0, h.1, h.2),
                    b,
                ),
                0.0125 * b,
            ),
        ];
        if let Some(s) = SharedShape::round_convex_hull(&pts, b) {
            shapes.push((s, 0.0125 * b));
        }
        for (s, bound) in shapes {
            let (inner, _) = round_parts(s.as_ref()).unwrap();
            let left_out = b <= 1e-4 * inner.compute_local_aabb().extents().length();
            let bound = if left_out { bound + b } else { bound };
            let m = TouchMesh::from_shape(s.as_ref()).unwrap();
            // A triangle without its border is flat: an open mesh.
            let flat = left_out && s.shape_type() == ShapeType::RoundTriangle;
            prop_assert!(m.is_convex() != flat, "{:?} {m:?}", s.shape_type());
            check_mesh(s.as_ref(), &m, bound)
                .map_err(|e| TestCaseError::fail(format!("{:?}: {e}", s.shape_type())))?;
        }
    }
}
