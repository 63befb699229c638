//! Sharp tools on a coarse surface, in a real rapier pipeline: a needle tip, a cube corner and a
//! blade edge pressed into the middle of large triangles (no surface vertex under the tool)
//! get the force of the static spring solution with the load at the contact points (solved
//! here, with the Laplacian written in the test), and never get below the deformed surface.
//! A property test repeats it for plates from 0.1 mm to 10 km, turned any way, stiff and soft,
//! light and heavy, with convex and triangle-mesh tools, anywhere inside a triangle.

use crate::common::strategies::rotation;
use crate::common::{edge_laplacian, point_compliance, steady};
use proptest::prelude::*;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

const N: u32 = 4; // cells per side: 5 x 5 vertices, 0.25 m apart (1 m plate)
const STEP: f32 = 0.25;
const K: f32 = 100.0;

fn vid(i: u32, j: u32) -> u32 {
    i * (N + 1) + j
}

fn plate_mesh() -> (Vec<Vector>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for i in 0..=N {
        for j in 0..=N {
            v.push(Vector::new(i as f32 * STEP, 0.0, j as f32 * STEP));
        }
    }
    let mut t = Vec::new();
    for i in 0..N {
        for j in 0..N {
            let a = vid(i, j);
            let b = a + N + 1;
            t.push([a, b, a + 1]);
            t.push([b, b + 1, a + 1]);
        }
    }
    (v, t)
}

fn pinned(i: u32) -> bool {
    let (a, b) = (i / (N + 1), i % (N + 1));
    a == 0 || b == 0 || a == N || b == N
}

/// The plate's setting: its size (the unit plate times `scale`), how its fixed body is turned,
/// its springs and masses, and how it is stepped.
#[derive(Copy, Clone, Debug)]
struct Plate {
    scale: f32,
    turn: Rotation,
    stiffness: f32,
    damping: f32,
    mass: f32,
    substeps: u32,
    integrator: Integrator,
}

impl Plate {
    fn unit(substeps: u32, mass: f32, integrator: Integrator) -> Self {
        Plate {
            scale: 1.0,
            turn: Rotation::IDENTITY,
            stiffness: K,
            damping: 1.0,
            mass,
            substeps,
            integrator,
        }
    }
}

fn world_with_plate(plate: &Plate) -> (PhysicsWorld, SurfaceSet, SurfaceHandle) {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    let body = world.insert_body(RigidBodyBuilder::fixed().rotation(plate.turn.to_scaled_axis()));
    let (v, t) = plate_mesh();
    let v = v.into_iter().map(|p| p * plate.scale).collect();
    let n = plate_mesh().0.len() as u32;
    let surface = MassSpringSurfaceBuilder::new(v, t)
        .stiffness(plate.stiffness)
        .damping(plate.damping)
        .mass(MassDistribution::PerVertex(plate.mass))
        .pinned((0..n).filter(|&i| pinned(i)))
        .integrator(plate.integrator)
        .build()
        .unwrap();
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: plate.substeps,
        collider: true,
    };
    let h = set.insert(surface, body, &mut world, options).unwrap();
    (world, set, h)
}

/// Barycentric weights of the undeformed plate at `(x, z)`: `(vertex, weight)`.
fn weights_at(x: f32, z: f32) -> Vec<(usize, f64)> {
    let (v, t) = plate_mesh();
    for tri in &t {
        let p = tri.map(|i| v[i as usize]);
        let (ax, az) = (p[0].x as f64, p[0].z as f64);
        let (e1x, e1z) = (p[1].x as f64 - ax, p[1].z as f64 - az);
        let (e2x, e2z) = (p[2].x as f64 - ax, p[2].z as f64 - az);
        let det = e1x * e2z - e2x * e1z;
        let (rx, rz) = (x as f64 - ax, z as f64 - az);
        let b = (rx * e2z - e2x * rz) / det;
        let c = (e1x * rz - rx * e1z) / det;
        if b >= -1e-9 && c >= -1e-9 && b + c <= 1.0 + 1e-9 {
            return vec![
                (tri[0] as usize, 1.0 - b - c),
                (tri[1] as usize, b),
                (tri[2] as usize, c),
            ];
        }
    }
    panic!("({x}, {z}) is off the plate");
}

