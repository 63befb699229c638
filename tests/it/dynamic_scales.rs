//! A dynamic ball dropped on a soft plate at every scale from 0.1 mm to 10 km: with lengths
//! scaled by `s`, gravity by `s`, masses by `s³` and stiffnesses by `s³` (so that the sag under
//! the ball's weight scales with `s` too), the scene is the same at every scale in units of
//! `s` and seconds. So the ball must land, sink and rest at the same place in those units at
//! every scale (dimensional analysis is the reference: the 1 m run), and at each scale create
//! no energy and be carried by the plate. rapier's `length_unit` is set to `s`, as its docs ask
//! (its sleep thresholds are in it).

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim};

/// What the drop at scale `s` did, in units of `s`.
#[derive(Debug)]
struct Scaled {
    impact: f32,
    rebound: f32,
    /// The ball centre's lowest height.
    lowest: f32,
    /// Its height at the end.
    end: f32,
    /// The plate's mean force on it over the last second, relative to its weight.
    support: f32,
}

/// What is dropped.
#[derive(Copy, Clone, Debug)]
enum Body {
    /// A ball of radius 0.08 s.
    Ball,
    /// A cube of half-side 0.08 s, landing flat.
    Cube,
    /// A U of triangles, legs down: 0.16 s wide and 0.1 s tall, legs 0.04 s wide, extruded
    /// 0.16 s (`common::u_collider`, the U of `dynamic_drops`).
    U,
    /// A compound: two balls of radius 0.05 s, 0.16 s apart, on a bar 0.02 s square.
    Dumbbell,
    /// A cylinder of radius 0.08 s, 0.08 s tall, landing on its flat end.
    Cylinder,
}

/// A plate of side `s` (16 × 16 cells, rim pinned, 0.5 s³ kg, edges of 100 s³ N/m with
/// dampers of `√(k m)`), a ball of radius 0.08 s and 0.1 s³ kg dropped from 0.3 s above it,
/// 10 s.
fn drop(s: f32, substeps: u32) -> Scaled {
    drop_body(Body::Ball, s, substeps)
}

/// [`drop`] with `body` (0.1 s³ kg; its centre 0.38 s above the plate).
fn drop_body(body_kind: Body, s: f32, substeps: u32) -> Scaled {
    let (mass, k) = (0.1 * s * s * s, 100.0 * s * s * s);
    let mut world = PhysicsWorld::default();
    world.gravity *= s;
    world.integration_parameters.length_unit = s;
    let fixed = world.insert_body(RigidBodyBuilder::fixed());
    let surface = MassSpringSurfaceBuilder::from_mesh(&plate(s, s, 16, 16))
        .stiffness(k)
        .damping((k * mass).sqrt())
        .mass(MassDistribution::Total(0.5 * s * s * s))
        .pinned(plate_rim(16, 16))
        .build()
        .unwrap();
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps,
        collider: true,
    };
    set.insert(surface, fixed, &mut world, options).unwrap();
    let r = 0.08 * s;
    let body = world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(
        0.01 * s,
        0.3 * s + r,
        0.0,
    )));
    let (shape, volume) = match body_kind {
        Body::Ball => (
            ColliderBuilder::ball(r),
            4.0 / 3.0 * std::f32::consts::PI * r * r * r,
        ),
        Body::Cube => (ColliderBuilder::cuboid(r, r, r), 8.0 * r * r * r),
        Body::U => crate::common::u_collider(r),
        Body::Dumbbell => {
            let rb = 0.625 * r;
            let parts = vec![
                (Pose::translation(-r, 0.0, 0.0), SharedShape::ball(rb)),
                (Pose::translation(r, 0.0, 0.0), SharedShape::ball(rb)),
                (Pose::IDENTITY, SharedShape::cuboid(r, 0.125 * r, 0.125 * r)),
            ];
            let volume = 2.0 * 4.0 / 3.0 * std::f32::consts::PI * rb * rb * rb;
            (ColliderBuilder::compound(parts), volume)
        }
        Body::Cylinder => (
            ColliderBuilder::cylinder(0.5 * r, r),
            std::f32::consts::PI * r * r * r,
        ),
    };
    let ball = world.insert_collider(shape.density(mass / volume), Some(body));
    set.add_tool(ball, &mut world).unwrap();
    let weight = world.bodies[body].mass() * world.gravity.length();
    let mut out = Scaled {
        impact: 0.0,
        rebound: 0.0,
        lowest: f32::MAX,
        end: 0.0,
        support: 0.0,
    };
    let mut touching = false;
    for step in 0..600 {
        let before = world.bodies[body].linvel().y;
        set.step(&mut world);
        let reaction = set.tool_reaction(ball).unwrap();
        let now = reaction.pressed_points + reaction.held_vertices > 0;
        if now && out.impact == 0.0 {
            out.impact = -before / s;
        }
        if touching && !now {
            out.rebound = out.rebound.max(world.bodies[body].linvel().y / s);
        }
        touching = now;
        let y = world.bodies[body].translation().y / s;
        out.lowest = out.lowest.min(y);
        if step >= 540 {
            out.support += reaction.mean_force.y / (60.0 * weight);
        }
    }
    out.end = world.bodies[body].translation().y / s;
    out
}

#[test]
fn a_ball_drops_onto_a_plate_alike_at_every_scale() {
    for substeps in [1, 17] {
        let reference = drop(1.0, substeps);
        for s in [1e-4, 1e-2, 1e2, 1e4] {
            let d = drop(s, substeps);
            let case = format!("{s} m, {substeps} substeps: {d:?} against {reference:?}");
            assert!(d.impact > 0.0 && d.rebound <= d.impact, "{case}");
            assert!((d.support - 1.0).abs() <= 0.02, "{case}");
            // The same landing, in units of the scale (a hundredth of the ball's radius).
            assert!((d.lowest - reference.lowest).abs() <= 8e-4, "{case}");
            assert!((d.end - reference.end).abs() <= 8e-4, "{case}");
        }
    }
}

/// A cube landing flat, a U of triangles landing on its legs, a dumbbell (a compound) and a
/// cylinder on its end, as the ball above: the same landing in units of the scale at 0.1 mm,
/// 1 cm, 100 m and 10 km as at 1 m, carried, and no rebound faster than the impact. (A cube
/// 16 µm across went through the plate, and a U 1.6 mm across at 17 substeps, while parry's
/// contact with the plate's triangles was asked at the tool's own size: its GJK's absolute
/// tolerance is then many times the contact margin.)
#[test]
fn cubes_us_dumbbells_and_cylinders_drop_onto_a_plate_alike_at_every_scale() {
    for body in [Body::Cube, Body::U, Body::Dumbbell, Body::Cylinder] {
        for substeps in [1, 17] {
            let reference = drop_body(body, 1.0, substeps);
            for s in [1e-4, 1e-2, 1e2, 1e4] {
                let d = drop_body(body, s, substeps);
                let case =
                    format!("{body:?}, {s} m, {substeps} substeps: {d:?} against {reference:?}");
                assert!(d.impact > 0.0 && d.rebound <= d.impact, "{case}");
                assert!((d.support - 1.0).abs() <= 0.02, "{case}");
                assert!((d.lowest - reference.lowest).abs() <= 8e-4, "{case}");
                assert!((d.end - reference.end).abs() <= 8e-4, "{case}");
            }
        }
    }
}
