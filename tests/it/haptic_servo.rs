//! The servo loop and its local contact model (issue 14), checked against independent answers:
//! a hovering tool's patch is every vertex near it (brute force); the proxy balances the
//! coupling spring and the model (solved by hand); a vertex held on a ball pushes from its
//! anchor; threads exchanging models while the world steps, refactors and swaps tools never
//! deadlock, tear a model or panic; a device that reads NaN gets no force. The model's
//! agreement with the full solution is in `haptic_agreement.rs`, the energy the rendering
//! gives a hand in `haptic_energy.rs`.

use crate::common::plate_scene;
use rapier_touch::haptics::{
    haptic_link, Servo, ServoLink, ServoModel, SimulatedHand, VirtualCoupling,
};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::math::Matrix;
use rapier_touch::rapier3d::prelude::*;
use std::time::{Duration, Instant};

#[test]
fn the_patch_near_a_hovering_tool_is_every_vertex_near_it() {
    // A ball pressed into a plate and lifted off while the plate swings back: out of contact,
    // each published model's patch (taken from the contact search's BVH) must be exactly the
    // unpinned vertices within one tool size of the tool's box, found here by brute force.
    let (mut world, mut set, tool, soft) =
        plate_scene(0.3, 24, 400.0, 0.05, 4, SharedShape::ball(0.03));
    let (world_end, _servo_end) = haptic_link();
    set.connect_haptic(tool, world_end, &mut world).unwrap();
    let body = world.colliders[tool].parent().unwrap();
    let (mut compared, mut nonempty) = (0, 0);
    for step in 0..120 {
        // Down 2 cm into the plate over half a second, then up to 1-3 cm above it, sideways.
        let t = step as f32 / 60.0;
        let y = if t < 0.5 {
            0.03 - 0.04 * t
        } else {
            0.04 + 0.02 * (t - 0.5)
        };
        let x = 0.04 * (t - 0.5).max(0.0);
        world.bodies[body].set_next_kinematic_translation(Vector::new(x, y, 0.0));
        set.step(&mut world);
        let model = set.haptic_model(tool).unwrap();
        if model.in_contact() {
            continue;
        }
        let co = &world.colliders[tool];
        let aabb = co.compute_aabb();
        let reach = co.shape().compute_local_aabb().half_extents().max_element();
        let (lo, hi) = (
            aabb.mins - Vector::splat(reach),
            aabb.maxs + Vector::splat(reach),
        );
        let surface = &set.get(soft).unwrap().surface;
        // Bitwise, with -0 and +0 as one (the model's positions went through the body's pose).
        let key = |p: Vector| {
            let p = p + Vector::ZERO;
            (p.x.to_bits(), p.y.to_bits(), p.z.to_bits())
        };
        let mut expected: Vec<_> = (0..surface.num_vertices() as u32)
            .filter(|&i| !surface.is_pinned(i))
            .map(|i| surface.position(i))
            .filter(|p| p.cmpge(lo).all() && p.cmple(hi).all())
            .map(key)
            .collect();
        let mut got: Vec<_> = model.patch.iter().map(|v| key(v.position)).collect();
        expected.sort_unstable();
        got.sort_unstable();
        assert_eq!(got, expected, "step {step}");
        compared += 1;
        nonempty += usize::from(!got.is_empty());
    }
    assert!(
        compared > 20 && nonempty > 10,
        "{compared} compared, {nonempty} with vertices"
    );
}

