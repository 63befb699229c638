//! The bevy plugin, headless: `MinimalPlugins`, bevy_rapier's plugin with the crate's hooks,
//! and the crate's plugin, run through bevy's schedule (`cargo test --features bevy --test
//! bevy_plugin`). Checked against physics, not against the crate: where a fast box ends
//! (and where it ends without the plugin), and a static solve of the plate's springs (for a
//! tool pressed by hand and for one driven by a simulated hand through a servo loop).

use bevy::asset::Assets;
use bevy::mesh::{Mesh, Mesh3d, VertexAttributeValues};
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy_rapier3d::plugin::context::{DefaultRapierContext, RapierContextSimulation};
use bevy_rapier3d::prelude::*;
use rapier_touch::bevy_plugin::*;
use rapier_touch::prelude::{AttachOptions, MassDistribution, MassSpringSurfaceBuilder};
use rapier_touch::surface::meshing::{plate, plate_rim};
use std::time::Duration;

// The static solves shared with the main integration tests (the rest of it is unused here).
#[allow(dead_code)]
#[path = "it/common.rs"]
mod common;

/// A headless app at 60 Hz, with (or without) the crate's plugin.
fn app(with_touch: bool) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, TransformPlugin));
    if with_touch {
        app.add_plugins(RapierPhysicsPlugin::<TouchPhysicsHooks>::default())
            .add_plugins(RapierTouchPlugin::default());
    } else {
        app.add_plugins(RapierPhysicsPlugin::<()>::default())
            .insert_resource(TimestepMode::Fixed {
                dt: 1.0 / 60.0,
                substeps: 1,
            });
    }
    app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f32(
        1.0 / 60.0,
    )))
    .insert_resource(Assets::<Mesh>::default());
    app.finish();
    app.update();
    app
}

/// Drops a spinning 0.2 m cube at 60 m/s (1 m per step) on a 2 cm floor, with rapier's CCD
/// off so that the step guard alone is tested; returns the lowest and the last height of its
/// lowest corner over two seconds.
fn drop_fast_box(with_touch: bool) -> (f32, f32) {
    let mut app = app(with_touch);
    let mut contexts = app
        .world_mut()
        .query_filtered::<&mut RapierContextSimulation, With<DefaultRapierContext>>();
    contexts
        .single_mut(app.world_mut())
        .unwrap()
        .integration_parameters
        .max_ccd_substeps = 0;
    let floor = app
        .world_mut()
        .spawn((Collider::cuboid(5.0, 0.01, 5.0), Transform::default()))
        .id();
    if with_touch {
        app.world_mut().entity_mut(floor).insert(TouchTracked);
    }
    let cube = app
        .world_mut()
        .spawn((
            RigidBody::Dynamic,
            Collider::cuboid(0.1, 0.1, 0.1),
            Velocity {
                linear: Vec3::new(0.0, -60.0, 0.0),
                angular: Vec3::new(3.0, 0.0, 5.0),
            },
            Transform::from_xyz(0.3, 1.5, -0.2),
        ))
        .id();
    if with_touch {
        app.world_mut().entity_mut(cube).insert(TouchTracked);
    }
    let mut lowest = f32::INFINITY;
    let mut bottom = 0.0;
    for _ in 0..120 {
        app.update();
        let t = app.world().get::<Transform>(cube).unwrap();
        // The lowest corner of the (possibly tilted) cube.
        bottom = [-1.0f32, 1.0]
            .iter()
            .flat_map(|&x| [-1.0f32, 1.0].map(move |y| (x, y)))
            .flat_map(|(x, y)| [-1.0f32, 1.0].map(move |z| Vec3::new(x, y, z) * 0.1))
            .map(|c| t.transform_point(c).y)
            .fold(f32::INFINITY, f32::min);
        lowest = lowest.min(bottom);
    }
    (lowest, bottom)
}

#[test]
fn a_tracked_floor_stops_a_fast_box_that_rapier_alone_lets_through() {
    // Without the plugin the box is below the floor after its first step into it.
    let (_, vanilla_end) = drop_fast_box(false);
    let (lowest, end) = drop_fast_box(true);
    assert!(
        vanilla_end < -0.5,
        "rapier alone: bottom at {vanilla_end} m"
    );
    // With it, the box never sinks into the floor (top at y = 0.01) by more than the
    // guard's slop, and ends resting on it.
    assert!(lowest > 0.01 - 1e-3, "lowest bottom {lowest} m");
    assert!((end - 0.01).abs() < 5e-3, "resting bottom {end} m");
}

