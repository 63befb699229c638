//! A world whose step changes after a surface was attached (a game's slow motion, a variable
//! step, a pause). The surface steps at the world's step over its substeps: a tool held still
//! in it keeps its force (a static press does not depend on the step), and a paused world
//! (a step of zero) moves no vertex. Before, the surface kept the step it was attached with:
//! a plate attached at 60 Hz and stepped at 240 Hz read the force of a still cube's corner
//! pressing a triangle (its impulse over the world's step) 4 times too large (59 N for
//! 14.7 N), and a paused world's surfaces kept moving. A ball's force (its held vertex's
//! springs) was right.

use crate::common::{lowest_point, plate_scene};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

#[test]
fn a_still_tool_keeps_its_force_when_the_worlds_step_changes_and_a_paused_world_moves_nothing() {
    // A cube corner-down between vertices (its corner's press on a triangle, eq. 3), a ball
    // over a vertex (its held vertex's springs).
    let down = Rotation::from_rotation_arc(Vector::new(1.0, 1.0, 1.0).normalize(), -Vector::Y);
    still_tool(
        SharedShape::cuboid(0.03, 0.03, 0.03),
        Pose::from_parts(Vector::new(0.006, 0.0, 0.011), down),
    );
    still_tool(SharedShape::ball(0.03), Pose::IDENTITY);
}

/// A 0.3 m plate (16 cells, 400 N/m edges, 0.2 kg) attached at 60 Hz in 4 substeps, a tool
/// of 3 cm half-size turned and placed by `at` pressed 1 cm in over half a second and held,
/// then the world's step changed to 240, 1000 and 30 Hz, and to zero.
fn still_tool(shape: SharedShape, at: Pose) {
    let lowest = lowest_point(&*shape, at.rotation);
    let (mut world, mut set, tool, plate) = plate_scene(0.3, 16, 400.0, 0.2, 4, shape);
    set.add_tool(tool, &mut world).unwrap();
    let body = world.colliders[tool].parent().unwrap();
    world.bodies[body].set_rotation(at.rotation, true);
    let held = at.translation + Vector::Y * (-lowest - 0.01);
    let run = |world: &mut PhysicsWorld, set: &mut SurfaceSet, secs: f32| {
        let dt = world.integration_parameters.dt;
        let from = world.bodies[body].translation();
        for s in 0..(secs / dt).round() as usize {
            let a = ((s + 1) as f32 * dt / 0.5).min(1.0);
            world.bodies[body].set_next_kinematic_translation(from.lerp(held, a));
            set.step(world);
        }
        set.tool_reaction(tool).unwrap().force
    };
    let at_60 = run(&mut world, &mut set, 3.0);
    assert!(at_60.y > 0.1, "the tool presses the plate: {at_60:?}");
    for rate in [240.0, 1000.0, 30.0] {
        world.integration_parameters.dt = 1.0 / rate;
        let f = run(&mut world, &mut set, 2.0);
        let surface = &set.get(plate).unwrap().surface;
        assert!(
            (f - at_60).length() <= 0.02 * at_60.length(),
            "{rate} Hz: {f:?} against {at_60:?} at 60 Hz"
        );
        assert!(
            (surface.dt() - 1.0 / (4.0 * rate)).abs() < 1e-6 / rate,
            "{rate} Hz: the surface steps {} s",
            surface.dt()
        );
    }
    // Paused: nothing moves, nothing turns NaN.
    let mut before = Vec::new();
    set.get(plate).unwrap().surface.positions_into(&mut before);
    world.integration_parameters.dt = 0.0;
    for _ in 0..10 {
        set.step(&mut world);
    }
    let mut after = Vec::new();
    set.get(plate).unwrap().surface.positions_into(&mut after);
    assert_eq!(before, after, "a paused world's surface moved");
}
