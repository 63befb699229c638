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
//! - *Organ (Fig. 7)*: `constrained_790`'s 788-node organ (`scenes::Fig7Organ`) hanging on its
//!   pinned internal polyline (black) under the six scheduled forces.
//! - *Multi-tool*: `multi_tool`'s organ dome pressed and dragged by six tools
//!   (`scenes::MultiToolScene`), each repeating its script every 3.5 s (it goes back to its
//!   first spot in the air).
//! - *Ball on plate*: `ball_on_plate`'s dynamic ball on a soft plate (`scenes::BallOnPlateScene`,
//!   two-way coupling).
//!
//! In the soft scenes and *Tool proxy* every tool sits in a see-through ghost, a dynamic body
//! that collides with nothing: the testbed's mouse grab (left-drag) only moves dynamic bodies,
//! so the kinematic tool follows its ghost. A grabbed scripted tool leaves its script until the
//! scene restarts (`R`). The ball of *Ball on plate* is dynamic and is grabbed directly. The
//! testbed drags in the plane facing the camera through the grabbed point: orbit the camera
//! (right-drag) to push a tool down. `T` pauses, `S` steps, `R` restarts.
//!
//! The organ, multi-tool and ball scenes are the library's, the very scenes the headless
//! examples step, print and check; the plate is `plate_step_force`'s set-up.

