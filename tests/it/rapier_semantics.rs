//! rapier's collision semantics hold through the touch pipeline (issue 12): a body dropped
//! slowly (2 m/s) and shot fast (60 m/s) at a floor that rapier lets it pass (a sensor, collision
//! groups that exclude the pair, solver groups that exclude it, a disabled collider, the user's
//! `filter_contact_pair` returning `None`, `ActiveCollisionTypes` that exclude dynamic-fixed
//! pairs) ends exactly where vanilla rapier puts it, below the floor, in both opt-in modes (hook
//! flags and `track_collider`); the plain floor stops it; and after a corrected step, collider
//! poses and a query-pipeline ray cast see the corrected pose. Joints with contacts disabled
//! and a one-way platform in the user's `modify_solver_contacts` are rapier's say too.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

/// The user's hooks: refuse every pair (a floor the game lets bodies through).
struct RefuseAll;

impl PhysicsHooks for RefuseAll {
    fn filter_contact_pair(&self, _: &PairFilterContext) -> Option<SolverFlags> {
        None
    }
}

#[derive(Copy, Clone, Debug)]
enum Semantic {
    Sensor,
    CollisionGroups,
    SolverGroups,
    DisabledCollider,
    UserFilter,
    CollisionTypes,
}

fn setup(
    semantic: Semantic,
    speed: f32,
    hook_flags: bool,
    s: f32,
) -> (PhysicsWorld, RigidBodyHandle, [ColliderHandle; 2]) {
    let mut w = scaled_world(s);
    let mut hooks = if hook_flags {
        ActiveHooks::MODIFY_SOLVER_CONTACTS
    } else {
        ActiveHooks::empty()
    };
    if matches!(semantic, Semantic::UserFilter) {
        hooks |= ActiveHooks::FILTER_CONTACT_PAIRS;
    }
    let mut floor = ColliderBuilder::cuboid(5.0 * s, 0.05 * s, 5.0 * s).active_hooks(hooks);
    let mut body = ColliderBuilder::cuboid(0.25 * s, 0.25 * s, 0.25 * s).active_hooks(hooks);
    let (g1, g2) = (
        InteractionGroups::new(Group::GROUP_1, Group::GROUP_1, InteractionTestMode::And),
        InteractionGroups::new(Group::GROUP_2, Group::GROUP_2, InteractionTestMode::And),
    );
    match semantic {
        Semantic::Sensor => floor = floor.sensor(true),
        Semantic::CollisionGroups => {
            floor = floor.collision_groups(g1);
            body = body.collision_groups(g2);
        }
        Semantic::SolverGroups => {
            floor = floor.solver_groups(g1);
            body = body.solver_groups(g2);
        }
        Semantic::DisabledCollider => floor = floor.enabled(false),
        Semantic::UserFilter => {}
        Semantic::CollisionTypes => {
            let none = ActiveCollisionTypes::empty();
            floor = floor.active_collision_types(none);
            body = body.active_collision_types(none);
        }
    }
    let fh = w.insert_collider(floor, None);
    let b = w.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, s, 0.0))
            .linvel(Vector::new(0.0, -speed * s, 0.0)),
    );
    let bh = w.insert_collider(body, Some(b));
    (w, b, [fh, bh])
}

/// A world at scale `s`: rapier's `length_unit` set to `s` (as its docs ask), gravity scaled
/// by `s`, the crate's integration parameters.
fn scaled_world(s: f32) -> PhysicsWorld {
    let mut w = PhysicsWorld::default();
    w.integration_parameters.length_unit = s;
    w.gravity *= s;
    TouchPipeline::configure(&mut w.integration_parameters);
    w
}

/// The scales the semantics are checked at: 0.1 mm to 10 km.
const SCALES: [f32; 5] = [1e-4, 1e-2, 1.0, 1e2, 1e4];

/// The body's height at the end, in units of `s`.
fn final_y(semantic: Semantic, speed: f32, mode: Option<bool>, s: f32) -> f32 {
    let hook_flags = mode.unwrap_or(true);
    let (mut w, b, handles) = setup(semantic, speed, hook_flags, s);
    let filter = matches!(semantic, Semantic::UserFilter);
    match mode {
        None => {
            for _ in 0..40 {
                if filter {
                    w.step_with_events(&RefuseAll, &());
                } else {
                    w.step();
                }
            }
        }
        Some(hook_flags) => {
            let mut touch = TouchPipeline::new(RefuseAllIf(filter));
            if !hook_flags {
                handles.iter().for_each(|h| touch.track_collider(*h));
            }
            for _ in 0..40 {
                touch.step(&mut w);
            }
        }
    }
    w.bodies[b].translation().y / s
}

/// `RefuseAll` when `.0`, no hooks otherwise.
struct RefuseAllIf(bool);

impl PhysicsHooks for RefuseAllIf {
    fn filter_contact_pair(&self, c: &PairFilterContext) -> Option<SolverFlags> {
        if self.0 {
            RefuseAll.filter_contact_pair(c)
        } else {
            Some(SolverFlags::default())
        }
    }
}

