//! A kinematic tool's reaction against the surface's momentum (issue 13): a free plate (no
//! pins, no gravity) takes momentum only from the tool, so the impulse the tool's reaction
//! reports over a run (`Σ mean_force · dt`) must be the plate's momentum change, reversed. The
//! books are the plate's own masses and velocities, not the crate's accounting.
//!
//! Before `ToolReaction::mean_force` summed what the tool gave the surface (the holds'
//! impulses, the velocities the holds set, the points' momentum), it averaged the springs'
//! force at the end of each substep. On a free 0.3 m plate of 12 cells at 60 Hz (100 N/m,
//! 0.2 kg), a 6 cm cube pressed at 0.1 m/s reported 2.3 times the momentum the plate took, a
//! 6 cm ball at 10 mm/s 1.25 times, and the cube at 2 m/s 13 times, up where the plate went
//! down; both tests below failed then (the property test at CI's seed: 0.036 N·s missed of
//! 1.24). At 8 substeps the old books were off by 1-5 %.
//!
//! Property test over scale (plates of 3 cm to 300 m), edge stiffness (10-1000 N/m), mass
//! (10 g-100 kg), the surface's rate (60 Hz to 1 kHz), the tool (a ball, a box flat or turned,
//! the box as a convex hull, a capsule, a cylinder), its motion (down and sideways, turning or
//! not, at speeds from slow to as fast as the plate's waves) and friction (none, Coulomb, or a
//! grasp).

use crate::common::cube_hull;
use proptest::prelude::*;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::plate;

/// How a run's tool meets the surface.
#[derive(Clone, Copy, Debug)]
enum Grip {
    Frictionless,
    Coulomb,
    Grasp,
}

/// One run.
#[derive(Clone, Debug)]
struct Run {
    /// Plate side (m); everything else scales with it.
    size: f32,
    k: f32,
    mass: f32,
    substeps: u32,
    shape: SharedShape,
    /// The tool's turn about a tilted axis at the start, and its spin (rad/s) about the
    /// vertical.
    tilt: f32,
    spin: f32,
    /// Pressing speed (plate sizes per second) and sideways drift (fraction of it).
    speed: f32,
    drift: f32,
    grip: Grip,
}

impl Run {
    /// The property test's run from its drawn values: the plate's size, edge stiffness and mass
    /// as powers of ten, the substeps and the tool's kind, its tilt, spin, pressing speed (a
    /// power of ten) and drift, and its grip.
    fn drawn(
        (scale_exp, k_exp, mass_exp): (f32, f32, f32),
        (substeps, kind): (u32, u8),
        (tilt, spin, speed_exp, drift): (f32, f32, f32, f32),
        grip: Grip,
    ) -> Run {
        let size = 10f32.powf(scale_exp);
        Run {
            size,
            k: 10f32.powf(k_exp),
            mass: 10f32.powf(mass_exp),
            substeps,
            shape: tool(kind, size),
            tilt,
            spin,
            speed: 10f32.powf(speed_exp),
            drift,
            grip,
        }
    }
}

/// A world with no gravity and, on a fixed body, a free plate (no pins) `size` wide of
/// `cells` per side, edges of `k` with light dampers, `mass` in all, stepped in `substeps`.
fn free_plate(
    (size, cells): (f32, u32),
    k: f32,
    mass: f32,
    substeps: u32,
) -> (PhysicsWorld, SurfaceSet, SurfaceHandle) {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    world.integration_parameters.length_unit = size;
    let fixed = world.insert_body(RigidBodyBuilder::fixed());
    let surface = MassSpringSurfaceBuilder::from_mesh(&plate(size, size, cells, cells))
        .stiffness(k)
        .damping(0.02 * (k * mass).sqrt() / cells as f32)
        .mass(MassDistribution::Total(mass))
        .build()
        .unwrap();
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps,
        collider: true,
    };
    let soft = set.insert(surface, fixed, &mut world, options).unwrap();
    (world, set, soft)
}