use kiss3d::color::Color;
use rapier_testbed3d::{ExampleEntry, TestbedViewer};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::{
    ActiveHooks, ColliderBuilder, ColliderHandle, InteractionGroups, PhysicsWorld,
    RigidBodyBuilder, RigidBodyHandle, SharedShape,
};
use rapier_touch::scenes::{
    attach_fixed, box_depth_below_floor, fig4_scenes, BallOnPlateScene, DropFloor, Fig7Organ,
    MultiToolScene, DROP_BOX_HALF,
};
use rapier_touch::surface::meshing::{
    paper_plate_outline, triangulate_planar, PAPER_PLATE_TARGET_EDGE,
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
    let examples: [(&str, &str, ExampleFn); 10] = [
        (CONTACTS, "Line (edge) contact", |v| {
            Box::pin(contact_case(v, 0))
        }),
        (CONTACTS, "Face contact", |v| Box::pin(contact_case(v, 1))),
        (CONTACTS, "Vertex contact", |v| Box::pin(contact_case(v, 2))),
        (CONTACTS, "Multiple contacts", |v| {
            Box::pin(contact_case(v, 3))
        }),
        (RIGID, "Penetration comparison", |v| {
            Box::pin(penetration_compare(v))
        }),
        (RIGID, "Tool proxy", |v| Box::pin(tool_proxy(v))),
        (SOFT, "Plate (Fig. 6)", |v| Box::pin(plate_fig6(v))),
        (SOFT, "Organ (Fig. 7)", |v| Box::pin(organ_fig7(v))),
        (SOFT, "Multi-tool", |v| Box::pin(multi_tool(v))),
        (SOFT, "Ball on plate", |v| Box::pin(ball_on_plate(v))),
    ];
    let (entries, runs): (Vec<_>, Vec<ExampleFn>) = examples
        .into_iter()
        .map(|(group, name, run)| (ExampleEntry::new(group, name), run))
        .unzip();
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

/// The touching vertices and edges of one mesh, yellow (touching faces show as the patch).
fn features(viewer: &mut TestbedViewer, mesh: &TouchMesh, pose: &Pose, list: &[Feature]) {
    let at = |v: u32| pose.transform_point(mesh.vertices()[v as usize]);
    for f in list {
        match *f {
            Feature::Vertex(v) => point(viewer, at(v), YELLOW, 12.0),
            Feature::Edge([a, b]) => line(viewer, at(a), at(b), YELLOW, 4.0),
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
/// testbed's panels (which cover the left of the window), and shows the scene's first label
/// in the example settings.
fn look(
    viewer: &mut TestbedViewer,
    [eye, at]: [Vector; 2],
    label: &'static str,
    text: impl Into<String>,
) {
    let right = (at - eye).cross(Vector::Y).normalize_or_zero();
    let shift = right * (0.25 * (at - eye).length());
    viewer.look_at(eye - shift, at - shift);
    viewer.example_settings_mut().set_label(label, text);
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

/// A see-through ghost: a dynamic, collision-free body the testbed's mouse grab can move (it
/// only grabs dynamic bodies). The kinematic tool it leads follows it.
struct Ghost {
    body: RigidBodyHandle,
    collider: ColliderHandle,
    /// Grabbed once: the tool left its script and follows its ghost.
    manual: bool,
}

impl Ghost {
    /// A ghost for a tool of `shape` at `pose` (slightly larger than the tool).
    fn insert(world: &mut PhysicsWorld, shape: &SharedShape, pose: Pose) -> Self {
        let body = world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(pose)
                .gravity_scale(0.0)
                .linear_damping(10.0)
                .lock_rotations()
                .additional_mass(0.1),
        );
        let collider = world.insert_collider(
            ColliderBuilder::new(ghost_shape(shape))
                .density(0.0)
                .collision_groups(InteractionGroups::none()),
            Some(body),
        );
        Self {
            body,
            collider,
            manual: false,
        }
    }

    /// Whether the mouse holds the ghost (the testbed ties it to the cursor with a joint).
    fn grabbed(&self, world: &PhysicsWorld) -> bool {
        world
            .impulse_joints
            .attached_joints(self.body)
            .next()
            .is_some()
    }

    /// The ghost's position: where the mouse wants the tool.
    fn device(&self, world: &PhysicsWorld) -> Pose {
        *world.bodies[self.body].position()
    }

    /// Where the tool goes: the script (`Some(target)`, the ghost is moved there) until the
    /// ghost is first grabbed, then the ghost.
    fn lead(&mut self, world: &mut PhysicsWorld, scripted: Option<Vector>) -> Vector {
        if self.grabbed(world) {
            self.manual = true;
        }
        match scripted {
            Some(at) if !self.manual => {
                let ghost = &mut world.bodies[self.body];
                ghost.set_translation(at, true);
                ghost.set_linvel(Vector::ZERO, true);
                at
            }
            _ => self.device(world).translation,
        }
    }
}

/// A kinematic tool and its ghost.
struct Tool {
    body: RigidBodyHandle,
    collider: ColliderHandle,
    ghost: Ghost,
}

impl Tool {
    fn insert(world: &mut PhysicsWorld, tool: ColliderBuilder, pose: Pose) -> Self {
        let shape = tool.shape.clone();
        let body = world.insert_body(RigidBodyBuilder::kinematic_position_based().pose(pose));
        let collider = world.insert_collider(tool, Some(body));
        let ghost = Ghost::insert(world, &shape, pose);
        Self {
            body,
            collider,
            ghost,
        }
    }

    /// Steel tool, see-through ghost.
    fn colors(&self, viewer: &mut TestbedViewer) {
        tool_colors(viewer, self.collider, &self.ghost);
    }

    /// Follows the script (`Some(target)`) until first grabbed, then the ghost.
    fn drive(&mut self, world: &mut PhysicsWorld, scripted: Option<Vector>) {
        let target = self.ghost.lead(world, scripted);
        world.bodies[self.body].set_next_kinematic_translation(target);
    }
}

fn tool_colors(viewer: &mut TestbedViewer, tool: ColliderHandle, ghost: &Ghost) {
    viewer.set_initial_collider_color(tool, STEEL);
    viewer.set_initial_collider_color(ghost.collider, GHOST);
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

/// The Fig. 6 and Fig. 7 scenes: a surface alone in a world at 60 Hz without gravity, one
/// surface step per rigid step (the paper's dt = 1/60 s), with a ball tool the mouse drags.
struct SoftDemo {
    world: PhysicsWorld,
    set: SurfaceSet,
    surface: SurfaceHandle,
    collider: ColliderHandle,
    tool: Tool,
    /// The integrator's name.
    name: &'static str,
    /// Cleared once the surface diverged (explicit Euler past its stability limit): from then
    /// on only rapier steps.
    alive: bool,
}

impl SoftDemo {
    /// Shows `surface` (stepped by integrator `name`) and a ball tool of `radius` at `tool_at`
    /// through `camera` ([`look`]), with the scene's `label`.
    fn new(
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

    fn surface(&self) -> &MassSpringSurface {
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
    fn labels(&self, viewer: &mut TestbedViewer) {
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

async fn organ_fig7(viewer: &mut TestbedViewer) {
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
const MULTI_TOOL_PAUSE: Real = 0.7;

/// Where tool `k` is at time `t` in its script repeated every `ACTIVE + MULTI_TOOL_PAUSE`
/// (3.5 s) from its start: the time to look its pose up at in the library's script.
fn repeated_script_time(k: usize, t: Real) -> Real {
    type S = MultiToolScene;
    let start = k as Real * S::STAGGER;
    if t <= start {
        t
    } else {
        start + (t - start) % (S::ACTIVE + MULTI_TOOL_PAUSE)
    }
}

async fn multi_tool(viewer: &mut TestbedViewer) {
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

async fn ball_on_plate(viewer: &mut TestbedViewer) {
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
