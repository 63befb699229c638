//! The crate's main loop, `TouchPipeline::step_with_surfaces`, on one world holding both halves:
//! a fast rigid box dropped on a guarded floor, and a soft plate pressed by a ball and a cube
//! corner, every collider opted in to the guard (the plate's collider and the tools included).
//! The box neither tunnels nor sinks; the tools reach the depth they are driven to (the guard
//! obeys the solver group `add_tool` takes off them, so it does not stop them at the plate's
//! collider); the tools' forces balance the pins' reaction; and the surface side matches the
//! same scene stepped by rapier's own step through `SurfaceSet::step`.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim};

const CELLS: u32 = 10;
const PLATE_Y: f32 = 1.0;

struct Scene {
    world: PhysicsWorld,
    surfaces: SurfaceSet,
    surface: SurfaceHandle,
    boxed: RigidBodyHandle,
    tools: Vec<(RigidBodyHandle, ColliderHandle, Vector, Vector)>,
    colliders: Vec<ColliderHandle>,
}

fn scene() -> Scene {
    let mut world = PhysicsWorld {
        gravity: Vector::new(0.0, -9.81, 0.0),
        ..Default::default()
    };
    TouchPipeline::configure(&mut world.integration_parameters);
    let mut colliders = vec![world.insert_collider(ColliderBuilder::cuboid(5.0, 0.05, 5.0), None)];
    let boxed = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(3.0, 3.0, 0.0))
            .linvel(Vector::new(0.0, -20.0, 0.0)),
    );
    colliders.push(world.insert_collider(ColliderBuilder::cuboid(0.2, 0.2, 0.2), Some(boxed)));

    let mut surfaces = SurfaceSet::new();
    let ground =
        world.insert_body(RigidBodyBuilder::fixed().translation(Vector::new(0.0, PLATE_Y, 0.0)));
    let soft = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, CELLS, CELLS))
        .stiffness(100.0)
        .damping(1.0)
        .mass(MassDistribution::PerVertex(0.01))
        .pinned(plate_rim(CELLS, CELLS))
        .integrator(Integrator::EXACT)
        .build()
        .unwrap();
    let options = AttachOptions {
        substeps: 8,
        collider: true,
    };
    let surface = surfaces.insert(soft, ground, &mut world, options).unwrap();
    colliders.push(surfaces.get(surface).unwrap().collider().unwrap());
    let mut tools = Vec::new();
    // A ball over a vertex, a cube corner-down inside a triangle; both 2 cm deep.
    let tilt = Rotation::from_rotation_arc(-Vector::ONE.normalize(), -Vector::Y);
    let corner = 0.05 * 3f32.sqrt();
    for (shape, turn, lowest, x, z) in [
        (SharedShape::ball(0.05), Rotation::IDENTITY, 0.05, -0.2, 0.1),
        (
            SharedShape::cuboid(0.05, 0.05, 0.05),
            tilt,
            corner,
            0.23,
            -0.17,
        ),
    ] {
        let from = Vector::new(x, PLATE_Y + 0.08 + lowest, z);
        let to = Vector::new(x, PLATE_Y - 0.02 + lowest, z);
        let b = world.insert_body(
            RigidBodyBuilder::kinematic_position_based().pose(Pose::from_parts(from, turn)),
        );
        let c = world.insert_collider(ColliderBuilder::new(shape), Some(b));
        surfaces.add_tool(c, &mut world).unwrap();
        colliders.push(c);
        tools.push((b, c, from, to));
    }
    Scene {
        world,
        surfaces,
        surface,
        boxed,
        tools,
        colliders,
    }
}

/// Drives the tools down over 40 steps and holds them; `step` steps the world and surfaces.
fn run(scene: &mut Scene, mut step: impl FnMut(&mut Scene), mut after: impl FnMut(&Scene)) {
    for k in 0..240 {
        let a = ((k + 1) as f32 / 40.0).min(1.0);
        for (b, _, from, to) in &scene.tools {
            scene.world.bodies[*b].set_next_kinematic_translation(from.lerp(*to, a));
        }
        step(scene);
        after(scene);
    }
}

#[test]
fn one_loop_steps_guard_and_surfaces_together() {
    let mut s = scene();
    let mut touch = TouchPipeline::default();
    for c in &s.colliders {
        touch.track_collider(*c);
    }
    let mut deepest = 0.0f32;
    run(
        &mut s,
        |s| touch.step_with_surfaces(&mut s.world, &mut s.surfaces),
        |s| {
            // The box's bottom against the floor's top (y = 0.05).
            let bottom = s.world.bodies[s.boxed].translation().y - 0.2;
            deepest = deepest.max(0.05 - bottom);
        },
    );
    // The box: never through or into the floor by more than the guard's slop and a hair.
    assert!(deepest < 1e-3, "the box went {deepest} m into the floor");
    let y = s.world.bodies[s.boxed].translation().y;
    assert!((y - 0.25).abs() < 1e-3, "the box rests at {y}");
    // The tools reached their depth: the guard did not stop them at the plate's collider.
    for (b, _, _, to) in &s.tools {
        let at = s.world.bodies[*b].translation();
        assert!(
            (at - *to).length() < 1e-5,
            "tool at {at:?}, driven to {to:?}"
        );
    }
    // Forces: each tool pushed back; together they balance the pins' reaction.
    let surface = &s.surfaces.get(s.surface).unwrap().surface;
    let pins: Vector = plate_rim(CELLS, CELLS)
        .into_iter()
        .map(|i| surface.internal_force(i))
        .sum();
    let forces: Vec<Vector> = s
        .tools
        .iter()
        .map(|(_, c, _, _)| s.surfaces.tool_reaction(*c).unwrap().force)
        .collect();
    assert!(forces.iter().all(|f| f.y > 0.0), "{forces:?}");
    let total: Vector = forces.iter().copied().sum();
    let scale: f32 = forces.iter().map(|f| f.length()).sum();
    assert!(
        (total + pins).length() <= 0.05 * scale,
        "tools {total:?} vs pins {pins:?}"
    );

    // The surface side is what it is under rapier's own step.
    let mut plain = scene();
    run(&mut plain, |s| s.surfaces.step(&mut s.world), |_| {});
    for ((_, c, _, _), f) in plain.tools.iter().zip(&forces) {
        let g = plain.surfaces.tool_reaction(*c).unwrap().force;
        assert!((g - *f).length() <= 0.01 * f.length(), "{g:?} vs {f:?}");
    }
}
