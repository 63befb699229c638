//! Sharp tools on a coarse surface, in a real rapier pipeline: a needle tip, a cube corner and a
//! blade edge pressed into the middle of large triangles (no surface vertex under the tool)
//! get the force of the static spring solution with the load at the contact points (solved
//! here, with the Laplacian written in the test), and never get below the deformed surface.

use crate::common::edge_laplacian;
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

fn world_with_plate(
    substeps: u32,
    mass: f32,
    integrator: Integrator,
) -> (PhysicsWorld, SurfaceSet, SurfaceHandle) {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    let body = world.insert_body(RigidBodyBuilder::fixed());
    let (v, t) = plate_mesh();
    let n = v.len() as u32;
    let surface = MassSpringSurfaceBuilder::new(v, t)
        .stiffness(K)
        .damping(1.0)
        .mass(MassDistribution::PerVertex(mass))
        .pinned((0..n).filter(|&i| pinned(i)))
        .integrator(integrator)
        .build()
        .unwrap();
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps,
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

/// Static reference: the surface points at `points` (x, z) pressed to depth `depth` (y), the
/// pins at zero, linear springs; returns the total force on the tool (up). With `G = Wᵀ K⁻¹ W`
/// (`W`: the points' weights, `K`: the free vertices' stiffness Laplacian) the point loads are
/// `G⁻¹ d 1` (least squares where points repeat a constraint).
fn static_force(points: &[(f32, f32)], depth: f64) -> f64 {
    let (v, t) = plate_mesh();
    let n = v.len();
    let lap = edge_laplacian(&t, n, K as f64);
    let free: Vec<usize> = (0..n).filter(|&i| !pinned(i as u32)).collect();
    let slot = |i: usize| free.iter().position(|&f| f == i);
    let kff = nalgebra::DMatrix::from_fn(free.len(), free.len(), |r, c| lap[(free[r], free[c])]);
    let kinv = kff.try_inverse().unwrap();
    let mut w = nalgebra::DMatrix::<f64>::zeros(free.len(), points.len());
    for (c, &(x, z)) in points.iter().enumerate() {
        for (i, wt) in weights_at(x, z) {
            if let Some(s) = slot(i) {
                w[(s, c)] += wt;
            }
        }
    }
    let g = w.transpose() * kinv * &w;
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

/// Lowers a kinematic tool (shape `shape`, turned by `rotation`) so that the lowest points
/// `probes` (tool frame) go from 5 cm above the plate to `depth` below it over 30 steps, holds
/// it 240 steps; checks after every step that no probe is below the deformed surface; returns
/// the final reaction.
#[allow(clippy::too_many_arguments)]
fn press_tool(
    shape: SharedShape,
    rotation: Rotation,
    lowest: f32,
    probes: &[Vector],
    at: (f32, f32),
    depth: f32,
    substeps: u32,
    mass: f32,
    integrator: Integrator,
) -> ToolReaction {
    let (mut world, mut set, h) = world_with_plate(substeps, mass, integrator);
    let above = Vector::new(at.0, 0.05 - lowest, at.1);
    let below = Vector::new(at.0, -depth - lowest, at.1);
    let b = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().pose(Pose::from_parts(above, rotation)),
    );
    let tool = world.insert_collider(ColliderBuilder::new(shape), Some(b));
    set.add_tool(tool, &mut world);
    for step in 0..270 {
        let a = ((step + 1) as f32 / 30.0).min(1.0);
        world.bodies[b].set_next_kinematic_translation(above.lerp(below, a));
        set.step(&mut world);
        let pose = *world.colliders[tool].position();
        for probe in probes {
            let p = pose.transform_point(*probe);
            let y = surface_height(&set, h, p.x, p.z).expect("probe over the plate");
            assert!(
                p.y >= y - 1e-5,
                "step {step}: tool point {p:?} is {} m below the surface",
                y - p.y
            );
        }
    }
    set.tool_reaction(tool).unwrap()
}

fn check(name: &str, reaction: ToolReaction, expected: f64) {
    let got = reaction.force.y as f64;
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
}

const SETTINGS: [(u32, f32, Integrator); 3] = [
    (8, 0.01, Integrator::EXACT),
    (1, 1e-4, Integrator::EXACT),
    (8, 0.01, Integrator::NEIGHBOUR),
];

#[test]
fn needle_tip_inside_a_large_triangle_gets_the_static_force() {
    // A slim pyramid, tip down at the origin of its frame.
    let r = 0.003;
    let points = [
        Vector::ZERO,
        Vector::new(-r, 0.1, -r),
        Vector::new(r, 0.1, -r),
        Vector::new(r, 0.1, r),
        Vector::new(-r, 0.1, r),
    ];
    let needle = SharedShape::convex_hull(&points).unwrap();
    // 0.5, 0.3, 0.2 of the triangle (1,1) (2,1) (1,2).
    let at = (0.325, 0.3);
    let depth = 0.01;
    let expected = static_force(&[at], depth as f64);
    for (substeps, mass, integrator) in SETTINGS {
        let r = press_tool(
            needle.clone(),
            Rotation::IDENTITY,
            0.0,
            &[Vector::ZERO],
            at,
            depth,
            substeps,
            mass,
            integrator,
        );
        check(&format!("needle, {substeps} substeps"), r, expected);
    }
}

#[test]
fn cube_corner_inside_a_large_triangle_gets_the_static_force() {
    let half = 0.05;
    let tilt = Rotation::from_rotation_arc(-Vector::ONE.normalize(), -Vector::Y);
    let corner = -half * 3f32.sqrt();
    let at = (0.62, 0.7);
    let depth = 0.01;
    let expected = static_force(&[at], depth as f64);
    let probe = tilt.inverse() * Vector::new(0.0, corner, 0.0);
    for (substeps, mass, integrator) in SETTINGS {
        let r = press_tool(
            SharedShape::cuboid(half, half, half),
            tilt,
            corner,
            &[probe],
            at,
            depth,
            substeps,
            mass,
            integrator,
        );
        check(&format!("cube corner, {substeps} substeps"), r, expected);
    }
}

#[test]
fn blade_edge_across_surface_edges_gets_the_static_force() {
    // A thin blade along x, turned 45° about x so its lowest feature is an edge along x. It
    // spans x = 0.30 .. 0.68 at z = 0.55: across a diagonal (x = 0.45) and a grid line
    // (x = 0.5) of the plate, its two ends inside triangles.
    let (hx, hy, hz) = (0.19, 0.05, 0.002);
    let tilt = Rotation::from_axis_angle(Vector::X, std::f32::consts::FRAC_PI_4);
    let offset = tilt * Vector::new(0.0, -hy, hz); // the lowest edge, from the centre
    let at = (0.49, 0.55 - offset.z);
    let lowest = offset.y;
    let depth = 0.01;
    let contacts = [(0.30, 0.55), (0.45, 0.55), (0.5, 0.55), (0.68, 0.55)];
    let expected = static_force(&contacts, depth as f64);
    let edge = |x: f32| Vector::new(x, -hy, hz);
    let probes: Vec<Vector> = (0..=8).map(|k| edge(-hx + k as f32 * hx / 4.0)).collect();
    for (substeps, mass, integrator) in SETTINGS {
        let r = press_tool(
            SharedShape::cuboid(hx, hy, hz),
            tilt,
            lowest,
            &probes,
            at,
            depth,
            substeps,
            mass,
            integrator,
        );
        check(&format!("blade, {substeps} substeps"), r, expected);
    }
}