/// A plate 1 m square of `cells` × `cells`, clamped at its rim, edges of `k`, 0.1 kg in all.
fn rim_plate(cells: u32, k: f32) -> MassSpringSurfaceBuilder {
    MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, cells, cells))
        .stiffness(k)
        .mass(MassDistribution::Total(0.1))
        .pinned(plate_rim(cells, cells))
}

/// The index of [`rim_plate`]'s centre vertex.
fn centre_vertex(cells: u32) -> usize {
    (cells / 2 * (cells + 1) + cells / 2) as usize
}

/// The force pressing the centre vertex of [`rim_plate`] to depth `d` with the rim pinned and
/// the other vertices in equilibrium (linear springs `k` on every edge): `-(L u)_c`.
fn static_force(cells: u32, d: f64, k: f64) -> f64 {
    let mesh = plate(1.0, 1.0, cells, cells);
    let (triangles, n) = (&mesh.triangles, mesh.vertices.len());
    let (pins, c) = (plate_rim(cells, cells), centre_vertex(cells));
    let lap = common::edge_laplacian(triangles, n, k);
    let known: Vec<bool> = (0..n)
        .map(|i| i == c || pins.contains(&(i as u32)))
        .collect();
    let mut u = vec![0.0; n];
    u[c] = -d;
    common::dirichlet_solve(&lap, &known, &mut u);
    -(0..n).map(|j| lap[(c, j)] * u[j]).sum::<f64>()
}

#[test]
fn a_tool_dents_a_soft_plate_its_mesh_follows_and_its_reaction_matches_a_static_solve() {
    let mut app = app(true);
    // A plate 1 m square, 10 x 10 cells, clamped at its rim, on a turned and moved body.
    let (cells, k, depth, r) = (10, 100.0, 0.01, 0.02);
    let soft = rim_plate(cells, k).build().unwrap();
    let centre = centre_vertex(cells);
    let mesh = app
        .world_mut()
        .resource_mut::<Assets<Mesh>>()
        .add(surface_mesh(&soft));
    let body = Transform::from_xyz(2.0, 1.0, -1.0).with_rotation(Quat::from_rotation_y(0.3));
    let options = AttachOptions {
        substeps: 8,
        collider: true,
    };
    let surface = app
        .world_mut()
        .spawn((
            RigidBody::Fixed,
            body,
            SoftSurface::new(soft, options),
            Mesh3d(mesh.clone()),
        ))
        .id();
    // A kinematic ball lowered onto the centre vertex, down to `depth` below the plate.
    let above = body.transform_point(Vec3::new(0.0, 0.1, 0.0));
    let below = body.transform_point(Vec3::new(0.0, r - depth, 0.0));
    let ball = app
        .world_mut()
        .spawn((
            RigidBody::KinematicPositionBased,
            Collider::ball(r),
            SurfaceTool,
            Transform::from_translation(above),
        ))
        .id();
    for frame in 1..=270 {
        let a = (frame as f32 / 30.0).min(1.0);
        app.world_mut()
            .get_mut::<Transform>(ball)
            .unwrap()
            .translation = above.lerp(below, a);
        app.update();
    }

    assert!(app
        .world()
        .get::<SoftSurface>(surface)
        .unwrap()
        .handle()
        .is_some());
    // The reaction component: up along the plate's normal, the static solve's size.
    let reaction = app.world().get::<SurfaceToolReaction>(ball).unwrap().0;
    assert_eq!(reaction.held_vertices, 1);
    let expected = static_force(cells, depth as f64, k as f64);
    let normal = body.rotation * Vec3::Y;
    let got = reaction.force.dot(normal) as f64;
    assert!(
        (got - expected).abs() <= 0.05 * expected,
        "force {got} N against the static {expected} N"
    );
    assert!((reaction.force - normal * got as f32).length() < 0.01 * got as f32);

    // The mesh asset shows the dent: the centre vertex `depth` down in the body's frame, the
    // rim where it was.
    let meshes = app.world().resource::<Assets<Mesh>>();
    let Some(VertexAttributeValues::Float32x3(positions)) = meshes
        .get(&mesh)
        .unwrap()
        .attribute(Mesh::ATTRIBUTE_POSITION)
    else {
        panic!("no positions");
    };
    assert!(
        (positions[centre][1] + depth).abs() < 1e-3,
        "{:?}",
        positions[centre]
    );
    assert_eq!(positions[0], [-0.5, 0.0, -0.5]);
}

