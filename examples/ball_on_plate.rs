//! A dynamic ball dropped on a soft plate, two-way coupled: the plate's force is all that stops
//! it.
//!
//! The scene is the library's `rapier_touch::scenes::BallOnPlateScene` (also drawn by the
//! `frames` example); this example steps it, prints it and checks it.
//!
//! **Scene.** `plate(0.3, 0.3, 15, 15)`: 256 nodes 20 mm apart at y = 0, its 60 rim vertices
//! pinned, attached to a fixed body with `SurfaceSet::insert`. The paper's linear springs,
//! k = 30 N/m and c = 1 N·s/m per edge, 0.05 kg spread evenly, the exact filter, 17 substeps
//! (the surface at 1020 Hz: at the 1.2 m/s impact the ball moves 1.2 mm per substep, so the
//! vertices it meets are walked back over short motions). The plate's own weight is left out,
//! so its pins carry the ball alone. A rapier dynamic ball, r = 30 mm and 0.1 kg, registered
//! with `SurfaceSet::add_tool`, is released at rest with its centre 100 mm above the plate
//! (4 mm and 3 mm off its centre) under gravity (9.81 m/s², 60 Hz rigid steps). The ball is a
//! rigid holder of the plate's constraint solve: its mass meets the plate's in each substep
//! (implicit coupling), which is the only thing that stops it (the ball's solver groups leave
//! the plate's collider out).
//!
//! **Printed** every 3 steps up to 1.2 s, then every 0.5 s: the time, the ball centre's height
//! (mm), its vertical velocity, the points it presses, the surface's force on it
//! (`ToolReaction::mean_force`, N, vertical) and the plate's largest displacement (mm). Then the
//! bounces and their apex heights, the least height of the ball centre above the lowest plate
//! vertex, the resting state, the forces at rest and a closing `summary:` line.
//!
//! What happens: the ball hits at 1.15 m/s, dents the plate 19 mm, rides the plate back up
//! without leaving it and is at rest 0.5 s after the drop in the middle of a cell, (10, -10) mm
//! off the plate's centre, 9.2 mm deep, with the surface force equal to its weight to 0.01 %.
//!
//! **Checks** (asserts): the ball, its force and the plate stay finite; the ball never goes
//! through the plate (straight above its centre there is no plate, and its centre stays above
//! the lowest plate vertex by at least 0.95 r: the ball presses the triangles' faces and edges
//! as well as their vertices, so it does not sink between the vertices of a cell; measured:
//! 30.75 mm); it leaves the plate no faster than it hit it (no energy created); it comes to
//! rest (speed below 1 mm/s, height within 0.1 mm over the last second); at rest the surface
//! force on it is its weight within 5 % (also averaged over the last second), and so is the
//! pins' reaction.
//!
//! **Other plates.** Until the ball's mass entered the plate's solve, its force reached it a
//! rigid step late, and the plates around this one blew up: the ball gained energy at every
//! bounce (k = 60 N/m, c = 1 N·s/m: 9 bounces, then off the edge) or went through (k = 100
//! with c = 1; k = 30 with c = 0.3, or 0.5 from 150 mm). Each of those now settles, the ball
//! leaving the plate slower than it hit it (k = 100, c = 1: 1.15 m/s in, 0.16 out; k = 30,
//! c = 0.3: 0.44 out; from 150 mm with c = 0.5: 1.47 in, 0.39 out), its centre never closer
//! than 30 mm to the lowest vertex, the ball and plate's energy rising by at most 2e-5 J over
//! 10 s (out of 0.1 J).
//!
//! Run with `cargo run --release --example ball_on_plate`.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::scenes::BallOnPlateScene;

type Scene = BallOnPlateScene;
const RADIUS: Real = Scene::RADIUS;

