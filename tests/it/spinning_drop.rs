//! Spinning bodies do not sink in (issue 11): boxes and a non-convex TriMesh body spinning at up
//! to 30 rad/s, dropped at up to 50 m/s onto a fixed cuboid and onto a zero-thickness TriMesh
//! floor (100 m wide: a spinning box that lands can roll far), in a real rapier pipeline (dt = 1/60, rapier's CCD off), through the touch pipeline
//! in both opt-in modes. After every step no vertex of the body is more than 1 mm below the
//! floor's top (measured from the body's pose, independently of the crate), and the body never
//! goes through.

use rapier_touch::geometry::generators::extruded_polygon;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

#[derive(Copy, Clone, Debug)]
enum Floor {
    Cuboid,
    ThinTriMesh,
}

#[derive(Copy, Clone, Debug)]
enum Mover {
    Box,
    LPrism,
    /// Curved shapes with corners or rims (their touch meshes are tessellations).
    Cone,
    RoundCylinder,
    RoundHull,
}

fn l_prism() -> (Vec<Vector>, Vec<[u32; 3]>) {
    let (v, i) = extruded_polygon(
        &[
            [0.0, 0.0],
            [0.5, 0.0],
            [0.5, 0.2],
            [0.2, 0.2],
            [0.2, 0.5],
            [0.0, 0.5],
        ],
        0.3,
    )
    .unwrap();
    // Centre it roughly on its bounding box.
    let c = Vector::new(0.25, 0.25, 0.15);
    (v.into_iter().map(|p| p - c).collect(), i)
}

/// The zero-thickness floor: two triangles 100 m wide in the plane `y = 0`, facing up.
fn thin_trimesh_floor() -> ColliderBuilder {
    ColliderBuilder::trimesh(
        vec![
            Vector::new(-50.0, 0.0, -50.0),
            Vector::new(50.0, 0.0, -50.0),
            Vector::new(50.0, 0.0, 50.0),
            Vector::new(-50.0, 0.0, 50.0),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
    )
    .unwrap()
}

/// Drops `mover` (of the given density) from 2 m with vertical speed `speed` and angular
/// velocity `spin`; returns the deepest any vertex went below `y = 0` after a step, or `None` if
/// it went through.
fn drop(
    floor: Floor,
    mover: Mover,
    speed: f32,
    spin: Vector,
    hook_flags: bool,
    density: f32,
) -> Option<f32> {
    let mut w = PhysicsWorld::default();
    w.integration_parameters.max_ccd_substeps = 0; // rapier's CCD off: the guard alone
    TouchPipeline::configure(&mut w.integration_parameters);
    let flags = if hook_flags {
        ActiveHooks::MODIFY_SOLVER_CONTACTS
    } else {
        ActiveHooks::empty()
    };
    let floor = match floor {
        Floor::Cuboid => {
            ColliderBuilder::cuboid(50.0, 0.5, 50.0).translation(Vector::new(0.0, -0.5, 0.0))
        }
        Floor::ThinTriMesh => thin_trimesh_floor(),
    };
    let fh = w.insert_collider(floor.active_hooks(flags), None);
    let body = w.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.1, 2.0, -0.2))
            .linvel(Vector::new(0.5, -speed, 0.0))
            .angvel(spin),
    );
    let (verts, collider) = match mover {
        Mover::Box => {
            let shape = parry3d::shape::Cuboid::new(Vector::splat(0.25));
            let mesh = TouchMesh::from_shape(&shape).unwrap();
            (
                mesh.vertices().to_vec(),
                ColliderBuilder::cuboid(0.25, 0.25, 0.25),
            )
        }
        Mover::LPrism => {
            let (v, i) = l_prism();
            (v.clone(), ColliderBuilder::trimesh(v, i).unwrap())
        }
        Mover::Cone => (Vec::new(), ColliderBuilder::cone(0.25, 0.25)),
        Mover::RoundCylinder => (Vec::new(), ColliderBuilder::round_cylinder(0.2, 0.25, 0.05)),
        Mover::RoundHull => {
            let corners: Vec<Vector> = (0..8)
                .map(|c| {
                    let s = |bit: u32, h: f32| if c & bit == 0 { -h } else { h };
                    Vector::new(s(1, 0.2), s(2, 0.15), s(4, 0.1))
                })
                .collect();
            (
                Vec::new(),
                ColliderBuilder::round_convex_hull(&corners, 0.05).unwrap(),
            )
        }
    };
    let ch = w.insert_collider(collider.active_hooks(flags).density(density), Some(body));
    let mut touch = TouchPipeline::default();
    if !hook_flags {
        touch.track_collider(fh);
        touch.track_collider(ch);
    }
    let mut deepest = 0.0f32;
    for _ in 0..60 {
        touch.step(&mut w);
        let body_pose = *w.bodies[body].position();
        if body_pose.translation.y < -0.05 {
            return None;
        }
        // A polyhedron's lowest vertex; a curved shape's support point straight down.
        let lowest = if verts.is_empty() {
            let co = &w.colliders[ch];
            co.shape()
                .as_support_map()
                .expect("the curved movers are support maps")
                .support_point(co.position(), -Vector::Y)
                .y
        } else {
            verts
                .iter()
                .map(|&v| body_pose.transform_point(v).y)
                .fold(f32::MAX, f32::min)
        };
        deepest = deepest.max(-lowest);
    }
    Some(deepest)
}

