//! Every scene of the crate in rapier's testbed (`rapier_testbed3d`, a kiss3d window), picked
//! from one launcher like rapier's own `all_examples3`:
//!
//! ```text
//! cargo run --release --features testbed --example all_examples
//! ```
//!
//! **Contacts (Fig. 4)**: the paper's four cases (`scenes::fig4_scenes`). The fixed object is
//! blue-grey, the moving one orange and see-through at its penetrating pose; the green wireframe
//! is the moving object at first touch, the green arrow the reversing vector (from where a
//! contact point is now to where it first touched), red the contact patches (polygon, segment or
//! points), yellow the touching vertices and edges of both meshes, the grey line the trajectory
//! walked back along. Left-drag the orange object: it passes through the fixed one, and every
//! frame the reconstruction walks it back along the drag (from its last pose that did not
//! penetrate) to first touch.
//!
//! **Rigid**:
//! - *Penetration comparison*: the `penetration_compare` drop, vanilla rapier (CCD off, left)
//!   next to the same box stepped by `TouchPipeline` (right), at the speed and floor picked in
//!   the example settings, dropped again every 3 s. The red wireframe is where the guarded box
//!   had got to before the step guard put it back at first touch. Both boxes can be thrown with
//!   the mouse.
//! - *Tool proxy*: a kinematic tool driven by the mouse through `TouchPipeline::set_tool_target`
//!   (the god-object). Drag the see-through ghost (the device) into the U block: the solid tool
//!   (the proxy) stops at first touch; the orange line is the feedback offset.
//!
//! **Soft surfaces** (`SurfaceSet`; the surface's collider is redrawn after every step):
//! - *Plate (Fig. 6)*: `plate_step_force`'s 519-node plate, rim pinned, under its step force
//!   (red arrows), regime and integrator picked in the settings (explicit Euler diverges in the
//!   stiff regime, as the paper says: the scene then stops the surface).
//! - *Organ (Fig. 7)*: `constrained_790`'s 788-node organ (`scenes::Fig7Organ`) hanging on its
//!   pinned internal polyline (black) under the six scheduled forces.
//! - *Multi-tool*: `multi_tool`'s organ dome pressed and dragged by six tools
//!   (`scenes::MultiToolScene`), each repeating its script every 3.5 s (it goes back to its
//!   first spot in the air).
//! - *Ball on plate*: `ball_on_plate`'s dynamic ball on a soft plate (`scenes::BallOnPlateScene`,
//!   two-way coupling).
//!
//! In the soft scenes and *Tool proxy* every tool sits in a see-through ghost, a dynamic body
//! that collides with nothing: the testbed's mouse grab (left-drag) only moves dynamic bodies,
//! so the kinematic tool follows its ghost. A grabbed scripted tool leaves its script until the
//! scene restarts (`R`). The ball of *Ball on plate* is dynamic and is grabbed directly. The
//! testbed drags in the plane facing the camera through the grabbed point: orbit the camera
//! (right-drag) to push a tool down. `T` pauses, `S` steps, `R` restarts.
//!
//! The organ, multi-tool and ball scenes are the library's, the very scenes the headless
//! examples step, print and check; the plate is `plate_step_force`'s set-up.

use kiss3d::color::Color;
use rapier_testbed3d::{ExampleEntry, TestbedViewer};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::{
    ActiveHooks, ColliderBuilder, ColliderHandle, InteractionGroups, PhysicsWorld,
    RigidBodyBuilder, RigidBodyHandle, SharedShape,
};
use rapier_touch::scenes::{
    attach_fixed, box_depth_below_floor, fig4_scenes, BallOnPlateScene, DropFloor, Fig7Organ,
    MultiToolScene, DROP_BOX_HALF,
};
use rapier_touch::surface::meshing::{
    paper_plate_outline, triangulate_planar, PAPER_PLATE_TARGET_EDGE,
};
use std::future::Future;
use std::pin::Pin;

mod contacts;
mod draw;
mod rigid;
mod soft;
mod tools;

use contacts::*;
use draw::*;
use rigid::*;
use soft::*;
use tools::*;

const DT: Real = 1.0 / 60.0;

const SLATE: Color = Color::new(0.59, 0.67, 0.78, 1.0);
const ORANGE_GLASS: Color = Color::new(0.96, 0.59, 0.2, 0.55);
const ORANGE: Color = Color::new(0.96, 0.55, 0.15, 1.0);
const RED: Color = Color::new(0.86, 0.12, 0.12, 1.0);
const YELLOW: Color = Color::new(0.98, 0.78, 0.0, 1.0);
const GREEN: Color = Color::new(0.0, 0.6, 0.24, 1.0);
const GREY: Color = Color::new(0.35, 0.35, 0.38, 1.0);
const BLACK: Color = Color::new(0.05, 0.05, 0.05, 1.0);
const TISSUE: Color = Color::new(0.85, 0.45, 0.45, 1.0);
const STEEL: Color = Color::new(0.3, 0.33, 0.4, 1.0);
const GHOST: Color = Color::new(0.45, 0.65, 0.95, 0.2);

/// One launcher entry: runs the example's own loop until the UI switches or quits.
type ExampleFn = for<'a> fn(&'a mut TestbedViewer) -> Pin<Box<dyn Future<Output = ()> + 'a>>;

#[kiss3d::main]
async fn main() {
    const CONTACTS: &str = "Contacts (Fig. 4)";
    const RIGID: &str = "Rigid";
    const SOFT: &str = "Soft surfaces";
    let examples: [(&str, &str, ExampleFn); 10] = [
        (CONTACTS, "Line (edge) contact", |v| {
            Box::pin(contact_case(v, 0))
        }),
        (CONTACTS, "Face contact", |v| Box::pin(contact_case(v, 1))),
        (CONTACTS, "Vertex contact", |v| Box::pin(contact_case(v, 2))),
        (CONTACTS, "Multiple contacts", |v| {
            Box::pin(contact_case(v, 3))
        }),
        (RIGID, "Penetration comparison", |v| {
            Box::pin(penetration_compare(v))
        }),
        (RIGID, "Tool proxy", |v| Box::pin(tool_proxy(v))),
        (SOFT, "Plate (Fig. 6)", |v| Box::pin(plate_fig6(v))),
        (SOFT, "Organ (Fig. 7)", |v| Box::pin(organ_fig7(v))),
        (SOFT, "Multi-tool", |v| Box::pin(multi_tool(v))),
        (SOFT, "Ball on plate", |v| Box::pin(ball_on_plate(v))),
    ];
    let (entries, runs): (Vec<_>, Vec<ExampleFn>) = examples
        .into_iter()
        .map(|(group, name, run)| (ExampleEntry::new(group, name), run))
        .unzip();
    let mut viewer = TestbedViewer::new(entries).await;
    // Each example owns its world and its loop; this loop starts the one the UI selected.
    loop {
        viewer.clear_scene();
        let index = viewer.selected();
        runs[index](&mut viewer).await;
        if viewer.quitting() {
            break;
        }
    }
}
