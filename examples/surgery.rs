//! Surgery on the 788-node organ (`scenes::SurgeryScene`): a grasper (with friction) comes
//! down, grasps and lifts a fold, holds it and lets go; a scalpel blade presses edge-down and
//! slides 20 mm (its edge presses between the organ's vertices, where contact is
//! frictionless); a needle pokes 4 mm in. All three at once, in a rapier
//! world, through `SurfaceSet::step` with 17 surface substeps per 60 Hz step.
//!
//! Prints, every step, each tool's force split along the organ's home normal at its site (N,
//! positive: pushed out; negative: pulled in, a grasped fold) and across it (T), and how many
//! vertices it holds / sticks to / presses between vertices. Ends with a summary line per tool.
//!
//! Run with `cargo run --release --example surgery`.

use rapier_touch::scenes::SurgeryScene;

fn main() {
    let mut scene = SurgeryScene::new();
    println!(
        "organ: {} nodes; tools: {}",
        scene.surface().num_vertices(),
        scene
            .tools
            .iter()
            .map(|t| t.name)
            .collect::<Vec<_>>()
            .join(", ")
    );
    let n = scene.tools.len();
    let (mut peak_n, mut peak_t, mut least_n) = (vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]);
    for _ in 0..SurgeryScene::total_steps() {
        scene.step();
        let mut line = format!("t = {:.3} s", scene.time());
        for k in 0..n {
            let (normal, tangential) = scene.normal_and_tangential(k);
            assert!(
                normal.is_finite() && tangential.is_finite(),
                "finite forces"
            );
            let r = scene.tool_reaction(k);
            peak_n[k] = peak_n[k].max(normal);
            least_n[k] = least_n[k].min(normal);
            peak_t[k] = peak_t[k].max(tangential);
            line += &format!(
                " | {} N {:+.4} T {:.4} ({}/{}/{})",
                scene.tools[k].name,
                normal,
                tangential,
                r.held_vertices,
                r.sticking_vertices,
                r.pressed_points
            );
        }
        println!("{line}");
    }
    for k in 0..n {
        println!(
            "{}: most push {:.4} N, most pull {:.4} N, most tangential {:.4} N",
            scene.tools[k].name, peak_n[k], -least_n[k], peak_t[k]
        );
    }
    // The grasper pulled the fold up, the blade and the needle were pushed back; all let go.
    assert!(least_n[0] < 0.0, "the grasped fold pulls the grasper");
    assert!(peak_n[1] > 0.0, "the blade is pushed back");
    assert!(peak_n[2] > 0.0, "the needle is pushed back");
    for k in 0..n {
        assert_eq!(
            scene.tool_reaction(k).force,
            rapier_touch::prelude::Vector::ZERO
        );
    }
}
