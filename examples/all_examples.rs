//! Every scene of the crate in rapier's testbed (`rapier_testbed3d`, a kiss3d window), picked
//! from one launcher like rapier's own `all_examples3`:
//!
//! ```text
//! cargo run --release --features testbed --example all_examples
//! ```
//!
//! **Contacts (Fig. 4)**: the paper's four cases (`scenes::fig4_scenes`). The fixed object is
//! blue-grey, the moving one orange and see-through at its penetrating pose; the green wireframe
//! is the moving object at first touch, the green arrow the reversing vector (from where a
//! contact point is now to where it first touched), red the contact patches (polygon, segment or
//! points), yellow the touching vertices and edges of both meshes, the grey line the trajectory
//! walked back along. Left-drag the orange object: it passes through the fixed one, and every
//! frame the reconstruction walks it back along the drag (from its last pose that did not
//! penetrate) to first touch.
//!
//! **Rigid**:
//! - *Penetration comparison*: the `penetration_compare` drop, vanilla rapier (CCD off, left)
//!   next to the same box stepped by `TouchPipeline` (right), at the speed and floor picked in
//!   the example settings, dropped again every 3 s. The red wireframe is where the guarded box
//!   had got to before the step guard put it back at first touch. Both boxes can be thrown with
//!   the mouse.
//! - *Tool proxy*: a kinematic tool driven by the mouse through `TouchPipeline::set_tool_target`
//!   (the god-object). Drag the see-through ghost (the device) into the U block: the solid tool
//!   (the proxy) stops at first touch; the orange line is the feedback offset.
//!
//! **Soft surfaces** (`SurfaceSet`; the surface's collider is redrawn after every step):
//! - *Plate (Fig. 6)*: `plate_step_force`'s 519-node plate, rim pinned, under its step force
//!   (red arrows), regime and integrator picked in the settings (explicit Euler diverges in the
//!   stiff regime, as the paper says: the scene then stops the surface).
//! - *Organ (Fig. 7)*: `constrained_790`'s 788-node organ hanging on its pinned internal
//!   polyline (black) under the six scheduled forces.
//! - *Multi-tool*: `multi_tool`'s organ dome pressed and dragged by six tools on a loop.
//! - *Ball on plate*: `ball_on_plate`'s dynamic ball on a soft plate (two-way coupling).
//!
//! In the soft scenes and *Tool proxy* every tool sits in a see-through ghost, a dynamic body
//! that collides with nothing: the testbed's mouse grab (left-drag) only moves dynamic bodies,
//! so the kinematic tool follows its ghost. A grabbed scripted tool leaves its script until the
//! scene restarts (`R`). The ball of *Ball on plate* is dynamic and is grabbed directly. The
//! testbed drags in the plane facing the camera through the grabbed point: orbit the camera
//! (right-drag) to push a tool down. `T` pauses, `S` steps, `R` restarts.
//!
//! The plate, organ, multi-tool and ball scenes are simplified copies of the headless
//! examples' set-ups (same meshes and parameters, without their checks and printing).

use kiss3d::color::Color;
use rapier_testbed3d::{ExampleEntry, TestbedViewer};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::{
    ActiveHooks, ColliderBuilder, ColliderHandle, InteractionGroups, PhysicsWorld,
    RigidBodyBuilder, RigidBodyHandle, SharedShape,
};
use rapier_touch::scenes::{box_depth_below_floor, fig4_scenes, DropFloor, DROP_BOX_HALF};
use rapier_touch::surface::meshing::{
    paper_organ_outline, paper_plate_outline, plate, triangulate_planar, PlanarMesh, SurfaceMesh,
    PAPER_PLATE_TARGET_EDGE,
};
use std::future::Future;
use std::pin::Pin;

const DT: Real = 1.0 / 60.0;

const SLATE: Color = Color::new(0.59, 0.67, 0.78, 1.0);
const ORANGE_GLASS: Color = Color::new(0.96, 0.59, 0.2, 0.55);
const ORANGE: Color = Color::new(0.96, 0.55, 0.15, 1.0);
const RED: Color = Color::new(0.86, 0.12, 0.12, 1.0);
const YELLOW: Color = Color::new(0.98, 0.78, 0.0, 1.0);
const GREEN: Color = Color::new(0.0, 0.6, 0.24, 1.0);
const GREY: Color = Color::new(0.35, 0.35, 0.38, 1.0);
const BLACK: Color = Color::new(0.05, 0.05, 0.05, 1.0);
const TISSUE: Color = Color::new(0.85, 0.45, 0.45, 1.0);
const STEEL: Color = Color::new(0.3, 0.33, 0.4, 1.0);
const GHOST: Color = Color::new(0.45, 0.65, 0.95, 0.2);

/// One launcher entry: runs the example's own loop until the UI switches or quits.
type ExampleFn = for<'a> fn(&'a mut TestbedViewer) -> Pin<Box<dyn Future<Output = ()> + 'a>>;