/// The plate's momentum change and the impulse the tool's reaction reports over the run,
/// and the largest momentum the plate had (world frame).
fn books(run: &Run) -> (Vector, Vector, f32) {
    let size = run.size;
    let (mut world, mut set, soft) = free_plate((size, 16), run.k, run.mass, run.substeps);
    let tilt = Rotation::from_axis_angle(Vector::new(1.0, 0.0, 0.4).normalize(), run.tilt);
    let low = -run
        .shape
        .compute_aabb(&Pose::from_parts(Vector::ZERO, tilt))
        .mins
        .y;
    let start = Vector::new(0.013 * size, low, 0.021 * size);
    let body = world.insert_body(
        RigidBodyBuilder::kinematic_position_based()
            .translation(start)
            .rotation(tilt.to_scaled_axis()),
    );
    let tool = world.insert_collider(ColliderBuilder::new(run.shape.clone()), Some(body));
    set.add_tool(tool, &mut world).unwrap();
    match run.grip {
        Grip::Frictionless => {}
        Grip::Coulomb => set
            .set_tool_friction(tool, Friction::new(0.6, 0.4).unwrap())
            .unwrap(),
        Grip::Grasp => set.set_grasp(tool, true).unwrap(),
    }
    let dt = world.integration_parameters.dt;
    let momentum = |set: &SurfaceSet| {
        let s = &set.get(soft).unwrap().surface;
        (0..s.num_vertices() as u32)
            .map(|i| (s.velocity(i) * s.mass(i)).as_dvec3())
            .sum::<glamx::DVec3>()
    };
    let p0 = momentum(&set);
    let mut impulse = glamx::DVec3::ZERO;
    let mut largest: f32 = 0.0;
    // Pressed in for half a second (down to a fifth of the plate's size below where it
    // touched), then held where it got to for another half.
    let steps = (1.0 / dt).round() as usize;
    let (mut at, mut angle) = (start, 0.0f32);
    for step in 0..steps {
        if step < steps / 2 {
            let v = run.speed * size;
            let depth = (start.y - at.y) / size;
            if depth < 0.2 {
                at += Vector::new(run.drift * v, -v, 0.5 * run.drift * v) * dt;
            }
            angle += run.spin * dt;
        }
        let pose = Pose::from_parts(at, Rotation::from_rotation_y(angle) * tilt);
        world.bodies[body].set_next_kinematic_position(pose);
        set.step(&mut world);
        let r = set.tool_reaction(tool).unwrap();
        assert!(r.mean_force.is_finite(), "{r:?}");
        impulse += (r.mean_force * dt).as_dvec3();
        largest = largest.max((momentum(&set) - p0).length() as f32);
    }
    ((momentum(&set) - p0).as_vec3(), impulse.as_vec3(), largest)
}

/// The tools of the property test, `size` the plate's side.
fn tool(kind: u8, size: f32) -> SharedShape {
    let r = 0.12 * size;
    match kind % 6 {
        0 => SharedShape::ball(r),
        1 => SharedShape::cuboid(r, r, r),
        2 => cube_hull(r),
        3 => SharedShape::capsule_z(r, r),
        4 => SharedShape::cylinder(0.5 * r, r),
        _ => SharedShape::cuboid(1.5 * r, 0.5 * r, r),
    }
}