/// Static reference: the surface points at `points` (x, z, unit plate) pressed to depth `depth`
/// (y, m), the pins at zero, linear springs of stiffness `k`; returns the total force on the
/// tool (up). With `G = Wᵀ K⁻¹ W`
/// (`W`: the points' weights, `K`: the free vertices' stiffness Laplacian) the point loads are
/// `G⁻¹ d 1` (least squares where points repeat a constraint).
fn static_force(points: &[(f32, f32)], depth: f64, k: f64) -> f64 {
    let (v, t) = plate_mesh();
    let n = v.len();
    let lap = edge_laplacian(&t, n, k);
    let rim: Vec<bool> = (0..n as u32).map(pinned).collect();
    let weights: Vec<Vec<(usize, f64)>> = points.iter().map(|&(x, z)| weights_at(x, z)).collect();
    let weights: Vec<&[(usize, f64)]> = weights.iter().map(|w| w.as_slice()).collect();
    let g = point_compliance(&lap, &rim, &weights);
    let ones = nalgebra::DVector::from_element(points.len(), depth);
    let loads = g.svd(true, true).solve(&ones, 1e-12).unwrap();
    loads.sum()
}

/// The deformed surface's height under `(x, z)` (its triangle in the current xz projection).
fn surface_height(set: &SurfaceSet, h: SurfaceHandle, x: f32, z: f32) -> Option<f32> {
    let s = &set.get(h)?.surface;
    for tri in s.triangles() {
        let p = tri.map(|i| s.position(i));
        let e1 = p[1] - p[0];
        let e2 = p[2] - p[0];
        let det = e1.x * e2.z - e2.x * e1.z;
        let (rx, rz) = (x - p[0].x, z - p[0].z);
        let b = (rx * e2.z - e2.x * rz) / det;
        let c = (e1.x * rz - rx * e1.z) / det;
        if b >= -1e-6 && c >= -1e-6 && b + c <= 1.0 + 1e-6 {
            return Some(p[0].y + b * e1.y + c * e2.y);
        }
    }
    None
}

/// A tool at unit scale: its shape for a given scale, how it is turned in the plate's frame,
/// the height of its lowest point below its origin (unit plate) and points of it that must
/// stay above the surface (tool frame, unit plate).
struct Tool {
    shape: fn(f32) -> SharedShape,
    rotation: Rotation,
    lowest: f32,
    probes: Vec<Vector>,
}

/// Lowers a kinematic tool in the plate's frame so that its lowest point goes from 5 cm (unit
/// plate) above the plate, over `at`, to `depth` below it over 30 steps, holds it 240 steps;
/// checks after every step that no probe is below the deformed surface (by more than 1e-5 of
/// the scale); returns the final reaction's force in the plate's frame, with the reaction.
fn press_tool(plate: &Plate, tool: &Tool, at: (f32, f32), depth: f32) -> (Vector, ToolReaction) {
    let (mut world, mut set, h) = world_with_plate(plate);
    let k = plate.scale;
    let above = Vector::new(at.0, 0.05 - tool.lowest, at.1) * k;
    let below = Vector::new(at.0, -depth - tool.lowest, at.1) * k;
    let in_world = |p: Vector| plate.turn * p;
    let b = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().pose(Pose::from_parts(
            in_world(above),
            plate.turn * tool.rotation,
        )),
    );
    let c = world.insert_collider(ColliderBuilder::new((tool.shape)(k)), Some(b));
    set.add_tool(c, &mut world).unwrap();
    for step in 0..270 {
        let a = ((step + 1) as f32 / 30.0).min(1.0);
        world.bodies[b].set_next_kinematic_translation(in_world(above.lerp(below, a)));
        set.step(&mut world);
        let pose = *world.colliders[c].position();
        for probe in &tool.probes {
            let p = plate.turn.inverse() * pose.transform_point(*probe * k);
            let y = surface_height(&set, h, p.x, p.z).expect("probe over the plate");
            assert!(
                p.y >= y - 1e-5 * k,
                "step {step}: tool point {p:?} is {} m below the surface",
                y - p.y
            );
        }
    }
    let r = set.tool_reaction(c).unwrap();
    (plate.turn.inverse() * r.force, r)
}

fn check(name: &str, (force, reaction): (Vector, ToolReaction), expected: f64) {
    let got = force.y as f64;
    assert!(expected > 0.0);
    assert!(
        (got - expected).abs() <= 0.05 * expected,
        "{name}: force {got} N vs static {expected} N ({reaction:?})"
    );
    assert_eq!(
        reaction.held_vertices, 0,
        "{name}: no surface vertex is under the tool"
    );
    assert!(reaction.pressed_points > 0);
    assert!(steady(&reaction), "{name}: not at rest: {reaction:?}");
}

const SETTINGS: [(u32, f32, Integrator); 3] = [
    (8, 0.01, Integrator::EXACT),
    (1, 1e-4, Integrator::EXACT),
    (8, 0.01, Integrator::NEIGHBOUR),
];

/// A slim pyramid, tip down at the origin of its frame.
fn needle_points(k: f32) -> Vec<Vector> {
    let r = 0.003;
    [
        Vector::ZERO,
        Vector::new(-r, 0.1, -r),
        Vector::new(r, 0.1, -r),
        Vector::new(r, 0.1, r),
        Vector::new(-r, 0.1, r),
    ]
    .map(|p| p * k)
    .to_vec()
}

