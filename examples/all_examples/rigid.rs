//! Rigid: penetration comparison and tool proxy.

use super::*;

pub(crate) const SPEEDS: [Real; 5] = [1.0, 5.0, 20.0, 50.0, 100.0];
pub(crate) const REDROP: &str = "Drop again every 3 s";

/// One half of the comparison: `scenes::drop_world`'s floor (narrowed) and box, moved to `x`.
pub(crate) struct DropSide {
    pub(crate) x: Real,
    pub(crate) body: RigidBodyHandle,
    pub(crate) collider: ColliderHandle,
    pub(crate) tunneled: bool,
    pub(crate) max_penetration: Real,
    /// How far the box's centre went below the floor's top.
    pub(crate) deepest_centre: Real,
}

impl DropSide {
    pub(crate) fn insert(
        world: &mut PhysicsWorld,
        x: Real,
        floor: DropFloor,
        hooks: ActiveHooks,
    ) -> Self {
        const HALF: Real = 1.2;
        let floor = match floor {
            DropFloor::Cuboid => {
                ColliderBuilder::cuboid(HALF, 0.5, HALF).translation(Vector::new(x, -0.5, 0.0))
            }
            DropFloor::ThinTriMesh => ColliderBuilder::trimesh(
                vec![
                    Vector::new(x - HALF, 0.0, -HALF),
                    Vector::new(x + HALF, 0.0, -HALF),
                    Vector::new(x + HALF, 0.0, HALF),
                    Vector::new(x - HALF, 0.0, HALF),
                ],
                vec![[0, 2, 1], [0, 3, 2]],
            )
            .expect("a valid quad"),
        };
        world.insert_collider(floor.active_hooks(hooks), None);
        let body = world.insert_body(RigidBodyBuilder::dynamic());
        let h = DROP_BOX_HALF;
        let collider = world.insert_collider(
            ColliderBuilder::cuboid(h, h, h).active_hooks(hooks),
            Some(body),
        );
        Self {
            x,
            body,
            collider,
            tunneled: false,
            max_penetration: 0.0,
            deepest_centre: 0.0,
        }
    }

    /// Puts the box 3 m up, falling at `speed`.
    pub(crate) fn drop(&mut self, world: &mut PhysicsWorld, speed: Real) {
        let b = &mut world.bodies[self.body];
        b.set_position(Pose::from_translation(Vector::new(self.x, 3.0, 0.0)), true);
        b.set_linvel(Vector::new(0.0, -speed, 0.0), true);
        b.set_angvel(Vector::ZERO, true);
        self.tunneled = false;
        self.max_penetration = 0.0;
        self.deepest_centre = 0.0;
    }

    pub(crate) fn measure(&mut self, world: &PhysicsWorld) -> String {
        let pose = *world.bodies[self.body].position();
        // Tunneled as `penetration_compare` counts it: the centre went below the floor's top.
        if pose.translation.y < 0.0 {
            self.tunneled = true;
            self.deepest_centre = self.deepest_centre.max(-pose.translation.y);
        }
        if self.tunneled {
            return format!(
                "tunneled: its centre went {:.0} mm below the floor's top",
                self.deepest_centre * 1e3
            );
        }
        let now = box_depth_below_floor(&pose, DROP_BOX_HALF);
        self.max_penetration = self.max_penetration.max(now);
        format!(
            "max penetration {:.2} mm, now {:.2} mm",
            self.max_penetration * 1e3,
            now * 1e3
        )
    }
}

