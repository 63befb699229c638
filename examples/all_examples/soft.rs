//! Soft surfaces.

use super::*;

pub(crate) const INTEGRATORS: [(&str, Integrator); 4] = [
    ("exact filter", Integrator::EXACT),
    ("neighbour filter", Integrator::NEIGHBOUR),
    ("Baraff-Witkin", Integrator::BARAFF_WITKIN),
    ("explicit Euler", Integrator::ExplicitEuler),
];

pub(crate) fn pick_integrator(viewer: &mut TestbedViewer) -> (&'static str, Integrator) {
    let names = INTEGRATORS.iter().map(|(n, _)| n.to_string()).collect();
    let i = viewer
        .example_settings_mut()
        .get_or_set_string("Integrator", 0, names);
    INTEGRATORS[i.min(INTEGRATORS.len() - 1)]
}

/// Red arrows of length `len` along `force` ending at `vertices` (drawn when it is not zero).
pub(crate) fn force_arrows(
    viewer: &mut TestbedViewer,
    s: &MassSpringSurface,
    vertices: &[u32],
    force: Vector,
    len: Real,
) {
    let Some(dir) = force.try_normalize() else {
        return;
    };
    for &i in vertices {
        let p = s.position(i);
        arrow(viewer, p - dir * len, p, RED, 2.0);
    }
}

/// The Fig. 6 and Fig. 7 scenes: a surface alone in a world at 60 Hz without gravity, one
/// surface step per rigid step (the paper's dt = 1/60 s), with a ball tool the mouse drags.
pub(crate) struct SoftDemo {
    pub(crate) world: PhysicsWorld,
    pub(crate) set: SurfaceSet,
    pub(crate) surface: SurfaceHandle,
    pub(crate) collider: ColliderHandle,
    pub(crate) tool: Tool,
    /// The integrator's name.
    pub(crate) name: &'static str,
    /// Cleared once the surface diverged (explicit Euler past its stability limit): from then
    /// on only rapier steps.
    pub(crate) alive: bool,
}

