//! The bevy plugin with a window: a ball tool follows the mouse over the paper's 788-node
//! organ (pinned along its internal polyline); hold the left button to press it 1 cm in.
//! The organ's mesh follows the deformed surface; the tool's reaction (its
//! `SurfaceToolReaction` component) is printed twice a second.
//!
//! Run with `cargo run --release --features bevy-viewer --example bevy_organ` (needs a
//! display; bevy 0.20 declares Rust 1.97.1, add `--ignore-rust-version` on an older
//! toolchain: its crates build on 1.95).

use bevy::camera::Camera3d;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use rapier_touch::bevy_plugin::*;
use rapier_touch::prelude::{AttachOptions, MassDistribution, MassSpringSurfaceBuilder};
use rapier_touch::scenes::Fig7Organ;

/// Height of the tool's lowest point when hovering, and how deep it presses (m).
const HOVER: f32 = 0.02;
const DEPTH: f32 = 0.01;
const RADIUS: f32 = 0.008;

#[derive(Component)]
struct Tool;

fn main() {
    App::new()
        .add_plugins(DefaultPlugins)
        .add_plugins(RapierPhysicsPlugin::<TouchPhysicsHooks>::default())
        .add_plugins(RapierTouchPlugin::default())
        .add_systems(Startup, setup)
        .add_systems(Update, (drive_tool, print_reaction))
        .run();
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let organ = Fig7Organ::new();
    let surface = MassSpringSurfaceBuilder::from_mesh(&organ.planar.mesh)
        .stiffness(20.0)
        .damping(0.02)
        .mass(MassDistribution::Total(0.05))
        .pinned(organ.polyline.iter().copied())
        .build()
        .expect("the organ mesh is valid");
    println!(
        "organ: {} nodes, {} triangles",
        surface.num_vertices(),
        surface.triangles().len()
    );
    let mesh = meshes.add(surface_mesh(&surface));
    commands.spawn((
        RigidBody::Fixed,
        Transform::default(),
        SoftSurface::new(
            surface,
            AttachOptions {
                substeps: 8,
                collider: true,
            },
        ),
        Mesh3d(mesh),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.8, 0.35, 0.35),
            double_sided: true,
            cull_mode: None,
            ..default()
        })),
    ));
    commands.spawn((
        Tool,
        RigidBody::KinematicPositionBased,
        Collider::ball(RADIUS),
        SurfaceTool,
        Transform::from_xyz(0.0, HOVER + RADIUS, 0.0),
        Mesh3d(meshes.add(Sphere::new(RADIUS))),
        MeshMaterial3d(materials.add(Color::srgb(0.7, 0.7, 0.75))),
    ));
    commands.spawn((
        Camera3d::default(),
        Transform::from_xyz(0.0, 0.18, 0.2).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    commands.spawn((
        DirectionalLight {
            illuminance: 8000.0,
            ..default()
        },
        Transform::from_xyz(0.3, 1.0, 0.5).looking_at(Vec3::ZERO, Vec3::Y),
    ));
}

/// The tool follows the cursor on the hover plane and goes down while the left button is
/// held (at most 1 mm per frame).
fn drive_tool(
    window: Single<&Window>,
    camera: Single<(&Camera, &GlobalTransform)>,
    buttons: Res<ButtonInput<MouseButton>>,
    mut tool: Single<&mut Transform, With<Tool>>,
) {
    let (camera, camera_pose) = *camera;
    let Some(cursor) = window.cursor_position() else {
        return;
    };
    let Ok(ray) = camera.viewport_to_world(camera_pose, cursor) else {
        return;
    };
    let plane_height = HOVER + RADIUS;
    let Some(d) = ray.intersect_plane(
        Vec3::new(0.0, plane_height, 0.0),
        InfinitePlane3d::new(Vec3::Y),
    ) else {
        return;
    };
    let mut target = ray.get_point(d);
    if buttons.pressed(MouseButton::Left) {
        target.y = RADIUS - DEPTH;
    }
    let step = (target - tool.translation).clamp_length_max(0.001);
    tool.translation += step;
}

fn print_reaction(
    time: Res<Time>,
    mut next: Local<f32>,
    tool: Single<&SurfaceToolReaction, With<Tool>>,
) {
    if time.elapsed_secs() < *next {
        return;
    }
    *next = time.elapsed_secs() + 0.5;
    let r = tool.0;
    println!(
        "t = {:.1} s: force [{:.4}, {:.4}, {:.4}] N, {} vertices held",
        time.elapsed_secs(),
        r.force.x,
        r.force.y,
        r.force.z,
        r.held_vertices
    );
}
