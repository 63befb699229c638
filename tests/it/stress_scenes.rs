//! rapier's own pyramid stress scene (its `examples3d/stress_tests/pyramid3.rs`, 8 layers) through
//! the touch pipeline in both opt-in modes, against vanilla rapier in the same test: nothing
//! goes through the floor, the pile falls asleep as in vanilla, and the deepest overlap of any
//! solved pair (measured on the colliders' poses, see `deepest_solved_overlap`) is never worse
//! than vanilla's.

use rapier_touch::scenes::{run_stress, StressScene, StressSide};

#[test]
fn the_pyramid_sleeps_and_stays_out_of_the_floor_as_in_vanilla_rapier() {
    let steps = 200;
    let vanilla = run_stress(StressScene::Pyramid, StressSide::Rapier, steps);
    assert_eq!(vanilla.through_floor, 0);
    for side in [StressSide::TouchHooks, StressSide::TouchTracked] {
        let r = run_stress(StressScene::Pyramid, side, steps);
        assert_eq!(r.bodies, vanilla.bodies);
        assert_eq!(r.through_floor, 0, "{side:?}");
        assert!(
            r.asleep >= vanilla.asleep,
            "{side:?}: {} asleep, vanilla {}",
            r.asleep,
            vanilla.asleep
        );
        assert!(
            r.max_penetration <= vanilla.max_penetration,
            "{side:?}: {} m, vanilla {} m",
            r.max_penetration,
            vanilla.max_penetration
        );
    }
}