#[test]
fn the_proxy_rests_where_the_coupling_and_the_model_balance() {
    // A contact at the origin pushing 3 N up, stiff 400 N/m along y and 100 N/m along x;
    // the device 2 cm below it and 1 cm aside, a 2 kN/m coupling.
    let model = ServoModel {
        sequence: 1,
        force: Vector::new(0.0, 3.0, 0.0),
        stiffness: Matrix::from_diagonal(Vector::new(100.0, 400.0, 0.0)),
        ..ServoModel::default()
    };
    let device = Vector::new(0.01, -0.02, 0.0);
    let kc = 2000.0;
    let (proxy, f) = model.proxy(device, kc);
    // By hand, per axis: kc (d - p) + f0 - k p = 0, p = (kc d + f0) / (kc + k).
    let expect = Vector::new(
        kc * 0.01 / (kc + 100.0),
        (kc * -0.02 + 3.0) / (kc + 400.0),
        0.0,
    );
    assert!((proxy - expect).length() < 1e-6, "{proxy:?} vs {expect:?}");
    assert!((f - (device - proxy) * -kc).length() < 1e-3);
    // Pulled 5 cm out: the contact lets go, the proxy is the device.
    let up = Vector::new(0.0, 0.05, 0.0);
    assert_eq!(model.proxy(up, kc), (up, Vector::ZERO));
    // A grasp pulls back.
    let grasp = ServoModel {
        grasping: true,
        ..model.clone()
    };
    let (p, f) = grasp.proxy(up, kc);
    assert!(f.y < 0.0 && p.y < up.y, "a grasp holds: {f:?}");
    // Out of contact, a patch vertex 1 cm inside a 5 cm ball pushes it out by its stiffness.
    let touch = ServoModel {
        sequence: 2,
        shape: Some(SharedShape::ball(0.05)),
        patch: vec![rapier_touch::haptics::PatchVertex {
            position: Vector::new(0.0, -0.04, 0.0),
            stiffness: 200.0,
        }],
        ..ServoModel::default()
    };
    let f = touch.force_at(Vector::ZERO);
    assert!((f - Vector::new(0.0, 2.0, 0.0)).length() < 1e-4, "{f:?}");
    // No world update yet, or a link dropped: nothing.
    assert_eq!(ServoModel::default().force_at(Vector::ZERO), Vector::ZERO);
    let gone = ServoModel {
        attached: false,
        ..model
    };
    assert_eq!(gone.force_at(Vector::new(0.0, -0.02, 0.0)), Vector::ZERO);
}

/// The push on a ball of radius `r` centred at `c` of a point `p` with stiffness `k`: `k`
/// times how deep `p` lies inside, along the line from `p` to the centre; and that depth.
fn ball_push(c: Vector, r: f32, p: Vector, k: f32) -> (Vector, f32) {
    let d = c - p;
    let depth = r - d.length();
    let push = if depth > 0.0 {
        d.normalize() * (k * depth)
    } else {
        Vector::ZERO
    };
    (push, depth)
}

/// The model of a ball of radius `r` at the origin holding the vertex under it with `load`,
/// all of the contact's stiffness `s` that vertex's normal one.
fn ball_holding_its_lowest_vertex(r: f32, load: f32, s: f32) -> ServoModel {
    use rapier_touch::haptics::HeldVertex;
    let normal = Vector::new(0.0, -1.0, 0.0);
    ServoModel {
        sequence: 1,
        force: Vector::new(0.0, load, 0.0),
        stiffness: Matrix::from_cols(normal * normal.x, normal * normal.y, normal * normal.z) * s,
        shape: Some(SharedShape::ball(r)),
        held: vec![HeldVertex {
            position: Vector::new(0.0, -r, 0.0),
            load,
            normal,
            stiffness: s,
            depth: load / s,
        }],
        ..ServoModel::default()
    }
}