impl SoftDemo {
    /// Shows `surface` (stepped by integrator `name`) and a ball tool of `radius` at `tool_at`
    /// through `camera` ([`look`]), with the scene's `label`.
    pub(crate) fn new(
        viewer: &mut TestbedViewer,
        surface: MassSpringSurface,
        name: &'static str,
        (radius, tool_at): (Real, Vector),
        camera: [Vector; 2],
        (label, text): (&'static str, String),
    ) -> Self {
        let mut world = PhysicsWorld {
            gravity: Vector::ZERO,
            ..Default::default()
        };
        world.integration_parameters.dt = DT;
        let (mut set, handle, collider) = attach_fixed(&mut world, surface, 1);
        let tool = Tool::insert(
            &mut world,
            ColliderBuilder::ball(radius),
            Pose::from_translation(tool_at),
        );
        set.add_tool(tool.collider, &mut world).unwrap();
        viewer.set_world(&mut world);
        viewer.set_initial_collider_color(collider, TISSUE);
        tool.colors(viewer);
        look(viewer, camera, label, text);
        Self {
            world,
            set,
            surface: handle,
            collider,
            tool,
            name,
            alive: true,
        }
    }

    pub(crate) fn surface(&self) -> &MassSpringSurface {
        &self.set.get(self.surface).expect("surface").surface
    }

    /// Draws a frame, then takes a step if the testbed runs: the tool follows its ghost, rapier
    /// and the surface step (rapier alone once the surface diverged) and the surface's collider
    /// is redrawn. `false` once the UI switches or restarts.
    async fn frame(&mut self, viewer: &mut TestbedViewer) -> bool {
        if !viewer.render_frame(&mut self.world).await {
            return false;
        }
        if viewer.simulating() {
            self.tool.drive(&mut self.world, None);
            if self.alive {
                self.set.step(&mut self.world);
                // Stopped long before the state leaves f32 (the collider's vertices): the
                // surfaces are 0.3 m wide at most.
                let s = self.surface();
                self.alive = s.is_finite() && s.max_displacement() < 0.5;
                // The testbed redraws only rapier's own soft bodies: rebuild the render mesh.
                viewer.update_collider(self.collider, &self.world);
            } else {
                self.world.step();
            }
        }
        true
    }

    /// The time, the largest displacement (or when the surface diverged) and the tool's force.
    pub(crate) fn labels(&self, viewer: &mut TestbedViewer) {
        let s = self.surface();
        let time = s.time();
        let text = if self.alive {
            format!("{:.2} mm", s.max_displacement() * 1e3)
        } else {
            format!("{} diverged at t = {time:.2} s (stopped)", self.name)
        };
        let r = self
            .set
            .tool_reaction(self.tool.collider)
            .unwrap_or_default();
        let settings = viewer.example_settings_mut();
        settings.set_label("Time", format!("{time:.2} s"));
        settings.set_label("Largest displacement", text);
        settings.set_label(
            "Tool",
            format!(
                "{:.4} N, {} vertices held",
                r.force.length(),
                r.held_vertices
            ),
        );
    }
}

pub(crate) async fn plate_fig6(viewer: &mut TestbedViewer) {
    // `plate_step_force`: the notched 0.3 m x 0.2 m plate, rim pinned, 1 g per vertex, the
    // step force on the 7 free vertices nearest to (0, -0.02).
    let regimes = vec![
        "soft: k = 0.1 N/m, 1 mN per vertex (s ~ 0.27)".to_string(),
        "stiff: k = 2 N/m, 20 mN per vertex (s ~ 5)".to_string(),
    ];
    let stiff = viewer
        .example_settings_mut()
        .get_or_set_string("Regime", 0, regimes)
        == 1;
    let (name, integrator) = pick_integrator(viewer);
    let (k, c, force) = if stiff {
        (2.0, 0.02, 0.02)
    } else {
        (0.1, 0.001, 0.001)
    };
    let planar =
        triangulate_planar(&paper_plate_outline(), PAPER_PLATE_TARGET_EDGE).expect("meshes");
    let centre = Vector::new(0.0, 0.0, -0.02);
    let mut order: Vec<u32> = (0..planar.mesh.num_vertices() as u32)
        .filter(|i| !planar.boundary.contains(i))
        .collect();
    order.sort_by(|&a, &b| {
        let da = (planar.mesh.vertices[a as usize] - centre).length();
        let db = (planar.mesh.vertices[b as usize] - centre).length();
        da.total_cmp(&db)
    });
    let loaded: Vec<u32> = order[..7].to_vec();
    let down = Vector::new(0.0, -force, 0.0);
    let mut surface = MassSpringSurfaceBuilder::from_mesh(&planar.mesh)
        .stiffness(k)
        .damping(c)
        .mass(MassDistribution::PerVertex(0.001))
        .pinned(planar.boundary.iter().copied())
        .integrator(integrator)
        .neighbour_max_error(Real::INFINITY)
        .build()
        .expect("valid plate");
    surface
        .add_force_schedule(
            loaded.clone(),
            ForceProfile::Step {
                force: down,
                start: 0.0,
                end: None,
            },
        )
        .expect("valid force");

    let label = format!(
        "{} nodes, rim pinned, step force on 7 vertices, {name}",
        planar.mesh.num_vertices()
    );
    let mut demo = SoftDemo::new(
        viewer,
        surface,
        name,
        (0.015, Vector::new(0.08, 0.04, 0.03)),
        [Vector::new(0.2, 0.2, 0.32), Vector::new(0.0, -0.01, 0.0)],
        ("Plate", label),
    );
    while demo.frame(viewer).await {
        force_arrows(viewer, demo.surface(), &loaded, down, 0.02);
        demo.labels(viewer);
    }
}

pub(crate) async fn organ_fig7(viewer: &mut TestbedViewer) {
    // `scenes::Fig7Organ` (`constrained_790`): 788 nodes, the internal polyline pinned, the
    // outer boundary free, k = 0.1 N/m, c = 0.001 N*s/m, 1 g per vertex, dt = 1/60 s, six
    // scheduled forces.
    let (name, integrator) = pick_integrator(viewer);
    let organ = Fig7Organ::new();
    let forces = Fig7Organ::forces();
    let label = format!(
        "{} nodes, {} polyline vertices pinned, six forces, {name}",
        organ.planar.mesh.num_vertices(),
        organ.polyline.len()
    );
    let mut demo = SoftDemo::new(
        viewer,
        organ.surface(integrator),
        name,
        (0.008, Vector::new(0.02, 0.03, 0.0)),
        [Vector::new(0.14, 0.18, 0.24), Vector::new(0.0, -0.01, 0.0)],
        ("Organ", label),
    );
    while demo.frame(viewer).await {
        let s = demo.surface();
        let t = s.time();
        for (g, (_, profile)) in organ.groups.iter().zip(&forces) {
            force_arrows(viewer, s, g, profile.force_at(t), 0.012);
        }
        for w in organ.polyline.windows(2) {
            line(viewer, s.position(w[0]), s.position(w[1]), BLACK, 3.0);
        }
        demo.labels(viewer);
    }
}

/// How long each multi-tool tool waits above the organ before it repeats its script (s).
pub(crate) const MULTI_TOOL_PAUSE: Real = 0.7;

/// Where tool `k` is at time `t` in its script repeated every `ACTIVE + MULTI_TOOL_PAUSE`
/// (3.5 s) from its start: the time to look its pose up at in the library's script.
pub(crate) fn repeated_script_time(k: usize, t: Real) -> Real {
    type S = MultiToolScene;
    let start = k as Real * S::STAGGER;
    if t <= start {
        t
    } else {
        start + (t - start) % (S::ACTIVE + MULTI_TOOL_PAUSE)
    }
}

pub(crate) async fn multi_tool(viewer: &mut TestbedViewer) {
    // `scenes::MultiToolScene` (`multi_tool`): 788 nodes lifted into a 30 mm dome, base
    // pinned, k = 10 N/m, c = 0.1 N*s/m, 15 kg/m², exact filter, 17 substeps (the surface at
    // 1020 Hz), six tools on their scripts, each repeated, or dragged by the mouse.
    let mut scene = MultiToolScene::new();
    let mut ghosts: Vec<Ghost> = scene
        .tools
        .iter()
        .map(|tool| {
            let shape = scene.world.colliders[tool.collider].shared_shape().clone();
            let pose = *scene.world.bodies[tool.body].position();
            Ghost::insert(&mut scene.world, &shape, pose)
        })
        .collect();
    viewer.set_world(&mut scene.world);
    viewer.set_initial_collider_color(scene.organ_collider, TISSUE);
    for (tool, ghost) in scene.tools.iter().zip(&ghosts) {
        tool_colors(viewer, tool.collider, ghost);
    }
    let camera = [Vector::new(0.12, 0.16, 0.2), Vector::new(0.01, 0.01, 0.0)];
    look(
        viewer,
        camera,
        "Mouse",
        "left-drag a tool's ghost: it leaves its script and follows the mouse",
    );

    while viewer.render_frame(&mut scene.world).await {
        if viewer.simulating() {
            // The end of the coming step, where the scene drives its tools.
            let t = (scene.steps() + 1) as Real * MultiToolScene::DT;
            for (k, ghost) in ghosts.iter_mut().enumerate() {
                let (scripted, _, _) = scene.place(k, repeated_script_time(k, t));
                let target = ghost.lead(&mut scene.world, Some(scripted));
                scene.set_tool_target(k, Some(target));
            }
            scene.step();
            viewer.update_collider(scene.organ_collider, &scene.world);
        }
        let mut text = Vec::new();
        for (k, tool) in scene.tools.iter().enumerate() {
            let r = scene.tool_reaction(k);
            let at = scene.world.bodies[tool.body].translation();
            // The surface's force on the tool, 1 N drawn 10 cm long.
            arrow(viewer, at, at + r.force * 0.1, RED, 2.0);
            text.push(format!("{:.3}", r.force.length()));
        }
        let disp = scene.surface().max_displacement();
        let settings = viewer.example_settings_mut();
        settings.set_label("Tool forces N", text.join(", "));
        settings.set_label("Largest displacement", format!("{:.2} mm", disp * 1e3));
    }
}

pub(crate) async fn ball_on_plate(viewer: &mut TestbedViewer) {
    // `scenes::BallOnPlateScene` (`ball_on_plate`): 256 nodes 20 mm apart, rim pinned,
    // k = 30 N/m, c = 1 N*s/m, 0.05 kg, exact filter, 17 substeps; a 30 mm, 0.1 kg dynamic ball
    // dropped from 100 mm.
    let mut scene = BallOnPlateScene::new();
    let weight = scene.weight();
    viewer.set_world(&mut scene.world);
    viewer.set_initial_collider_color(scene.plate_collider, TISSUE);
    viewer.set_initial_collider_color(scene.ball_collider, STEEL);
    let camera = [Vector::new(0.25, 0.22, 0.38), Vector::new(0.0, 0.0, 0.0)];
    look(
        viewer,
        camera,
        "Mouse",
        "left-drag the ball to lift and throw it; the plate's force is all that stops it",
    );

    while viewer.render_frame(&mut scene.world).await {
        if viewer.simulating() {
            scene.step();
            viewer.update_collider(scene.plate_collider, &scene.world);
            // Fell off the plate: drop it again.
            if scene.ball_position().y < -0.5 {
                let world = &mut scene.world;
                let b = &mut world.bodies[scene.ball];
                b.set_translation(BallOnPlateScene::START, true);
                b.set_linvel(Vector::ZERO, true);
                // The surfaces sweep a tool from its collider's pose at the start of the
                // step: move the collider too, or the ball sweeps up through the plate.
                world
                    .bodies
                    .propagate_modified_body_positions_to_colliders(&mut world.colliders);
            }
        }
        let r = scene.reaction();
        let at = scene.ball_position();
        // The surface's force on the ball, its weight drawn 5 cm long.
        arrow(viewer, at, at + r.mean_force * (0.05 / weight), RED, 2.0);
        let disp = scene.surface().max_displacement();
        let settings = viewer.example_settings_mut();
        settings.set_label("Ball height", format!("{:.1} mm", at.y * 1e3));
        settings.set_label(
            "Surface force",
            format!(
                "{:.3} N (weight {weight:.3} N), {} points pressed",
                r.mean_force.y,
                r.held_vertices + r.pressed_points
            ),
        );
        settings.set_label("Largest displacement", format!("{:.2} mm", disp * 1e3));
    }
}
