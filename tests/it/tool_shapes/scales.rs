//! The U pressed corner-first at every scale: the scene of
//! `u_shaped_trimesh_tool_pressed_corner_first_holds_and_gets_the_pins_force` with every length
//! scaled by `s` from 0.1 mm to 100 m (the plate, the U, the press; edge stiffness, damping and
//! masses by `s`, rapier's `length_unit` by `s`), so that the force scales by `s²`: it must be
//! the 1 m scene's force times `s²`, balance the pins, and leave no vertex in the U and no
//! corner of it under the surface, each to the same share of the scale.

use super::*;

/// What the press at scale `s` did: the tool's force over `s²`, the pins' mismatch relative to
/// it, the deepest vertex inside the U and the deepest U corner under the surface (over `s`).
fn pressed_at(s: f32) -> (f32, f32, f32, f32) {
    let (mut world, mut set, surface) = plate_world(s);
    let turn = Rotation::from_rotation_z(0.35) * Rotation::from_rotation_x(0.25);
    let corners: Vec<Vector> = [-0.09, -0.05, 0.05, 0.09]
        .iter()
        .flat_map(|&x| {
            [
                Vector::new(x, 0.0, -0.04) * s,
                Vector::new(x, 0.0, 0.04) * s,
            ]
        })
        .collect();
    let lowest = corners
        .iter()
        .map(|c| (turn * *c).y)
        .fold(f32::MAX, f32::min);
    let above = Vector::new(0.013 * s, 0.05 * s - lowest, -0.021 * s);
    let below = Vector::new(0.013 * s, -DEPTH * s - lowest, -0.021 * s);
    let body = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().pose(Pose::from_parts(above, turn)),
    );
    let tool = world.insert_collider(ColliderBuilder::new(u_shape_scaled(s)), Some(body));
    set.add_tool(tool, &mut world).unwrap();
    let mut under = 0.0f32;
    for step in 0..240 {
        let a = ((step + 1) as f32 / 40.0).min(1.0);
        world.bodies[body].set_next_kinematic_translation(above.lerp(below, a));
        set.step(&mut world);
        let pose = *world.colliders[tool].position();
        let plate = &set.get(surface).unwrap().surface;
        for corner in &corners {
            let p = pose.transform_point(*corner);
            under = under.max(height_under(plate, p.x, p.z) - p.y);
        }
    }
    let r = Pressed {
        world,
        set,
        surface,
        tool,
    };
    let inside = inside_u(&r);
    let plate = &r.set.get(r.surface).unwrap().surface;
    let deepest = (0..plate.num_vertices() as u32)
        .map(|i| inside(plate.position(i)))
        .fold(0.0f32, f32::max);
    let force = r.set.tool_reaction(r.tool).unwrap().force;
    let pins: Vector = plate_rim(CELLS, CELLS)
        .into_iter()
        .map(|i| plate.internal_force(i))
        .sum();
    (
        force.length() / (s * s),
        (force + pins).length() / force.length(),
        deepest / s,
        under / s,
    )
}

#[test]
fn a_u_pressed_corner_first_holds_alike_at_every_scale() {
    let (reference, ..) = pressed_at(1.0);
    assert!(reference > 0.0);
    for s in [1e-4, 1e-2, 1.0, 1e2] {
        let (force, mismatch, deepest, under) = pressed_at(s);
        let case = format!(
            "{s} m: force {force} s² (1 m: {reference}), pins off by {mismatch}, a vertex {deepest} s \
             inside, a corner {under} s under"
        );
        assert!((force - reference).abs() <= 1e-2 * reference, "{case}");
        assert!(mismatch <= 0.05, "{case}");
        assert!(deepest <= 1e-5 && under <= 1e-5, "{case}");
    }
}