/// A ball of radius r holding one vertex at its bottom with load λ and stiffness s: the model
/// is a spring of stiffness s from the vertex's anchor, λ/s above the vertex, to the ball's
/// surface. Slid and pressed anywhere, the force is s (r - |a - c|) along (c - a) / |c - a|
/// for the anchor a and the ball's centre c (written here from the sphere's geometry): it
/// turns with the ball and pushes it on as it slides (the sign of a slide), and it is gone
/// when the ball lifts off the anchor.
#[test]
fn a_vertex_held_on_a_ball_pushes_from_its_anchor_as_the_ball_slides_and_presses() {
    let (r, load, s) = (0.05, 2.0, 400.0);
    let normal = Vector::new(0.0, -1.0, 0.0);
    let vertex = Vector::new(0.0, -r, 0.0);
    let model = ball_holding_its_lowest_vertex(r, load, s);
    let anchor = vertex - normal * (load / s);
    let mut pushed_on = 0;
    for i in 0..40 {
        let t = i as f32 / 39.0;
        let c = Vector::new(
            0.03 * (2.0 * t - 1.0),
            -0.004 + 0.008 * ((7.0 * t).sin()),
            0.01 * (3.0 * t).cos(),
        );
        let (expect, depth) = ball_push(c, r, anchor, s);
        let f = model.force_at(c);
        assert!(
            (f - expect).length() <= 1e-4 * load,
            "ball at {c}: {f} against {expect}"
        );
        if depth > 0.0 && c.x.abs() > 0.005 {
            assert!(f.x * c.x > 0.0, "slid to {c}: {f}");
            pushed_on += 1;
        }
    }
    assert!(pushed_on > 10, "{pushed_on}");
    // Lifted past the anchor: no force.
    assert_eq!(
        model.force_at(Vector::new(0.0, load / s + 1e-3, 0.0)),
        Vector::ZERO
    );
    // At the pose the world stepped to: the world's force.
    assert!((model.force_at(Vector::ZERO) - model.force).length() < 1e-5);
    // A device reading NaN gets nothing; a held vertex with a NaN position hands no NaN on.
    assert_eq!(model.force_at(Vector::NAN), Vector::ZERO);
    let mut broken = model.clone();
    broken.held[0].position = Vector::NAN;
    assert!(broken.force_at(Vector::new(0.01, 0.0, 0.0)).is_finite());
}

/// A ball holding one vertex under it, slid toward a free vertex of the last world step (in
/// the model's patch): the free vertex adds nothing until the ball's surface reaches it, then
/// `k · depth` along the line from the ball's centre through it (the sphere's geometry, written
/// here), so the force does not jump where the vertex is captured between world updates.
#[test]
fn a_vertex_a_held_ball_reaches_between_updates_pushes_from_its_first_touch() {
    use rapier_touch::haptics::PatchVertex;
    let (r, load, s, k) = (0.05, 2.0, 400.0, 300.0);
    // A free vertex ahead and a little below the ball's side.
    let free = Vector::new(0.06, -0.01, 0.0);
    let model = ServoModel {
        patch: vec![PatchVertex {
            position: free,
            stiffness: k,
        }],
        ..ball_holding_its_lowest_vertex(r, load, s)
    };
    let without = ServoModel {
        patch: Vec::new(),
        ..model.clone()
    };
    let mut captured = 0;
    for i in 0..60 {
        let c = Vector::new(0.03 * i as f32 / 59.0, 0.0, 0.0);
        let (expect, depth) = ball_push(c, r, free, k);
        let added = model.force_at(c) - without.force_at(c);
        assert!(
            (added - expect).length() <= 1e-4 * load,
            "ball at {c}: {added} added against {expect}"
        );
        captured += (depth > 0.0) as usize;
    }
    assert!(captured > 10 && captured < 50, "{captured}");
}

