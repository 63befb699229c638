//! Reference scenes shared by the examples, tests and benchmarks (fixed, deterministic).

use crate::geometry::generators::{extruded_polygon, subdivided_box};
use crate::geometry::{ContactKind, TouchMesh};
use crate::math::{Pose, Real, Rotation, Vector};

/// A fixed and a moving mesh with the moving one's pose before and after a step.
#[derive(Clone, Debug)]
pub struct ContactScene {
    /// Short name.
    pub name: &'static str,
    /// What the scene shows.
    pub description: &'static str,
    /// The fixed object.
    pub fixed: TouchMesh,
    /// Its pose.
    pub fixed_pose: Pose,
    /// The moving object.
    pub moving: TouchMesh,
    /// Its pose after the step (penetrating).
    pub pose: Pose,
    /// Its pose before the step.
    pub prev_pose: Pose,
    /// The contact kind of every patch the reconstruction should find, in no particular order.
    pub expected_kinds: Vec<ContactKind>,
    /// The expected reversing vector.
    pub expected_reversing: Vector,
}

fn cuboid(half: Vector) -> TouchMesh {
    let (v, i) = subdivided_box(half, 1);
    TouchMesh::new(v, i).expect("a box is a valid mesh")
}

/// The four test cases of the paper's Fig. 4: a line (edge) contact, a face contact, a vertex
/// contact, and multiple point contacts of two non-convex objects.
pub fn fig4_scenes() -> Vec<ContactScene> {
    let floor = cuboid(Vector::new(2.0, 0.5, 2.0));
    let floor_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
    let cube = cuboid(Vector::splat(0.5));
    let half_diag = (0.5 as Real) * (2.0 as Real).sqrt();
    let rot_edge = Rotation::from_rotation_z(std::f32::consts::FRAC_PI_4);
    let rot_vertex = Rotation::from_rotation_arc(Vector::NEG_ONE.normalize(), Vector::NEG_Y);
    let corner = (0.5 as Real) * (3.0 as Real).sqrt();

    // (d): a fixed U-shaped block with two plateaus, and a moving bar with two V-shaped tips,
    // tilted so each tip touches with a single corner.
    let u_block = extruded_polygon(
        &[
            [-2.0, -1.0],
            [2.0, -1.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 0.0],
            [-1.0, 0.0],
            [-1.0, 1.0],
            [-2.0, 1.0],
        ],
        2.0,
    )
    .expect("valid outline");
    let tips = extruded_polygon(
        &[
            [-1.5, 0.0],
            [-1.2, 0.5],
            [1.2, 0.5],
            [1.5, 0.0],
            [1.8, 0.5],
            [1.8, 1.0],
            [-1.8, 1.0],
            [-1.8, 0.5],
        ],
        1.0,
    )
    .expect("valid outline");
    let tilt: Real = 0.2;
    let tip_drop = 0.5 * tilt.sin();

    vec![
        ContactScene {
            name: "line",
            description: "a cube standing on an edge sinks 0.1 m into a slab: line (edge) contact",
            fixed: floor.clone(),
            fixed_pose: floor_pose,
            moving: cube.clone(),
            pose: Pose::from_parts(Vector::new(0.2, half_diag - 0.1, 0.1), rot_edge),
            prev_pose: Pose::from_parts(Vector::new(0.2, half_diag + 0.3, 0.1), rot_edge),
            expected_kinds: vec![ContactKind::Edge],
            expected_reversing: Vector::new(0.0, 0.1, 0.0),
        },
        ContactScene {
            name: "face",
            description: "a cube falling at a slant sinks 0.15 m flat into a slab: face contact",
            fixed: floor.clone(),
            fixed_pose: floor_pose,
            moving: cube.clone(),
            pose: Pose::from_translation(Vector::new(0.0, 0.35, 0.0)),
            prev_pose: Pose::from_translation(Vector::new(-0.2, 0.85, 0.1)),
            // |D| along y is 0.5 of |D| = 0.5477: walking back 0.15 in y walks back 0.2 in x
            // times 0.15/0.5 = 0.06 and 0.03 in z.
            expected_kinds: vec![ContactKind::Face],
            expected_reversing: Vector::new(-0.06, 0.15, 0.03),
        },
        ContactScene {
            name: "vertex",
            description: "a cube falling corner first sinks 0.05 m into a slab: vertex contact",
            fixed: floor,
            fixed_pose: floor_pose,
            moving: cube,
            pose: Pose::from_parts(Vector::new(-0.4, corner - 0.05, 0.3), rot_vertex),
            prev_pose: Pose::from_parts(Vector::new(-0.4, corner + 0.45, 0.3), rot_vertex),
            expected_kinds: vec![ContactKind::Vertex],
            expected_reversing: Vector::new(0.0, 0.05, 0.0),
        },
        ContactScene {
            name: "multi_point",
            description: "a tilted two-tipped bar lands on the two plateaus of a U block: \
                          two point contacts between non-convex objects",
            fixed: TouchMesh::new(u_block.0, u_block.1).expect("valid mesh"),
            fixed_pose: Pose::IDENTITY,
            moving: TouchMesh::new(tips.0, tips.1).expect("valid mesh"),
            pose: Pose::from_parts(
                Vector::new(0.0, 1.0 + tip_drop - 0.05, 0.0),
                Rotation::from_rotation_x(tilt),
            ),
            prev_pose: Pose::from_parts(
                Vector::new(0.0, 1.0 + tip_drop + 0.25, 0.0),
                Rotation::from_rotation_x(tilt),
            ),
            expected_kinds: vec![ContactKind::Vertex, ContactKind::Vertex],
            expected_reversing: Vector::new(0.0, 0.05, 0.0),
        },
    ]
}
