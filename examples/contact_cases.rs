//! The paper's Fig. 4 test cases: prints, for each, the state, the reversing vector, and every
//! contact patch with its kind, normal, polygon and the features on both meshes.
//!
//! Run with `cargo run --release --example contact_cases`.

use rapier_touch::prelude::*;
use rapier_touch::scenes::fig4_scenes;

fn main() {
    let mut rec = Reconstructor::default();
    for scene in fig4_scenes() {
        let c = rec
            .reconstruct(
                &scene.fixed,
                &scene.fixed_pose,
                &scene.moving,
                &scene.pose,
                &scene.prev_pose,
            )
            .expect("finite poses");
        println!("== {}: {}", scene.name, scene.description);
        println!(
            "   state {:?}, reversing vector [{:.5}, {:.5}, {:.5}], depth along trajectory {:.5} m, \
             first touch at {:.3} of the step",
            c.state,
            c.reversing_vector.x,
            c.reversing_vector.y,
            c.reversing_vector.z,
            c.depth,
            c.time_of_impact.unwrap_or(f32::NAN),
        );
        for (k, p) in c.patches.iter().enumerate() {
            let poly: Vec<String> = p
                .polygon
                .iter()
                .map(|v| format!("[{:.3}, {:.3}, {:.3}]", v.x, v.y, v.z))
                .collect();
            println!(
                "   patch {k}: {:?} contact, normal [{:.3}, {:.3}, {:.3}], shape {}",
                p.kind,
                p.normal.x,
                p.normal.y,
                p.normal.z,
                poly.join(" ")
            );
            println!("      fixed features:  {:?}", p.fixed_features);
            println!("      moving features: {:?}", p.moving_features);
        }
        let mut kinds: Vec<_> = c.patches.iter().map(|p| format!("{:?}", p.kind)).collect();
        let mut want: Vec<_> = scene.known.kinds.iter().map(|k| format!("{k:?}")).collect();
        kinds.sort();
        want.sort();
        assert_eq!(kinds, want, "{}: contact kinds", scene.name);
        assert!(
            (c.reversing_vector - scene.known.reversing).length() < 1e-4,
            "{}: reversing vector",
            scene.name
        );
    }
}