#[test]
fn servo_threads_and_a_busy_world_never_block_tear_or_panic() {
    // Two tools on servo threads at 2 kHz; the world thread steps, refactors the surface's
    // springs, removes a tool and links a new one, at random, for a bounded time. Every
    // model a servo loop reads must be one the world published whole.
    use std::collections::HashMap;
    use std::sync::mpsc;
    let (mut world, mut set, tool_a, plate_h) =
        plate_scene(0.4, 20, 200.0, 0.2, 2, SharedShape::ball(0.04));
    let body_b = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.1, 0.4, 0.0)),
    );
    let tool_b = world.insert_collider(ColliderBuilder::ball(0.03), Some(body_b));
    let rate = 2000.0;
    let coupling = VirtualCoupling {
        stiffness: 2000.0,
        damping: 0.0,
        max_force: 30.0,
    };
    // Each servo reports (sequence, force, pose) of the models it read, checked afterwards
    // against what the world published.
    let spawn = |link: rapier_touch::haptics::ServoLink,
                 x: f32,
                 tx: mpsc::Sender<(u64, Vector, Vector)>| {
        let arm = move |t: f32| {
            Pose::from_translation(Vector::new(x, 0.06 - 0.05 * (3.0 * t).sin().abs(), 0.0))
        };
        let hand = SimulatedHand::new(rate, arm).unwrap();
        let mut servo = Servo::new(hand, link, coupling, rate).unwrap();
        std::thread::spawn(move || {
            let start = Instant::now();
            let mut ticks = 0u64;
            while start.elapsed() < Duration::from_millis(1500) {
                let t = servo.tick();
                assert!(t.force.is_finite() && t.force.length() <= 30.0 + 1e-3);
                ticks += 1;
                if ticks.is_multiple_of(16) {
                    tx.send((t.model_sequence, t.model_force, t.proxy)).ok();
                }
                std::thread::sleep(Duration::from_micros(300));
            }
            ticks
        })
    };
    let (tx, rx) = mpsc::channel();
    let (wa, sa) = haptic_link();
    let (wb, sb) = haptic_link();
    set.connect_haptic(tool_a, wa, &mut world).unwrap();
    set.connect_haptic(tool_b, wb, &mut world).unwrap();
    let (tx_b, _rx_b) = mpsc::channel();
    let threads = [spawn(sa, 0.0, tx.clone()), spawn(sb, 0.1, tx_b.clone())];
    let mut published_a: HashMap<u64, Vector> = HashMap::new();
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        rng
    };
    let start = Instant::now();
    let mut steps = 0;
    let mut late_threads = Vec::new();
    while start.elapsed() < Duration::from_millis(1200) {
        match next() % 10 {
            0 => {
                let k = 50.0 + (next() % 400) as f32;
                set.get_mut(plate_h)
                    .unwrap()
                    .surface
                    .set_spring(k, 1.0)
                    .unwrap();
            }
            1 => {
                // Tool b leaves and comes back on a fresh link and a fresh servo thread.
                set.remove_tool(tool_b, &mut world);
                let (w, s) = haptic_link();
                set.connect_haptic(tool_b, w, &mut world).unwrap();
                late_threads.push(spawn(s, 0.1, tx_b.clone()));
            }
            _ => {}
        }
        set.step(&mut world);
        steps += 1;
        let m = set.haptic_model(tool_a).unwrap();
        published_a.insert(m.sequence, m.force);
        for h in [tool_a, tool_b] {
            let f = set.tool_reaction(h).map_or(Vector::ZERO, |r| r.force);
            assert!(f.is_finite());
        }
    }
    drop((tx, tx_b));
    for t in threads.into_iter().chain(late_threads) {
        let ticks = t.join().expect("a servo thread panicked");
        assert!(ticks > 100, "a servo thread was starved: {ticks} ticks");
    }
    assert!(steps > 10, "the world was blocked: {steps} steps");
    // Whole models only: every model tool a's servo read carries the force the world
    // published under its number.
    let reads: Vec<(u64, Vector, Vector)> = rx.iter().collect();
    let mut seen = 0;
    for (seq, f, _) in &reads {
        if let Some(published) = published_a.get(seq) {
            assert_eq!(f, published, "model {seq} read torn");
            seen += 1;
        }
    }
    assert!(seen > 10, "only {seen} models of tool a checked");
}

/// A device that reads `pose(tick)` and keeps every force it is sent.
struct Scripted {
    tick: usize,
    pose: fn(usize) -> Vector,
    forces: Vec<Vector>,
}

impl rapier_touch::haptics::HapticDevice for Scripted {
    fn state(&mut self) -> rapier_touch::haptics::DeviceState {
        self.tick += 1;
        rapier_touch::haptics::DeviceState {
            pose: Pose::from_translation((self.pose)(self.tick)),
            buttons: 0,
        }
    }

    fn set_force(&mut self, force: Vector) {
        self.forces.push(force);
    }
}