fn needle() -> Tool {
    Tool {
        shape: |k| SharedShape::convex_hull(&needle_points(k)).unwrap(),
        rotation: Rotation::IDENTITY,
        lowest: 0.0,
        probes: vec![Vector::ZERO],
    }
}

/// The same needle as a triangle mesh (the general, non-convex path).
fn trimesh_needle() -> Tool {
    Tool {
        shape: |k| {
            let hull = SharedShape::convex_hull(&needle_points(k)).unwrap();
            let (v, i) = hull.as_convex_polyhedron().unwrap().to_trimesh();
            SharedShape::trimesh(v, i).unwrap()
        },
        ..needle()
    }
}

const HALF: f32 = 0.05;

/// A cube with its body diagonal vertical, corner down.
fn cube_corner() -> Tool {
    let tilt = Rotation::from_rotation_arc(-Vector::ONE.normalize(), -Vector::Y);
    let corner = -HALF * 3f32.sqrt();
    Tool {
        shape: |k| SharedShape::cuboid(HALF * k, HALF * k, HALF * k),
        rotation: tilt,
        lowest: corner,
        probes: vec![tilt.inverse() * Vector::new(0.0, corner, 0.0)],
    }
}

#[test]
fn needle_tip_inside_a_large_triangle_gets_the_static_force() {
    // 0.5, 0.3, 0.2 of the triangle (1,1) (2,1) (1,2).
    let at = (0.325, 0.3);
    let depth = 0.01;
    let expected = static_force(&[at], depth as f64, K as f64);
    for (substeps, mass, integrator) in SETTINGS {
        let r = press_tool(
            &Plate::unit(substeps, mass, integrator),
            &needle(),
            at,
            depth,
        );
        check(&format!("needle, {substeps} substeps"), r, expected);
    }
}

#[test]
fn cube_corner_inside_a_large_triangle_gets_the_static_force() {
    let at = (0.62, 0.7);
    let depth = 0.01;
    let expected = static_force(&[at], depth as f64, K as f64);
    for (substeps, mass, integrator) in SETTINGS {
        let plate = Plate::unit(substeps, mass, integrator);
        let r = press_tool(&plate, &cube_corner(), at, depth);
        check(&format!("cube corner, {substeps} substeps"), r, expected);
    }
}

#[test]
fn blade_edge_across_surface_edges_gets_the_static_force() {
    // A thin blade along x, turned 45° about x so its lowest feature is an edge along x. It
    // spans x = 0.30 .. 0.68 at z = 0.55: across a diagonal (x = 0.45) and a grid line
    // (x = 0.5) of the plate, its two ends inside triangles.
    const HX: f32 = 0.19;
    const HY: f32 = 0.05;
    const HZ: f32 = 0.002;
    let tilt = Rotation::from_axis_angle(Vector::X, std::f32::consts::FRAC_PI_4);
    let offset = tilt * Vector::new(0.0, -HY, HZ); // the lowest edge, from the centre
    let at = (0.49, 0.55 - offset.z);
    let depth = 0.01;
    let contacts = [(0.30, 0.55), (0.45, 0.55), (0.5, 0.55), (0.68, 0.55)];
    let expected = static_force(&contacts, depth as f64, K as f64);
    let blade = Tool {
        shape: |k| SharedShape::cuboid(HX * k, HY * k, HZ * k),
        rotation: tilt,
        lowest: offset.y,
        probes: (0..=8)
            .map(|i| Vector::new(-HX + i as f32 * HX / 4.0, -HY, HZ))
            .collect(),
    };
    for (substeps, mass, integrator) in SETTINGS {
        let r = press_tool(&Plate::unit(substeps, mass, integrator), &blade, at, depth);
        check(&format!("blade, {substeps} substeps"), r, expected);
    }
}

