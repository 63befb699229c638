//! Headless pictures of the paper's figures, drawn with the crate's software renderer
//! (`rapier_touch::render`, cargo feature `render`):
//!
//! - `fig4_line.png`, `fig4_face.png`, `fig4_vertex.png`, `fig4_multi.png`: each Fig. 4 case
//!   (`scenes::fig4_scenes`) at first touch, the moving object moved by its reversing vector.
//!   The fixed object is blue-grey, the moving one orange and semi-transparent; its
//!   penetrating pose is the thin red wireframe. Contact patches are red (polygon, segment or
//!   dots), the touching vertices and edges of both meshes yellow, the reversing vector a green
//!   arrow ending at the patch centre, scaled by the integer factor the title gives (the
//!   vectors are 5-15 cm on metre-sized objects).
//! - `fig6_plate.png`: the paper's Fig. 6 plate (`paper_plate_outline`, rim pinned) under its
//!   step force after 10 s (stiff regime of `plate_step_force`, exact filter: the static
//!   deflection), coloured by displacement, the shape drawn with the displacement × 3, the
//!   force as a red arrow.
//! - `fig7_organ.png`: the 790-node organ of `constrained_790` (`scenes::Fig7Organ`) at
//!   t = 5 s (exact filter), coloured by displacement, its pinned internal polyline in black,
//!   the six force groups' forces at that time as red arrows.
//!
//! Run with `cargo run --release --features render --example pictures [output dir]`
//! (default `docs/img`).

use rapier_touch::prelude::*;
use rapier_touch::render::{Camera, Color, Legend, MeshStyle, Projection, Scene};
use rapier_touch::scenes::{fig4_scenes, Fig7Organ};
use rapier_touch::surface::meshing::{
    paper_plate_outline, triangulate_planar, PAPER_PLATE_TARGET_EDGE,
};
use std::error::Error;
use std::path::{Path, PathBuf};

const W: u32 = 800;
const H: u32 = 600;

fn rgba(r: u8, g: u8, b: u8, a: u8) -> Color {
    Color::from_rgba8(r, g, b, a)
}

fn save(scene: &Scene, cam: &Camera, dir: &Path, name: &str) -> Result<(), Box<dyn Error>> {
    let path: PathBuf = dir.join(name);
    scene.save_png(cam, W, H, &path)?;
    println!("wrote {}", path.display());
    Ok(())
}