pub(crate) async fn penetration_compare(viewer: &mut TestbedViewer) {
    let settings = viewer.example_settings_mut();
    let names = SPEEDS.iter().map(|s| format!("{s} m/s")).collect();
    let speed = SPEEDS[settings.get_or_set_string("Drop speed", 3, names)];
    let floors = vec!["cuboid".into(), "thin TriMesh (zero thickness)".into()];
    let floor = match settings.get_or_set_string("Floor", 0, floors) {
        0 => DropFloor::Cuboid,
        _ => DropFloor::ThinTriMesh,
    };
    settings.get_or_set_bool(REDROP, true);
    settings.set_restart_on_change(REDROP, false);

    // The parameters of `scenes::drop_world`: dt = 1/60, rapier's CCD off, no clustering.
    let mut world = PhysicsWorld::default();
    world.integration_parameters.dt = DT;
    world.integration_parameters.max_ccd_substeps = 0;
    TouchPipeline::configure(&mut world.integration_parameters);
    let mut sides = [
        DropSide::insert(&mut world, -1.5, floor, ActiveHooks::empty()),
        DropSide::insert(&mut world, 1.5, floor, ActiveHooks::MODIFY_SOLVER_CONTACTS),
    ];
    for s in &mut sides {
        s.drop(&mut world, speed);
    }
    viewer.set_world(&mut world);
    viewer.set_initial_collider_color(sides[0].collider, SLATE);
    viewer.set_initial_collider_color(sides[1].collider, ORANGE);
    let camera = [Vector::new(0.0, 3.0, 8.0), Vector::new(0.0, 0.8, 0.0)];
    look(
        viewer,
        camera,
        "Boxes",
        "left: vanilla rapier (CCD off); right: TouchPipeline. Throw them with the mouse.",
    );

    let mut touch = TouchPipeline::default();
    let mut since_drop = 0usize;
    let mut corrections = 0usize;
    // The last correction on the right: the report and where the box had got to.
    let mut last: Option<(PairReport, Pose)> = None;
    let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(DROP_BOX_HALF))).expect("box");
    while viewer.render_frame(&mut world).await {
        if viewer.simulating() {
            let redrop = viewer.example_settings().get_bool(REDROP).unwrap_or(true);
            if redrop && since_drop >= 180 {
                for s in &mut sides {
                    s.drop(&mut world, speed);
                }
                since_drop = 0;
                last = None;
            }
            touch.step(&mut world);
            since_drop += 1;
            corrections += touch.corrections();
            let guarded = sides[1].collider;
            if let Some(r) = touch
                .reports()
                .iter()
                .find(|r| r.moving == guarded && r.state != TouchState::Touching)
            {
                let now = *world.bodies[sides[1].body].position();
                let sunk = Pose::from_parts(now.translation - r.reversing_vector, now.rotation);
                last = Some((r.clone(), sunk));
            }
        }
        let left = sides[0].measure(&world);
        let right = sides[1].measure(&world);
        if let Some((r, sunk)) = &last {
            wireframe(viewer, &cube, sunk, RED, 1.5);
            for p in &r.patches {
                patch(viewer, p, r.reversing_vector);
            }
        }
        let settings = viewer.example_settings_mut();
        settings.set_label("rapier", left);
        settings.set_label("rapier_touch", right);
        settings.set_label("Guard corrections", corrections.to_string());
        let text = match &last {
            Some((r, _)) => format!(
                "{:?}, reversing vector {:.1} mm, {}",
                r.state,
                r.depth * 1e3,
                kinds(&r.patches)
            ),
            None => "-".into(),
        };
        settings.set_label("Last correction", text);
    }
}

pub(crate) async fn tool_proxy(viewer: &mut TestbedViewer) {
    // The U block and the two-tipped bar of the paper's multiple-contact case.
    let scene = fig4_scenes().swap_remove(3);
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    world.integration_parameters.dt = DT;
    TouchPipeline::configure(&mut world.integration_parameters);
    let hooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;
    let block_body = world.insert_body(RigidBodyBuilder::fixed().pose(scene.fixed_pose));
    let block = world.insert_collider(
        mesh_collider(&scene.fixed).active_hooks(hooks),
        Some(block_body),
    );
    let start = Pose::from_parts(
        scene.prev_pose.translation + Vector::new(0.0, 0.6, 0.0),
        scene.prev_pose.rotation,
    );
    let tool = Tool::insert(
        &mut world,
        mesh_collider(&scene.moving).active_hooks(hooks),
        start,
    );
    viewer.set_world(&mut world);
    viewer.set_initial_collider_color(block, SLATE);
    tool.colors(viewer);
    let camera = [Vector::new(4.0, 4.5, 8.0), Vector::new(0.0, 1.0, 0.0)];
    look(
        viewer,
        camera,
        "Mouse",
        "left-drag the see-through ghost (the device) into the block: the tool (the proxy) \
         stops at first touch",
    );

    let mut touch = TouchPipeline::default();
    touch.options.report_touching = true;
    let mut last_rv = Vector::ZERO;
    while viewer.render_frame(&mut world).await {
        if viewer.simulating() {
            touch.set_tool_target(tool.body, tool.ghost.device(&world));
            touch.step(&mut world);
            if let Some(r) = touch.reports().iter().find(|r| r.depth > 0.0) {
                last_rv = r.reversing_vector;
            }
        }
        let fb = touch.tool_feedback(tool.body);
        if let Some(fb) = fb {
            line(
                viewer,
                fb.proxy.translation,
                fb.device.translation,
                ORANGE,
                3.0,
            );
        }
        let reports = touch.reports().to_vec();
        for r in &reports {
            for p in &r.patches {
                features(viewer, &scene.fixed, &scene.fixed_pose, &p.fixed_features);
                patch(viewer, p, Vector::ZERO);
            }
        }
        let settings = viewer.example_settings_mut();
        settings.set_label(
            "Feedback offset",
            fb.map_or("-".into(), |fb| {
                format!("{:.1} mm", fb.offset.length() * 1e3)
            }),
        );
        settings.set_label(
            "Contacts",
            reports.first().map_or("none".into(), |r| {
                format!("{:?}: {}", r.state, kinds(&r.patches))
            }),
        );
        settings.set_label("Last reversing vector", mm(last_rv));
    }
}
