//! Mesh inputs: what `TouchMesh::from_shape` and `TouchMesh::new` make of what users give.
//! (1) A `ConvexPolyhedron` becomes its true hull: the mesh is convex, its support in every
//! direction is the original point cloud's (within `1e-6 ×` the cloud's diagonal, at scales
//! from `1e-3` to `1e3`), and every original point lies on or inside every face plane.
//! (2) Duplicated vertices are welded: a cube given as a triangle soup (each triangle with its
//! own vertex copies, exact or jittered by up to `1e-7` of its size) reconstructs against a slab
//! exactly as the indexed cube, with one face patch of four corners, and its features name the
//! lowest user index of each group of copies; copies `1e-4` apart are not welded.
//! (3) Every shape type a rapier collider can have gets a mesh or a refusal naming it: the
//! mesh's vertices lie on parry's own surface of the shape, and for convex shapes the mesh's
//! support in every direction falls short of parry's support map by no more than
//! `from_shape` documents (and never exceeds it); a compound's mesh has the compound's box;
//! half-spaces, segments and polylines (and compounds with one) are the only refusals.
//! References are parry's point queries and support maps and the input points themselves,
//! never the crate's own output.

use crate::common::round_parts;
use parry3d::bounding_volume::Aabb;
use parry3d::math::IVector;
use parry3d::query::PointQuery;
use parry3d::shape::{Shape, ShapeType, SharedShape, Triangle};
use parry3d::utils::Array2;
use proptest::prelude::*;
use rapier_touch::geometry::generators::MeshBuffers;
use rapier_touch::prelude::*;