fn main() {
    let mut scene = Scene::new();
    let mass = scene.ball_mass();
    let weight = scene.weight();
    println!(
        "plate {size} x {size} m, {} nodes ({} on the rim pinned), k = {} N/m, c = {} N*s/m \
         per edge, {} kg, exact filter, {} substeps; ball r = {} mm, {mass:.3} kg (weight \
         {weight:.4} N), dropped from y = {} mm",
        scene.mesh.num_vertices(),
        scene.rim.len(),
        Scene::K,
        Scene::C,
        Scene::PLATE_MASS,
        Scene::SUBSTEPS,
        RADIUS * 1e3,
        Scene::START.y * 1e3,
        size = Scene::SIZE,
    );
    println!(
        "{:>6} {:>8} {:>8} {:>5} {:>8} {:>8}",
        "t s", "y mm", "vy m/s", "press", "Fy N", "disp mm"
    );

    let steps = Scene::total_steps();
    let mut positions = Vec::new();
    let mut lowest_gap = Real::MAX;
    let mut touched = false;
    let mut flight: Option<(Real, Real)> = None;
    let mut bounces: Vec<Real> = Vec::new();
    // The ball's downward speed when it first touched, and its fastest upward speed leaving.
    let (mut impact, mut rebound, mut vy_before) = (0.0, 0.0, 0.0);
    let (mut y_lo, mut y_hi, mut support) = (Real::MAX, Real::MIN, 0.0);
    let last_second = (1.0 / Scene::DT).round() as usize;
    for step in 1..=steps {
        scene.step();
        let t = scene.time();
        debug_assert_eq!(t, step as Real * Scene::DT);
        let (p, v) = (scene.ball_position(), scene.ball_velocity());
        let r = scene.reaction();
        let s = scene.surface();
        assert!(p.is_finite() && v.is_finite(), "ball at t = {t}");
        assert!(
            r.force.is_finite() && r.mean_force.is_finite() && r.torque.is_finite(),
            "force at t = {t}: {r:?}"
        );
        assert!(s.is_finite(), "plate at t = {t}");

        // Never through the plate: its centre stays above the lowest plate vertex, and straight
        // above it there is no plate.
        s.positions_into(&mut positions);
        let low = positions.iter().map(|q| q.y).fold(Real::MAX, Real::min);
        lowest_gap = lowest_gap.min(p.y - low);
        let plate = &scene.world.colliders[scene.plate_collider];
        let plate_pose = *plate.position();
        let up = Ray::new(p, Vector::Y);
        assert!(
            plate
                .shape()
                .cast_ray(&plate_pose, &up, 10.0, false)
                .is_none(),
            "the ball is under the plate at t = {t}"
        );

        // Bounces: a flight between two contacts that rises at least 1 mm; its apex.
        let in_contact = r.held_vertices + r.pressed_points > 0;
        if in_contact && !touched {
            impact = -vy_before;
        }
        if touched && !in_contact && flight.is_none() {
            rebound = v.y.max(rebound);
        }
        vy_before = v.y;
        if in_contact {
            if let Some((exit, top)) = flight.take() {
                if top > exit + 1e-3 {
                    bounces.push(top);
                }
            }
            touched = true;
        } else if touched {
            let f = flight.get_or_insert((p.y, p.y));
            f.1 = f.1.max(p.y);
        }

        if step + last_second > steps {
            y_lo = y_lo.min(p.y);
            y_hi = y_hi.max(p.y);
            support += r.mean_force.y / last_second as Real;
        }
        if (t <= 1.2 && step % 3 == 0) || step % 30 == 0 {
            println!(
                "{t:>6.3} {:>8.2} {:>8.4} {:>5} {:>8.4} {:>8.3}",
                p.y * 1e3,
                v.y,
                r.held_vertices + r.pressed_points,
                r.mean_force.y,
                s.max_displacement() * 1e3
            );
        }
    }
    let (p, v) = (scene.ball_position(), scene.ball_velocity());
    let r = scene.reaction();
    let s = scene.surface();
    let pins = scene.pins_reaction();
    println!();
    println!(
        "bounces: {} (apex heights {:?} mm)",
        bounces.len(),
        bounces
            .iter()
            .map(|y| (y * 1e4).round() / 10.0)
            .collect::<Vec<_>>()
    );
    println!("impact {impact:.3} m/s, fastest off the plate {rebound:.3} m/s");
    println!(
        "lowest ball centre above the lowest plate vertex: {:.2} mm (radius {} mm)",
        lowest_gap * 1e3,
        RADIUS * 1e3
    );
    println!(
        "at rest: y = {:.2} mm (range over the last second {:.4} mm), |v| = {:.1e} m/s, \
         {} points pressed, dent {:.2} mm, ({:.1}, {:.1}) mm off the plate's centre",
        p.y * 1e3,
        (y_hi - y_lo) * 1e3,
        v.length(),
        r.held_vertices + r.pressed_points,
        s.max_displacement() * 1e3,
        p.x * 1e3,
        p.z * 1e3
    );
    println!(
        "surface force on the ball {:.4} N (mean over the last second {support:.4} N), weight \
         {weight:.4} N; pins carry {:.4} N",
        r.mean_force.y, -pins.y
    );
    let error = (r.mean_force.y - weight).abs() / weight;
    println!(
        "summary: bounces={} min_gap_mm={:.2} final_speed_m_s={:.1e} support_n={:.4} \
         weight_n={weight:.4} support_error_pct={:.2}",
        bounces.len(),
        lowest_gap * 1e3,
        v.length(),
        r.mean_force.y,
        100.0 * error
    );

    assert!(impact > 0.0, "the ball never touched");
    assert!(
        rebound <= impact,
        "left at {rebound} m/s after hitting at {impact} m/s"
    );
    assert!(
        lowest_gap > 0.95 * RADIUS,
        "the ball sank {lowest_gap} m onto the lowest vertex"
    );
    assert!(v.length() < 1e-3, "still moving at {v:?}");
    assert!(y_hi - y_lo < 1e-4, "still moving: y in [{y_lo}, {y_hi}]");
    assert!(
        error < 0.05,
        "support {} N vs weight {weight} N",
        r.mean_force.y
    );
    assert!((support - weight).abs() < 0.05 * weight);
    assert!(
        (pins.y + weight).abs() < 0.05 * weight,
        "pins carry {pins:?}"
    );
}
