//! Frames of the two soft-surface scenes in a rapier world, drawn headless (no window, no GPU)
//! with the crate's software renderer (cargo feature `render`), into `docs/img/frames/`:
//!
//! - `multi_tool_<t>s.png`: `scenes::MultiToolScene` (the `multi_tool` example) every 0.9 s
//!   from t = 0.5 s to 5.0 s (the last tool holds). The organ dome is coloured by displacement (the same colour range
//!   in every frame), its pinned base as dark dots; the tools are drawn grey and
//!   semi-transparent; the vertices each tool holds (its contact points) are red dots and the
//!   mesh edges between two held vertices (the contact patch) yellow; the force of the organ on
//!   each tool is a red arrow from the tool's centre, 10 mm per 0.1 N.
//! - `ball_on_plate_<n>.png`: `scenes::BallOnPlateScene` (the `ball_on_plate` example) at the
//!   release (1), at the deepest dent of the first impact (2), at the top of the first bounce
//!   if it bounces (3; it does not since its mass entered the plate's solve), and at rest at
//!   the end (4). The plate is coloured by displacement, the ball drawn, its held vertices
//!   red, the plate's force on the ball (averaged over the step's substeps) a red arrow and the
//!   ball's weight a black one, 20 mm per N.
//!
//! - `surgery_<t>s.png`: `scenes::SurgeryScene` (the `surgery` example) at 0.5 s (the tools
//!   down), 1.5 s (the grasped fold up, the needle in), 2.5 s (the blade half-way along its
//!   slide) and 3.3 s (all three at work, just before the grasper lets go), drawn as
//!   `multi_tool`'s frames (1 cm arrow = 0.1 N).
//!
//! A progress bar on stderr follows the runs (`--quiet` hides it).
//!
//! Run with `cargo run --release --features render --example frames [-- output dir] [--quiet]`
//! (default `docs/img/frames`).

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::render::{Color, Legend, MeshStyle, Projection, Scene};
use rapier_touch::scenes::{BallOnPlateScene, MultiToolScene, SurgeryScene};
use std::error::Error;
use std::path::Path;

#[path = "common/progress.rs"]
mod progress;

/// multi_tool frames: at t = 0.5, 1.4, 2.3, 3.2, 4.1 and 5.0 s.
const FRAMES: usize = 6;
const FRAME_EVERY: Real = 0.9;
const W: u32 = 560;
const H: u32 = 420;

fn rgba(r: u8, g: u8, b: u8, a: u8) -> Color {
    Color::from_rgba8(r, g, b, a)
}

fn red() -> Color {
    rgba(220, 30, 30, 255)
}

/// A soft surface coloured by displacement over `(0, max)`, its pins as dark dots, its held
/// vertices red and the edges between two held vertices yellow.
fn add_surface(scene: &mut Scene, s: &MassSpringSurface, max: Real) -> Result<(), Box<dyn Error>> {
    let mut pos = Vec::new();
    s.positions_into(&mut pos);
    let n = s.num_vertices() as u32;
    let disp: Vec<Real> = (0..n).map(|i| s.displacement(i).length()).collect();
    let style = MeshStyle {
        edges: Some(rgba(20, 20, 30, 25)),
        ..Default::default()
    };
    scene.add_mesh_scalar(&pos, s.triangles(), &disp, (0.0, max), &style)?;
    for i in (0..n).filter(|&i| s.is_pinned(i)) {
        scene.add_point(pos[i as usize], rgba(40, 40, 40, 255), 1.2);
    }
    for &[a, b] in s.edges() {
        if s.is_held(a) && s.is_held(b) {
            let yellow = rgba(250, 200, 0, 255);
            scene.add_segment(pos[a as usize], pos[b as usize], yellow, 3.0);
        }
    }
    for i in (0..n).filter(|&i| s.is_held(i)) {
        scene.add_point(pos[i as usize], red(), 3.0);
    }
    Ok(())
}

/// A tool's collider as a semi-transparent grey mesh.
fn add_tool(scene: &mut Scene, world: &PhysicsWorld, tool: ColliderHandle) {
    let c = &world.colliders[tool];
    let style = MeshStyle {
        color: rgba(120, 125, 135, 150),
        edges: None,
        edge_width: 1.0,
    };
    scene.add_shape(c.shape(), c.position(), &style);
}

