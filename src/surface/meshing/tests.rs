use super::*;

fn square(lo: Real, hi: Real) -> Vec<[Real; 2]> {
    vec![[lo, lo], [hi, lo], [hi, hi], [lo, hi]]
}

/// Every triangle's normal points to +y (counter-clockwise seen from above).
fn all_ccw_from_up(mesh: &SurfaceMesh) -> bool {
    mesh.triangles.iter().all(|&[a, b, c]| {
        let [a, b, c] = [a, b, c].map(|i| mesh.vertices[i as usize]);
        (b - a).cross(c - a).y > 0.0
    })
}

fn edges(mesh: &SurfaceMesh) -> HashSet<(u32, u32)> {
    mesh.triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect()
}

fn compact(mesh: &SurfaceMesh) -> bool {
    let used: HashSet<u32> = mesh.triangles.iter().flatten().copied().collect();
    used.len() == mesh.vertices.len()
}

#[test]
fn unit_square_meshes_to_target_size() {
    let outline = PlanarOutline {
        outer: square(0.0, 1.0),
        ..Default::default()
    };
    let planar = triangulate_planar(&outline, 0.1).unwrap();
    let mesh = &planar.mesh;
    let n = mesh.num_vertices();
    assert!((100..=300).contains(&n), "{n} vertices");
    assert!(all_ccw_from_up(mesh));
    assert!((mesh.area() - 1.0).abs() < 1e-4, "area {}", mesh.area());
    assert!(compact(mesh));
    assert!(planar.refinement_complete);
    assert!(mesh.vertices.iter().all(|v| v.y == 0.0));
    // The outline's own points come first, in order.
    assert_eq!(mesh.vertices[2], Vector::new(1.0, 0.0, 1.0));
    // Boundary vertices are exactly those on the square's sides.
    let on_side = |v: Vector| v.x.min(v.z).min(1.0 - v.x).min(1.0 - v.z) < 1e-6;
    for (i, v) in mesh.vertices.iter().enumerate() {
        assert_eq!(
            planar.boundary.binary_search(&(i as u32)).is_ok(),
            on_side(*v)
        );
    }
    // Edges are at most about the target length.
    let longest = edges(mesh)
        .iter()
        .map(|&(i, j)| (mesh.vertices[i as usize] - mesh.vertices[j as usize]).length())
        .fold(0.0, Real::max);
    assert!(longest < 0.16, "longest edge {longest}");
}

#[test]
fn hole_is_left_out() {
    let outline = PlanarOutline {
        outer: square(0.0, 1.0),
        // Clockwise on purpose: orientation does not matter.
        holes: vec![square(0.3, 0.6).into_iter().rev().collect()],
        constraints: Vec::new(),
    };
    let planar = triangulate_planar(&outline, 0.1).unwrap();
    let mesh = &planar.mesh;
    assert!(
        (mesh.area() - (1.0 - 0.09)).abs() < 1e-4,
        "area {}",
        mesh.area()
    );
    assert!(all_ccw_from_up(mesh));
    assert!(compact(mesh));
    for &[a, b, c] in &mesh.triangles {
        let g = (mesh.vertices[a as usize] + mesh.vertices[b as usize] + mesh.vertices[c as usize])
            / 3.0;
        assert!(!(g.x > 0.3 && g.x < 0.6 && g.z > 0.3 && g.z < 0.6), "{g}");
    }
    // The hole's corners are boundary vertices.
    let corner = mesh
        .vertices
        .iter()
        .position(|v| (*v - Vector::new(0.3, 0.0, 0.6)).length() < 1e-6)
        .unwrap();
    assert!(planar.boundary.contains(&(corner as u32)));
}