#[test]
fn a_tool_gives_a_free_plate_the_momentum_its_reaction_reports() {
    // The cases the old reaction failed (module docs), at 60 Hz.
    let cases = [
        (tool(1, 0.3), 0.1 / 0.3, Grip::Frictionless),
        (tool(0, 0.3), 0.01 / 0.3, Grip::Frictionless),
        (tool(1, 0.3), 2.0 / 0.3, Grip::Frictionless),
        (tool(2, 0.3), 0.5 / 0.3, Grip::Coulomb),
        (tool(0, 0.3), 0.5 / 0.3, Grip::Grasp),
    ];
    for (shape, speed, grip) in cases {
        let run = Run {
            size: 0.3,
            k: 100.0,
            mass: 0.2,
            substeps: 1,
            shape,
            tilt: 0.3,
            spin: 1.0,
            speed,
            drift: 0.3,
            grip,
        };
        let (plate, reported, largest) = books(&run);
        let miss = (plate + reported).length();
        assert!(
            largest > 1e-4 && miss <= 1e-3 * largest,
            "{run:?}: the plate took {plate:?}, the reaction reports {reported:?} (largest {largest})"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn the_momentum_a_free_plate_takes_is_what_the_tools_reaction_reports(
        scale_exp in -1.5f32..2.5,
        k_exp in 1.0f32..3.0,
        mass_exp in -2.0f32..2.0,
        substeps in prop::sample::select(vec![1u32, 2, 4, 17]),
        kind in 0u8..6,
        tilt in 0.0f32..1.2,
        spin in -3.0f32..3.0,
        speed_exp in -1.5f32..1.0,
        drift in -0.5f32..0.5,
        grip in 0u8..3,
    ) {
        let run = Run::drawn(
            (scale_exp, k_exp, mass_exp),
            (substeps, kind),
            (tilt, spin, speed_exp, drift),
            [Grip::Frictionless, Grip::Coulomb, Grip::Grasp][grip as usize],
        );
        let (plate, reported, largest) = books(&run);
        let miss = (plate + reported).length();
        // Single-precision positions and velocities: a hair of the largest momentum.
        // (A round tool pressed slowly between the plate's vertices may hold none.)
        prop_assume!(largest > 0.0);
        prop_assert!(
            miss <= 1e-3 * largest + 1e-9,
            "the plate took {plate:?}, the reaction reports {reported:?} (largest {largest}, miss {miss})"
        );
    }
}

/// A dynamic body thrown (spinning) at a free plate in zero gravity, for two thirds of a
/// second: the momentum of body and plate together at the start and at the end, and their
/// energy (the body's kinetic, the plate's kinetic and elastic) at the start and the most it
/// reached after a step; and whether the plate moved.
#[allow(clippy::too_many_arguments)]
fn thrown(
    shape: SharedShape,
    body_mass: f32,
    plate_mass: f32,
    k: f32,
    speed: f32,
    substeps: u32,
    spin: f32,
) -> (Vector, Vector, f64, (f64, f64), bool) {
    let (mut world, mut set, soft) = free_plate((0.3, 12), k, plate_mass, substeps);
    let low = -shape.compute_local_aabb().mins.y;
    let body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.01, low + 0.01, 0.013))
            .linvel(Vector::new(0.1 * speed, -speed, 0.05 * speed))
            .angvel(Vector::new(0.2 * spin, spin, 0.3 * spin)),
    );
    let tool = world.insert_collider(ColliderBuilder::new(shape).mass(body_mass), Some(body));
    set.add_tool(tool, &mut world).unwrap();
    let books = |world: &PhysicsWorld, set: &SurfaceSet| {
        let s = &set.get(soft).unwrap().surface;
        let b = &world.bodies[body];
        let plate = (0..s.num_vertices() as u32)
            .map(|i| (s.velocity(i) * s.mass(i)).as_dvec3())
            .sum::<glamx::DVec3>();
        let p = plate + (b.linvel() * b.mass()).as_dvec3();
        let kinetic = s.kinetic_energy() + b.kinetic_energy() as f64;
        (
            p.as_vec3(),
            kinetic,
            s.elastic_energy(),
            plate.length() > 0.0,
        )
    };
    let (p0, k0, e0, _) = books(&world, &set);
    let (mut kinetic, mut total) = (k0, k0 + e0);
    for _ in 0..40 {
        set.step(&mut world);
        let (_, k, e, _) = books(&world, &set);
        kinetic = kinetic.max(k);
        total = total.max(k + e);
    }
    let (p1, _, _, moved) = books(&world, &set);
    (p0, p1, k0 + e0, (kinetic, total), moved)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// The implicit coupling's books (issue 13, two-way coupling for any mass ratio): body and
    /// plate exchange momentum and keep it, over body masses of 1 g to 10 kg, plates of 10 g
    /// to 10 kg, edge stiffness 10-1000 N/m, throws of 5 cm/s to 2 m/s with spin, 60 Hz to
    /// 1 kHz surfaces and six tools: within 1e-4 of it (single precision), and their energy
    /// (kinetic, and with the springs') never above where it started. Passed at CI's seed and
    /// seeds 1-11; with the surface pressed out in place of the body (before push_out.rs), the
    /// energy rose at seeds 2 and 5 (the cases of the test below).
    #[test]
    fn a_body_thrown_at_a_free_plate_keeps_the_momentum(
        body_exp in -3.0f32..1.0,
        plate_exp in -2.0f32..1.0,
        k_exp in 1.0f32..3.0,
        speed_exp in -1.3f32..0.3,
        substeps in prop::sample::select(vec![1u32, 4, 17]),
        kind in 0u8..6,
        spin in -4.0f32..4.0,
    ) {
        let (p0, p1, e0, (kinetic, total), moved) = thrown(
            tool(kind, 0.25),
            10f32.powf(body_exp),
            10f32.powf(plate_exp),
            10f32.powf(k_exp),
            10f32.powf(speed_exp),
            substeps,
            spin,
        );
        prop_assume!(moved);
        books_kept((p0, p1), e0, (kinetic, total)).map_err(TestCaseError::fail)?;
    }
}

