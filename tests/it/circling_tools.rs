//! Tools pressed into a pinned plate and circled over it, as a hand or a bench drives them
//! (issue 13): the plate's vertices that lie on a tool's faces are grazed along them at every
//! step. Checked against the energy books, not against the crate: with no gravity and no
//! friction the plate's mechanical energy (`kinetic_energy + elastic_energy`) can only rise by
//! the work the tool does on it; the dampers only take energy out. That work is bounded by
//! `Σ |F · Δx|` over the steps (`F` the tool's mean reaction over a step, `Δx` the tool's
//! motion in it). The signed sum is no tighter book: a flat cube circling slowly on a soft
//! plate reads a sideways reaction of 3-4 % of its press (its corners' and edges' points pressed
//! along the bent plate's normals) whose signed work swings by about the plate's own energy
//! over a circle while that energy stays within 6 % (seen, not traced; held still at offsets
//! of 0-16 mm the same cube reads at most 1.1 % of its press sideways, as large as the
//! gradient of the plate's energy there).
//!
//! Two defects showed here. A vertex lying on a cube's face entered it by a micrometre at a
//! substep, was walked back to where it entered, and kept its tangential velocity without
//! its tangential motion: on a 1 kHz plate a cube circling at 30 mm/s took the plate from
//! 1.4 mJ to 65 mJ in 2.4 s, doing 0.1 µJ of work a step. And a tool moved by its collider's
//! `set_position` in a rigid step of the user's own (its body left where it was; rapier's
//! step would put the collider back on its body) started every step from its body's pose,
//! up to 10 mm off: six such cubes took a 10,000-node plate from 5 mJ to 3 J (the crate's
//! own bench drove its tools that way). A third showed once the world's rate reached the
//! surface: a vertex let go at once kept the pull its hold gave it (below, at 4 kHz).
//!
//! Property test over scale (plates of 3 mm-300 m), stiffness (10-1000 N/m), mass (10 g-100 kg),
//! the world's rate (60 Hz-1 kHz) and the surface's substeps (1 or 4: surfaces of 60 Hz to
//! 4 kHz), the circle's size and speed,
//! the tool (a box flat or turned, the box as a convex hull, a ball, a cylinder, a capsule)
//! and how it is driven (its body, or its collider).

use crate::common::{cube_hull, lowest_point, plate_scene};
use proptest::prelude::*;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim};

/// How the test moves the tool.
#[derive(Copy, Clone, Debug)]
enum Drive {
    /// Its kinematic body's next position, then [`SurfaceSet::step`].
    Body,
    /// Its collider's `set_position` as [`SurfaceSet::step_with`]'s rigid step, the body left
    /// where it was (a rigid step of the user's that only moves the tools: rapier's own step
    /// puts an awake kinematic body's colliders back on it).
    Collider,
}

/// The energy books of one circling run.
#[derive(Debug)]
struct Books {
    /// The plate's energy when the circling starts (J).
    start: f64,
    /// The most the plate's energy rose above `start` while circling (J).
    rise: f64,
    /// The bound on the tool's work on the plate so far, `Σ |F · Δx|` (J).
    work: f64,
}

impl Books {
    /// Whether the plate gained no more than the tool's work and a tenth of its start (its
    /// swing as the tool starts circling).
    fn balance(&self) -> bool {
        self.rise <= 0.1 * self.start + self.work
    }
}

/// Drives `tool` along `path` (a pose at each time) for `secs` and keeps the books of the
/// plate `plate` from time `circle` on.
fn run(
    (world, set): (&mut PhysicsWorld, &mut SurfaceSet),
    (tool, plate): (ColliderHandle, SurfaceHandle),
    path: impl Fn(f32) -> Pose,
    drive: Drive,
    (circle, secs): (f32, f32),
) -> Books {
    let dt = world.integration_parameters.dt;
    let body = world.colliders[tool].parent().unwrap();
    world.bodies[body].set_position(path(0.0), true);
    let energy = |set: &SurfaceSet| {
        let s = &set.get(plate).unwrap().surface;
        s.kinetic_energy() + s.elastic_energy()
    };
    let mut books = Books {
        start: 0.0,
        rise: 0.0,
        work: 0.0,
    };
    for s in 0..(secs / dt).round() as usize {
        let (from, to) = (path(s as f32 * dt), path((s + 1) as f32 * dt));
        match drive {
            Drive::Body => {
                world.bodies[body].set_next_kinematic_position(to);
                set.step(world);
            }
            Drive::Collider => set.step_with(world, |w| w.colliders[tool].set_position(to)),
        }
        let r = set.tool_reaction(tool).unwrap();
        assert!(r.mean_force.is_finite(), "reaction {r:?}");
        let e = energy(set);
        assert!(e.is_finite(), "plate energy {e}");
        if (s + 1) as f32 * dt <= circle {
            books.start = e;
            continue;
        }
        books.work += (r.mean_force.dot(to.translation - from.translation) as f64).abs();
        books.rise = books.rise.max(e - books.start);
    }
    books
}