#[test]
fn constraint_polyline_is_traced_in_order() {
    let line = vec![[0.2, 0.3], [0.5, 0.6], [0.8, 0.35]];
    let outline = PlanarOutline {
        outer: square(0.0, 1.0),
        holes: Vec::new(),
        constraints: vec![line.clone()],
    };
    let planar = triangulate_planar(&outline, 0.1).unwrap();
    let mesh = &planar.mesh;
    assert!((mesh.area() - 1.0).abs() < 1e-4);
    assert!(all_ccw_from_up(mesh));
    let chain = &planar.constrained[0];
    // Refinement split the 0.42 m and 0.39 m segments.
    assert!(chain.len() >= 7, "{chain:?}");
    let at = |i: u32| {
        let v = mesh.vertices[i as usize];
        [v.x, v.z]
    };
    assert_eq!(at(chain[0]), line[0]);
    assert_eq!(at(*chain.last().unwrap()), line[2]);
    assert!(chain.iter().any(|&i| at(i) == line[1]));
    // In order along the polyline: arc length strictly increases, every point lies on it.
    let mesh_edges = edges(mesh);
    let mut travelled = 0.0;
    for w in chain.windows(2) {
        assert!(mesh_edges.contains(&(w[0].min(w[1]), w[0].max(w[1]))));
        let (p, q) = (at(w[0]), at(w[1]));
        let step = (q[0] - p[0]).hypot(q[1] - p[1]);
        assert!(step > 1e-4);
        travelled += step;
    }
    let length = (0.3f32.hypot(0.3)) + (0.3f32.hypot(0.25));
    assert!((travelled - length).abs() < 1e-4, "{travelled} vs {length}");
    // No constraint vertex is on the outer boundary.
    assert!(chain.iter().all(|i| !planar.boundary.contains(i)));
}

#[test]
fn constraint_touching_boundary_and_single_point() {
    let outline = PlanarOutline {
        outer: square(0.0, 1.0),
        holes: Vec::new(),
        constraints: vec![vec![[0.0, 0.5], [1.0, 0.5]], vec![[0.25, 0.75]]],
    };
    let planar = triangulate_planar(&outline, 0.2).unwrap();
    let chain = &planar.constrained[0];
    assert!(planar.boundary.contains(&chain[0]));
    assert!(planar.boundary.contains(chain.last().unwrap()));
    assert!(chain
        .iter()
        .all(|&i| planar.mesh.vertices[i as usize].z == 0.5));
    assert_eq!(planar.constrained[1].len(), 1);
    let p = planar.mesh.vertices[planar.constrained[1][0] as usize];
    assert_eq!(p, Vector::new(0.25, 0.0, 0.75));
}

