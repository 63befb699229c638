//! The paper's Fig. 4 cases are reconstructed with the right kind, reversing vector, shape and
//! features; and the 3D edge-edge case (no vertex inside the other object) is found.

use rapier_touch::prelude::*;
use rapier_touch::scenes::fig4_scenes;

fn run(name: &str) -> (ContactConfiguration, rapier_touch::scenes::ContactScene) {
    let s = fig4_scenes().into_iter().find(|s| s.name == name).unwrap();
    let c = Reconstructor::default()
        .reconstruct(&s.fixed, &s.fixed_pose, &s.moving, &s.pose, &s.prev_pose)
        .unwrap();
    assert_eq!(c.state, TouchState::Penetrating, "{name}");
    assert!(
        (c.reversing_vector - s.known.reversing).length() < 1e-5,
        "{name}: {:?}",
        c.reversing_vector
    );
    (c, s)
}

fn polygon_area(p: &ContactPatch) -> f32 {
    let mut a = Vector::ZERO;
    for i in 0..p.polygon.len() {
        a += p.polygon[i].cross(p.polygon[(i + 1) % p.polygon.len()]);
    }
    0.5 * a.dot(p.normal)
}

#[test]
fn line_contact_is_the_cubes_bottom_edge() {
    let (c, _) = run("line");
    assert_eq!(c.patches.len(), 1);
    let p = &c.patches[0];
    assert_eq!(p.kind, ContactKind::Edge);
    assert!((p.polygon[0] - p.polygon[1]).length() - 1.0 < 1e-5); // the cube's unit edge
    assert!(p.polygon.iter().all(|v| v.y.abs() < 1e-5)); // on the slab's top (y = 0)
    assert!(p
        .moving_features
        .iter()
        .any(|f| matches!(f, Feature::Edge(_))));
    assert!((p.normal - Vector::Y).length() < 1e-5);
}

#[test]
fn face_contact_is_the_cubes_bottom_square() {
    let (c, s) = run("face");
    assert_eq!(c.patches.len(), 1);
    let p = &c.patches[0];
    assert_eq!(p.kind, ContactKind::Face);
    assert_eq!(p.polygon.len(), 4);
    assert!(
        (polygon_area(p) - 1.0).abs() < 1e-4,
        "area {}",
        polygon_area(p)
    );
    // Counter-clockwise about the normal (positive area) and centred under the cube.
    let centre = s.pose.translation + c.reversing_vector;
    assert!((p.center() - Vector::new(centre.x, 0.0, centre.z)).length() < 1e-4);
    assert_eq!(c.time_of_impact.map(|t| (t * 1000.0).round()), Some(700.0));
}

#[test]
fn vertex_contact_is_one_corner_on_a_face() {
    let (c, _) = run("vertex");
    assert_eq!(c.patches.len(), 1);
    let p = &c.patches[0];
    assert_eq!(p.kind, ContactKind::Vertex);
    assert_eq!(p.moving_features.len(), 1);
    assert!(matches!(p.moving_features[0], Feature::Vertex(_)));
    assert!(matches!(p.fixed_features[0], Feature::Face(_)));
}

#[test]
fn non_convex_objects_touch_in_two_separate_points() {
    let (c, _) = run("multi_point");
    assert_eq!(c.patches.len(), 2);
    assert!(c.patches.iter().all(|p| p.kind == ContactKind::Vertex));
    let d = c.patches[0].polygon[0] - c.patches[1].polygon[0];
    assert!((d.x.abs() - 3.0).abs() < 1e-4, "tips are 3 m apart: {d:?}");
}

fn bar(half: Vector) -> TouchMesh {
    TouchMesh::from_shape(&Cuboid::new(half)).unwrap()
}

/// Two bars crossed like an X, each resting on a sharp edge: the first touch is an edge of one
/// against an edge of the other, with no vertex of either inside the other. The paper's 2D
/// vertex-only method finds nothing here.
#[test]
fn crossed_edges_penetrate_with_no_vertex_inside() {
    let fixed = bar(Vector::new(2.0, 0.1, 0.1));
    let moving = bar(Vector::new(0.1, 0.1, 2.0));
    let q = std::f32::consts::FRAC_PI_4;
    let fixed_pose = Pose::from_parts(Vector::ZERO, Rotation::from_rotation_x(q));
    let rot_m = Rotation::from_rotation_z(q);
    let r = 0.1 * 2f32.sqrt(); // centre-to-edge distance of a bar standing on its edge
    let now = Pose::from_parts(Vector::new(0.0, 2.0 * r - 0.03, 0.0), rot_m);
    let before = Pose::from_parts(Vector::new(0.0, 2.0 * r + 0.2, 0.0), rot_m);
    let c = Reconstructor::default()
        .reconstruct(&fixed, &fixed_pose, &moving, &now, &before)
        .unwrap();
    assert_eq!(c.state, TouchState::Penetrating);
    assert!((c.depth - 0.03).abs() < 1e-5, "depth {}", c.depth);
    assert_eq!(c.patches.len(), 1);
    let p = &c.patches[0];
    assert_eq!(p.kind, ContactKind::Vertex);
    assert!(matches!(p.points[0].fixed_feature, Feature::Edge(_)));
    assert!(matches!(p.points[0].moving_feature, Feature::Edge(_)));
    assert!((p.polygon[0] - Vector::new(0.0, r, 0.0)).length() < 1e-5);
}
