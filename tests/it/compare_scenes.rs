//! The scenes `penetration_compare` adds (issue 12): a spinning box, a box onto a thin dynamic
//! plate, a non-convex TriMesh mover and the cuboid drop at 1/100 scale, each run once at its
//! fastest speed (100 m/s; 1 m/s at 1/100 scale) in a real rapier pipeline (dt = 1/60, rapier's
//! CCD off). Every step is measured here, from the colliders' shapes and world poses alone:
//! vertex heights against the floor's top (its world AABB), and parry's contact query with a
//! vertex cross-check for the box in the plate. The touch pipeline never lets anything go
//! through or penetrate more than 1 mm (2 % of the 5 mm box at 1/100 scale) and leaves the mover
//! above the floor; rapier alone does worse in at least one scene (the check can fail); and the
//! example's figures (`run_compare_side`) are these measurements.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::scenes::{compare_world, run_compare_side, CompareScene, DropSide};

const STEPS: usize = 120;

/// The vertices of a cuboid or TriMesh collider, in world coordinates.
fn world_vertices(c: &Collider) -> Vec<Vector> {
    let pose = c.position();
    let local: Vec<Vector> = match c.shape().as_typed_shape() {
        TypedShape::Cuboid(b) => {
            let h = b.half_extents;
            let mut v = Vec::new();
            for sx in [-h.x, h.x] {
                for sy in [-h.y, h.y] {
                    for sz in [-h.z, h.z] {
                        v.push(Vector::new(sx, sy, sz));
                    }
                }
            }
            v
        }
        TypedShape::TriMesh(m) => m.vertices().to_vec(),
        _ => panic!("a cuboid or TriMesh mover"),
    };
    local.iter().map(|&p| pose.transform_point(p)).collect()
}

/// What one run did, measured here after every step.
#[derive(Debug)]
struct Measured {
    /// Something went through (the mover's centre below the floor's top or the plate's
    /// mid-plane, or the plate's centre below the floor's top).
    through: bool,
    /// The deepest penetration over the steps before anything went through (m).
    deepest: f32,
    /// The mover's lowest vertex above the floor's top after the last step (m; negative below).
    final_clearance: f32,
}

fn measure_run(scene: CompareScene, speed: f32, touch: bool) -> Measured {
    let mut cw = compare_world(scene, speed);
    assert_eq!(cw.world.integration_parameters.max_ccd_substeps, 0);
    let mut pipeline = TouchPipeline::default();
    let floor_top = cw.world.colliders[cw.floor].compute_aabb().maxs.y;
    let mut m = Measured {
        through: false,
        deepest: 0.0,
        final_clearance: 0.0,
    };
    for _ in 0..STEPS {
        if touch {
            pipeline.step(&mut cw.world);
        } else {
            cw.world.step();
        }
        let w = &cw.world;
        let mover = &w.colliders[cw.mover_collider];
        let lowest = |c: &Collider| {
            world_vertices(c)
                .iter()
                .map(|p| p.y)
                .fold(f32::MAX, f32::min)
        };
        let (depth, through) = match cw.plate {
            Some((_, plate_handle)) => {
                let plate = &w.colliders[plate_handle];
                let into_plate = parry3d::query::contact(
                    plate.position(),
                    plate.shape(),
                    mover.position(),
                    mover.shape(),
                    0.0,
                )
                .unwrap()
                .map_or(0.0, |c| (-c.dist).max(0.0));
                // Cross-check: the box's corners below the plate's top face, in its frame (the
                // box lands near the plate's middle, far from its edges).
                let top = plate.shape().as_cuboid().unwrap().half_extents.y;
                let corners = world_vertices(mover)
                    .iter()
                    .map(|&p| top - plate.position().inverse_transform_point(p).y)
                    .fold(0.0f32, f32::max);
                let centre_in_plate = plate
                    .position()
                    .inverse_transform_point(mover.translation())
                    .y;
                if centre_in_plate >= 0.0 {
                    // (parry's f32 query and the corners agree to 10 µm on a tilted box.)
                    assert!(
                        (into_plate - corners).abs() <= 5e-5,
                        "contact query {into_plate} vs corners {corners}"
                    );
                }
                let into_floor = (floor_top - lowest(plate)).max(0.0);
                (
                    into_plate.max(into_floor),
                    centre_in_plate < 0.0 || plate.translation().y < floor_top,
                )
            }
            None => (
                (floor_top - lowest(mover)).max(0.0),
                mover.translation().y < floor_top,
            ),
        };
        m.through |= through;
        if !m.through {
            m.deepest = m.deepest.max(depth);
        }
        m.final_clearance = lowest(mover) - floor_top;
    }
    m
}

/// The bound the touch side must keep in `scene`: 1 mm, and 2 % of the box at 1/100 scale.
fn bound(scene: CompareScene) -> f32 {
    match scene {
        CompareScene::SmallScale => 0.02 * 0.5 * scene.scale(),
        _ => 1e-3,
    }
}

#[test]
fn touch_keeps_every_compare_scene_within_a_millimetre_and_rapier_alone_does_not() {
    let mut failures = Vec::new();
    let mut rapier_worse = Vec::new();
    for scene in CompareScene::ALL {
        let speed = scene.speeds()[2];
        let touch = measure_run(scene, speed, true);
        if touch.through || touch.deepest > bound(scene) || touch.final_clearance < -bound(scene) {
            failures.push(format!("{} at {speed} m/s: {touch:?}", scene.name()));
        }
        // The example reports what is measured here.
        let run = run_compare_side(scene, speed, DropSide::Touch, STEPS);
        assert_eq!(run.tunneled(), touch.through, "{}", scene.name());
        assert!(
            (run.max_penetration - touch.deepest).abs() <= 1e-6,
            "{}: example {} vs measured {}",
            scene.name(),
            run.max_penetration,
            touch.deepest
        );
        let rapier = measure_run(scene, speed, false);
        if rapier.through || rapier.deepest > bound(scene) {
            rapier_worse.push(format!("{} at {speed} m/s: {rapier:?}", scene.name()));
        }
    }
    assert!(
        failures.is_empty(),
        "touch side failed:\n{}",
        failures.join("\n")
    );
    assert!(
        !rapier_worse.is_empty(),
        "rapier alone (CCD off) kept every scene within the bound: the check cannot fail"
    );
}

/// The non-convex TriMesh mover is a dynamic body with the mass of its closed mesh: the ∩
/// prism's volume, (0.6 × 0.5 − 0.3 × 0.3) × 0.3 = 0.063 m³, at density 1.
#[test]
fn trimesh_mover_has_the_mass_of_its_volume() {
    let cw = compare_world(CompareScene::TrimeshMover, 100.0);
    let body = &cw.world.bodies[cw.mover];
    assert!(body.is_dynamic());
    assert!((body.mass() - 0.063).abs() <= 1e-4, "mass {}", body.mass());
    assert!(matches!(
        cw.world.colliders[cw.mover_collider]
            .shape()
            .as_typed_shape(),
        TypedShape::TriMesh(_)
    ));
}

/// At 1/100 scale every side runs with rapier's `length_unit` at the scale, and gravity scaled.
#[test]
fn small_scale_sets_length_unit_and_scales_gravity() {
    let cw = compare_world(CompareScene::SmallScale, 1.0);
    assert_eq!(cw.world.integration_parameters.length_unit, 0.01);
    assert!((cw.world.gravity.y + 9.81 * 0.01).abs() <= 1e-6);
    let full = compare_world(CompareScene::Spinning, 1.0);
    assert_eq!(full.world.integration_parameters.length_unit, 1.0);
}