/// A scene of a surface (coloured by displacement up to `max`), its tools, and each tool's
/// force as an arrow from the tool's centre over everything else, 0.1 N drawn 10 mm long.
fn tools_scene(
    s: &MassSpringSurface,
    world: &PhysicsWorld,
    tools: &[(ColliderHandle, Vector)],
    max: Real,
) -> Result<Scene, Box<dyn Error>> {
    let mut scene = Scene::new();
    add_surface(&mut scene, s, max)?;
    for (c, _) in tools {
        add_tool(&mut scene, world, *c);
    }
    for (c, f) in tools {
        let centre = world.colliders[*c].position().translation;
        if f.length() > 1e-4 {
            scene.add_arrow(centre, centre + *f * 0.1, red(), 3.0);
        }
    }
    Ok(scene)
}

/// Steps `sim` with `step` up to each of `times` (s, ascending; `dt` a step) and calls `draw`
/// there.
fn at_times<S>(
    sim: &mut S,
    times: &[Real],
    dt: Real,
    bar: &indicatif::ProgressBar,
    step: fn(&mut S),
    mut draw: impl FnMut(&S) -> Result<(), Box<dyn Error>>,
) -> Result<(), Box<dyn Error>> {
    let frames: Vec<usize> = times.iter().map(|t| (t / dt).round() as usize).collect();
    for k in 1..=frames.last().copied().unwrap_or(0) {
        step(sim);
        bar.inc(1);
        if frames.contains(&k) {
            draw(sim)?;
        }
    }
    Ok(())
}

/// The home positions of a surface's vertices.
fn home(s: &MassSpringSurface) -> Vec<Vector> {
    (0..s.num_vertices() as u32).map(|i| s.home(i)).collect()
}

/// Gives `scene` the displacement legend over `(0, max)`, frames `points` seen along `view`
/// (perspective) and saves it to `path`.
fn save(
    scene: &mut Scene,
    max: Real,
    points: &[Vector],
    view: Vector,
    path: &Path,
) -> Result<(), Box<dyn Error>> {
    scene.set_legend(Legend {
        title: "DISPL. MM".into(),
        low: "0".into(),
        high: format!("{:.1}", max * 1e3),
    });
    let cam = scene.frame(
        points.iter().copied(),
        view,
        Vector::Y,
        Projection::Perspective { fov_y: 0.6 },
        W,
        H,
    );
    scene.save_png(&cam, W, H, path)?;
    println!("wrote {}", path.display());
    Ok(())
}

fn multi_tool(dir: &Path, bar: &indicatif::ProgressBar) -> Result<(), Box<dyn Error>> {
    bar.set_message("multi_tool");
    type S = MultiToolScene;
    let mut sim = S::new();
    // The same view and colour range in every frame: the organ and the tools' waiting height.
    let frame_points: Vec<Vector> = home(sim.surface())
        .into_iter()
        .flat_map(|p| [p, p + Vector::new(0.0, 0.03, 0.0)])
        .collect();
    let max = 1.25 * S::DEPTH;
    let times: Vec<Real> = (0..FRAMES).map(|k| 0.5 + FRAME_EVERY * k as Real).collect();
    at_times(&mut sim, &times, S::DT, bar, S::step, |sim| {
        let t = sim.time();
        let tools: Vec<(ColliderHandle, Vector)> = (0..sim.tools.len())
            .map(|k| (sim.tools[k].collider, sim.tool_reaction(k).force))
            .collect();
        let mut scene = tools_scene(sim.surface(), &sim.world, &tools, max)?;
        let held: usize = (0..sim.tools.len())
            .map(|k| sim.tool_reaction(k).held_vertices)
            .sum();
        scene.set_title(format!(
            "MULTI_TOOL   T = {t:.2} S\n\
             RED: {held} HELD VERTICES\n\
             ARROWS: TOOL FORCE, 1 CM = 0.1 N"
        ));
        save(
            &mut scene,
            max,
            &frame_points,
            Vector::new(-0.45, -0.75, -1.0),
            &dir.join(format!("multi_tool_{t:.1}s.png")),
        )?;
        Ok(())
    })
}

/// Surgery frames: at these times (s).
const SURGERY_FRAMES: [Real; 4] = [0.5, 1.5, 2.5, 3.3];

fn surgery(dir: &Path, bar: &indicatif::ProgressBar) -> Result<(), Box<dyn Error>> {
    bar.set_message("surgery");
    type S = SurgeryScene;
    let mut sim = S::new();
    let frame_points: Vec<Vector> = home(sim.surface())
        .into_iter()
        .flat_map(|p| [p, p + Vector::new(0.0, 0.025, 0.0)])
        .collect();
    let max = 0.012;
    at_times(&mut sim, &SURGERY_FRAMES, S::DT, bar, S::step, |sim| {
        let t = sim.time();
        let tools: Vec<(ColliderHandle, Vector)> = (0..sim.tools.len())
            .map(|k| (sim.tools[k].collider, sim.tool_reaction(k).force))
            .collect();
        let mut scene = tools_scene(sim.surface(), &sim.dome.world, &tools, max)?;
        let mut lines = Vec::new();
        for (k, tool) in sim.tools.iter().enumerate() {
            let (normal, tangential) = sim.normal_and_tangential(k);
            lines.push(format!(
                "{}: N {normal:+.3} T {tangential:.3}",
                tool.name.to_uppercase()
            ));
        }
        scene.set_title(format!("SURGERY   T = {t:.2} S\n{}", lines.join("\n")));
        save(
            &mut scene,
            max,
            &frame_points,
            Vector::new(-0.45, -0.75, -1.0),
            &dir.join(format!("surgery_{t:.1}s.png")),
        )?;
        Ok(())
    })
}