/// A plate `0.3 · scale` wide (16 cells, rim pinned, edges of `k`, `mass` in all, stepped at
/// `rate` Hz in `substeps`) on a fixed body; a tool of `half`-size `0.03 · scale` pressed a
/// third of its half-size in over half a second, held half a second, then circled for two
/// seconds on a circle of `radius` half-sizes at `speed` half-sizes a second.
#[allow(clippy::too_many_arguments)]
fn circle(
    scale: f32,
    k: f32,
    mass: f32,
    (rate, substeps): (f32, u32),
    shape: u8,
    (radius, speed): (f32, f32),
    drive: Drive,
) -> Books {
    let half = 0.03 * scale;
    let (shape, turned) = tool_shape(shape, half);
    let (mut world, mut set, tool, plate) = plate_scene(0.3 * scale, 16, k, mass, substeps, shape);
    world.integration_parameters.dt = 1.0 / rate;
    set.add_tool(tool, &mut world).unwrap();
    // The lowest point of the turned tool below its centre.
    let reach = lowest_point(world.colliders[tool].shape(), turned);
    let depth = half / 3.0;
    let path = |t: f32| {
        let top = -reach + 0.2 * half;
        let y = top - (0.2 * half + depth) * (2.0 * t).min(1.0);
        let a = (t - 1.0).max(0.0) * speed / radius;
        let r = radius * half;
        Pose::from_parts(Vector::new(r * (a.cos() - 1.0), y, r * a.sin()), turned)
    };
    run(
        (&mut world, &mut set),
        (tool, plate),
        path,
        drive,
        (1.0, 3.0),
    )
}

/// Tool `kind` of half-size `half` and how it is turned: a box flat or turned, the box as a
/// convex hull, a ball, a cylinder, a capsule lying tilted.
fn tool_shape(kind: u8, half: f32) -> (SharedShape, Rotation) {
    match kind {
        0 => (SharedShape::cuboid(half, half, half), Rotation::IDENTITY),
        1 => (
            SharedShape::cuboid(half, half, half),
            Rotation::from_scaled_axis(Vector::new(0.3, 0.5, 0.2)),
        ),
        2 => (cube_hull(half), Rotation::IDENTITY),
        3 => (SharedShape::ball(half), Rotation::IDENTITY),
        4 => (SharedShape::cylinder(half, half), Rotation::IDENTITY),
        _ => (
            SharedShape::capsule_y(0.5 * half, half),
            Rotation::from_rotation_x(1.0),
        ),
    }
}

/// The coupled-step bench's cube scene (`benches/coupled_step.rs`): a 0.3 m plate of 28 × 28
/// nodes (10 N/m, 2 g a node, dampers of 0.05 N·s/m) stepped at 1 kHz, and a 4 cm cube
/// pressed 6 mm in over half a second, held half a second, then circled 5 mm around its spot
/// at 6 rad/s for 2.5 s, flat or turned, driven by its body or by its collider.
fn bench_cube(turned: bool, drive: Drive) -> Books {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    world.integration_parameters.dt = 1e-3;
    let fixed = world.insert_body(RigidBodyBuilder::fixed());
    let surface = MassSpringSurfaceBuilder::from_mesh(&plate(0.3, 0.3, 27, 27))
        .stiffness(10.0)
        .damping(0.05)
        .mass(MassDistribution::PerVertex(2e-3))
        .pinned(plate_rim(27, 27))
        .build()
        .unwrap();
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: 1,
        collider: true,
    };
    let plate = set.insert(surface, fixed, &mut world, options).unwrap();
    let body = world.insert_body(RigidBodyBuilder::kinematic_position_based());
    let tool = world.insert_collider(ColliderBuilder::cuboid(0.02, 0.02, 0.02), Some(body));
    set.add_tool(tool, &mut world).unwrap();
    let rotation = if turned {
        Rotation::from_scaled_axis(Vector::new(0.3, 0.5, 0.2))
    } else {
        Rotation::IDENTITY
    };
    let reach = lowest_point(world.colliders[tool].shape(), rotation);
    let path = |t: f32| {
        let y = -reach + 0.05 - (0.05 + 0.006) * (2.0 * t).min(1.0);
        let a = (t - 1.0).max(0.0) * 6.0;
        let offset = Vector::new(0.005 * (a.cos() - 1.0), y, 0.005 * a.sin());
        Pose::from_parts(offset, rotation)
    };
    run(
        (&mut world, &mut set),
        (tool, plate),
        path,
        drive,
        (1.0, 3.5),
    )
}