/// The 0.3 m plate of the bad-input tests below, a 3 cm ball as its tool, linked to a servo
/// whose end is returned.
fn linked_plate() -> (PhysicsWorld, SurfaceSet, ColliderHandle, ServoLink) {
    let (mut world, mut set, tool, _) =
        plate_scene(0.3, 24, 400.0, 0.5, 4, SharedShape::ball(0.03));
    let (world_end, servo_end) = haptic_link();
    set.connect_haptic(tool, world_end, &mut world).unwrap();
    (world, set, tool, servo_end)
}

/// The device at tick `t`: down from 2 cm over the plate to 1 cm into it over the first 500
/// ticks, then held there.
fn pressing_in(t: usize) -> Vector {
    Vector::new(0.0, 0.02 + 0.03 * (1.0 - t as f32 / 500.0).max(0.0), 0.0)
}

#[test]
fn a_device_that_reads_nan_mid_press_gets_no_force_and_moves_no_tool() {
    // Pressed 1 cm into a plate, then the device reads NaN (a dropped USB frame) for 200
    // ticks, then presses again: no NaN reaches the device or the world, the tool waits
    // where it was, and the press is felt again after.
    // With the passivity controller off and on.
    for passive in [false, true] {
        let (mut world, mut set, tool, servo_end) = linked_plate();
        let device = Scripted {
            tick: 0,
            pose: |t| {
                if (2000..2200).contains(&t) {
                    Vector::splat(f32::NAN)
                } else {
                    pressing_in(t)
                }
            },
            forces: Vec::new(),
        };
        let coupling = VirtualCoupling {
            stiffness: 2000.0,
            damping: 0.0,
            max_force: 30.0,
        };
        let mut servo = Servo::new(device, servo_end, coupling, 5000.0).unwrap();
        servo.set_passivity(passive);
        let mut before_gap = Vector::ZERO;
        for step in 0..60 {
            for _ in 0..83 {
                servo.tick();
            }
            set.step(&mut world);
            let at = world.colliders[tool].position().translation;
            assert!(at.is_finite(), "step {step}: tool at {at:?}");
            if servo.device().tick < 2000 {
                before_gap = at;
            } else if servo.device().tick < 2200 {
                assert_eq!(
                    at, before_gap,
                    "step {step}: the tool moved during the NaN reads"
                );
            }
        }
        let forces = &servo.device().forces;
        assert!(forces.iter().all(|f| f.is_finite()));
        assert!(forces[2000..2199].iter().all(|f| *f == Vector::ZERO));
        // Pressed before and after: the ball's centre 1 cm under its rest height pushes back.
        assert!(
            forces[1990].y > 0.5 && forces.last().unwrap().y > 0.5,
            "{:?}",
            forces.last()
        );
    }
}

#[test]
fn a_coupling_of_no_stiffness_renders_nothing_and_no_nan_with_the_passivity_controller() {
    // Zero, negative and NaN coupling stiffness: the controller's spring energy and its
    // bounded step must not divide by zero or pass a NaN on; the device gets no force.
    for stiffness in [0.0, -5.0, f32::NAN] {
        let (mut world, mut set, tool, servo_end) = linked_plate();
        let device = Scripted {
            tick: 0,
            pose: pressing_in,
            forces: Vec::new(),
        };
        let coupling = VirtualCoupling {
            stiffness,
            damping: 0.0,
            max_force: 30.0,
        };
        let mut servo = Servo::new(device, servo_end, coupling, 5000.0).unwrap();
        assert!(servo.passivity());
        for _ in 0..20 {
            for _ in 0..83 {
                servo.tick();
            }
            set.step(&mut world);
            assert!(world.colliders[tool].position().translation.is_finite());
        }
        let forces = &servo.device().forces;
        assert!(
            forces.iter().all(|f| *f == Vector::ZERO),
            "stiffness {stiffness}: {:?}",
            forces.iter().find(|f| **f != Vector::ZERO)
        );
    }
}
