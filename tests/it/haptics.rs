//! The haptic device layer (issue 14, first part), against analytic answers: a simulated hand
//! pressing a virtual wall through the virtual coupling comes to rest where its arm and the
//! wall balance (a static solve by hand) when the coupling is under the passive stiffness,
//! and buzzes when it is ten times over; recordings survive CSV; the workspace keeps power.

use rapier_touch::haptics::{
    DeviceState, HapticDevice, Recording, RecordingError, SimulatedHand, VirtualCoupling, Workspace,
};
use rapier_touch::prelude::*;

/// Presses a 1 kHz simulated hand (device damping 2 N·s/m) into a wall at y = 0 rendered by
/// a coupling of stiffness `k` to the proxy (the device held on the wall's surface), its arm
/// aiming 2 cm into the wall from t = 1 s; returns the hand's final height, the RMS speed over
/// the last 5 s, and the rendered work and the device's damping loss over the run.
fn press_wall(k: f32) -> (f32, f32, f64, f64) {
    let rate = 1000.0;
    let arm = |t: f32| Pose::from_translation(Vector::new(0.0, 0.01 - 0.03 * t.min(1.0), 0.0));
    let mut hand = SimulatedHand::new(rate, arm).unwrap();
    let coupling = VirtualCoupling {
        stiffness: k,
        damping: 0.0,
        max_force: 20.0,
    };
    let (mut sum_v2, mut n) = (0.0f64, 0);
    for tick in 0..(10.0 * rate) as usize {
        let p = hand.state().pose.translation;
        let proxy = Vector::new(p.x, p.y.max(0.0), p.z);
        hand.set_force(coupling.force(p, hand.velocity(), proxy, Vector::ZERO));
        hand.step();
        if tick as f32 >= 5.0 * rate {
            sum_v2 += hand.velocity().length_squared() as f64;
            n += 1;
        }
    }
    let y = hand.state().pose.translation.y;
    (
        y,
        (sum_v2 / n as f64).sqrt() as f32,
        hand.rendered_work(),
        hand.damping_loss(),
    )
}

#[test]
fn under_the_passive_stiffness_a_pressed_hand_settles_over_it_the_wall_buzzes() {
    let k_max = VirtualCoupling::max_passive_stiffness(1000.0, 2.0);
    assert_eq!(k_max, 4000.0);
    let arm = 300.0;
    let mut rms_passive = 0.0f32;
    for k in [0.25 * k_max, 0.5 * k_max, 0.9 * k_max] {
        let (y, rms, work, loss) = press_wall(k);
        // Static balance of the arm (aiming at -2 cm) and the wall's spring.
        let expected = -0.02 * arm / (arm + k);
        assert!(
            (y - expected).abs() < 1e-5,
            "k {k}: rests at {y}, static {expected}"
        );
        assert!(rms < 1e-5, "k {k}: still moving, rms {rms} m/s");
        // Energy: the held (sampled) spring gives back a little more than a spring would (the
        // rendered work plus what it stores is what it generated), and the device's own
        // damping takes more than that: the hand gained no energy from the rendering.
        let stored = 0.5 * k as f64 * (expected as f64).powi(2);
        let generated = work + stored;
        assert!(
            generated <= loss,
            "k {k}: generated {generated} J, damping took {loss} J"
        );
        rms_passive = rms_passive.max(rms);
    }
    // Ten times over the bound, the same press never settles.
    let (_, rms, _, _) = press_wall(10.0 * k_max);
    assert!(
        rms > 1e3 * rms_passive.max(1e-9) && rms > 1e-3,
        "rms {rms} m/s"
    );
}

