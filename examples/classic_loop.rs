//! The crate in a classic rapier loop: separate sets and `PhysicsPipeline`, as rapier's own
//! examples and most engines keep them. `PhysicsSets` lends the sets to the crate for each
//! call (moved into a `PhysicsWorld` and back, no copy); the results are the `PhysicsWorld`
//! front's, bit for bit (`tests/it/classic_loop.rs`).
//!
//! Scene: a 40 m/s box dropped on a 2 cm floor the step guard watches, and a ball tool
//! pressing a soft plate, one `TouchPipeline::step_with_surfaces` call per step.
//!
//! `cargo run --release --example classic_loop` prints the box's height and speed and the
//! tool's force every 0.25 s, then a `summary:` line.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim};

fn main() {
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
    TouchPipeline::configure(&mut params);
    let gravity = Vector::new(0.0, -9.81, 0.0);

    // Rigid side, built on the sets directly.
    let floor = colliders.insert(ColliderBuilder::cuboid(5.0, 0.01, 5.0));
    let boxed = bodies.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(2.0, 3.0, 0.0))
            .linvel(Vector::new(0.0, -40.0, 0.0)),
    );
    colliders.insert_with_parent(ColliderBuilder::cuboid(0.2, 0.2, 0.2), boxed, &mut bodies);
    let holder = bodies.insert(RigidBodyBuilder::fixed().translation(Vector::new(0.0, 1.0, 0.0)));
    let tool_body = bodies.insert(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.0, 1.1, 0.0)),
    );
    let tool = colliders.insert_with_parent(ColliderBuilder::ball(0.05), tool_body, &mut bodies);

    let mut touch = TouchPipeline::default();
    touch.track_collider(floor);
    let mut surfaces = SurfaceSet::new();
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
    // Soft side: the crate's functions that take a `PhysicsWorld`, on the sets.
    let soft = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 10, 10))
        .stiffness(200.0)
        .pinned(plate_rim(10, 10))
        .build()
        .expect("a valid plate");
    let options = AttachOptions {
        substeps: 8,
        collider: true,
    };
    sets!().with_world(|w| {
        surfaces
            .insert(soft, holder, w, options)
            .expect("the holder exists");
        surfaces
            .add_tool(tool, w)
            .expect("a ball of positive radius");
    });

    println!("   t s | box y m | box vy m/s | tool force N");
    for step in 1..=120 {
        let y = (1.1 - 0.002 * step as f32).max(1.03);
        bodies[tool_body].set_next_kinematic_translation(Vector::new(0.0, y, 0.0));
        sets!().with_world(|w| touch.step_with_surfaces(w, &mut surfaces));
        if step % 15 == 0 {
            let f = surfaces.tool_reaction(tool).map_or(0.0, |r| r.force.y);
            println!(
                "{:>6.2} | {:>7.3} | {:>10.3} | {:>12.3}",
                step as f32 / 60.0,
                bodies[boxed].translation().y,
                bodies[boxed].linvel().y,
                f
            );
        }
    }
    let f = surfaces.tool_reaction(tool).map_or(0.0, |r| r.force.y);
    println!(
        "summary: box_y_m={:.4} tool_force_n={f:.3}",
        bodies[boxed].translation().y
    );
    assert!(
        bodies[boxed].translation().y > 0.2,
        "the box went through the floor"
    );
    assert!(f > 0.0, "the plate does not push the tool back");
}