#[test]
fn bad_outlines_are_errors() {
    let empty = PlanarOutline::default();
    assert!(matches!(
        triangulate_planar(&empty, 0.1),
        Err(MeshingError::TooFewPoints {
            part: OutlinePart::Outer,
            distinct: 0
        })
    ));
    let mut nan = PlanarOutline {
        outer: square(0.0, 1.0),
        ..Default::default()
    };
    nan.outer[2][1] = Real::NAN;
    assert!(matches!(
        triangulate_planar(&nan, 0.1),
        Err(MeshingError::NonFinitePoint {
            part: OutlinePart::Outer,
            index: 2
        })
    ));
    let ok = PlanarOutline {
        outer: square(0.0, 1.0),
        ..Default::default()
    };
    for h in [0.0, -1.0, Real::NAN, Real::INFINITY] {
        assert!(matches!(
            triangulate_planar(&ok, h),
            Err(MeshingError::InvalidTargetEdge(_))
        ));
    }
    assert!(matches!(
        triangulate_planar(&ok, 1e-6),
        Err(MeshingError::TooManyVertices { .. })
    ));
    // Repeated closing point is fine; two distinct points are not a polygon.
    let line = PlanarOutline {
        outer: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 0.0]],
        ..Default::default()
    };
    assert!(matches!(
        triangulate_planar(&line, 0.1),
        Err(MeshingError::TooFewPoints { distinct: 2, .. })
    ));
    // Collinear points: no area.
    let flat = PlanarOutline {
        outer: vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
        ..Default::default()
    };
    assert!(matches!(
        triangulate_planar(&flat, 0.1),
        Err(MeshingError::EmptyMesh)
    ));
    // A bow tie crosses itself.
    let bow_tie = PlanarOutline {
        outer: vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]],
        ..Default::default()
    };
    assert!(matches!(
        triangulate_planar(&bow_tie, 0.1),
        Err(MeshingError::Intersecting {
            part: OutlinePart::Outer,
            ..
        })
    ));
    // A constraint crossing the boundary, one crossing another, one outside, one in a hole.
    let crossing = |constraints: Vec<Vec<[Real; 2]>>| PlanarOutline {
        outer: square(0.0, 1.0),
        holes: vec![square(0.6, 0.9)],
        constraints,
    };
    assert!(matches!(
        triangulate_planar(&crossing(vec![vec![[0.5, 0.5], [1.5, 0.5]]]), 0.1),
        Err(MeshingError::Intersecting {
            part: OutlinePart::Constraint(0),
            segment: 0
        })
    ));
    assert!(matches!(
        triangulate_planar(
            &crossing(vec![
                vec![[0.1, 0.1], [0.5, 0.5]],
                vec![[0.1, 0.5], [0.2, 0.4], [0.5, 0.1]]
            ]),
            0.1
        ),
        Err(MeshingError::Intersecting {
            part: OutlinePart::Constraint(1),
            segment: 1
        })
    ));
    assert!(matches!(
        triangulate_planar(&crossing(vec![vec![[1.5, 0.5], [2.0, 0.5]]]), 0.1),
        Err(MeshingError::ConstraintOutsideDomain { constraint: 0 })
    ));
    assert!(matches!(
        triangulate_planar(&crossing(vec![vec![[0.7, 0.7], [0.8, 0.8]]]), 0.1),
        Err(MeshingError::ConstraintOutsideDomain { constraint: 0 })
    ));
    // A chord across the hole between two of its corners.
    assert!(matches!(
        triangulate_planar(&crossing(vec![vec![[0.6, 0.6], [0.9, 0.9]]]), 0.1),
        Err(MeshingError::ConstraintOutsideDomain { constraint: 0 })
    ));
    let empty_line = crossing(vec![vec![]]);
    assert!(matches!(
        triangulate_planar(&empty_line, 0.1),
        Err(MeshingError::TooFewPoints {
            part: OutlinePart::Constraint(0),
            distinct: 0
        })
    ));
    let tiny = PlanarOutline {
        outer: vec![[0.0, 0.0], [1e-44, 0.0], [0.0, 1.0]],
        ..Default::default()
    };
    assert!(matches!(
        triangulate_planar(&tiny, 0.1),
        Err(MeshingError::Insertion { index: 1, .. })
    ));
}

#[test]
fn plate_grid() {
    let p = plate(2.0, 1.0, 4, 2);
    assert_eq!(p.num_vertices(), 15);
    assert_eq!(p.num_triangles(), 16);
    assert!(all_ccw_from_up(&p));
    assert!(compact(&p));
    assert!((p.area() - 2.0).abs() < 1e-6);
    assert_eq!(p.vertices[0], Vector::new(-1.0, 0.0, -0.5));
    assert_eq!(p.vertices[14], Vector::new(1.0, 0.0, 0.5));
    // Edge-manifold: 4·2 cells have 4·3 + 5·2 + 8 = 30 edges.
    assert_eq!(edges(&p).len(), 30);
    let degenerate = plate(1.0, 1.0, 0, 0);
    assert_eq!(degenerate.num_triangles(), 2);
}

#[test]
fn plate_rim_is_the_outer_boundary() {
    for (size, n) in [(0.3, 15), (0.3, 27), (0.3, 99), (0.3, 54), (2.0, 1)] {
        let p = plate(size, size, n, n);
        let edge = 0.5 * size - 1e-4;
        let by_position: Vec<u32> = (0..p.num_vertices() as u32)
            .filter(|&i| {
                let v = p.vertices[i as usize];
                v.x.abs() > edge || v.z.abs() > edge
            })
            .collect();
        assert_eq!(plate_rim(n, n), by_position, "{n} cells");
    }
    assert_eq!(plate_rim(0, 0), [0, 1, 2, 3]);
}