/// The books of a body thrown at a free plate ([`thrown`]): the momentum within 1e-4 of where
/// it started (single precision), the energy (kinetic, and with the springs') never above.
fn books_kept(
    (p0, p1): (Vector, Vector),
    e0: f64,
    (kinetic, total): (f64, f64),
) -> Result<(), String> {
    if (p1 - p0).length() > 1e-4 * p0.length() {
        return Err(format!("momentum {p0:?} -> {p1:?}"));
    }
    if kinetic > e0 * (1.0 + 1e-4) || total > e0 * (1.0 + 1e-4) {
        return Err(format!(
            "energy {e0} J -> kinetic up to {kinetic} J, with the springs {total} J"
        ));
    }
    Ok(())
}

/// Known failure, kept ignored: a case the property test above found at four times its cases
/// (`PROPTEST_RNG_SEED=5144`, stop 66; stop 65's code fails it the same way, rebuilt and run):
/// a 2.9 g body of kind 4 spinning at 2.1 rad/s meets a free 13 g plate of 953 N/m at 1.4 m/s,
/// one substep: the kinetic energy stays within the 2.89 mJ it started with, but kinetic plus
/// the springs' reads 4.09 mJ (+41 %). Not traced.
#[test]
#[ignore = "known failure: a light body thrown at a light stiff plate stores energy it did not pay"]
fn a_light_body_thrown_at_a_light_stiff_plate_stores_no_energy_it_has_not_paid_for() {
    let (p0, p1, e0, (kinetic, total), moved) = thrown(
        tool(4, 0.25),
        10f32.powf(-2.536_522_2),
        10f32.powf(-1.889_038_1),
        10f32.powf(2.979_137),
        10f32.powf(0.146_206_42),
        1,
        2.082_452_3,
    );
    assert!(moved);
    books_kept((p0, p1), e0, (kinetic, total)).unwrap();
}

/// A case the property test above found at 96 cases with `PROPTEST_RNG_SEED=5102` (on the
/// code before stop 60 too). A 2.3 g cube (6 cm) spinning at 3.8 rad/s, mostly about the
/// vertical, meets a free 1 kg plate of 127 N/m at 5 cm/s, one substep at 60 Hz. At its first
/// touch a press of the cube's edge moved two surface vertices by 13 and 66 um: the linear
/// springs stored 2.2 uJ at once, 17 % of the scene's 13 uJ, before the body had paid anything
/// (a rigid holder's press changes no velocity), and kinetic plus elastic energy read 7.8 %
/// above where it started. The surface's point now keeps only the cube's plastic-impact share
/// of the overlap its approach made (`coupling/dynamic_tools/push_out.rs`), and the cube is
/// moved out of the rest.
#[test]
fn a_light_spinning_cube_stores_no_energy_it_has_not_paid_for() {
    let (p0, p1, e0, (kinetic, total), moved) = thrown(
        tool(1, 0.25),
        10f32.powf(-2.646_486_5),
        1.0,
        10f32.powf(2.104_762_3),
        10f32.powf(-1.295_905_4),
        1,
        -3.637_803_8,
    );
    assert!(moved);
    books_kept((p0, p1), e0, (kinetic, total)).unwrap();
}