/// Unit directions: a Fibonacci sphere plus the axes and diagonals.
fn directions(n: usize) -> Vec<Vector> {
    let mut d: Vec<Vector> = (0..n)
        .map(|k| {
            let z = 1.0 - 2.0 * (k as Real + 0.5) / n as Real;
            let phi = k as Real * 2.399_963;
            let r = (1.0 - z * z).sqrt();
            Vector::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect();
    for i in -1i32..=1 {
        for j in -1i32..=1 {
            for k in -1i32..=1 {
                if (i, j, k) != (0, 0, 0) {
                    d.push(Vector::new(i as Real, j as Real, k as Real).normalize());
                }
            }
        }
    }
    d
}

/// The vertices some kept triangle uses (unused ones, such as interior points of a cloud,
/// must not count).
fn used_vertices(m: &TouchMesh) -> Vec<Vector> {
    let mut used = vec![false; m.num_vertices()];
    for &v in m.indices().iter().flatten() {
        used[v as usize] = true;
    }
    (0..m.num_vertices())
        .filter(|&v| used[v])
        .map(|v| m.vertices()[v])
        .collect()
}

fn support(points: &[Vector], d: Vector) -> f64 {
    points
        .iter()
        .map(|p| p.as_dvec3().dot(d.as_dvec3()))
        .fold(f64::MIN, f64::max)
}

// ---------------------------------------------------------------------------------------------
// (1) ConvexPolyhedron: the true hull.

fn cloud() -> impl Strategy<Value = Vec<Vector>> {
    (
        prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), 6..40),
        -3i32..=3,
        (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
    )
        .prop_map(|(pts, e, c)| {
            let s = Real::powi(10.0, e);
            let c = Vector::new(c.0, c.1, c.2) * s;
            pts.into_iter()
                .map(|(x, y, z)| c + Vector::new(x, y, z) * s)
                .collect()
        })
}

/// The hull checks of claim (1) against the original cloud `pts`.
fn check_true_hull(pts: &[Vector], m: &TouchMesh) -> Result<(), TestCaseError> {
    let bbox = Aabb::from_points(pts.iter().copied());
    let scale = bbox.extents().length() as f64;
    let tol = 1e-6 * scale;
    prop_assert!(m.is_convex(), "{m:?}");
    let hull = used_vertices(m);
    for d in directions(300) {
        let (hm, hp) = (support(&hull, d), support(pts, d));
        prop_assert!(
            (hm - hp).abs() <= tol,
            "support {hm} vs cloud {hp} along {d}"
        );
    }
    let centre = hull.iter().map(|p| p.as_dvec3()).sum::<glamx::DVec3>() / hull.len() as f64;
    for t in m.indices() {
        let [a, b, c] = t.map(|i| m.vertices()[i as usize].as_dvec3());
        let mut n = (b - a).cross(c - a).normalize();
        if n.dot(centre - a) > 0.0 {
            n = -n;
        }
        for p in pts {
            let h = n.dot(p.as_dvec3() - a);
            prop_assert!(h <= tol, "point {p} is {h} outside face {t:?}");
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn convex_polyhedron_becomes_its_true_hull(pts in cloud()) {
        let Some(poly) = ConvexPolyhedron::from_convex_hull(&pts) else {
            return Ok(());
        };
        let m = TouchMesh::from_shape(&poly).unwrap();
        check_true_hull(&pts, &m)?;
        // The features name the polyhedron's own points.
        prop_assert_eq!(m.vertices(), poly.points());
    }
}

// ---------------------------------------------------------------------------------------------
// (2) Welding.

/// The indexed cube and the same cube as a soup: triangle `t` uses vertices `3t..3t+3`, each
/// moved by `jitter()`.
fn cube_soup(h: Real, mut jitter: impl FnMut() -> Vector) -> (MeshBuffers, MeshBuffers) {
    let (v, i) = Cuboid::new(Vector::splat(h)).to_trimesh();
    let soup_v: Vec<Vector> = i
        .iter()
        .flat_map(|t| t.map(|k| v[k as usize]))
        .map(|p| p + jitter())
        .collect();
    let soup_i = (0..i.len() as u32)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    ((v, i), (soup_v, soup_i))
}

/// A small deterministic generator of jitter vectors with components in `[-a, a]`.
fn jitter(a: Real) -> impl FnMut() -> Vector {
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    move || {
        let mut c = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            ((seed >> 40) as Real / (1u64 << 24) as Real * 2.0 - 1.0) * a
        };
        Vector::new(c(), c(), c())
    }
}

/// The crate's quick-start scene: a cube that fell flat onto a slab and now sinks `0.2 s`.
fn drop_on_slab(cube: &TouchMesh, s: Real) -> ContactConfiguration {
    let slab = TouchMesh::from_shape(&Cuboid::new(Vector::new(2.0, 0.5, 2.0) * s)).unwrap();
    let slab_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0) * s);
    let now = Pose::from_translation(Vector::new(0.3, 0.3, 0.0) * s);
    let before = Pose::from_translation(Vector::new(0.3, 0.8, 0.0) * s);
    Reconstructor::default()
        .reconstruct(&slab, &slab_pose, cube, &now, &before)
        .unwrap()
}