#[kiss3d::main]
async fn main() {
    const CONTACTS: &str = "Contacts (Fig. 4)";
    const RIGID: &str = "Rigid";
    const SOFT: &str = "Soft surfaces";
    let examples: Vec<(ExampleEntry, ExampleFn)> = vec![
        (ExampleEntry::new(CONTACTS, "Line (edge) contact"), |v| {
            Box::pin(contact_case(v, 0))
        }),
        (ExampleEntry::new(CONTACTS, "Face contact"), |v| {
            Box::pin(contact_case(v, 1))
        }),
        (ExampleEntry::new(CONTACTS, "Vertex contact"), |v| {
            Box::pin(contact_case(v, 2))
        }),
        (ExampleEntry::new(CONTACTS, "Multiple contacts"), |v| {
            Box::pin(contact_case(v, 3))
        }),
        (ExampleEntry::new(RIGID, "Penetration comparison"), |v| {
            Box::pin(penetration_compare(v))
        }),
        (ExampleEntry::new(RIGID, "Tool proxy"), |v| {
            Box::pin(tool_proxy(v))
        }),
        (ExampleEntry::new(SOFT, "Plate (Fig. 6)"), |v| {
            Box::pin(plate_fig6(v))
        }),
        (ExampleEntry::new(SOFT, "Organ (Fig. 7)"), |v| {
            Box::pin(organ_fig7(v))
        }),
        (ExampleEntry::new(SOFT, "Multi-tool"), |v| {
            Box::pin(multi_tool(v))
        }),
        (ExampleEntry::new(SOFT, "Ball on plate"), |v| {
            Box::pin(ball_on_plate(v))
        }),
    ];
    let (entries, runs): (Vec<_>, Vec<ExampleFn>) = examples.into_iter().unzip();
    let mut viewer = TestbedViewer::new(entries).await;
    // Each example owns its world and its loop; this loop starts the one the UI selected.
    loop {
        viewer.clear_scene();
        let index = viewer.selected();
        runs[index](&mut viewer).await;
        if viewer.quitting() {
            break;
        }
    }
}

// ------------------------------------------------------------------------------------------
// Drawing (immediate mode: drawn on the next frame only, so every frame).

fn line(viewer: &mut TestbedViewer, a: Vector, b: Vector, color: Color, width: f32) {
    viewer.window_mut().draw_line(a, b, color, width, false);
}

fn point(viewer: &mut TestbedViewer, p: Vector, color: Color, size: f32) {
    viewer.window_mut().draw_point(p, color, size);
}

/// A line with a small head at `to`.
fn arrow(viewer: &mut TestbedViewer, from: Vector, to: Vector, color: Color, width: f32) {
    line(viewer, from, to, color, width);
    let d = to - from;
    let len = d.length();
    if len.is_nan() || len <= 1e-9 {
        return;
    }
    let dir = d / len;
    let side = dir.any_orthonormal_vector();
    let up = dir.cross(side);
    let head = 0.25 * len;
    for s in [side, -side, up, -up] {
        line(viewer, to, to - dir * head + s * (0.4 * head), color, width);
    }
}

/// The edges of `mesh` at `pose`.
fn wireframe(viewer: &mut TestbedViewer, mesh: &TouchMesh, pose: &Pose, color: Color, w: f32) {
    for [a, b] in mesh.edges() {
        let pa = pose.transform_point(mesh.vertices()[*a as usize]);
        let pb = pose.transform_point(mesh.vertices()[*b as usize]);
        line(viewer, pa, pb, color, w);
    }
}

/// The touching vertices and edges of one mesh (touching faces show as the patch).
fn features(
    viewer: &mut TestbedViewer,
    mesh: &TouchMesh,
    pose: &Pose,
    list: &[Feature],
    color: Color,
) {
    let at = |v: u32| pose.transform_point(mesh.vertices()[v as usize]);
    for f in list {
        match *f {
            Feature::Vertex(v) => point(viewer, at(v), color, 12.0),
            Feature::Edge([a, b]) => line(viewer, at(a), at(b), color, 4.0),
            Feature::Face(_) => {}
        }
    }
}

/// A contact patch at first touch: the polygon, segment or point in red with its points, and
/// the reversing vector `rv` as a green arrow ending at the patch centre.
fn patch(viewer: &mut TestbedViewer, p: &ContactPatch, rv: Vector) {
    match p.kind {
        ContactKind::Face => {
            let n = p.polygon.len();
            for k in 0..n {
                line(viewer, p.polygon[k], p.polygon[(k + 1) % n], RED, 4.0);
            }
        }
        ContactKind::Edge => {
            if let (Some(a), Some(b)) = (p.polygon.first(), p.polygon.last()) {
                line(viewer, *a, *b, RED, 6.0);
            }
        }
        ContactKind::Vertex => {}
    }
    for q in &p.points {
        point(viewer, q.point, RED, 9.0);
    }
    if rv.length() > 0.0 {
        let c = p.center();
        arrow(viewer, c - rv, c, GREEN, 3.0);
    }
}

/// Points the camera from `eye` at `at`, aimed left of `at` so the scene shows right of the
/// testbed's panels (which cover the left of the window).
fn look(viewer: &mut TestbedViewer, eye: Vector, at: Vector) {
    let right = (at - eye).cross(Vector::Y).normalize_or_zero();
    let shift = right * (0.25 * (at - eye).length());
    viewer.look_at(eye - shift, at - shift);
}

