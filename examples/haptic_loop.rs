//! A haptic loop: one ball tool driven along a device trajectory at the surface's rate
//! (1020 Hz: a 60 Hz scene with 17 surface substeps) presses (with a tremor) into a 784-node
//! plate pinned on its rim, then lifts off, through `SurfaceSet::haptic_step` (tool contact, surface step and tool
//! force; no rigid step, no collider update). Prints the force every 0.5 s, then the achieved
//! update rate (wall clock, information only) and the largest jump in force between two
//! consecutive updates; the last line reads `rate_hz=<achieved> max_force_jump_n=<largest>`.
//!
//! Run with `cargo run --release --example haptic_loop`.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::scenes::attach_fixed;
use rapier_touch::surface::meshing::{plate, plate_rim};
use std::time::Instant;

fn main() {
    let mut world = PhysicsWorld::default();
    let side = 27; // 28 x 28 = 784 nodes on a 0.3 m square
    let surface = MassSpringSurfaceBuilder::from_mesh(&plate(0.3, 0.3, side, side))
        .stiffness(30.0)
        .damping(0.05)
        .mass(MassDistribution::Total(0.2))
        .pinned(plate_rim(side, side))
        .integrator(Integrator::NEIGHBOUR)
        .build()
        .expect("valid plate");
    let (mut set, h, _) = attach_fixed(&mut world, surface, 17);
    let rate = 60.0 * 17.0;
    let tool_body = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.05, 0.05, 0.0)),
    );
    let tool = world.insert_collider(ColliderBuilder::ball(0.03), Some(tool_body));
    set.add_tool(tool, &mut world).unwrap();
    println!(
        "plate: {} nodes, neighbour filter, s max {:.3}, surface dt {:.3} ms",
        set.get(h).unwrap().surface.num_vertices(),
        set.get(h)
            .unwrap()
            .surface
            .s_values()
            .iter()
            .cloned()
            .fold(0.0, f32::max),
        set.get(h).unwrap().surface.dt() * 1e3
    );

    // The device: comes down, presses up to 8 mm with a 2 Hz tremor of 1 mm, lifts off.
    let device = |t: f32| -> Pose {
        let envelope = (t / 1.0).clamp(0.0, 1.0) * ((4.5 - t) / 0.5).clamp(0.0, 1.0);
        let tremor = 0.001 * (2.0 * std::f32::consts::TAU * t).sin();
        let depth = envelope * (0.007 + tremor);
        Pose::from_translation(Vector::new(0.03, 0.03 - depth, 0.02))
    };
    let steps = (5.0 * rate) as usize;
    let mut last = Vector::ZERO;
    let (mut max_jump, mut max_force) = (0.0f32, 0.0f32);
    let start = Instant::now();
    for k in 0..steps {
        let t = k as f32 / rate;
        let r = set
            .haptic_step(&world, tool, device(t))
            .expect("tool present");
        assert!(r.force.is_finite());
        max_jump = max_jump.max((r.force - last).length());
        max_force = max_force.max(r.force.length());
        last = r.force;
        if k % (rate as usize / 2) == 0 {
            println!(
                "t = {t:.2} s: force [{:.4}, {:.4}, {:.4}] N on {} vertices",
                r.force.x, r.force.y, r.force.z, r.held_vertices
            );
        }
    }
    let elapsed = start.elapsed().as_secs_f64();
    let achieved = steps as f64 / elapsed;
    assert!(max_force > 0.01, "the tool pressed the plate");
    assert!(last.length() < 1e-6, "lifted off: no force left");
    // Vertices stay in contact while the tool turns back (they are released only when their
    // springs pull them off the tool), so the force is continuous: steps of the tremor's
    // slope, not whole vertices' worth of force.
    assert!(
        max_jump < 0.1 * max_force,
        "force jumps {max_jump} N of {max_force} N"
    );
    println!(
        "max force {max_force:.4} N; largest jump {:.1} % of it",
        100.0 * max_jump / max_force
    );
    println!("rate_hz={achieved:.0} max_force_jump_n={max_jump:.5}");
}