#[test]
fn triangle_soup_welds_into_one_face_contact() {
    for s in [1.0e-3, 1.0, 1.0e3] {
        let h = 0.5 * s;
        let diag = 2.0 * h * Real::sqrt(3.0);
        for rel in [0.0, 1.0e-9, 1.0e-7] {
            let ((v, i), (soup_v, soup_i)) = cube_soup(h, jitter(rel * diag));
            let moved = soup_v
                .iter()
                .zip(i.iter().flatten())
                .filter(|(p, &k)| **p != v[k as usize])
                .count();
            if rel == 1.0e-7 {
                assert!(moved > 20, "the jitter must move copies ({moved})");
            }
            let indexed = TouchMesh::new(v, i).unwrap();
            let soup = TouchMesh::new(soup_v.clone(), soup_i).unwrap();
            assert_eq!(soup.num_vertices(), 36);
            assert_eq!(soup.welded_vertices(), 28, "s {s} jitter {rel}");
            assert_eq!(soup.num_triangles(), 12);
            assert_eq!(soup.num_edges(), 18);
            assert!(soup.is_closed() && soup.is_convex());

            let (a, b) = (drop_on_slab(&indexed, s), drop_on_slab(&soup, s));
            assert_eq!(a.state, TouchState::Penetrating);
            assert_eq!(b.state, a.state);
            assert!(((a.depth - 0.2 * s) / s).abs() < 1e-5, "{}", a.depth);
            assert!(
                ((b.depth - a.depth) / s).abs() < 1e-6,
                "{} {}",
                b.depth,
                a.depth
            );
            for c in [&a, &b] {
                assert_eq!(c.patches.len(), 1, "s {s} jitter {rel}: {:?}", c.patches);
                assert_eq!(c.patches[0].kind, ContactKind::Face);
                assert_eq!(c.patches[0].polygon.len(), 4);
            }
            // Each moving vertex named is the lowest soup index among the copies of its
            // corner (copies of one corner are the soup vertices nearest to each other).
            for p in &b.patches[0].points {
                if let Feature::Vertex(k) = p.moving_feature {
                    let corner = soup_v[k as usize];
                    let lowest = (0..soup_v.len())
                        .find(|&j| (soup_v[j] - corner).length() < 0.1 * h)
                        .unwrap();
                    assert_eq!(k as usize, lowest);
                    assert_eq!(soup.welded_to(k), k);
                }
            }
        }
    }
    // Copies 1e-4 of the size apart are distinct vertices: nothing welds.
    let (_, (soup_v, soup_i)) = cube_soup(0.5, jitter(1.0e-4));
    let soup = TouchMesh::new(soup_v, soup_i).unwrap();
    assert_eq!(soup.welded_vertices(), 0);
    assert!(!soup.is_closed());
}

// ---------------------------------------------------------------------------------------------
// (3) Every shape type.

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

/// An open mover, a single triangle, that crosses a closed cube within one step is
/// `Perforated` (with the analytic first touch on the cube's top face), and one that ends inside
/// the cube is `Penetrating`; with an open cube (one face missing) the triangle that ends inside
/// touches nothing.
#[test]
fn open_mover_through_a_closed_mesh_is_perforated() {
    let cube = TouchMesh::from_shape(&parry3d::shape::Cuboid::new(Vector::splat(0.5))).unwrap();
    assert!(cube.is_closed());
    let tri = TouchMesh::new(
        vec![
            Vector::new(-0.2, 0.0, -0.1),
            Vector::new(0.2, 0.0, -0.1),
            Vector::new(0.0, 0.0, 0.2),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let id = Pose::IDENTITY;
    let mut rec = Reconstructor::default();
    for fast in [true, false] {
        rec.options.convex_fast_path = fast;
        let prev = Pose::from_translation(Vector::new(0.05, 2.0, 0.0));
        let through = Pose::from_translation(Vector::new(0.05, -2.0, 0.0));
        let c = rec.reconstruct(&cube, &id, &tri, &through, &prev).unwrap();
        assert_eq!(c.state, TouchState::Perforated);
        assert!((c.reversing_vector - Vector::new(0.0, 2.5, 0.0)).length() < 1e-5);
        assert_eq!(c.patches[0].kind, ContactKind::Face);
        let inside = Pose::from_translation(Vector::new(0.05, 0.1, 0.0));
        let c = rec.reconstruct(&cube, &id, &tri, &inside, &prev).unwrap();
        assert_eq!(c.state, TouchState::Penetrating);
        assert!((c.depth - 0.4).abs() < 1e-5, "depth {}", c.depth);
    }
    // Without its top face the cube is open: the triangle inside crosses nothing.
    let (v, mut i) = (cube.vertices().to_vec(), cube.indices().to_vec());
    i.retain(|t| !t.iter().all(|&k| v[k as usize].y > 0.4));
    let open = TouchMesh::new(v, i).unwrap();
    assert!(!open.is_closed());
    let prev = Pose::from_translation(Vector::new(0.05, 2.0, 0.0));
    let inside = Pose::from_translation(Vector::new(0.05, 0.1, 0.0));
    let c = rec.reconstruct(&open, &id, &tri, &inside, &prev).unwrap();
    assert_eq!(c.state, TouchState::Separated);
}
