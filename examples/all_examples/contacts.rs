//! Contacts (Fig. 4).

use super::*;

pub(crate) async fn contact_case(viewer: &mut TestbedViewer, index: usize) {
    let scene = fig4_scenes().swap_remove(index);
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    world.integration_parameters.dt = DT;
    let fixed_body = world.insert_body(RigidBodyBuilder::fixed().pose(scene.fixed_pose));
    let fixed = world.insert_collider(mesh_collider(&scene.fixed), Some(fixed_body));
    // Dynamic so the testbed's mouse grab can move it; colliding with nothing so it can be
    // pushed into the fixed object; rotations locked so it keeps the case's orientation.
    let moving_body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .pose(scene.pose)
            .lock_rotations()
            .linear_damping(8.0)
            .additional_mass(1.0),
    );
    let moving = world.insert_collider(
        mesh_collider(&scene.moving)
            .density(0.0)
            .collision_groups(InteractionGroups::none()),
        Some(moving_body),
    );
    viewer.set_world(&mut world);
    viewer.set_initial_collider_color(fixed, SLATE);
    viewer.set_initial_collider_color(moving, ORANGE_GLASS);
    let camera = [Vector::new(2.6, 2.4, 4.2), Vector::new(0.0, 0.4, 0.0)];
    look(viewer, camera, "Case", scene.description);
    viewer.example_settings_mut().set_label(
        "Mouse",
        "left-drag the orange object into the fixed one: it is walked back along the drag \
         to first touch",
    );

    let mut rec = Reconstructor::default();
    // The moving object's last pose that did not penetrate: the start of the trajectory the
    // reconstruction walks back along (the case's own previous pose at first).
    let mut last_free = scene.prev_pose;
    while viewer.render_frame(&mut world).await {
        if viewer.simulating() {
            world.step();
        }
        let pose = *world.bodies[moving_body].position();
        let Ok(c) = rec.reconstruct(
            &scene.fixed,
            &scene.fixed_pose,
            &scene.moving,
            &pose,
            &last_free,
        ) else {
            continue;
        };
        let touch = Pose::from_parts(pose.translation + c.reversing_vector, pose.rotation);
        line(viewer, last_free.translation, pose.translation, GREY, 1.5);
        if c.state != TouchState::Separated {
            wireframe(viewer, &scene.moving, &touch, GREEN, 1.5);
        }
        for p in &c.patches {
            features(viewer, &scene.fixed, &scene.fixed_pose, &p.fixed_features);
            features(viewer, &scene.moving, &touch, &p.moving_features);
            patch(viewer, p, c.reversing_vector);
        }
        let settings = viewer.example_settings_mut();
        settings.set_label("State", format!("{:?}", c.state));
        settings.set_label(
            "Reversing vector",
            format!(
                "{}, depth {:.1} mm along the trajectory",
                mm(c.reversing_vector),
                c.depth * 1e3
            ),
        );
        settings.set_label("Contacts", kinds(&c.patches));
        if !c.needs_correction() {
            last_free = pose;
        }
    }
}