#[test]
fn despawning_tools_and_surfaces_mid_press_is_safe() {
    let mut app = app(true);
    let soft = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 10, 10))
        .pinned(plate_rim(10, 10))
        .build()
        .unwrap();
    let options = AttachOptions {
        substeps: 4,
        collider: true,
    };
    let surface = app
        .world_mut()
        .spawn((
            RigidBody::Fixed,
            Transform::default(),
            SoftSurface::new(soft, options),
        ))
        .id();
    // Balls 1 cm into the plate over two of its vertices.
    let ball = |app: &mut App, x: f32| {
        app.world_mut()
            .spawn((
                RigidBody::KinematicPositionBased,
                Collider::ball(0.03),
                SurfaceTool,
                Transform::from_xyz(x, 0.02, 0.0),
            ))
            .id()
    };
    let first = ball(&mut app, -0.2);
    let second = ball(&mut app, 0.2);
    for _ in 0..30 {
        app.update();
    }
    for tool in [first, second] {
        let pressed = app.world().get::<SurfaceToolReaction>(tool).unwrap().0;
        assert!(pressed.force.y > 0.0 && pressed.held_vertices == 1);
    }
    // A tool goes mid-press: the other keeps its force, nothing panics.
    app.world_mut().despawn(first);
    for _ in 0..30 {
        app.update();
    }
    let r = app.world().get::<SurfaceToolReaction>(second).unwrap().0;
    assert!(r.force.y > 0.0 && r.force.is_finite());
    // The surface goes: the tool's reaction drops to nothing.
    app.world_mut().despawn(surface);
    for _ in 0..30 {
        app.update();
    }
    let r = app.world().get::<SurfaceToolReaction>(second).unwrap().0;
    assert_eq!(r.force, Vec3::ZERO);
}

#[test]
fn a_haptic_tool_follows_its_servo_and_the_hand_feels_the_plate() {
    use rapier_touch::haptics::{haptic_link, Servo, SimulatedHand, VirtualCoupling};
    use rapier_touch::math::{Pose, Vector};

    let mut app = app(true);
    let (cells, k, r) = (10, 100.0, 0.02);
    let soft = rim_plate(cells, k).damping(0.2).build().unwrap();
    let options = AttachOptions {
        substeps: 8,
        collider: true,
    };
    app.world_mut().spawn((
        RigidBody::Fixed,
        Transform::default(),
        SoftSurface::new(soft, options),
    ));
    // A kinematic ball driven by a simulated hand at 5 kHz, served on this thread between
    // frames; the hand's arm lowers its target from 10 cm above the plate to the plate's
    // plane over a second and holds it there: the plate pushes back, the hand rests
    // between its arm and the rendered force.
    let (world_end, servo_end) = haptic_link();
    let ball = app
        .world_mut()
        .spawn((
            RigidBody::KinematicPositionBased,
            Collider::ball(r),
            HapticTool::new(world_end),
            Transform::from_xyz(0.0, 0.1, 0.0),
        ))
        .id();
    let rate = 5000.0;
    let hand = SimulatedHand::new(rate, |t| {
        Pose::from_translation(Vector::new(0.0, 0.1 * (1.0 - t.min(1.0)), 0.0))
    })
    .unwrap();
    let coupling = VirtualCoupling {
        stiffness: 0.5 * VirtualCoupling::max_passive_stiffness(rate, 2.0),
        damping: 0.0,
        max_force: 20.0,
    };
    let mut servo = Servo::new(hand, servo_end, coupling, rate).unwrap();
    let mut last = None;
    for frame in 0..240 {
        for _ in 0..83 + (frame % 3 == 0) as usize {
            last = Some(servo.tick());
        }
        app.update();
    }
    let tick = last.unwrap();

    // The tool stands where the servo's proxy was sent, and presses the plate.
    let tool = app.world().get::<Transform>(ball).unwrap().translation;
    assert!(
        (tool - tick.proxy).length() < 1e-3,
        "tool at {tool}, proxy at {}",
        tick.proxy
    );
    let reaction = app.world().get::<SurfaceToolReaction>(ball).unwrap().0;
    assert_eq!(reaction.held_vertices, 1);
    let depth = r - tool.y;
    assert!(depth > 5e-3, "the tool is {depth} m into the plate");
    // The plate's reaction is the static solve's at the tool's depth; the hand feels it.
    let expected = static_force(cells, depth as f64, k as f64);
    let got = reaction.force.y as f64;
    assert!(
        (got - expected).abs() <= 0.05 * expected,
        "force {got} N against the static {expected} N"
    );
    let rendered = tick.force.y as f64;
    assert!(
        (rendered - got).abs() <= 0.05 * got,
        "rendered {rendered} N, the plate's {got} N"
    );
    // At rest the hand balances its arm: 300 N/m from the plate's plane down to it.
    let hand = servo.device();
    let arm = hand.arm_stiffness * tick.device.translation.y;
    assert!(
        (arm as f64 - rendered).abs() <= 0.05 * rendered,
        "arm {arm} N, rendered {rendered} N"
    );
}
