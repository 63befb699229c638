//! Non-convex and compound tools on a soft plate, in a real rapier pipeline: a U-shaped
//! triangle-mesh tool pressed legs-down and corner-first, and a two-jaw compound tool, hold the
//! surface and get forces. Checked against independent answers: at rest the tool's force
//! balances the pins' reaction (Newton's third law over the spring network: the surface's
//! internal forces sum to zero), no surface vertex is inside the tool (parry's own query on an
//! oriented copy of the mesh, or on the compound's parts), no probe point of the tool is below
//! the deformed surface, and the surface is dented under every leg or jaw.

use parry3d::query::PointQuery;
use proptest::prelude::*;
use rapier_touch::geometry::generators::extruded_polygon;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim};

const CELLS: u32 = 16; // 1 m plate, 62.5 mm cells
const DEPTH: f32 = 0.03;

struct Pressed {
    world: PhysicsWorld,
    set: SurfaceSet,
    surface: SurfaceHandle,
    tool: ColliderHandle,
}

/// Lowers a kinematic tool (its lowest point `lowest` below its origin, turned by `turn`) from
/// 5 cm above the plate's centre to `DEPTH` into it over 40 steps, then holds it 200 steps;
/// after every step no probe (tool frame) is below the deformed surface.
fn press(shape: SharedShape, turn: Rotation, lowest: f32, probes: &[Vector]) -> Pressed {
    press_at(shape, turn, lowest, probes, (0.013, -0.021))
}

/// [`press`] over the plate point `at` (x, z).
fn press_at(
    shape: SharedShape,
    turn: Rotation,
    lowest: f32,
    probes: &[Vector],
    at: (f32, f32),
) -> Pressed {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    let mesh = plate(1.0, 1.0, CELLS, CELLS);
    let surface = MassSpringSurfaceBuilder::from_mesh(&mesh)
        .stiffness(50.0)
        .damping(0.5)
        .mass(MassDistribution::PerVertex(0.005))
        .pinned(plate_rim(CELLS, CELLS))
        .integrator(Integrator::EXACT)
        .build()
        .unwrap();
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: 8,
        collider: true,
    };
    let surface = set.insert(surface, ground, &mut world, options).unwrap();
    let above = Vector::new(at.0, 0.05 - lowest, at.1);
    let below = Vector::new(at.0, -DEPTH - lowest, at.1);
    let body = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().pose(Pose::from_parts(above, turn)),
    );
    let tool = world.insert_collider(ColliderBuilder::new(shape), Some(body));
    set.add_tool(tool, &mut world).unwrap();
    for step in 0..240 {
        let a = ((step + 1) as f32 / 40.0).min(1.0);
        world.bodies[body].set_next_kinematic_translation(above.lerp(below, a));
        set.step(&mut world);
        let pose = *world.colliders[tool].position();
        let s = &set.get(surface).unwrap().surface;
        for probe in probes {
            let p = pose.transform_point(*probe);
            let y = height_under(s, p.x, p.z);
            assert!(
                p.y >= y - 1e-5,
                "step {step}: {p:?} is {} m under the surface",
                y - p.y
            );
        }
    }
    Pressed {
        world,
        set,
        surface,
        tool,
    }
}

/// The deformed surface's height under `(x, z)`.
fn height_under(s: &MassSpringSurface, x: f32, z: f32) -> f32 {
    for tri in s.triangles() {
        let p = tri.map(|i| s.position(i));
        let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
        let det = e1.x * e2.z - e2.x * e1.z;
        let (rx, rz) = (x - p[0].x, z - p[0].z);
        let b = (rx * e2.z - e2.x * rz) / det;
        let c = (e1.x * rz - rx * e1.z) / det;
        if b >= -1e-6 && c >= -1e-6 && b + c <= 1.0 + 1e-6 {
            return p[0].y + b * e1.y + c * e2.y;
        }
    }
    panic!("({x}, {z}) is off the plate");
}

