//! Mesh inputs: what `TouchMesh::from_shape` and `TouchMesh::new` make of what users give.
//! (1) A `ConvexPolyhedron` becomes its true hull: the mesh is convex, its support in every
//! direction is the original point cloud's (within `1e-6 ×` the cloud's diagonal, at scales
//! from `1e-3` to `1e3`), and every original point lies on or inside every face plane.
//! (2) Duplicated vertices are welded: a cube given as a triangle soup (each triangle with its
//! own vertex copies, exact or jittered by up to `1e-7` of its size) reconstructs against a slab
//! exactly as the indexed cube, with one face patch of four corners, and its features name the
//! lowest user index of each group of copies; copies `1e-4` apart are not welded.
//! (3) Every shape type gets a mesh or a refusal: `shape_meshes.rs`.
//! References are parry's point queries and support maps and the input points themselves,
//! never the crate's own output.

use parry3d::bounding_volume::Aabb;
use proptest::prelude::*;
use rapier_touch::geometry::generators::MeshBuffers;
use rapier_touch::prelude::*;

/// Unit directions: a Fibonacci sphere plus the axes and diagonals.
pub(crate) fn directions(n: usize) -> Vec<Vector> {
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
pub(crate) fn used_vertices(m: &TouchMesh) -> Vec<Vector> {
    let mut used = vec![false; m.num_vertices()];
    for &v in m.indices().iter().flatten() {
        used[v as usize] = true;
    }
    (0..m.num_vertices())
        .filter(|&v| used[v])
        .map(|v| m.vertices()[v])
        .collect()
}

pub(crate) fn support(points: &[Vector], d: Vector) -> f64 {
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