fn mm(v: Vector) -> String {
    format!("({:.1}, {:.1}, {:.1}) mm", v.x * 1e3, v.y * 1e3, v.z * 1e3)
}

fn kinds(patches: &[ContactPatch]) -> String {
    if patches.is_empty() {
        return "none".into();
    }
    let k: Vec<String> = patches.iter().map(|p| format!("{:?}", p.kind)).collect();
    k.join(", ")
}

// ------------------------------------------------------------------------------------------
// Mouse-driven tools.

/// A kinematic tool and its ghost: a dynamic, collision-free body the testbed's mouse grab can
/// move (it only grabs dynamic bodies). The tool follows the ghost.
struct Tool {
    body: RigidBodyHandle,
    collider: ColliderHandle,
    ghost: RigidBodyHandle,
    ghost_collider: ColliderHandle,
    /// Grabbed once: the tool left its script and follows its ghost.
    manual: bool,
}

impl Tool {
    fn insert(world: &mut PhysicsWorld, tool: ColliderBuilder, pose: Pose) -> Self {
        let shape = ghost_shape(&tool.shape);
        let body = world.insert_body(RigidBodyBuilder::kinematic_position_based().pose(pose));
        let collider = world.insert_collider(tool, Some(body));
        let ghost = world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(pose)
                .gravity_scale(0.0)
                .linear_damping(10.0)
                .lock_rotations()
                .additional_mass(0.1),
        );
        let ghost_collider = world.insert_collider(
            ColliderBuilder::new(shape)
                .density(0.0)
                .collision_groups(InteractionGroups::none()),
            Some(ghost),
        );
        Self {
            body,
            collider,
            ghost,
            ghost_collider,
            manual: false,
        }
    }

    fn colors(&self, viewer: &mut TestbedViewer) {
        viewer.set_initial_collider_color(self.collider, STEEL);
        viewer.set_initial_collider_color(self.ghost_collider, GHOST);
    }

    /// Whether the mouse holds the ghost (the testbed ties it to the cursor with a joint).
    fn grabbed(&self, world: &PhysicsWorld) -> bool {
        world
            .impulse_joints
            .attached_joints(self.ghost)
            .next()
            .is_some()
    }

    /// The ghost's position: where the mouse wants the tool.
    fn device(&self, world: &PhysicsWorld) -> Pose {
        *world.bodies[self.ghost].position()
    }

    /// Follows the script (`Some(target)`) until first grabbed, then the ghost.
    fn drive(&mut self, world: &mut PhysicsWorld, scripted: Option<Vector>) {
        if self.grabbed(world) {
            self.manual = true;
        }
        let target = match scripted {
            Some(at) if !self.manual => {
                let ghost = &mut world.bodies[self.ghost];
                ghost.set_translation(at, true);
                ghost.set_linvel(Vector::ZERO, true);
                at
            }
            _ => self.device(world).translation,
        };
        world.bodies[self.body].set_next_kinematic_translation(target);
    }
}

/// A slightly larger copy of a tool's shape for its ghost.
fn ghost_shape(shape: &SharedShape) -> SharedShape {
    const GROW: Real = 1.2;
    if let Some(b) = shape.as_ball() {
        return SharedShape::ball(b.radius * GROW);
    }
    if let Some(c) = shape.as_cuboid() {
        let h = c.half_extents * GROW;
        return SharedShape::cuboid(h.x, h.y, h.z);
    }
    if let Some(m) = shape.as_trimesh() {
        let centre = m.local_aabb().center();
        let v: Vec<Vector> = m
            .vertices()
            .iter()
            .map(|p| centre + (*p - centre) * 1.05)
            .collect();
        if let Ok(s) = SharedShape::trimesh(v, m.indices().to_vec()) {
            return s;
        }
    }
    SharedShape::ball(shape.compute_local_bounding_sphere().radius * GROW)
}

fn mesh_collider(mesh: &TouchMesh) -> ColliderBuilder {
    ColliderBuilder::trimesh(mesh.vertices().to_vec(), mesh.indices().to_vec())
        .expect("a touch mesh is a valid TriMesh")
}

// ------------------------------------------------------------------------------------------
// Contacts (Fig. 4).