#[test]
fn closed_generators() {
    let b = box_surface(Vector::new(1.0, 0.5, 0.25), 3);
    assert_eq!(b.num_triangles(), 6 * 9 * 2);
    assert!((b.area() - 7.0).abs() < 1e-5);
    let s = sphere_surface(2.0, 3);
    assert_eq!(s.num_triangles(), 20 * 64);
    assert!(s.vertices.iter().all(|v| (v.length() - 2.0).abs() < 1e-5));
    // Outward winding: the signed volume is positive.
    let volume: Real = s
        .triangles
        .iter()
        .map(|&[a, b, c]| {
            let [a, b, c] = [a, b, c].map(|i| s.vertices[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!(volume > 0.9 * 4.0 / 3.0 * std::f32::consts::PI * 8.0);
}

const CUBE_OBJ: &str = "\
# unit cube, quads, with normals (which must not split the vertices)
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vn 0 0 -1
vn 0 0 1
vn 0 -1 0
vn 0 1 0
vn -1 0 0
vn 1 0 0
f 1//1 4//1 3//1 2//1
f 5//2 6//2 7//2 8//2
f 1//3 2//3 6//3 5//3
f 4//4 8//4 7//4 3//4
f 1//5 5//5 8//5 4//5
f 2//6 3//6 7//6 6//6
";

#[test]
fn obj_cube() {
    let mesh = parse_obj(CUBE_OBJ).unwrap();
    assert_eq!(mesh.num_vertices(), 8);
    assert_eq!(mesh.num_triangles(), 12);
    assert!((mesh.area() - 6.0).abs() < 1e-6);
    assert!(compact(&mesh));
    // Two objects merge with offset indices.
    let two = format!("{CUBE_OBJ}o second\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf 9 10 11\n");
    let mesh = parse_obj(&two).unwrap();
    assert_eq!((mesh.num_vertices(), mesh.num_triangles()), (11, 13));
    assert_eq!(mesh.triangles[12], [8, 9, 10]);
    assert_eq!(mesh.vertices[10], Vector::new(5.0, 1.0, 0.0));
}

#[test]
fn obj_errors() {
    assert!(matches!(parse_obj(""), Err(MeshingError::EmptyMesh)));
    assert!(matches!(
        parse_obj("v 0 0 0\nv 1 0 0\nl 1 2\n"),
        Err(MeshingError::EmptyMesh)
    ));
    assert!(matches!(
        parse_obj("v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"),
        Err(MeshingError::NonFinitePosition { vertex: 1 })
    ));
    assert!(matches!(
        parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"),
        Err(MeshingError::Obj(_))
    ));
    assert!(matches!(
        parse_obj("v 0 x 0\nf 1 1 1\n"),
        Err(MeshingError::Obj(_))
    ));
    assert!(matches!(
        load_obj("/nonexistent/definitely/missing.obj"),
        Err(MeshingError::Io { .. })
    ));
}

#[test]
fn obj_file_round_trip() {
    let path = std::env::temp_dir().join(format!("rapier_touch_cube_{}.obj", std::process::id()));
    std::fs::write(&path, CUBE_OBJ).unwrap();
    let mesh = load_obj(&path);
    let _ = std::fs::remove_file(&path);
    assert_eq!(mesh.unwrap().num_triangles(), 12);
}

#[test]
fn paper_plate_size() {
    let planar = triangulate_planar(&paper_plate_outline(), PAPER_PLATE_TARGET_EDGE).unwrap();
    let n = planar.mesh.num_vertices() as i64;
    assert!((n - 517).abs() <= 40, "{n} nodes");
    assert!(all_ccw_from_up(&planar.mesh));
    // The notch is half a regular 24-gon: 12 triangles of apex angle π/12.
    let notch = 12.0 * 0.5 * 0.04f32.powi(2) * (std::f32::consts::PI / 12.0).sin();
    let area = 0.3 * 0.2 - notch;
    assert!(
        (planar.mesh.area() - area).abs() < 1e-6,
        "{}",
        planar.mesh.area()
    );
    assert!(planar.refinement_complete);
}

#[test]
fn paper_organ_size() {
    let (outline, h) = paper_organ_outline();
    let planar = triangulate_planar(&outline, h).unwrap();
    let n = planar.mesh.num_vertices() as i64;
    assert!((n - 790).abs() <= 50, "{n} nodes");
    assert!(all_ccw_from_up(&planar.mesh));
    assert!(compact(&planar.mesh));
    assert!(planar.refinement_complete);
    let chain = &planar.constrained[0];
    assert!(chain.len() > outline.constraints[0].len());
    let mesh_edges = edges(&planar.mesh);
    assert!(chain
        .windows(2)
        .all(|w| mesh_edges.contains(&(w[0].min(w[1]), w[0].max(w[1])))));
}
