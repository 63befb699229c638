//! A flat-bottomed tool pressed deep into a pinned plate and dragged slowly sideways (issue 13):
//! the plate's vertices that lie on the tool's bottom face, touching it without being pushed,
//! are grazed along the face. Checked against what a slow, frictionless drag must give: the
//! reaction stays near the resting press (quasi-static: the plate's shape travels with the
//! tool). Before the fix a vertex on the face, "inside" by a rounding error, was walked back
//! along its relative motion to the tool's far side: a 43 cm cube 14 cm deep in a 400 N/m
//! plate met 2 kN at the first step of the drag against a 436 N press. Property test over
//! scale (plates of 0.3 mm-300 m, tools of 30 µm-30 m: at a 0.23 mm plate the hull tool met
//! 2.4 times its resting press, past this bound; not yet understood), stiffness
//! (10-1000 N/m), mass (10 g-100 kg), substeps, drag direction
//! and tool: a box, a cylinder, and the same box as a convex hull (parry's `ConvexPolyhedron`,
//! whose point queries take another path).

use crate::common::{cube_hull, plate_scene};
use proptest::prelude::*;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

/// What one drag saw.
struct Drag {
    /// The reaction's length at the end of the rest before the drag (N).
    resting: f32,
    /// Its spread over the last quarter second of the rest (N).
    settling: f32,
    /// Its largest length during the drag (N).
    dragging: f32,
}

/// A plate `0.3 · scale` wide (24 cells, rim pinned, edges of `k`, `mass` in all) on a fixed
/// body; a tool of `half`-size `0.03 · scale` pressed `depth` of its half-size in over a
/// second, held a second, dragged one half-size along `direction` over a second.
fn drag(scale: f32, k: f32, mass: f32, substeps: u32, shape: u8, direction: f32) -> Drag {
    let size = 0.3 * scale;
    let half = 0.03 * scale;
    let shape = match shape {
        0 => SharedShape::cuboid(half, half, half),
        1 => SharedShape::cylinder(half, half),
        _ => cube_hull(half),
    };
    let (mut world, mut set, tool, _) = plate_scene(size, 24, k, mass, substeps, shape);
    let body = world.colliders[tool].parent().unwrap();
    set.add_tool(tool, &mut world).unwrap();
    let depth = 0.6 * half;
    let along = Vector::new(direction.cos(), 0.0, direction.sin()) * half;
    let path = |t: f32| {
        let top = half + 0.2 * half;
        let down = t.min(1.0);
        let slide = (t - 2.0).clamp(0.0, 1.0);
        Vector::new(0.0, top - (top + depth - half) * down, 0.0) + along * slide
    };
    let dt = world.integration_parameters.dt;
    let mut run = Drag {
        resting: 0.0,
        settling: 0.0,
        dragging: 0.0,
    };
    let (mut low, mut high) = (f32::MAX, 0.0f32);
    for s in 0..(3.0 / dt).round() as usize {
        let t = (s + 1) as f32 * dt;
        world.bodies[body].set_next_kinematic_translation(path(t));
        set.step(&mut world);
        let f = set.tool_reaction(tool).unwrap().force;
        assert!(f.is_finite(), "reaction {f:?} at t {t}");
        if t <= 2.0 {
            run.resting = f.length();
            if t > 1.75 {
                (low, high) = (low.min(run.resting), high.max(run.resting));
                run.settling = high - low;
            }
        } else {
            run.dragging = run.dragging.max(f.length());
        }
    }
    run
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn a_tool_dragged_over_the_plate_it_rests_in_meets_no_spike(
        scale_exp in -3.0f32..3.0,
        k_exp in 1.0f32..3.0,
        mass_exp in -2.0f32..2.0,
        substeps in prop::sample::select(vec![1u32, 4]),
        shape in 0u8..3,
        direction in 0.0f32..std::f32::consts::TAU,
    ) {
        let scale = 10f32.powf(scale_exp);
        let r = drag(scale, 10f32.powf(k_exp), 10f32.powf(mass_exp), substeps, shape, direction);
        prop_assert!(r.resting > 0.0, "the tool does not press the plate");
        // Quasi-static drags only: a heavy plate on soft springs still swinging after the
        // rest has no resting press to compare with.
        prop_assume!(r.settling <= 0.01 * r.resting);
        // Slow and frictionless: the press travels with the tool. The leading edge piles the
        // plate up, and on small soft plates with one substep vertices there are caught and let
        // go on alternate steps (a force that swings by a third from one step to the next):
        // measured over 4 seeds of this test, up to 1.27 times the resting press for the box,
        // 1.15 for the cylinder, 1.41 for the box's hull (1.41, 1.21 and 1.74 before the face's
        // points beside a vertex it holds were pressed, and 2.07 for the hull when those
        // presses reported the held vertex's share of their impulses too). A vertex thrown
        // across the tool gave 4.3-4.8 times it.
        prop_assert!(
            r.dragging <= 2.0 * r.resting,
            "{scale} m: {} N while dragging, {} N at rest",
            r.dragging,
            r.resting
        );
    }
}