#[test]
fn the_benchs_cubes_circling_on_a_soft_1khz_plate_put_in_no_more_than_their_work() {
    // Before the fixes the flat cube driven by its body took the plate from 1.41 mJ to
    // 4.30 mJ doing 0.28 mJ of work (a vertex lying on its face, walked back where it entered,
    // sped up in place); now the plate rises by 0.6 µJ, the turned cube's by 0.12 mJ for
    // 1.5 mJ of work.
    for turned in [false, true] {
        for drive in [Drive::Body, Drive::Collider] {
            let b = bench_cube(turned, drive);
            assert!(b.start > 0.0, "the cube does not press the plate: {b:?}");
            assert!(b.balance(), "turned {turned}, {drive:?}: {b:?}");
        }
    }
}

/// Slow tools on heavy plates stepped at 4 kHz (a 1 kHz world in 4 substeps): the property
/// test's shrunk cases at three seeds (15, 16 and CI's) once the world's rate reached the
/// surface (`tests/it/world_step.rs`). A plate vertex a hair inside a cylinder's receding side
/// was given the side's normal velocity, toward the tool, and let go at once (its springs
/// pulled it away), keeping that pull: at every substep. The plates gained 6.4 mJ over 4.1 mJ
/// for 1.1 mJ of work (a cylinder, 10 kg of 10 N/m), 60 mJ over 0.30 J for 2.6 mJ (a cylinder
/// at 6 mm/s, 79 kg of 880 N/m), 10.2 J over 10.4 J for 8.0 J (a cube's hull, 7.7 m, 54 kg).
#[test]
fn slow_tools_on_heavy_plates_stepped_at_4_khz_put_in_no_more_than_their_work() {
    for (scale, k, mass, shape, radius, speed) in [
        (1.0, 10.0, 10f32.powf(1.0243926), 4, 0.44876558, 0.44661888),
        (
            1.0,
            10f32.powf(2.9444616),
            10f32.powf(1.8958708),
            4,
            0.49327558,
            0.2,
        ),
        (
            10f32.powf(0.88914144),
            10f32.powf(2.5452213),
            10f32.powf(1.7320682),
            2,
            0.3962264,
            2.072615,
        ),
    ] {
        let b = circle(
            scale,
            k,
            mass,
            (1000.0, 4),
            shape,
            (radius, speed),
            Drive::Body,
        );
        assert!(b.balance(), "{scale} m, tool {shape}: {b:?}");
    }
}

proptest! {
    // After the fixes 20 seeds of 16 cases pass, and CI's (surfaces stepped at 60 Hz to
    // 4 kHz). The largest rises are under cylinders (0.95 of the bound at one seed while the
    // surface still kept its 60 Hz step): a cylinder's rim does not press the plate's
    // triangles as a polyhedron's edges do, so the plate's vertices meet its side and are
    // pushed along, the work going into the plate. Before the fixes, a tool driven by its
    // collider failed at every seed tried (4 of 4).
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn a_tool_circling_in_a_plate_puts_in_no_more_energy_than_its_work(
        scale_exp in -2.0f32..3.0,
        k_exp in 1.0f32..3.0,
        mass_exp in -2.0f32..2.0,
        (rate, substeps) in prop::sample::select(vec![
            (60.0f32, 1u32), (60.0, 4), (240.0, 1), (240.0, 4), (1000.0, 1), (1000.0, 4)
        ]),
        shape in 0u8..6,
        radius in 0.1f32..0.5,
        speed in 0.2f32..3.0,
        by_collider in any::<bool>(),
    ) {
        let scale = 10f32.powf(scale_exp);
        // Tools as fast as the plate's waves too (up to 0.9 of a cell over the time a node's
        // mass takes on an edge's spring): `mean_force` books the impulses of the vertices
        // they hit (`tests/it/momentum_books.rs`). Before it did, the test kept to a tenth of
        // the waves' speed.
        let (k, mass) = (10f32.powf(k_exp), 10f32.powf(mass_exp));
        let drive = if by_collider { Drive::Collider } else { Drive::Body };
        let b = circle(
            scale,
            k,
            mass,
            (rate, substeps),
            shape,
            (radius, speed),
            drive,
        );
        prop_assert!(b.start > 0.0, "the tool does not press the plate: {b:?}");
        prop_assert!(b.balance(), "{scale} m, {drive:?}: {b:?}");
    }
}