/// The checks every pressed tool must pass; `inside` tells how deep a world point is inside
/// the tool (0 outside), `dents`: world points (x, z) under each leg or jaw.
fn check(r: &Pressed, inside: impl Fn(Vector) -> f32, dents: &[(f32, f32)], name: &str) {
    let reaction = r.set.tool_reaction(r.tool).unwrap();
    let s = &r.set.get(r.surface).unwrap().surface;
    let force = reaction.force;
    assert!(force.y > 0.0, "{name}: {reaction:?}");
    // The pins' reaction: the springs' pull on the pinned vertices.
    let pins: Vector = plate_rim(CELLS, CELLS)
        .into_iter()
        .map(|i| s.internal_force(i))
        .sum();
    assert!(
        (force + pins).length() <= 0.05 * force.length(),
        "{name}: tool {force:?} vs pins {pins:?}"
    );
    for i in 0..s.num_vertices() as u32 {
        let depth = inside(s.position(i));
        assert!(
            depth <= 1e-5,
            "{name}: vertex {i} is {depth} m inside the tool"
        );
    }
    for &(x, z) in dents {
        let y = height_under(s, x, z);
        assert!(y < -0.5 * DEPTH, "{name}: only {y} m deep at ({x}, {z})");
    }
}

/// A U: two legs 40 mm wide, 100 mm apart, 100 mm long, joined on top; 80 mm deep in z.
fn u_shape() -> SharedShape {
    let outline = [
        [-0.09, 0.0],
        [-0.05, 0.0],
        [-0.05, 0.1],
        [0.05, 0.1],
        [0.05, 0.0],
        [0.09, 0.0],
        [0.09, 0.15],
        [-0.09, 0.15],
    ];
    let (v, i) = extruded_polygon(&outline, 0.08).unwrap();
    SharedShape::trimesh(v, i).unwrap()
}

/// How deep `p` (world) is inside the U (0 outside), by parry on an oriented copy of its mesh.
fn inside_u(r: &Pressed) -> impl Fn(Vector) -> f32 + '_ {
    let pose = *r.world.colliders[r.tool].position();
    let mesh = r.world.colliders[r.tool].shape().as_trimesh().unwrap();
    let oriented = TriMesh::with_flags(
        mesh.vertices().to_vec(),
        mesh.indices().to_vec(),
        parry3d::shape::TriMeshFlags::ORIENTED,
    )
    .unwrap();
    move |p| {
        let proj = oriented.project_point(&pose, p, false);
        if proj.is_inside {
            (proj.point - p).length()
        } else {
            0.0
        }
    }
}

#[test]
fn u_shaped_trimesh_tool_pressed_legs_down_holds_and_gets_the_pins_force() {
    let corners: Vec<Vector> = [-0.09, -0.05, 0.05, 0.09]
        .iter()
        .flat_map(|&x| [Vector::new(x, 0.0, -0.04), Vector::new(x, 0.0, 0.04)])
        .collect();
    let r = press(u_shape(), Rotation::IDENTITY, 0.0, &corners);
    let inside = inside_u(&r);
    check(
        &r,
        inside,
        &[(-0.057, -0.021), (0.083, -0.021)],
        "U legs down",
    );
}

#[test]
fn u_shaped_trimesh_tool_pressed_corner_first_holds_and_gets_the_pins_force() {
    // Tilted about z and x: one leg's outer corner comes down first.
    let turn = Rotation::from_rotation_z(0.35) * Rotation::from_rotation_x(0.25);
    let corners: Vec<Vector> = [-0.09, -0.05, 0.05, 0.09]
        .iter()
        .flat_map(|&x| [Vector::new(x, 0.0, -0.04), Vector::new(x, 0.0, 0.04)])
        .collect();
    let lowest = corners
        .iter()
        .map(|c| (turn * *c).y)
        .fold(f32::MAX, f32::min);
    let r = press(u_shape(), turn, lowest, &corners);
    let tip = corners
        .iter()
        .copied()
        .min_by(|a, b| (turn * *a).y.total_cmp(&(turn * *b).y))
        .unwrap();
    let pose = *r.world.colliders[r.tool].position();
    let at = pose.transform_point(tip);
    let inside = inside_u(&r);
    check(&r, inside, &[(at.x, at.z)], "U corner first");
}

/// Two cuboid jaws (30 x 60 x 40 mm) 120 mm apart on a 20 mm thick bar, and their bottom
/// corners.
fn jaws() -> (SharedShape, Vec<Vector>) {
    let jaw = SharedShape::cuboid(0.015, 0.03, 0.02);
    let bar = SharedShape::cuboid(0.09, 0.01, 0.02);
    let shape = SharedShape::compound(vec![
        (
            Pose::from_translation(Vector::new(-0.075, 0.03, 0.0)),
            jaw.clone(),
        ),
        (Pose::from_translation(Vector::new(0.075, 0.03, 0.0)), jaw),
        (Pose::from_translation(Vector::new(0.0, 0.07, 0.0)), bar),
    ]);
    let probes = [-0.09, -0.06, 0.06, 0.09]
        .iter()
        .flat_map(|&x| [Vector::new(x, 0.0, -0.02), Vector::new(x, 0.0, 0.02)])
        .collect();
    (shape, probes)
}