#[test]
fn bodies_pass_whatever_rapier_lets_them_pass() {
    let mut failures = Vec::new();
    for semantic in [
        Semantic::Sensor,
        Semantic::CollisionGroups,
        Semantic::SolverGroups,
        Semantic::DisabledCollider,
        Semantic::UserFilter,
        Semantic::CollisionTypes,
    ] {
        for (speed, s) in [2.0, 60.0].into_iter().flat_map(|v| SCALES.map(|s| (v, s))) {
            let vanilla = final_y(semantic, speed, None, s);
            assert!(
                vanilla < -1.0,
                "{semantic:?} {speed} s/s at {s} m: vanilla rapier stops the body at {vanilla} s"
            );
            for hook_flags in [true, false] {
                let ours = final_y(semantic, speed, Some(hook_flags), s);
                if (ours - vanilla).abs() > 1e-5 {
                    failures.push(format!(
                        "{semantic:?} {speed} s/s at {s} m, hooks {hook_flags}: y {ours} s vs \
                         vanilla {vanilla} s"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A 60 m/s box 1 m above a plain 10 cm floor slab (top at `y = 0.05 + floor_y`), rapier's CCD
/// off, stepped by the touch pipeline in one opt-in mode; the box's collider sits `offset`
/// above its body's origin. Returns the world, the body, its collider and the pipeline.
fn plain_drop(
    hook_flags: bool,
    floor_y: f32,
    offset: f32,
) -> (PhysicsWorld, RigidBodyHandle, ColliderHandle, TouchPipeline) {
    let mut w = PhysicsWorld::default();
    TouchPipeline::configure(&mut w.integration_parameters);
    w.integration_parameters.max_ccd_substeps = 0;
    let flags = if hook_flags {
        ActiveHooks::MODIFY_SOLVER_CONTACTS
    } else {
        ActiveHooks::empty()
    };
    let fh = w.insert_collider(
        ColliderBuilder::cuboid(5.0, 0.05, 5.0)
            .translation(Vector::new(0.0, floor_y, 0.0))
            .active_hooks(flags),
        None,
    );
    let b = w.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 1.0, 0.0))
            .linvel(Vector::new(0.0, -60.0, 0.0)),
    );
    let bh = w.insert_collider(
        ColliderBuilder::cuboid(0.25, 0.25, 0.25)
            .translation(Vector::new(0.0, offset, 0.0))
            .active_hooks(flags),
        Some(b),
    );
    let mut touch = TouchPipeline::default();
    if !hook_flags {
        touch.track_collider(fh);
        touch.track_collider(bh);
    }
    (w, b, bh, touch)
}

/// The control: the same floor without any of those settings stops the body in both modes.
#[test]
fn the_plain_floor_stops_the_body() {
    for hook_flags in [true, false] {
        let (mut w, b, _, mut touch) = plain_drop(hook_flags, 0.0, 0.0);
        for _ in 0..40 {
            touch.step(&mut w);
        }
        assert!(
            w.bodies[b].translation().y > 0.25,
            "hooks {hook_flags}: {}",
            w.bodies[b].translation().y
        );
    }
}

/// Poses in sync (issue 12): right after a step in which the guard moved a body back, its
/// collider's pose and a query-pipeline ray cast see the corrected pose, not the pose rapier's
/// step left.
#[test]
fn collider_poses_and_ray_casts_see_the_corrected_pose() {
    for hook_flags in [true, false] {
        // The collider sits 0.1 m above the body's origin: its pose is the body's times that.
        let (mut w, b, bh, mut touch) = plain_drop(hook_flags, -0.05, 0.1);
        let mut corrected = false;
        for _ in 0..10 {
            touch.step(&mut w);
            if touch.corrections() == 0 {
                continue;
            }
            corrected = true;
            let body = *w.bodies[b].position();
            let expected = body * Pose::from_translation(Vector::new(0.0, 0.1, 0.0));
            let co = *w.colliders[bh].position();
            assert!(
                (co.translation - expected.translation).length() < 1e-5,
                "collider at {:?}, body says {:?}",
                co.translation,
                expected.translation
            );
            // A ray straight down from 5 m hits the box's top face where the body now is.
            let ray = Ray::new(Vector::new(0.0, 5.0, 0.0), Vector::new(0.0, -1.0, 0.0));
            let (hit, toi) = w
                .query_pipeline()
                .cast_ray(&ray, 10.0, true)
                .expect("the ray hits the box");
            assert_eq!(hit, bh);
            let top = co.translation.y + 0.25;
            assert!(
                (5.0 - toi - top).abs() < 1e-4,
                "ray hits at {} but the top is at {top}",
                5.0 - toi
            );
        }
        assert!(corrected, "the guard never corrected the 60 m/s box");
    }
}

/// A body swung by a spherical joint (contacts disabled, as in rapier's ragdolls) through the
/// fixed plate it hangs from: rapier never pairs jointed bodies whose joint disables contacts,
/// so the guard must not stop it either. It ends where vanilla rapier puts it, in both modes.
#[test]
fn a_joint_with_contacts_disabled_lets_the_body_swing_through_its_anchor_plate() {
    let run = |mode: Option<bool>| -> Vector {
        let mut w = PhysicsWorld::default();
        TouchPipeline::configure(&mut w.integration_parameters);
        let flags = if mode == Some(true) {
            ActiveHooks::MODIFY_SOLVER_CONTACTS
        } else {
            ActiveHooks::empty()
        };
        let anchor = w.insert_body(RigidBodyBuilder::fixed());
        let plate = w.insert_collider(
            ColliderBuilder::cuboid(2.5, 0.05, 2.5).active_hooks(flags),
            Some(anchor),
        );
        let b = w.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, 2.0, 0.0))
                .linvel(Vector::new(12.0, 0.0, 0.0)),
        );
        let bc = w.insert_collider(
            ColliderBuilder::cuboid(0.2, 0.2, 0.2).active_hooks(flags),
            Some(b),
        );
        let joint = SphericalJointBuilder::new()
            .local_anchor1(Vector::ZERO)
            .local_anchor2(Vector::new(0.0, -2.0, 0.0))
            .contacts_enabled(false);
        w.insert_impulse_joint(anchor, b, joint);
        let mut touch = TouchPipeline::default();
        if mode == Some(false) {
            touch.track_collider(plate);
            touch.track_collider(bc);
        }
        let mut crossed = false;
        for _ in 0..40 {
            match mode {
                None => w.step(),
                Some(_) => touch.step(&mut w),
            }
            crossed |= w.bodies[b].translation().y < -0.5;
        }
        assert!(crossed, "{mode:?}: the body never swung below the plate");
        w.bodies[b].translation()
    };
    let vanilla = run(None);
    for mode in [Some(true), Some(false)] {
        let p = run(mode);
        assert!(
            (p - vanilla).length() < 1e-3,
            "{mode:?}: {p:?}, vanilla {vanilla:?}"
        );
    }
}

/// rapier's one-way platform (its `one_way_platforms3` example): the user's
/// `modify_solver_contacts` keeps only contacts whose normal points up out of the platform.
struct OneWay {
    platform: ColliderHandle,
}

impl PhysicsHooks for OneWay {
    fn modify_solver_contacts(&self, context: &mut ContactModificationContext) {
        let allowed = if context.collider1 == self.platform {
            Vector::Y
        } else {
            -Vector::Y
        };
        context.update_as_oneway_platform(allowed, 0.1);
    }
}

/// A body shot up through a one-way platform (slowly: it comes back down and lands on it; fast:
/// it flies on) ends where vanilla rapier puts it, in both opt-in modes; dropped fast from
/// above, it stops on the platform.
#[test]
fn a_one_way_platform_in_the_users_hooks_is_passed_from_below_only() {
    let run = |start_y: f32, vy: f32, mode: Option<bool>, s: f32| -> f32 {
        let mut w = scaled_world(s);
        let hook = ActiveHooks::MODIFY_SOLVER_CONTACTS;
        // The platform needs the flag for the user's hooks in every mode.
        let platform = w.insert_collider(
            ColliderBuilder::cuboid(5.0 * s, 0.05 * s, 5.0 * s).active_hooks(hook),
            None,
        );
        let b = w.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.0, start_y * s, 0.0))
                .linvel(Vector::new(0.0, vy * s, 0.0)),
        );
        let flags = if mode == Some(true) {
            hook
        } else {
            ActiveHooks::empty()
        };
        let bc = w.insert_collider(
            ColliderBuilder::cuboid(0.25 * s, 0.25 * s, 0.25 * s).active_hooks(flags),
            Some(b),
        );
        let hooks = OneWay { platform };
        let mut touch = TouchPipeline::new(OneWay { platform });
        if mode == Some(false) {
            touch.track_collider(bc);
        }
        for _ in 0..150 {
            match mode {
                None => w.step_with_events(&hooks, &()),
                Some(_) => touch.step(&mut w),
            }
        }
        w.bodies[b].translation().y / s
    };
    for s in SCALES {
        for (start_y, vy) in [(-1.0, 6.0), (-1.0, 60.0)] {
            let vanilla = run(start_y, vy, None, s);
            // Slow: back down and resting on top; fast: far above.
            assert!(vanilla > 0.25, "{s} m: vanilla ended at {vanilla} s");
            for mode in [Some(true), Some(false)] {
                let y = run(start_y, vy, mode, s);
                assert!(
                    (y - vanilla).abs() <= 2e-3 * vanilla.abs().max(1.0),
                    "{vy} s/s at {s} m, {mode:?}: {y} s, vanilla {vanilla} s"
                );
            }
        }
        for mode in [Some(true), Some(false)] {
            let y = run(3.0, -60.0, mode, s);
            assert!(
                y > 0.25 && y < 0.35,
                "{s} m, {mode:?}: dropped from above ended at {y} s"
            );
        }
    }
}