#[test]
fn recordings_round_trip_and_replay_and_bad_csv_is_an_error() {
    // A hand with a tremor, recorded at 1 kHz for a second.
    let path = |t: f32| {
        Pose::from_parts(
            Vector::new(0.01 * t, 0.002 * (30.0 * t).sin(), 0.0),
            Rotation::from_rotation_y(0.3 * t),
        )
    };
    let mut hand = SimulatedHand::new(1000.0, path).unwrap();
    let mut rec = Recording::default();
    for k in 0..1000 {
        hand.set_buttons(if k > 500 { 1 } else { 0 });
        rec.record(hand.time(), hand.state()).unwrap();
        hand.step();
    }
    let back = Recording::from_csv(&rec.to_csv()).unwrap();
    assert_eq!(back.samples().len(), 1000);
    for ((ta, a), (tb, b)) in rec.samples().iter().zip(back.samples()) {
        assert_eq!(ta, tb);
        assert_eq!(a.buttons, b.buttons);
        assert!((a.pose.translation - b.pose.translation).length() < 1e-9);
        assert!(a.pose.rotation.angle_between(b.pose.rotation) < 1e-5);
    }
    // Replay: a hand driven by the recording follows it.
    let replay = back.clone();
    let mut follower = SimulatedHand::new(1000.0, move |t| replay.pose_at(t)).unwrap();
    for _ in 0..1000 {
        follower.step();
    }
    let end = back.samples().last().unwrap().1.pose.translation;
    assert!((follower.state().pose.translation - end).length() < 1e-3);

    let bad = [
        ("", RecordingError::Header),
        ("t,x,y\n0,0,0", RecordingError::Header),
        (Recording::HEADER, RecordingError::Empty),
        (
            "t,x,y,z,qx,qy,qz,qw,buttons\n0,0,0,0,0,0,0,1",
            RecordingError::Line(2),
        ),
        (
            "t,x,y,z,qx,qy,qz,qw,buttons\n0,NaN,0,0,0,0,0,1,0",
            RecordingError::Line(2),
        ),
        (
            "t,x,y,z,qx,qy,qz,qw,buttons\n0,0,0,0,0,0,0,0,0",
            RecordingError::Line(2),
        ),
        (
            "t,x,y,z,qx,qy,qz,qw,buttons\n0,0,0,0,0,0,0,1,-1",
            RecordingError::Line(2),
        ),
        (
            "t,x,y,z,qx,qy,qz,qw,buttons\n1,0,0,0,0,0,0,1,0\n1,0,0,0,0,0,0,1,0",
            RecordingError::Time(3),
        ),
    ];
    for (csv, err) in bad {
        assert_eq!(Recording::from_csv(csv), Err(err), "{csv:?}");
    }
    let mut rec = Recording::default();
    let state = DeviceState {
        pose: Pose::IDENTITY,
        buttons: 0,
    };
    assert!(rec.record(f32::NAN, state).is_err());
    assert!(SimulatedHand::new(0.0, |_| Pose::IDENTITY).is_err());
    assert!(
        SimulatedHand::new(1000.0, |_| Pose::from_translation(Vector::splat(f32::NAN))).is_err()
    );
}

#[test]
fn the_workspace_keeps_power() {
    for (scale, offset) in [
        (1.0, Pose::IDENTITY),
        (
            10.0,
            Pose::from_parts(Vector::new(0.3, 1.0, -2.0), Rotation::from_rotation_y(0.7)),
        ),
        (
            0.01,
            Pose::from_parts(Vector::ZERO, Rotation::from_rotation_x(-1.2)),
        ),
    ] {
        let w = Workspace { scale, offset };
        let p = Pose::from_translation(Vector::new(0.02, -0.01, 0.05));
        let d = Vector::new(1e-3, -2e-3, 5e-4);
        let moved = w
            .to_world(&Pose::from_translation(p.translation + d))
            .translation
            - w.to_world(&p).translation;
        let f = Vector::new(0.4, -1.5, 2.0);
        // The same work in the world as at the device.
        let (world, device) = (f.dot(moved), w.force_to_device(f).dot(d));
        assert!((world - device).abs() < 1e-5 * f.length() * moved.length().max(1e-9) * 10.0);
    }
}