fn ball_on_plate(dir: &Path, bar: &indicatif::ProgressBar) -> Result<(), Box<dyn Error>> {
    bar.set_message("ball_on_plate");
    type S = BallOnPlateScene;
    let steps = S::total_steps();
    // A first run finds the moments to draw: the deepest dent of the first impact and the top
    // of the first bounce.
    let (mut deepest, mut apex) = ((0, 0.0), (0, Real::MIN));
    let (mut touched, mut left) = (false, false);
    let mut max_disp: Real = 0.0;
    let mut sim = S::new();
    for step in 1..=steps {
        sim.step();
        bar.inc(1);
        let r = sim.reaction();
        let held = r.held_vertices + r.pressed_points > 0;
        let d = sim.surface().max_displacement();
        max_disp = max_disp.max(d);
        if held && !left && d > deepest.1 {
            deepest = (step, d);
        }
        touched |= held;
        if touched && !held {
            left = true;
        }
        let y = sim.ball_position().y;
        if left && apex.0 == 0 && held {
            apex.0 = usize::MAX; // landed again: the apex is found
        } else if left && apex.0 != usize::MAX && y > apex.1 {
            apex = (step, y);
        }
    }
    // (step, caption, file number: the same moment keeps its file whether the ball bounces or
    // not).
    let mut moments = vec![(0, "RELEASED", 1), (deepest.0, "DEEPEST DENT", 2)];
    if apex.0 != usize::MAX && apex.0 > 0 {
        moments.push((apex.0, "TOP OF THE BOUNCE", 3));
    }
    moments.push((steps, "AT REST", 4));
    moments.sort_by_key(|m| m.0);

    let mut sim = S::new();
    // The plate's middle 0.2 m, the ball's release point and room for the dent below.
    let frame_points: Vec<Vector> = home(sim.surface())
        .into_iter()
        .filter(|p| p.x.abs().max(p.z.abs()) <= 0.1)
        .chain([
            Vector::new(0.0, S::START.y + S::RADIUS, 0.0),
            Vector::new(0.0, -0.04, 0.0),
        ])
        .collect();
    for (at, what, file) in &moments {
        while sim.steps() < *at {
            sim.step();
            bar.inc(1);
        }
        let t = sim.time();
        let mut scene = Scene::new();
        add_surface(&mut scene, sim.surface(), max_disp)?;
        add_tool(&mut scene, &sim.world, sim.ball_collider);
        let centre = sim.ball_position();
        let f = sim.reaction().mean_force;
        let scale = 0.02; // 20 mm per N
        if f.length() > 1e-4 {
            scene.add_arrow(centre, centre + f * scale, red(), 3.0);
        }
        let weight = Vector::new(0.0, -sim.weight(), 0.0);
        scene.add_arrow(centre, centre + weight * scale, rgba(20, 20, 20, 255), 3.0);
        scene.set_title(format!(
            "BALL_ON_PLATE   T = {t:.2} S\n\
             {what}\n\
             PLATE FORCE {:.2} N (RED)\n\
             WEIGHT {:.2} N (BLACK)",
            f.y,
            sim.weight()
        ));
        save(
            &mut scene,
            max_disp,
            &frame_points,
            Vector::new(-0.35, -0.15, -1.0),
            &dir.join(format!("ball_on_plate_{file}.png")),
        )?;
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let dir = progress::output_dir("docs/img/frames")?;
    let last = 0.5 + FRAME_EVERY * (FRAMES - 1) as Real;
    let multi_steps = (last / MultiToolScene::DT).round() as u64;
    let ball_steps = 2 * BallOnPlateScene::total_steps() as u64;
    let surgery_steps = (SURGERY_FRAMES[3] / SurgeryScene::DT).round() as u64;
    let bar = progress::bar(multi_steps + ball_steps + surgery_steps, "frames");
    multi_tool(&dir, &bar)?;
    surgery(&dir, &bar)?;
    ball_on_plate(&dir, &bar)?;
    bar.finish_and_clear();
    Ok(())
}