/// Three cases the property test above found (seeds 2 and 5), where a dynamic tool's points
/// were pressed onto it by moving the surface's vertices (the press's position change) without
/// moving the body, which stored energy in the plate's springs that the tool never paid for;
/// on a light, stiff plate part of it came back as motion. A 137 g cube spinning at 2.8 rad/s,
/// meeting a 23 g plate of 133 N/m a second time at 4 substeps (its standing edge came back
/// 0.6 mm through a plate edge every substep): 0.39 mJ stored at once, the kinetic energy
/// 1.45 -> 1.69 mJ (+16 %) in a world with no source. A 2.5 g hull at 2 m/s on a 12 g plate of
/// 308 N/m at 60 Hz: 40 mJ stored for one step in a 4.9 mJ scene; a cylinder there, 8 mJ
/// (two vertices pushed 2 mm along the plate). The body is now moved out instead
/// (`coupling/dynamic_tools/push_out.rs`).
#[test]
fn a_body_thrown_at_a_light_stiff_free_plate_creates_no_energy() {
    for (body, plate, k, speed, substeps, kind, spin) in [
        (-0.8644629, -1.6429113, 2.124634, -0.860218, 4, 1, 2.7030013),
        (
            -2.6008058, -1.9370503, 2.4890945, 0.29205832, 1, 2, 0.6312505,
        ),
        (
            -2.6008058, -1.9370503, 2.4890945, 0.29205832, 1, 5, 0.6312505,
        ),
    ] {
        let (_, _, e0, (kinetic, total), moved) = thrown(
            tool(kind, 0.25),
            10f32.powf(body),
            10f32.powf(plate),
            10f32.powf(k),
            10f32.powf(speed),
            substeps,
            spin,
        );
        assert!(moved);
        assert!(
            kinetic <= e0 * (1.0 + 1e-4) && total <= e0 * (1.0 + 1e-4),
            "energy {e0} J -> kinetic up to {kinetic} J, with the springs {total} J"
        );
    }
}

/// Two cases `the_momentum_a_free_plate_takes_is_what_the_tools_reaction_reports` found at
/// four times its cases (`PROPTEST_RNG_SEED=5107` and `5108`): grasping tools turning as they
/// press (a cube spinning at 1.1 rad/s on a 0.79 m plate at four substeps; a cube's hull
/// tilted 1.1 rad, spinning and drifting at 7 m/s over a 4.7 m plate at one). Twisting the plate, the tool holds its vertices with impulses tens
/// of times the plate's net momentum change (0.05 N·s a substep against 1e-5), and the
/// reaction summed them in single precision: it reported 2.3e-3 and 1.6e-3 of the largest
/// momentum the plate had that the plate never took (the test allows 1e-3). The coupling now
/// keeps a tool's books in double precision, as the surface keeps its impulses.
#[test]
fn a_grasping_tool_twisting_a_plate_keeps_its_books() {
    let cases = [
        (
            -0.102_857_51,
            2.276_632_8,
            -1.568_198_8,
            4,
            1,
            0.0,
            1.082_651_4,
            -1.183_47,
            0.0,
        ),
        (
            0.675_819_2,
            2.049_525_7,
            -1.210_918_3,
            1,
            2,
            1.089_583_5,
            -1.550_712_7,
            0.185_483_16,
            0.237_953_45,
        ),
    ];
    for (scale_exp, k_exp, mass_exp, substeps, kind, tilt, spin, speed_exp, drift) in cases {
        let run = Run::drawn(
            (scale_exp, k_exp, mass_exp),
            (substeps, kind),
            (tilt, spin, speed_exp, drift),
            Grip::Grasp,
        );
        let (plate, reported, largest) = books(&run);
        let miss = (plate + reported).length();
        assert!(
            largest > 0.0 && miss <= 1e-3 * largest,
            "{} m: the plate took {plate:?}, the reaction reports {reported:?} (largest {largest})",
            run.size
        );
    }
}
