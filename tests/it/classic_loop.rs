//! The crate driven from a classic rapier loop (separate sets, `PhysicsPipeline`) through
//! `PhysicsSets`: the same scene (a fast box on a guarded floor, a ball tool pressing a soft
//! plate) built and stepped in a `PhysicsWorld` and in separate sets gives the same poses and
//! forces, bit for bit, step after step.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim};

struct Handles {
    boxed: RigidBodyHandle,
    tool_body: RigidBodyHandle,
    tool: ColliderHandle,
    floor: ColliderHandle,
}

/// Builds the scene in `world` (a `PhysicsWorld`, or one lent by `PhysicsSets::with_world`).
fn build(world: &mut PhysicsWorld, surfaces: &mut SurfaceSet) -> Handles {
    TouchPipeline::configure(&mut world.integration_parameters);
    let floor = world.insert_collider(ColliderBuilder::cuboid(5.0, 0.01, 5.0), None);
    let boxed = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(2.0, 3.0, 0.0))
            .linvel(Vector::new(0.0, -40.0, 0.0))
            .angvel(Vector::new(3.0, 0.0, 1.0)),
    );
    world.insert_collider(ColliderBuilder::cuboid(0.2, 0.1, 0.3), Some(boxed));
    let holder =
        world.insert_body(RigidBodyBuilder::fixed().translation(Vector::new(0.0, 1.0, 0.0)));
    let soft = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 8, 8))
        .pinned(plate_rim(8, 8))
        .build()
        .unwrap();
    let options = AttachOptions {
        substeps: 4,
        collider: true,
    };
    surfaces.insert(soft, holder, world, options).unwrap();
    let tool_body = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.1, 1.1, 0.0)),
    );
    let tool = world.insert_collider(ColliderBuilder::ball(0.05), Some(tool_body));
    surfaces.add_tool(tool, world).unwrap();
    Handles {
        boxed,
        tool_body,
        tool,
        floor,
    }
}

fn drive(world: &mut PhysicsWorld, h: &Handles, step: usize) {
    let y = (1.1 - 0.004 * step as f32).max(1.02);
    world.bodies[h.tool_body].set_next_kinematic_translation(Vector::new(0.1, y, 0.0));
}

#[test]
fn a_classic_sets_loop_gives_the_physics_world_results_bit_for_bit() {
    // The PhysicsWorld front.
    let mut world = PhysicsWorld::default();
    let mut surfaces = SurfaceSet::new();
    let hw = build(&mut world, &mut surfaces);
    let mut touch = TouchPipeline::default();
    touch.track_collider(hw.floor);

    // The classic loop's sets.
    let (mut bodies, mut colliders) = (RigidBodySet::new(), ColliderSet::new());
    let (mut islands, mut broad_phase, mut narrow_phase) = (
        IslandManager::new(),
        DefaultBroadPhase::default(),
        NarrowPhase::new(),
    );
    let (mut impulse_joints, mut multibody_joints) =
        (ImpulseJointSet::new(), MultibodyJointSet::new());
    let (mut soft_bodies, mut ccd_solver) = (SoftBodySet::default(), CCDSolver::new());
    let mut pipeline = PhysicsPipeline::new();
    let mut params = IntegrationParameters::default();
    let mut sets_surfaces = SurfaceSet::new();
    let mut sets_touch = TouchPipeline::default();
    let gravity = Vector::new(0.0, -9.81, 0.0);
    macro_rules! sets {
        () => {
            PhysicsSets {
                gravity,
                integration_parameters: &mut params,
                physics_pipeline: &mut pipeline,
                islands: &mut islands,
                broad_phase: &mut broad_phase,
                narrow_phase: &mut narrow_phase,
                bodies: &mut bodies,
                colliders: &mut colliders,
                impulse_joints: &mut impulse_joints,
                multibody_joints: &mut multibody_joints,
                soft_bodies: &mut soft_bodies,
                ccd_solver: &mut ccd_solver,
            }
        };
    }
    let hs = sets!().with_world(|w| build(w, &mut sets_surfaces));
    sets_touch.track_collider(hs.floor);

    for step in 1..=150 {
        drive(&mut world, &hw, step);
        touch.step_with_surfaces(&mut world, &mut surfaces);
        sets!().with_world(|w| {
            drive(w, &hs, step);
            sets_touch.step_with_surfaces(w, &mut sets_surfaces);
        });
        for (a, b) in [(hw.boxed, hs.boxed), (hw.tool_body, hs.tool_body)] {
            assert_eq!(
                world.bodies[a].position(),
                bodies[b].position(),
                "step {step}"
            );
            assert_eq!(world.bodies[a].linvel(), bodies[b].linvel(), "step {step}");
        }
        assert_eq!(
            surfaces.tool_reaction(hw.tool),
            sets_surfaces.tool_reaction(hs.tool),
            "step {step}"
        );
    }
    // And the scene did what it should: the box on the floor, the plate pushing the tool.
    assert!(bodies[hs.boxed].translation().y > 0.05);
    assert!(sets_surfaces.tool_reaction(hs.tool).unwrap().force.y > 0.0);
}