/// The interior triangles of the plate with no pinned vertex: cells (1..=2, 1..=2), both
/// halves.
fn free_triangle(k: usize) -> [u32; 3] {
    let (i, j) = (1 + (k / 2) as u32 % 2, 1 + (k / 4) as u32 % 2);
    let a = vid(i, j);
    let b = a + N + 1;
    if k.is_multiple_of(2) {
        [a, b, a + 1]
    } else {
        [b, b + 1, a + 1]
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Any scale from 0.1 mm to 10 km, the plate turned any way, springs from 10 to 1000 N/m
    /// (nearly critically damped), vertex masses from 0.1 g to 1 kg, 1 or 8 substeps, the exact
    /// or the neighbour filter (which falls back to the exact one where `s` is large), a convex
    /// or a triangle-mesh needle or a cube corner, pressed 0.5 to 1.5 % of the plate anywhere
    /// inside a free triangle (at least 0.15 from its edges in barycentric terms): the static
    /// force within 5 %, steady from substep to substep at rest, and never below the surface.
    #[test]
    fn sharp_tools_get_the_static_force_at_any_scale_turn_stiffness_and_mass(
        exp in -4.0f32..4.0, turn in rotation(), kexp in 1.0f32..3.0, mexp in -4.0f32..0.0,
        substeps in prop::sample::select(vec![1u32, 8]), tool in 0usize..3, tri in 0usize..8,
        (b, c) in (0.15f32..0.7, 0.15f32..0.7).prop_filter("inside", |(b, c)| b + c <= 0.85),
        depth in 0.005f32..0.015,
        integrator in prop::sample::select(vec![Integrator::EXACT, Integrator::NEIGHBOUR]),
    ) {
        let (stiffness, mass) = (10f32.powf(kexp), 10f32.powf(mexp));
        let plate = Plate {
            scale: 10f32.powf(exp),
            turn,
            stiffness,
            damping: 2.0 * (stiffness * mass).sqrt(),
            mass,
            substeps,
            integrator,
        };
        let (v, _) = plate_mesh();
        let [p0, p1, p2] = free_triangle(tri).map(|i| v[i as usize]);
        let p = p0 * (1.0 - b - c) + p1 * b + p2 * c;
        let at = (p.x, p.z);
        let tool = vec![needle(), trimesh_needle(), cube_corner()].swap_remove(tool);
        let expected = static_force(&[at], (depth * plate.scale) as f64, stiffness as f64);
        let (force, r) = press_tool(&plate, &tool, at, depth);
        prop_assert!(
            (force.y as f64 - expected).abs() <= 0.05 * expected,
            "force {force:?} vs static {expected} N ({r:?})"
        );
        prop_assert_eq!(r.held_vertices, 0);
        prop_assert!(steady(&r), "last substep {:?} vs the step's mean {:?}", r.force, r.mean_force);
    }
}

/// The contact search on bad input: no triangles, a degenerate triangle, a candidate index
/// out of range, NaN or infinite poses and NaN surface positions give no contact (and no NaN),
/// never a panic; the same call on good input finds the corner.
#[test]
fn surface_contact_search_on_bad_input_finds_nothing() {
    use rapier_touch::geometry::{tool_surface_contacts, SurfaceSnapshot};
    let square = [
        Vector::new(-1.0, 0.0, -1.0),
        Vector::new(1.0, 0.0, -1.0),
        Vector::new(1.0, 0.0, 1.0),
        Vector::new(-1.0, 0.0, 1.0),
    ];
    let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.1))).unwrap();
    let tilt = Rotation::from_rotation_arc(Vector::ONE.normalize(), Vector::Y);
    let corner = 0.1 * 3f32.sqrt();
    let start = Pose::from_parts(Vector::new(0.3, corner + 0.01, 0.1), tilt);
    let end = Pose::from_parts(Vector::new(0.3, corner - 0.01, 0.1), tilt);
    let search = |pos: &[Vector], tris: &[[u32; 3]], cand: &[u32], s: &Pose, e: &Pose| {
        let surface = SurfaceSnapshot {
            before: pos,
            now: pos,
            triangles: tris,
        };
        let mut out = Vec::new();
        tool_surface_contacts(&surface, cand, &cube, s, e, 1e-6, &mut out);
        out
    };
    let good = [[0, 2, 1], [0, 3, 2]];
    assert_eq!(search(&square, &good, &[0, 1], &start, &end).len(), 1);
    assert!(search(&square, &[], &[0, 1], &start, &end).is_empty());
    assert!(search(&square, &[[0, 1, 1]], &[0], &start, &end).is_empty());
    assert!(search(&square, &[[0, 0, 0]], &[0], &start, &end).is_empty());
    assert!(search(&square, &good, &[7, 99], &start, &end).is_empty());
    assert!(search(&square, &[[0, 2, 9]], &[0], &start, &end).is_empty());
    let nan = Pose::from_parts(Vector::splat(f32::NAN), tilt);
    let inf = Pose::from_parts(Vector::new(f32::INFINITY, 0.0, 0.0), tilt);
    for (s, e) in [(nan, end), (start, nan), (inf, end), (start, inf)] {
        let out = search(&square, &good, &[0, 1], &s, &e);
        assert!(
            out.iter()
                .all(|c| c.depth.is_finite() && c.normal.is_finite() && c.point.is_finite()),
            "{out:?}"
        );
    }
    let mut bad = square;
    bad[2] = Vector::splat(f32::NAN);
    assert!(search(&bad, &good, &[0, 1], &start, &end).is_empty());
}