fn fig4(dir: &Path) -> Result<(), Box<dyn Error>> {
    let mut rec = Reconstructor::default();
    let red = rgba(220, 30, 30, 255);
    let yellow = rgba(250, 200, 0, 255);
    let green = rgba(0, 150, 60, 255);
    for s in fig4_scenes() {
        let c = rec.reconstruct(&s.fixed, &s.fixed_pose, &s.moving, &s.pose, &s.prev_pose)?;
        let touch = Pose::from_parts(s.pose.translation + c.reversing_vector, s.pose.rotation);
        let fixed: Vec<Vector> = s
            .fixed
            .vertices()
            .iter()
            .map(|v| s.fixed_pose.transform_point(*v))
            .collect();
        let moving: Vec<Vector> = s
            .moving
            .vertices()
            .iter()
            .map(|v| touch.transform_point(*v))
            .collect();
        let sunk: Vec<Vector> = s
            .moving
            .vertices()
            .iter()
            .map(|v| s.pose.transform_point(*v))
            .collect();

        let mut scene = Scene::new();
        let edges = Some(rgba(40, 50, 70, 255));
        let fixed_style = MeshStyle {
            color: rgba(150, 170, 200, 255),
            edges,
            edge_width: 1.0,
        };
        scene.add_mesh(&fixed, s.fixed.indices(), &fixed_style);
        let moving_style = MeshStyle {
            color: rgba(245, 150, 50, 150),
            edges,
            edge_width: 1.0,
        };
        scene.add_mesh(&moving, s.moving.indices(), &moving_style);
        for [a, b] in s.moving.edges() {
            scene.add_segment(
                sunk[*a as usize],
                sunk[*b as usize],
                rgba(220, 30, 30, 140),
                1.0,
            );
        }
        for p in &c.patches {
            // The touching vertices and edges of both meshes (faces show as the patch).
            for (feats, verts) in [(&p.fixed_features, &fixed), (&p.moving_features, &moving)] {
                for f in feats.iter() {
                    match *f {
                        Feature::Vertex(v) => scene.add_point(verts[v as usize], yellow, 7.0),
                        Feature::Edge([a, b]) => {
                            scene.add_segment(verts[a as usize], verts[b as usize], yellow, 3.0)
                        }
                        Feature::Face(_) => {}
                    }
                }
            }
            match p.kind {
                ContactKind::Face => {
                    scene.add_polygon(&p.polygon, rgba(220, 30, 30, 150), red, 3.0)
                }
                ContactKind::Edge => {
                    scene.add_segment(p.polygon[0], p.polygon[p.polygon.len() - 1], red, 4.0)
                }
                ContactKind::Vertex => {}
            }
            for q in &p.points {
                scene.add_point(q.point, red, 5.0);
            }
        }
        let rv = c.reversing_vector;
        let kinds: Vec<String> = c.patches.iter().map(|p| format!("{:?}", p.kind)).collect();
        let title = |k: Real| {
            let r = |x: Real| (x * 1000.0).round() / 1000.0 + 0.0; // no "-0.000"
            format!(
                "FIG 4 {}: {} CONTACT\nRV = ({:.3}, {:.3}, {:.3}) M, GREEN ARROW = RV X {k}",
                s.name.replace('_', " "),
                kinds.join(" + "),
                r(rv.x),
                r(rv.y),
                r(rv.z)
            )
        };
        scene.set_title(title(1.0));
        let (view, zoom) = if s.name == "multi_point" {
            (Vector::new(-0.35, -0.45, -1.0), 1.05)
        } else {
            (Vector::new(-0.5, -0.55, -1.0), 1.6)
        };
        // Frame the moving object at both poses (the slab is much larger).
        let frame: Vec<Vector> = if s.name == "multi_point" {
            scene.points().collect()
        } else {
            moving.iter().chain(&sunk).copied().collect()
        };
        let ortho = Projection::Orthographic { half_height: 1.0 };
        let cam = scene
            .frame(frame, view, Vector::Y, ortho, W, H)
            .zoomed(zoom);
        // The reversing vector is a few centimetres: drawn at least 80 px long, scaled by an
        // integer factor given in the title.
        let px = rv.length() / cam.world_per_pixel(H);
        let k = (80.0 / px.max(1e-3)).ceil().max(1.0);
        scene.set_title(title(k));
        for p in &c.patches {
            scene.add_arrow(p.center() - rv * k, p.center(), green, 3.0);
        }
        let file = match s.name {
            "multi_point" => "fig4_multi.png".to_string(),
            n => format!("fig4_{n}.png"),
        };
        save(&scene, &cam, dir, &file)?;
    }
    Ok(())
}

/// The positions of a surface with its displacements scaled by `scale`, and the displacement
/// lengths (unscaled).
fn deformed(s: &MassSpringSurface, scale: Real) -> (Vec<Vector>, Vec<Real>) {
    let n = s.num_vertices() as u32;
    (
        (0..n)
            .map(|i| s.home(i) + s.displacement(i) * scale)
            .collect(),
        (0..n).map(|i| s.displacement(i).length()).collect(),
    )
}

fn legend(max: Real) -> Legend {
    Legend {
        title: "DISPL. MM".into(),
        low: "0".into(),
        high: format!("{:.1}", max * 1000.0),
    }
}