async fn contact_case(viewer: &mut TestbedViewer, index: usize) {
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
    look(
        viewer,
        Vector::new(2.6, 2.4, 4.2),
        Vector::new(0.0, 0.4, 0.0),
    );
    let settings = viewer.example_settings_mut();
    settings.set_label("Case", scene.description);
    settings.set_label(
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
            features(
                viewer,
                &scene.fixed,
                &scene.fixed_pose,
                &p.fixed_features,
                YELLOW,
            );
            features(viewer, &scene.moving, &touch, &p.moving_features, YELLOW);
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

// ------------------------------------------------------------------------------------------
// Rigid: penetration comparison and tool proxy.

const SPEEDS: [Real; 5] = [1.0, 5.0, 20.0, 50.0, 100.0];
const REDROP: &str = "Drop again every 3 s";

/// One half of the comparison: `scenes::drop_world`'s floor (narrowed) and box, moved to `x`.
struct DropSide {
    x: Real,
    body: RigidBodyHandle,
    collider: ColliderHandle,
    tunneled: bool,
    max_penetration: Real,
    /// How far the box's centre went below the floor's top.
    deepest_centre: Real,
}

impl DropSide {
    fn insert(world: &mut PhysicsWorld, x: Real, floor: DropFloor, hooks: ActiveHooks) -> Self {
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
    fn drop(&mut self, world: &mut PhysicsWorld, speed: Real) {
        let b = &mut world.bodies[self.body];
        b.set_position(Pose::from_translation(Vector::new(self.x, 3.0, 0.0)), true);
        b.set_linvel(Vector::new(0.0, -speed, 0.0), true);
        b.set_angvel(Vector::ZERO, true);
        self.tunneled = false;
        self.max_penetration = 0.0;
        self.deepest_centre = 0.0;
    }

    fn measure(&mut self, world: &PhysicsWorld) -> String {
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

async fn penetration_compare(viewer: &mut TestbedViewer) {
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
    look(
        viewer,
        Vector::new(0.0, 3.0, 8.0),
        Vector::new(0.0, 0.8, 0.0),
    );
    viewer.example_settings_mut().set_label(
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

async fn tool_proxy(viewer: &mut TestbedViewer) {
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
    look(
        viewer,
        Vector::new(4.0, 4.5, 8.0),
        Vector::new(0.0, 1.0, 0.0),
    );
    viewer.example_settings_mut().set_label(
        "Mouse",
        "left-drag the see-through ghost (the device) into the block: the tool (the proxy) \
         stops at first touch",
    );

    let mut touch = TouchPipeline::default();
    touch.options.report_touching = true;
    let mut last_rv = Vector::ZERO;
    while viewer.render_frame(&mut world).await {
        if viewer.simulating() {
            touch.set_tool_target(tool.body, tool.device(&world));
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
                features(
                    viewer,
                    &scene.fixed,
                    &scene.fixed_pose,
                    &p.fixed_features,
                    YELLOW,
                );
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

// ------------------------------------------------------------------------------------------
// Soft surfaces.

const INTEGRATORS: [(&str, Integrator); 4] = [
    ("exact filter", Integrator::EXACT),
    ("neighbour filter", Integrator::NEIGHBOUR),
    ("Baraff-Witkin", Integrator::BARAFF_WITKIN),
    ("explicit Euler", Integrator::ExplicitEuler),
];

fn pick_integrator(viewer: &mut TestbedViewer) -> (&'static str, Integrator) {
    let names = INTEGRATORS.iter().map(|(n, _)| n.to_string()).collect();
    let i = viewer
        .example_settings_mut()
        .get_or_set_string("Integrator", 0, names);
    INTEGRATORS[i.min(INTEGRATORS.len() - 1)]
}

/// A world at 60 Hz and a fixed body for a surface.
fn soft_world(gravity: Vector) -> (PhysicsWorld, RigidBodyHandle) {
    let mut world = PhysicsWorld {
        gravity,
        ..Default::default()
    };
    world.integration_parameters.dt = DT;
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    (world, ground)
}

/// Steps rapier and the surfaces (rapier only once a surface diverged), then redraws the
/// surface's collider. Returns `false` once diverged (explicit Euler past its stability limit).
fn step_soft(
    viewer: &mut TestbedViewer,
    world: &mut PhysicsWorld,
    set: &mut SurfaceSet,
    h: SurfaceHandle,
    alive: bool,
) -> bool {
    if !alive {
        world.step();
        return false;
    }
    set.step(world);
    let s = set.get(h).expect("surface");
    let collider = s.collider().expect("collider");
    // Stopped long before the state leaves f32 (the collider's vertices): the plates are
    // 0.3 m wide.
    let alive = s.surface.is_finite() && s.surface.max_displacement() < 0.5;
    // The testbed redraws only rapier's own soft bodies: rebuild the render mesh.
    viewer.update_collider(collider, world);
    alive
}

fn tool_label(set: &SurfaceSet, tool: &Tool) -> String {
    let r = set.tool_reaction(tool.collider).unwrap_or_default();
    format!(
        "{:.4} N, {} vertices held",
        r.force.length(),
        r.held_vertices
    )
}

/// The force of a schedule at time `t` (as the surface applies it).
fn profile_at(p: &ForceProfile, t: Real) -> Vector {
    match *p {
        ForceProfile::Step { force, start, end } => {
            if t >= start && end.is_none_or(|e| t < e) {
                force
            } else {
                Vector::ZERO
            }
        }
        ForceProfile::Ramp {
            force,
            start,
            duration,
        } => {
            if t < start {
                Vector::ZERO
            } else {
                force * ((t - start) / duration.max(Real::EPSILON)).min(1.0)
            }
        }
    }
}

/// Red arrows of length `len` along `force` ending at `vertices` (drawn when it is not zero).
fn force_arrows(
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

async fn plate_fig6(viewer: &mut TestbedViewer) {
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

    let (mut world, ground) = soft_world(Vector::ZERO);
    let mut set = SurfaceSet::new();
    // One surface step per rigid step: the paper's dt = 1/60 s.
    let options = AttachOptions {
        substeps: 1,
        collider: true,
    };
    let h = set
        .insert(surface, ground, &mut world, options)
        .expect("attached");
    let plate_collider = set.get(h).and_then(|s| s.collider()).expect("collider");
    let mut tool = Tool::insert(
        &mut world,
        ColliderBuilder::ball(0.015),
        Pose::from_translation(Vector::new(0.08, 0.04, 0.03)),
    );
    set.add_tool(tool.collider, &mut world);
    viewer.set_world(&mut world);
    viewer.set_initial_collider_color(plate_collider, TISSUE);
    tool.colors(viewer);
    look(
        viewer,
        Vector::new(0.2, 0.2, 0.32),
        Vector::new(0.0, -0.01, 0.0),
    );
    viewer.example_settings_mut().set_label(
        "Plate",
        format!(
            "{} nodes, rim pinned, step force on 7 vertices, {name}",
            planar.mesh.num_vertices()
        ),
    );

    let mut alive = true;
    while viewer.render_frame(&mut world).await {
        if viewer.simulating() {
            tool.drive(&mut world, None);
            alive = step_soft(viewer, &mut world, &mut set, h, alive);
        }
        let s = &set.get(h).expect("surface").surface;
        force_arrows(viewer, s, &loaded, down, 0.02);
        let time = s.time();
        let text = if alive {
            format!("{:.2} mm", s.max_displacement() * 1e3)
        } else {
            format!("{name} diverged at t = {time:.2} s (stopped)")
        };
        let tool_text = tool_label(&set, &tool);
        let settings = viewer.example_settings_mut();
        settings.set_label("Time", format!("{time:.2} s"));
        settings.set_label("Largest displacement", text);
        settings.set_label("Tool", tool_text);
    }
}

/// `constrained_790`'s six force sites (u, v) and profiles.
fn organ_forces() -> [([Real; 2], ForceProfile); 6] {
    let mn = 0.001;
    let r = std::f32::consts::FRAC_1_SQRT_2;
    let step =
        |force: Vector, start: Real, end: Option<Real>| ForceProfile::Step { force, start, end };
    let ramp = |force: Vector, start: Real, duration: Real| ForceProfile::Ramp {
        force,
        start,
        duration,
    };
    [
        ([0.04, 0.03], step(Vector::new(0.0, -mn, 0.0), 0.0, None)),
        ([-0.02, 0.03], ramp(Vector::new(0.0, mn, 0.0), 0.0, 2.0)),
        ([0.07, 0.0], step(Vector::new(mn, 0.0, 0.0), 1.0, Some(6.0))),
        ([0.0, -0.035], ramp(Vector::new(0.0, 0.0, -mn), 0.5, 3.0)),
        (
            [-0.035, -0.03],
            step(Vector::new(-mn * r, -mn * r, 0.0), 2.0, None),
        ),
        (
            [0.055, -0.03],
            ramp(Vector::new(0.0, -0.6 * mn, 0.8 * mn), 3.0, 2.0),
        ),
    ]
}

/// Each site's group: the free vertex nearest to it and its free edge neighbours.
fn organ_groups(planar: &PlanarMesh, pinned: &[u32]) -> Vec<Vec<u32>> {
    let mesh = &planar.mesh;
    let mut adjacent = vec![Vec::new(); mesh.num_vertices()];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if !adjacent[a as usize].contains(&b) {
                adjacent[a as usize].push(b);
                adjacent[b as usize].push(a);
            }
        }
    }
    let free = |i: &u32| !pinned.contains(i);
    organ_forces()
        .iter()
        .map(|([u, v], _)| {
            let site = Vector::new(*u, 0.0, *v);
            let centre = (0..mesh.num_vertices() as u32)
                .filter(free)
                .min_by(|&a, &b| {
                    let da = (mesh.vertices[a as usize] - site).length();
                    let db = (mesh.vertices[b as usize] - site).length();
                    da.total_cmp(&db)
                })
                .expect("free vertices");
            std::iter::once(centre)
                .chain(adjacent[centre as usize].iter().copied())
                .filter(free)
                .collect()
        })
        .collect()
}

async fn organ_fig7(viewer: &mut TestbedViewer) {
    // `constrained_790`: 788 nodes, the internal polyline pinned, the outer boundary free,
    // k = 0.1 N/m, c = 0.001 N*s/m, 1 g per vertex, dt = 1/60 s, six scheduled forces.
    let (name, integrator) = pick_integrator(viewer);
    let (outline, target_edge) = paper_organ_outline();
    let planar = triangulate_planar(&outline, target_edge).expect("meshes");
    let polyline = planar.constrained.first().cloned().unwrap_or_default();
    let groups = organ_groups(&planar, &polyline);
    let mut surface = MassSpringSurfaceBuilder::from_mesh(&planar.mesh)
        .stiffness(0.1)
        .damping(0.001)
        .mass(MassDistribution::PerVertex(0.001))
        .pinned(polyline.iter().copied())
        .integrator(integrator)
        .neighbour_max_error(Real::INFINITY)
        .build()
        .expect("valid organ mesh");
    let forces = organ_forces();
    for (g, (_, profile)) in groups.iter().zip(&forces) {
        surface
            .add_force_schedule(g.clone(), *profile)
            .expect("valid force");
    }

    let (mut world, ground) = soft_world(Vector::ZERO);
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: 1,
        collider: true,
    };
    let h = set
        .insert(surface, ground, &mut world, options)
        .expect("attached");
    let organ_collider = set.get(h).and_then(|s| s.collider()).expect("collider");
    let mut tool = Tool::insert(
        &mut world,
        ColliderBuilder::ball(0.008),
        Pose::from_translation(Vector::new(0.02, 0.03, 0.0)),
    );
    set.add_tool(tool.collider, &mut world);
    viewer.set_world(&mut world);
    viewer.set_initial_collider_color(organ_collider, TISSUE);
    tool.colors(viewer);
    look(
        viewer,
        Vector::new(0.14, 0.18, 0.24),
        Vector::new(0.0, -0.01, 0.0),
    );
    viewer.example_settings_mut().set_label(
        "Organ",
        format!(
            "{} nodes, {} polyline vertices pinned, six forces, {name}",
            planar.mesh.num_vertices(),
            polyline.len()
        ),
    );

    let mut alive = true;
    while viewer.render_frame(&mut world).await {
        if viewer.simulating() {
            tool.drive(&mut world, None);
            alive = step_soft(viewer, &mut world, &mut set, h, alive);
        }
        let s = &set.get(h).expect("surface").surface;
        let t = s.time();
        for (g, (_, profile)) in groups.iter().zip(&forces) {
            force_arrows(viewer, s, g, profile_at(profile, t), 0.012);
        }
        for w in polyline.windows(2) {
            line(viewer, s.position(w[0]), s.position(w[1]), BLACK, 3.0);
        }
        let text = if alive {
            format!("{:.2} mm", s.max_displacement() * 1e3)
        } else {
            format!("{name} diverged at t = {t:.2} s (stopped)")
        };
        let tool_text = tool_label(&set, &tool);
        let settings = viewer.example_settings_mut();
        settings.set_label("Time", format!("{t:.2} s"));
        settings.set_label("Largest displacement", text);
        settings.set_label("Tool", tool_text);
    }
}

// Multi-tool: `multi_tool`'s organ dome and tools, on a repeating script.

const DOME_HEIGHT: Real = 0.03;
const DEPTH: Real = 0.006;
const CLEARANCE: Real = 0.02;
const STAGGER: Real = 0.5;
/// Per tool and cycle: come down, press, drag, hold, lift off, wait (s).
const PHASES: [Real; 6] = [0.3, 0.35, 1.5, 0.35, 0.3, 0.7];

/// A dome over the planar mesh: the graph Poisson problem `L h = 1` with `h = 0` on
/// `boundary` (SOR), scaled to a peak of 1 (as in `multi_tool`).
fn dome(mesh: &SurfaceMesh, boundary: &[u32]) -> Vec<Real> {
    let n = mesh.num_vertices();
    let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); n];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if !adjacent[a].contains(&b) {
                adjacent[a].push(b);
                adjacent[b].push(a);
            }
        }
    }
    let mut fixed = vec![false; n];
    for &b in boundary {
        fixed[b as usize] = true;
    }
    let mut h = vec![0.0f64; n];
    for _ in 0..20_000 {
        let mut change = 0.0f64;
        for i in (0..n).filter(|&i| !fixed[i]) {
            let sum: f64 = adjacent[i].iter().map(|&j| h[j]).sum();
            let delta = 1.8 * ((sum + 1.0) / adjacent[i].len() as f64 - h[i]);
            h[i] += delta;
            change = change.max(delta.abs());
        }
        if change < 1e-12 {
            break;
        }
    }
    let top = h.iter().copied().fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    h.iter().map(|x| (x / top) as Real).collect()
}

/// The home surface's height over (u, v), interpolated in the planar triangle under it.
fn home_height(flat: &SurfaceMesh, heights: &[Real], u: Real, v: Real) -> Real {
    for t in &flat.triangles {
        let [a, b, c] = t.map(|i| flat.vertices[i as usize]);
        let (e1, e2) = ((b.x - a.x, b.z - a.z), (c.x - a.x, c.z - a.z));
        let (px, pz) = (u - a.x, v - a.z);
        let det = e1.0 * e2.1 - e1.1 * e2.0;
        let l1 = (px * e2.1 - pz * e2.0) / det;
        let l2 = (e1.0 * pz - e1.1 * px) / det;
        let l0 = 1.0 - l1 - l2;
        if l0 >= -1e-6 && l1 >= -1e-6 && l2 >= -1e-6 {
            let [ha, hb, hc] = t.map(|i| heights[i as usize]);
            return l0 * ha + l1 * hb + l2 * hc;
        }
    }
    0.0
}

fn smooth(x: Real) -> Real {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Tool `k`'s spot (u, v) and the depth of its lowest point below the home surface at `t`:
/// `multi_tool`'s path, repeated, dragged back and forth on alternate cycles.
fn tool_script(from: [Real; 2], to: [Real; 2], k: usize, t: Real) -> ([Real; 2], Real) {
    let s = t - k as Real * STAGGER;
    if s < 0.0 {
        return (from, -CLEARANCE);
    }
    let cycle_len: Real = PHASES.iter().sum();
    let cycle = (s / cycle_len).floor();
    let (a, b) = if cycle as i64 % 2 == 0 {
        (from, to)
    } else {
        (to, from)
    };
    let mut s = s - cycle * cycle_len;
    let lerp = |x: Real| [a[0] + (b[0] - a[0]) * x, a[1] + (b[1] - a[1]) * x];
    let [down, press, drag, hold, lift, _] = PHASES;
    if s < down {
        return (a, -CLEARANCE + (DEPTH + CLEARANCE) * smooth(s / down));
    }
    s -= down;
    if s < press {
        return (a, DEPTH);
    }
    s -= press;
    if s < drag {
        return (lerp(smooth(s / drag)), DEPTH);
    }
    s -= drag;
    if s < hold {
        return (b, DEPTH);
    }
    s -= hold;
    if s < lift {
        return (b, DEPTH - (DEPTH + CLEARANCE) * smooth(s / lift));
    }
    (b, -CLEARANCE)
}

async fn multi_tool(viewer: &mut TestbedViewer) {
    // 788 nodes lifted into a 30 mm dome, base pinned, k = 10 N/m, c = 0.1 N*s/m, 15 kg/m²,
    // exact filter, 17 substeps (the surface at 1020 Hz).
    let (outline, target_edge) = paper_organ_outline();
    let planar = triangulate_planar(&outline, target_edge).expect("meshes");
    let flat = planar.mesh.clone();
    let heights: Vec<Real> = dome(&flat, &planar.boundary)
        .iter()
        .map(|h| h * DOME_HEIGHT)
        .collect();
    let vertices: Vec<Vector> = flat
        .vertices
        .iter()
        .zip(&heights)
        .map(|(v, h)| Vector::new(v.x, *h, v.z))
        .collect();
    let surface = MassSpringSurfaceBuilder::new(vertices, flat.triangles.clone())
        .stiffness(10.0)
        .damping(0.1)
        .mass(MassDistribution::AreaDensity(15.0))
        .pinned(planar.boundary.iter().copied())
        .integrator(Integrator::EXACT)
        .build()
        .expect("valid organ mesh");
    let (mut world, ground) = soft_world(Vector::ZERO);
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: 17,
        collider: true,
    };
    let h = set
        .insert(surface, ground, &mut world, options)
        .expect("attached");
    let organ_collider = set.get(h).and_then(|s| s.collider()).expect("collider");

    // `multi_tool`'s tools: five balls and a cuboid pitched like a sled, (from, to) in plan.
    let ball = ColliderBuilder::ball;
    let specs: [(ColliderBuilder, Vector, [Real; 2], [Real; 2]); 6] = [
        (ball(0.010), Vector::ZERO, [0.045, 0.022], [0.045, -0.018]),
        (ball(0.008), Vector::ZERO, [-0.035, 0.022], [-0.005, 0.025]),
        (
            ColliderBuilder::cuboid(0.008, 0.004, 0.006),
            Vector::new(0.0, 0.0, 0.4),
            [-0.012, 0.0],
            [0.018, 0.002],
        ),
        (ball(0.012), Vector::ZERO, [-0.03, -0.025], [0.0, -0.03]),
        (ball(0.007), Vector::ZERO, [0.012, 0.028], [0.035, 0.025]),
        (ball(0.009), Vector::ZERO, [0.062, 0.018], [0.062, -0.005]),
    ];
    // Each tool's path and its lowest point relative to its centre (world axes).
    let paths: Vec<([Real; 2], [Real; 2], Vector)> = specs
        .iter()
        .map(|(builder, tilt, from, to)| {
            let rot = Pose::from_parts(Vector::ZERO, Rotation::from_scaled_axis(*tilt));
            let lowest = builder
                .shape
                .as_support_map()
                .map_or(Vector::ZERO, |m| m.support_point(&rot, -Vector::Y));
            (*from, *to, lowest)
        })
        .collect();
    let place = |k: usize, t: Real| -> Vector {
        let (from, to, o) = paths[k];
        let ([u, v], depth) = tool_script(from, to, k, t);
        let y = home_height(&flat, &heights, u + o.x, v + o.z) - depth - o.y;
        Vector::new(u, y, v)
    };
    // Inserted where the script starts them: a tool's first step sweeps from its pose.
    let mut tools = Vec::new();
    for (k, (builder, tilt, _, _)) in specs.into_iter().enumerate() {
        let pose = Pose::from_parts(place(k, 0.0), Rotation::from_scaled_axis(tilt));
        let tool = Tool::insert(&mut world, builder, pose);
        set.add_tool(tool.collider, &mut world);
        tools.push(tool);
    }
    viewer.set_world(&mut world);
    viewer.set_initial_collider_color(organ_collider, TISSUE);
    for tool in &tools {
        tool.colors(viewer);
    }
    look(
        viewer,
        Vector::new(0.12, 0.16, 0.2),
        Vector::new(0.01, 0.01, 0.0),
    );
    viewer.example_settings_mut().set_label(
        "Mouse",
        "left-drag a tool's ghost: it leaves its script and follows the mouse",
    );

    let mut step = 0usize;
    while viewer.render_frame(&mut world).await {
        if viewer.simulating() {
            step += 1;
            let t = step as Real * DT;
            for (k, tool) in tools.iter_mut().enumerate() {
                tool.drive(&mut world, Some(place(k, t)));
            }
            step_soft(viewer, &mut world, &mut set, h, true);
        }
        let mut text = Vec::new();
        for tool in &tools {
            let r = set.tool_reaction(tool.collider).unwrap_or_default();
            let at = world.bodies[tool.body].translation();
            // The surface's force on the tool, 1 N drawn 10 cm long.
            arrow(viewer, at, at + r.force * 0.1, RED, 2.0);
            text.push(format!("{:.3}", r.force.length()));
        }
        let disp = set.get(h).expect("surface").surface.max_displacement();
        let settings = viewer.example_settings_mut();
        settings.set_label("Tool forces N", text.join(", "));
        settings.set_label("Largest displacement", format!("{:.2} mm", disp * 1e3));
    }
}

async fn ball_on_plate(viewer: &mut TestbedViewer) {
    // `ball_on_plate`: 256 nodes 20 mm apart, rim pinned, k = 30 N/m, c = 1 N*s/m, 0.05 kg,
    // exact filter, 17 substeps; a 30 mm, 0.1 kg dynamic ball dropped from 100 mm.
    const RADIUS: Real = 0.03;
    const START: Vector = Vector::new(0.004, 0.1, -0.003);
    let (mut world, ground) = soft_world(Vector::new(0.0, -9.81, 0.0));
    let mesh = plate(0.3, 0.3, 15, 15);
    let half = 0.15 - 1e-4;
    let rim: Vec<u32> = (0..mesh.num_vertices() as u32)
        .filter(|&i| {
            let v = mesh.vertices[i as usize];
            v.x.abs() > half || v.z.abs() > half
        })
        .collect();
    let surface = MassSpringSurfaceBuilder::from_mesh(&mesh)
        .stiffness(30.0)
        .damping(1.0)
        .mass(MassDistribution::Total(0.05))
        .pinned(rim)
        .integrator(Integrator::EXACT)
        .build()
        .expect("valid plate");
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: 17,
        collider: true,
    };
    let h = set
        .insert(surface, ground, &mut world, options)
        .expect("attached");
    let plate_collider = set.get(h).and_then(|s| s.collider()).expect("collider");
    let volume = 4.0 / 3.0 * std::f32::consts::PI * RADIUS.powi(3);
    let ball = world.insert_body(RigidBodyBuilder::dynamic().translation(START));
    let collider = world.insert_collider(
        ColliderBuilder::ball(RADIUS).density(0.1 / volume),
        Some(ball),
    );
    set.add_tool(collider, &mut world);
    let weight = world.bodies[ball].mass() * 9.81;
    viewer.set_world(&mut world);
    viewer.set_initial_collider_color(plate_collider, TISSUE);
    viewer.set_initial_collider_color(collider, STEEL);
    look(
        viewer,
        Vector::new(0.25, 0.22, 0.38),
        Vector::new(0.0, 0.0, 0.0),
    );
    viewer.example_settings_mut().set_label(
        "Mouse",
        "left-drag the ball to lift and throw it; the plate's force is all that stops it",
    );

    while viewer.render_frame(&mut world).await {
        if viewer.simulating() {
            step_soft(viewer, &mut world, &mut set, h, true);
            // Fell off the plate: drop it again.
            if world.bodies[ball].translation().y < -0.5 {
                let b = &mut world.bodies[ball];
                b.set_translation(START, true);
                b.set_linvel(Vector::ZERO, true);
                // The surfaces sweep a tool from its collider's pose at the start of the
                // step: move the collider too, or the ball sweeps up through the plate.
                world
                    .bodies
                    .propagate_modified_body_positions_to_colliders(&mut world.colliders);
            }
        }
        let r = set.tool_reaction(collider).unwrap_or_default();
        let at = world.bodies[ball].translation();
        // The surface's force on the ball, its weight drawn 5 cm long.
        arrow(viewer, at, at + r.mean_force * (0.05 / weight), RED, 2.0);
        let disp = set.get(h).expect("surface").surface.max_displacement();
        let settings = viewer.example_settings_mut();
        settings.set_label("Ball height", format!("{:.1} mm", at.y * 1e3));
        settings.set_label(
            "Surface force",
            format!(
                "{:.3} N (weight {weight:.3} N), {} vertices held",
                r.mean_force.y, r.held_vertices
            ),
        );
        settings.set_label("Largest displacement", format!("{:.2} mm", disp * 1e3));
    }
}
