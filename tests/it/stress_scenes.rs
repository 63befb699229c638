//! rapier's own stress scenes (its `examples3d/stress_tests/`) through the touch pipeline in
//! both opt-in modes, against vanilla rapier in the same test: nothing goes through the floor,
//! the pile falls asleep as in vanilla, and the deepest overlap of any solved pair (measured on
//! the colliders' poses, see `deepest_solved_overlap`) is never worse than vanilla's.
//!
//! A pile's deepest overlap is chaotic: with gravity scaled by 1 ± 1e-6, vanilla rapier's
//! pyramid reads anywhere from 93.2 to 99.0 mm. Vanilla's side is the deepest of three runs
//! (gravity scaled by 1, 1 + 1e-6 and 1 - 1e-6), its spread; the crate's side runs once.

use rapier_touch::scenes::{run_stress_with_gravity, StressRun, StressScene, StressSide};

/// Vanilla rapier's runs of `scene`: the first unperturbed, then with gravity scaled by
/// 1 ± 1e-6.
fn vanilla_runs(scene: StressScene, steps: usize) -> Vec<StressRun> {
    [1.0, 1.0 + 1e-6, 1.0 - 1e-6]
        .into_iter()
        .map(|g| run_stress_with_gravity(scene, StressSide::Rapier, steps, g))
        .collect()
}

/// `scene` in both opt-in modes against vanilla's runs.
fn as_in_vanilla(scene: StressScene, steps: usize) {
    let vanilla = vanilla_runs(scene, steps);
    let deepest = vanilla
        .iter()
        .map(|r| r.max_penetration)
        .fold(0.0, f32::max);
    let asleep = vanilla[0].asleep;
    for r in &vanilla {
        assert_eq!(r.through_floor, 0);
    }
    for side in [StressSide::TouchHooks, StressSide::TouchTracked] {
        let r = run_stress_with_gravity(scene, side, steps, 1.0);
        println!(
            "{scene:?} {side:?}: deepest {:.2} mm (vanilla up to {:.2} mm), {} asleep (vanilla {asleep})",
            1e3 * r.max_penetration,
            1e3 * deepest,
            r.asleep
        );
        assert_eq!(r.bodies, vanilla[0].bodies);
        assert_eq!(r.through_floor, 0, "{side:?}");
        assert!(
            r.asleep >= asleep,
            "{side:?}: {} asleep, vanilla {asleep}",
            r.asleep
        );
        assert!(
            r.max_penetration <= deepest,
            "{side:?}: {} m, vanilla up to {deepest} m",
            r.max_penetration
        );
    }
}

#[test]
fn the_pyramid_sleeps_and_stays_out_of_the_floor_as_in_vanilla_rapier() {
    as_in_vanilla(StressScene::Pyramid, 200);
}

/// rapier's plank tower (`examples3d/stress_tests/jenga3.rs`, scaled): the floor carries the
/// whole tower. When the guard held the bottom planks to 0.9 mm in the floor, pushing them out
/// each step into the planks above, the tower's compression went between the two lowest layers
/// (11.4 mm against vanilla's 6.5 mm).
#[test]
fn the_plank_tower_is_no_deeper_than_in_vanilla_rapier() {
    as_in_vanilla(StressScene::PlankTower, 120);
}