fn fig6(dir: &Path) -> Result<(), Box<dyn Error>> {
    let planar = triangulate_planar(&paper_plate_outline(), PAPER_PLATE_TARGET_EDGE)?;
    let n = planar.mesh.num_vertices() as u32;
    let centre = Vector::new(0.0, 0.0, -0.02);
    let mut free: Vec<u32> = (0..n)
        .filter(|i| planar.boundary.binary_search(i).is_err())
        .collect();
    free.sort_by(|&a, &b| {
        (planar.mesh.vertices[a as usize] - centre)
            .length()
            .total_cmp(&(planar.mesh.vertices[b as usize] - centre).length())
    });
    let loaded = free[..7].to_vec();
    // The stiff regime of plate_step_force: k = 2 N/m, c = 0.02 N s/m, 20 mN per vertex.
    let force = Vector::new(0.0, -0.02, 0.0);
    let mut s = MassSpringSurfaceBuilder::from_mesh(&planar.mesh)
        .stiffness(2.0)
        .damping(0.02)
        .mass(MassDistribution::PerVertex(0.001))
        .pinned(planar.boundary.iter().copied())
        .dt(1.0 / 60.0)
        .integrator(Integrator::EXACT)
        .build()?;
    s.add_force_schedule(
        loaded.clone(),
        ForceProfile::Step {
            force,
            start: 0.0,
            end: None,
        },
    )?;
    for _ in 0..600 {
        s.step();
    }
    let (pos, disp) = deformed(&s, 3.0);
    let max = disp.iter().copied().fold(0.0, Real::max);
    let mut scene = Scene::new();
    let style = MeshStyle {
        edges: Some(rgba(20, 20, 30, 90)),
        ..Default::default()
    };
    scene.add_mesh_scalar(&pos, &planar.mesh.triangles, &disp, (0.0, max), &style)?;
    let at = loaded.iter().map(|&i| pos[i as usize]).sum::<Vector>() / loaded.len() as Real;
    let up = Vector::new(0.0, 0.08, 0.0);
    scene.add_arrow(at + up, at, rgba(220, 30, 30, 255), 3.0);
    for &i in &planar.boundary {
        scene.add_point(pos[i as usize], rgba(40, 40, 40, 255), 1.5);
    }
    scene.set_title(format!(
        "FIG 6 PLATE, {n} NODES, RIM PINNED, T = 10 S (EXACT FILTER)\nSTEP FORCE 7 X 20 MN DOWN (RED), SHAPE: DISPL. X 3"
    ));
    scene.set_legend(legend(max));
    let cam = scene
        .fit_camera(
            Vector::new(-0.4, -0.75, -1.0),
            Vector::Y,
            Projection::Perspective { fov_y: 0.6 },
            W,
            H,
        )
        .zoomed(1.1);
    save(&scene, &cam, dir, "fig6_plate.png")
}

fn fig7(dir: &Path) -> Result<(), Box<dyn Error>> {
    let organ = Fig7Organ::new();
    let (mesh, polyline, groups) = (&organ.planar.mesh, &organ.polyline, &organ.groups);
    let forces = Fig7Organ::forces();
    let mut s = organ.surface(Integrator::EXACT);
    for _ in 0..300 {
        s.step();
    }
    let t = s.time();
    let (pos, disp) = deformed(&s, 1.0);
    let max = disp.iter().copied().fold(0.0, Real::max);
    let mut scene = Scene::new();
    let style = MeshStyle {
        edges: Some(rgba(20, 20, 30, 70)),
        ..Default::default()
    };
    scene.add_mesh_scalar(&pos, &mesh.triangles, &disp, (0.0, max), &style)?;
    for w in polyline.windows(2) {
        scene.add_segment(
            pos[w[0] as usize],
            pos[w[1] as usize],
            rgba(0, 0, 0, 255),
            3.0,
        );
    }
    // Arrows: the group's total force, 1 mN drawn 3 mm long.
    for (g, (_, profile)) in groups.iter().zip(&forces) {
        let f = profile.force_at(t);
        let at = g.iter().map(|&i| pos[i as usize]).sum::<Vector>() / g.len() as Real;
        for &i in g {
            scene.add_point(pos[i as usize], rgba(220, 30, 30, 255), 2.0);
        }
        if f.length() > 0.0 {
            scene.add_arrow(
                at,
                at + f * (g.len() as Real) * 5.0,
                rgba(220, 30, 30, 255),
                3.0,
            );
        }
    }
    println!(
        "fig7: t = {t:.2} s, largest displacement {:.2} mm",
        max * 1000.0
    );
    scene.set_title(format!(
        "FIG 7 ORGAN, {} NODES, T = {t:.1} S (EXACT FILTER)\n6 FORCES (RED, 3 MM PER MN), PINNED POLYLINE (BLACK)",
        mesh.num_vertices()
    ));
    scene.set_legend(legend(max));
    let cam = scene
        .fit_camera(
            Vector::new(-0.5, -0.8, -1.0),
            Vector::Y,
            Projection::Perspective { fov_y: 0.6 },
            W,
            H,
        )
        .zoomed(1.1);
    save(&scene, &cam, dir, "fig7_organ.png")
}

fn main() -> Result<(), Box<dyn Error>> {
    let dir = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "docs/img".into()));
    std::fs::create_dir_all(&dir)?;
    let t0 = std::time::Instant::now();
    fig4(&dir)?;
    fig6(&dir)?;
    fig7(&dir)?;
    println!("done in {:.1} s", t0.elapsed().as_secs_f64());
    Ok(())
}