#[test]
fn spinning_bodies_stay_within_a_millimetre_of_the_floor() {
    let mut worst = 0.0f32;
    let mut failures = Vec::new();
    for floor in [Floor::Cuboid, Floor::ThinTriMesh] {
        for mover in [Mover::Box, Mover::LPrism] {
            for speed in [5.0, 20.0, 50.0] {
                for spin in [
                    Vector::ZERO,
                    Vector::new(10.0, 0.0, 0.0),
                    Vector::new(0.0, 0.0, 30.0),
                    Vector::new(17.0, 17.0, 17.0), // |ω| = 29.4 rad/s about a diagonal
                ] {
                    for hook_flags in [false, true] {
                        let r = drop(floor, mover, speed, spin, hook_flags, 1.0);
                        match r {
                            Some(d) => {
                                worst = worst.max(d);
                                if d > 1e-3 {
                                    failures.push(format!(
                                        "{floor:?} {mover:?} {speed} m/s spin {spin} hooks {hook_flags}: {d} m"
                                    ));
                                }
                            }
                            None => failures.push(format!(
                                "{floor:?} {mover:?} {speed} m/s spin {spin} hooks {hook_flags}: went through"
                            )),
                        }
                    }
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "worst {worst} m:\n{}",
        failures.join("\n")
    );
}

/// The same bound for light and heavy bodies: the box at 1 g (density 0.008) and at 1 t
/// (density 8000), the L prism likewise, spinning at 29.4 rad/s and falling at 50 m/s.
#[test]
fn light_and_heavy_spinning_bodies_stay_within_a_millimetre() {
    let spin = Vector::new(17.0, 17.0, 17.0);
    for density in [0.008, 8000.0] {
        for floor in [Floor::Cuboid, Floor::ThinTriMesh] {
            for mover in [Mover::Box, Mover::LPrism] {
                for hook_flags in [false, true] {
                    let d = drop(floor, mover, 50.0, spin, hook_flags, density);
                    assert!(
                        d.is_some_and(|d| d <= 1e-3),
                        "{floor:?} {mover:?} density {density} hooks {hook_flags}: {d:?}"
                    );
                }
            }
        }
    }
}

/// Curved bodies with corners or rims (a cone, a rounded cylinder, a rounded hull), whose
/// touch meshes are tessellations, do not yet meet the millimetre: rapier's contact points on
/// them were trusted however far the body moved, and a turning cone or rounded hull brought in
/// a corner they did not hold (139 mm and 36 mm into the floors of rapier's CCD and
/// convex-hull stress scenes; here a cone 38 mm, a rounded cylinder 3.5 mm). No longer
/// trusted, the worst measured is a cone's 9.4 mm (rounded cylinder 1.5 mm, rounded hull
/// 1.4 mm; README, "Documented behaviours"). This holds them to a centimetre and never
/// through, and says by how much the millimetre is missed.
#[test]
fn spinning_cones_and_rounded_bodies_stay_within_a_centimetre_of_the_floor() {
    let mut failures = Vec::new();
    let mut worst: Vec<String> = Vec::new();
    for floor in [Floor::Cuboid, Floor::ThinTriMesh] {
        for mover in [Mover::Cone, Mover::RoundCylinder, Mover::RoundHull] {
            for speed in [5.0, 50.0] {
                for spin in [Vector::new(0.0, 0.0, 30.0), Vector::new(17.0, 17.0, 17.0)] {
                    for hook_flags in [false, true] {
                        let r = drop(floor, mover, speed, spin, hook_flags, 1.0);
                        let case = format!(
                            "{floor:?} {mover:?} {speed} m/s spin {spin} hooks {hook_flags}: {r:?}"
                        );
                        match r {
                            Some(d) if d <= 1e-2 => {
                                if d > 1e-3 {
                                    worst.push(case);
                                }
                            }
                            _ => failures.push(case),
                        }
                    }
                }
            }
        }
    }
    println!("past a millimetre:\n{}", worst.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A recorded state (from the L prism's 20 m/s drop spinning at 10 rad/s onto the TriMesh
/// floor, under a change of the rotating path's search): the prism rocks on the floor, its
/// lowest corner 8 µm above it, turning at 0.75 rad/s. rapier's contact points hold the corner
/// that touches; over the step the turn brings another corner down, which the guard, reading
/// rapier's points alone, left 1.12 mm in. Stepped from that state in both opt-in modes, the
/// prism's lowest vertex (from the body's pose, the prism's geometry written here) stays
/// within a millimetre of the floor.
#[test]
fn a_corner_a_rocking_trimesh_turns_down_is_pushed_back() {
    for hook_flags in [false, true] {
        let mut w = PhysicsWorld::default();
        w.integration_parameters.max_ccd_substeps = 0;
        TouchPipeline::configure(&mut w.integration_parameters);
        let flags = if hook_flags {
            ActiveHooks::MODIFY_SOLVER_CONTACTS
        } else {
            ActiveHooks::empty()
        };
        let fh = w.insert_collider(thin_trimesh_floor().active_hooks(flags), None);
        let body = w.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(Pose::from_parts(
                    Vector::new(0.17249814, 0.07090442, -0.32911396),
                    Rotation::from_xyzw(0.7899536, -0.020596169, -0.21339852, 0.5744652),
                ))
                .linvel(Vector::new(0.22525255, -0.07275607, 0.08333039))
                .angvel(Vector::new(-0.34821132, 0.028314624, -0.6591081)),
        );
        let (v, i) = l_prism();
        let ch = w.insert_collider(
            ColliderBuilder::trimesh(v.clone(), i)
                .unwrap()
                .active_hooks(flags),
            Some(body),
        );
        let mut touch = TouchPipeline::default();
        if !hook_flags {
            touch.track_collider(fh);
            touch.track_collider(ch);
        }
        let lowest = |w: &PhysicsWorld| {
            let p = w.bodies[body].position();
            v.iter()
                .map(|&q| p.transform_point(q).y)
                .fold(f32::MAX, f32::min)
        };
        assert!(lowest(&w) > 0.0, "the recorded state starts apart");
        for step in 0..5 {
            touch.step(&mut w);
            let low = lowest(&w);
            assert!(
                low >= -1e-3,
                "hooks {hook_flags}, step {step}: lowest vertex {low} m"
            );
        }
    }
}