/// The U's leg-bottom corners.
fn u_corners() -> Vec<Vector> {
    [-0.09, -0.05, 0.05, 0.09]
        .iter()
        .flat_map(|&x| [Vector::new(x, 0.0, -0.04), Vector::new(x, 0.0, 0.04)])
        .collect()
}

/// How deep `p` is inside the collider (0 outside), by parry's query on its shape.
fn inside_of(r: &Pressed) -> impl Fn(Vector) -> f32 + '_ {
    let pose = *r.world.colliders[r.tool].position();
    let shape = r.world.colliders[r.tool].shape();
    move |p| {
        let proj = shape.project_point(&pose, p, false);
        if proj.is_inside {
            (proj.point - p).length()
        } else {
            0.0
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    /// The U or the jaws, turned any way about the vertical and tilted up to 0.4 rad about a
    /// horizontal axis, pressed anywhere within 15 cm of the plate's centre: the pins' balance,
    /// no vertex inside, no corner under the surface, a dent under the lowest corner.
    #[test]
    fn tilted_non_convex_and_compound_tools_hold_anywhere(
        u in any::<bool>(), yaw in 0.0f32..std::f32::consts::TAU, tilt in 0.0f32..0.4,
        tilt_axis in 0.0f32..std::f32::consts::TAU, x in -0.15f32..0.15, z in -0.15f32..0.15,
    ) {
        let horizontal = Vector::new(tilt_axis.cos(), 0.0, tilt_axis.sin());
        let turn = Rotation::from_axis_angle(horizontal, tilt) * Rotation::from_rotation_y(yaw);
        let (shape, probes) = if u { (u_shape(), u_corners()) } else { jaws() };
        let lowest = probes.iter().map(|c| (turn * *c).y).fold(f32::MAX, f32::min);
        let r = press_at(shape, turn, lowest, &probes, (x, z));
        let tip = probes
            .iter()
            .copied()
            .min_by(|a, b| (turn * *a).y.total_cmp(&(turn * *b).y))
            .unwrap();
        let at = r.world.colliders[r.tool].position().transform_point(tip);
        if u {
            check(&r, inside_u(&r), &[(at.x, at.z)], "U");
        } else {
            check(&r, inside_of(&r), &[(at.x, at.z)], "jaws");
        }
    }
}

#[test]
fn two_jaw_compound_tool_holds_with_both_jaws_and_gets_the_pins_force() {
    let (shape, probes) = jaws();
    let r = press(shape, Rotation::IDENTITY, 0.0, &probes);
    check(
        &r,
        inside_of(&r),
        &[(-0.062, -0.021), (0.088, -0.021)],
        "two jaws",
    );
}

/// A case the property test above finds with `PROPTEST_RNG_SEED=3` (shrunk to the two jaws
/// over the plate's centre, untilted): one jaw alone, a 3 × 6 × 4 cm cuboid pressed flat at
/// (-0.075, 0), has its corner (-0.09, -0.02) 1.1 mm under the surface at step 25. Its face
/// holds the surface vertex at (-0.0625, 0); the corner lies in a triangle with that vertex,
/// whose press `MassSpringSurface::press_points` leaves to the vertex's holder, and the
/// triangle's two free vertices stay up. Pressing such points through the free vertices (the
/// held one immovable) kept the corner out but broke five friction and grasp tests: open
/// (issue 13).
#[test]
#[ignore = "known failure, issue 13: presses on a triangle with a held vertex are dropped"]
fn a_flat_cuboid_keeps_its_corners_out_of_a_triangle_beside_a_held_vertex() {
    let shape = SharedShape::cuboid(0.015, 0.03, 0.02);
    let probes: Vec<Vector> = [-0.015, 0.015]
        .iter()
        .flat_map(|&x| [Vector::new(x, -0.03, -0.02), Vector::new(x, -0.03, 0.02)])
        .collect();
    press_at(shape, Rotation::IDENTITY, -0.03, &probes, (-0.075, 0.0));
}
