//! A small headless software renderer (cargo feature `render`), for pictures of contacts and
//! soft surfaces without a window or a GPU.
//!
//! A [`Scene`] collects world-space triangle meshes (flat Lambert shading, optional per-vertex
//! scalar colouring through [`viridis`]), points, segments, arrows and polygons; a [`Camera`]
//! (look-at, perspective or orthographic, [`Camera::fit`] to the scene) projects them and
//! [`Scene::render`] paints them with [`tiny_skia`]. Triangles are drawn far to near (painter's
//! algorithm, no depth buffer); points, segments, arrows and polygons are drawn over the meshes,
//! in the order they were added. A built-in 3 × 5 pixel font writes the title and the legend
//! (digits, `A`-`Z` and `.-:=/()+,%|_'*<>[]`; lower case is drawn as upper case, `\n` starts a
//! line); [`draw_text`] writes with it on any picture.
//!
//! [`plot::LinePlot`] draws line plots (numbers over time) with `plotters`' bitmap backend and
//! the same font, so neither needs a system font library.

use crate::math::{Pose, Real, Vector};
use tiny_skia::{FillRule, LineCap, LineJoin, Paint, PathBuilder, Rect, Stroke, Transform};

mod camera;
pub mod plot;
mod text;

use camera::*;
pub use camera::{Camera, Projection};
use text::*;
pub use text::{draw_text, text_size};

pub use tiny_skia::{Color, Pixmap};

/// Why a picture could not be made or written.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Width or height is zero, or the picture is too large for tiny-skia.
    #[error("cannot make a {0} x {1} picture")]
    InvalidSize(u32, u32),
    /// [`Scene::add_mesh_scalar`] got a number of values different from the vertex count.
    #[error("{got} scalar values for {expected} vertices")]
    ScalarCount {
        /// The number of vertices.
        expected: usize,
        /// The number of values given.
        got: usize,
    },
    /// The PNG could not be encoded or written.
    #[error("cannot write the PNG: {0}")]
    Png(String),
}

/// A colour from channels, each clamped to `0..=1`.
fn rgba(r: f32, g: f32, b: f32, a: f32) -> Color {
    let c = |x: f32| {
        if x.is_finite() {
            x.clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    Color::from_rgba(c(r), c(g), c(b), c(a)).unwrap_or(Color::BLACK)
}

/// The viridis colour map (a polynomial fit), `t` clamped to `0..=1`: dark purple, blue, green,
/// yellow.
pub fn viridis(t: Real) -> Color {
    const C: [[f32; 3]; 7] = [
        [0.277_727_33, 0.005_407_344, 0.334_099_8],
        [0.105_093_04, 1.404_613_5, 1.384_590_2],
        [-0.330_861_83, 0.214_847_56, 0.095_095_16],
        [-4.634_230_6, -5.799_101, -19.332_441],
        [6.228_27, 14.179_933, 56.690_55],
        [4.776_385, -13.745_146, -65.353_03],
        [-5.435_456, 4.645_852_6, 26.312_435],
    ];
    let t = valid(t, Real::NEG_INFINITY, Real::INFINITY, 0.0).clamp(0.0, 1.0);
    let ch = |k: usize| C.iter().rev().fold(0.0, |acc, c| acc * t + c[k]);
    rgba(ch(0), ch(1), ch(2), 1.0)
}

/// How [`Scene::add_mesh`] draws a mesh.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct MeshStyle {
    /// Fill colour; its alpha below 1 makes the mesh semi-transparent.
    /// [`Scene::add_mesh_scalar`] uses only the alpha.
    pub color: Color,
    /// Colour of the triangle edges, if drawn.
    pub edges: Option<Color>,
    /// Edge width in pixels.
    pub edge_width: f32,
}

impl Default for MeshStyle {
    /// Opaque light blue-grey, no edges.
    fn default() -> Self {
        let color = Color::from_rgba8(170, 180, 195, 255);
        MeshStyle {
            color,
            edges: None,
            edge_width: 1.0,
        }
    }
}

/// A colour-bar legend for [`viridis`], drawn at the picture's right edge.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Legend {
    /// Written above the bar.
    pub title: String,
    /// Written at the bar's bottom (the value mapped to 0).
    pub low: String,
    /// Written at the bar's top (the value mapped to 1).
    pub high: String,
}

#[derive(Clone, Debug)]
struct Tri {
    p: [Vector; 3],
    c: [Color; 3],
    edges: Option<(Color, f32)>,
}

#[derive(Clone, Debug)]
enum Overlay {
    Point(Vector, Color, f32),
    Segment(Vector, Vector, Color, f32),
    Arrow(Vector, Vector, Color, f32),
    Polygon(Vec<Vector>, Color, Color, f32),
}

/// World-space things to draw and how to light them; see the [module docs](self).
///
/// ```no_run
/// use rapier_touch::prelude::*;
/// use rapier_touch::render::{Color, MeshStyle, Projection, Scene};
///
/// let plate = rapier_touch::surface::meshing::plate(1.0, 1.0, 8, 8);
/// let mut scene = Scene::new();
/// scene.add_mesh(&plate.vertices, &plate.triangles, &MeshStyle::default());
/// let red = Color::from_rgba8(200, 0, 0, 255);
/// scene.add_arrow(Vector::new(0.0, 0.5, 0.0), Vector::ZERO, red, 3.0);
/// scene.set_title("a plate");
/// let view = Vector::new(-1.0, -1.0, -1.5);
/// let persp = Projection::Perspective { fov_y: 0.6 };
/// let camera = scene.fit_camera(view, Vector::Y, persp, 800, 600);
/// let path = std::env::temp_dir().join("plate.png");
/// scene.save_png(&camera, 800, 600, path).unwrap();
/// ```
#[derive(Clone, Debug)]
pub struct Scene {
    tris: Vec<Tri>,
    overlays: Vec<Overlay>,
    legend: Option<Legend>,
    title: Option<String>,
    /// Picture background (white).
    pub background: Color,
    /// Direction toward the light, in camera space (`x` right, `y` up, `z` toward the viewer).
    pub light: Vector,
    /// Share of a triangle's colour it keeps when lit edge-on (0..1; 0.35).
    pub ambient: f32,
}

impl Default for Scene {
    fn default() -> Self {
        Self::new()
    }
}

impl Scene {
    /// An empty scene: white background, light from the upper left behind the viewer.
    pub fn new() -> Self {
        Scene {
            tris: Vec::new(),
            overlays: Vec::new(),
            legend: None,
            title: None,
            background: Color::WHITE,
            light: Vector::new(-0.4, 0.6, 1.0).normalize(),
            ambient: 0.35,
        }
    }

    /// Adds a world-space triangle mesh in one colour. Triangles with an index out of range
    /// or a non-finite vertex are skipped.
    pub fn add_mesh(&mut self, vertices: &[Vector], triangles: &[[u32; 3]], style: &MeshStyle) {
        self.push_mesh(vertices, triangles, style, |_| style.color);
    }

    /// Adds a world-space triangle mesh coloured per vertex: `values[i]` mapped from
    /// `range = (low, high)` onto [`viridis`] (interpolated across each triangle). The style's
    /// alpha and edges apply. Errors if `values` does not have one value per vertex.
    pub fn add_mesh_scalar(
        &mut self,
        vertices: &[Vector],
        triangles: &[[u32; 3]],
        values: &[Real],
        (low, high): (Real, Real),
        style: &MeshStyle,
    ) -> Result<(), RenderError> {
        let (expected, got) = (vertices.len(), values.len());
        if expected != got {
            return Err(RenderError::ScalarCount { expected, got });
        }
        let span = valid(high - low, 0.0, Real::INFINITY, 1.0);
        self.push_mesh(vertices, triangles, style, |i| {
            let mut c = viridis((values[i] - low) / span);
            c.set_alpha(style.color.alpha());
            c
        });
        Ok(())
    }

    fn push_mesh(
        &mut self,
        v: &[Vector],
        t: &[[u32; 3]],
        s: &MeshStyle,
        c: impl Fn(usize) -> Color,
    ) {
        let edges = s.edges.map(|c| (c, s.edge_width));
        let vertex = |i: u32| v.get(i as usize).copied().filter(|p| p.is_finite());
        for &[a, b, d] in t {
            if let (Some(pa), Some(pb), Some(pd)) = (vertex(a), vertex(b), vertex(d)) {
                let c = [a, b, d].map(|i| c(i as usize));
                self.tris.push(Tri {
                    p: [pa, pb, pd],
                    c,
                    edges,
                });
            }
        }
    }

    /// Adds a parry shape at `pose` as a mesh: balls, cuboids, capsules, cylinders, cones,
    /// convex polyhedra and triangle meshes (curved shapes tessellated). Returns `false`, adding
    /// nothing, for other shapes.
    pub fn add_shape(
        &mut self,
        shape: &dyn parry3d::shape::Shape,
        pose: &Pose,
        style: &MeshStyle,
    ) -> bool {
        use parry3d::shape::TypedShape;
        let (vertices, triangles) = match shape.as_typed_shape() {
            TypedShape::Ball(b) => b.to_trimesh(24, 12),
            TypedShape::Cuboid(c) => c.to_trimesh(),
            TypedShape::Capsule(c) => c.to_trimesh(24, 8),
            TypedShape::Cylinder(c) => c.to_trimesh(24),
            TypedShape::Cone(c) => c.to_trimesh(24),
            TypedShape::ConvexPolyhedron(c) => c.to_trimesh(),
            TypedShape::TriMesh(m) => (m.vertices().to_vec(), m.indices().to_vec()),
            _ => return false,
        };
        let world: Vec<Vector> = vertices.iter().map(|v| pose.transform_point(*v)).collect();
        self.add_mesh(&world, &triangles, style);
        true
    }

    /// Adds a dot of `radius` pixels with a dark outline.
    pub fn add_point(&mut self, p: Vector, color: Color, radius: f32) {
        self.overlays.push(Overlay::Point(p, color, radius));
    }

    /// Adds a line segment `width` pixels wide.
    pub fn add_segment(&mut self, a: Vector, b: Vector, color: Color, width: f32) {
        self.overlays.push(Overlay::Segment(a, b, color, width));
    }

    /// Adds an arrow from `from` to `to` (the head at `to`), `width` pixels wide, with a white
    /// halo so it shows on any background.
    pub fn add_arrow(&mut self, from: Vector, to: Vector, color: Color, width: f32) {
        self.overlays.push(Overlay::Arrow(from, to, color, width));
    }

    /// Adds a filled polygon with an outline `width` pixels wide (nothing for fewer than 3
    /// points).
    pub fn add_polygon(&mut self, points: &[Vector], fill: Color, outline: Color, width: f32) {
        if points.len() >= 3 {
            let points = points.to_vec();
            self.overlays
                .push(Overlay::Polygon(points, fill, outline, width));
        }
    }

    /// Sets the title written at the top left (`\n` starts a new line).
    pub fn set_title(&mut self, title: impl Into<String>) {
        self.title = Some(title.into());
    }

    /// Sets the colour-bar legend.
    pub fn set_legend(&mut self, legend: Legend) {
        self.legend = Some(legend);
    }

    /// Every world-space point of the scene (mesh vertices, overlay points).
    pub fn points(&self) -> impl Iterator<Item = Vector> + '_ {
        let over = self.overlays.iter().flat_map(|o| match o {
            Overlay::Point(p, ..) => vec![*p],
            Overlay::Segment(a, b, ..) | Overlay::Arrow(a, b, ..) => vec![*a, *b],
            Overlay::Polygon(ps, ..) => ps.clone(),
        });
        self.tris.iter().flat_map(|t| t.p).chain(over)
    }

    /// [`Scene::frame`] on all of [`Scene::points`].
    pub fn fit_camera(&self, dir: Vector, up: Vector, proj: Projection, w: u32, h: u32) -> Camera {
        self.frame(self.points(), dir, up, proj, w, h)
    }

    /// [`Camera::fit`] to `points` for a `w × h` picture, leaving room for the title (top) and
    /// the legend (right) when they are set.
    pub fn frame(
        &self,
        points: impl IntoIterator<Item = Vector>,
        dir: Vector,
        up: Vector,
        proj: Projection,
        w: u32,
        h: u32,
    ) -> Camera {
        let top = self
            .title
            .as_ref()
            .map_or(0.0, |t| 20.0 + 18.0 * t.lines().count() as Real);
        let (w, h) = (w.max(1) as Real, h.max(1) as Real);
        let (dx, dy) = ((w - 110.0).max(0.5 * w), (h - top).max(0.5 * h));
        let dx = if self.legend.is_some() { dx } else { w };
        let cam = Camera::fit(points, dir, up, proj, dx / dy).zoomed(h / dy);
        let (r, u, _) = basis(cam.target - cam.eye, up);
        // Move the framed region to the middle of the room left.
        let shift = (r * 0.5 * (w - dx) + u * 0.5 * (h - dy)) * cam.world_per_pixel(h as u32);
        Camera {
            eye: cam.eye + shift,
            target: cam.target + shift,
            ..cam
        }
    }

    /// Paints the scene as seen by `camera` into a new `width × height` picture. Parts behind a
    /// perspective camera are left out; an empty scene gives the bare background.
    pub fn render(&self, camera: &Camera, width: u32, height: u32) -> Result<Pixmap, RenderError> {
        let mut pm = Pixmap::new(width, height).ok_or(RenderError::InvalidSize(width, height))?;
        pm.fill(self.background);
        let (r, u, f) = basis(camera.target - camera.eye, camera.up);
        let light = (r * self.light.x + u * self.light.y - f * self.light.z).normalize_or(-f);
        let proj = |p: Vector| camera.project(p, width, height);
        let xy = |p: Vector| proj(p).map(|s| (s.0, s.1));
        let mut order: Vec<(f32, usize)> = Vec::with_capacity(self.tris.len());
        for (k, t) in self.tris.iter().enumerate() {
            if let [Some(a), Some(b), Some(c)] = t.p.map(proj) {
                order.push(((a.2 + b.2 + c.2) / 3.0, k));
            }
        }
        order.sort_by(|a, b| b.0.total_cmp(&a.0));
        for (_, k) in order {
            let Tri { p, c, edges } = &self.tris[k];
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            let shade = self.ambient + (1.0 - self.ambient) * n.dot(light).abs();
            let corners = [0, 1, 2].map(|i| (p[i], c[i]));
            let subs = if c[1] == c[0] && c[2] == c[0] {
                vec![corners]
            } else {
                // Split in four so the colour follows the vertices.
                let [a, b, d] = corners;
                let mid = |(p, c): (Vector, Color), (q, e): (Vector, Color)| {
                    (0.5 * (p + q), mix(&[c, e]))
                };
                let (ab, bd, da) = (mid(a, b), mid(b, d), mid(d, a));
                vec![[a, ab, da], [ab, b, bd], [da, bd, d], [ab, bd, da]]
            };
            for sub in subs {
                let c = mix(&sub.map(|s| s.1));
                let col = rgba(
                    c.red() * shade,
                    c.green() * shade,
                    c.blue() * shade,
                    c.alpha(),
                );
                if let [Some(a), Some(b), Some(d)] = sub.map(|s| xy(s.0)) {
                    // An opaque outline of the same colour hides anti-aliasing seams.
                    let seam = (col.alpha() > 0.999).then_some((col, 0.7));
                    draw(&mut pm, &[a, b, d], true, Some(col), seam);
                }
            }
            if let [Some(a), Some(b), Some(d)] = p.map(xy) {
                draw(&mut pm, &[a, b, d], true, None, *edges);
            }
        }
        for o in &self.overlays {
            draw_overlay(&mut pm, o, &xy);
        }
        if let Some(l) = &self.legend {
            draw_legend(&mut pm, l);
        }
        if let Some(t) = &self.title {
            text(
                &mut pm,
                14.0,
                14.0,
                3.0,
                t,
                Color::from_rgba8(30, 30, 30, 255),
            );
        }
        Ok(pm)
    }

    /// [`Scene::render`], then writes the picture as a PNG file.
    pub fn save_png(
        &self,
        camera: &Camera,
        width: u32,
        height: u32,
        path: impl AsRef<std::path::Path>,
    ) -> Result<(), RenderError> {
        let pm = self.render(camera, width, height)?;
        pm.save_png(path)
            .map_err(|e| RenderError::Png(e.to_string()))
    }
}

/// The mean of some colours (channel by channel, alpha too).
fn mix(cs: &[Color]) -> Color {
    let n = cs.len().max(1) as f32;
    let s = |g: fn(&Color) -> f32| cs.iter().map(g).sum::<f32>() / n;
    rgba(
        s(Color::red),
        s(Color::green),
        s(Color::blue),
        s(Color::alpha),
    )
}

fn paint(c: Color) -> Paint<'static> {
    let mut p = Paint {
        anti_alias: true,
        ..Default::default()
    };
    p.set_color(c);
    p
}

/// Fills and/or strokes (colour, width) the polyline `pts` (a polygon if `close`).
fn draw(
    pm: &mut Pixmap,
    pts: &[(f32, f32)],
    close: bool,
    fill: Option<Color>,
    stroke: Option<(Color, f32)>,
) {
    let mut pb = PathBuilder::new();
    let Some((first, rest)) = pts.split_first() else {
        return;
    };
    pb.move_to(first.0, first.1);
    rest.iter().for_each(|p| pb.line_to(p.0, p.1));
    if close {
        pb.close();
    }
    let Some(path) = pb.finish() else { return };
    if let Some(c) = fill {
        pm.fill_path(
            &path,
            &paint(c),
            FillRule::Winding,
            Transform::identity(),
            None,
        );
    }
    if let Some((c, width)) = stroke {
        let (line_cap, line_join) = (LineCap::Round, LineJoin::Round);
        let s = Stroke {
            width,
            line_cap,
            line_join,
            ..Default::default()
        };
        pm.stroke_path(&path, &paint(c), &s, Transform::identity(), None);
    }
}

fn draw_overlay(pm: &mut Pixmap, o: &Overlay, xy: &dyn Fn(Vector) -> Option<(f32, f32)>) {
    let dark = Color::from_rgba8(20, 20, 20, 255);
    let halo = Color::from_rgba8(255, 255, 255, 210);
    match o {
        Overlay::Point(p, c, r) => {
            let Some((x, y)) = xy(*p) else { return };
            let n = 16;
            let ring: Vec<_> = (0..n)
                .map(|k| std::f32::consts::TAU * k as f32 / n as f32)
                .map(|a| (x + r * a.cos(), y + r * a.sin()))
                .collect();
            draw(
                pm,
                &ring,
                true,
                Some(*c),
                Some((dark, (0.3 * r).clamp(1.0, 2.0))),
            );
        }
        Overlay::Segment(a, b, c, w) => {
            if let (Some(a), Some(b)) = (xy(*a), xy(*b)) {
                draw(pm, &[a, b], false, None, Some((*c, *w)));
            }
        }
        Overlay::Arrow(a, b, c, w) => {
            let (Some(a), Some(b)) = (xy(*a), xy(*b)) else {
                return;
            };
            let len = (b.0 - a.0).hypot(b.1 - a.1);
            if len < 1e-3 {
                return;
            }
            let (ux, uy) = ((b.0 - a.0) / len, (b.1 - a.1) / len);
            let head = (4.0 * w).max(10.0).min(0.6 * len.max(8.0));
            let (bx, by, s) = (b.0 - ux * head, b.1 - uy * head, 0.45 * head);
            let tip = [b, (bx - uy * s, by + ux * s), (bx + uy * s, by - ux * s)];
            draw(pm, &[a, (bx, by)], false, None, Some((halo, w + 3.0)));
            draw(pm, &tip, true, None, Some((halo, 3.0)));
            draw(pm, &[a, (bx, by)], false, None, Some((*c, *w)));
            draw(pm, &tip, true, Some(*c), None);
        }
        Overlay::Polygon(ps, fc, oc, w) => {
            if let Some(pts) = ps.iter().map(|p| xy(*p)).collect::<Option<Vec<_>>>() {
                draw(pm, &pts, true, Some(*fc), Some((*oc, *w)));
            }
        }
    }
}

fn draw_legend(pm: &mut Pixmap, l: &Legend) {
    let (w, h) = (pm.width() as f32, pm.height() as f32);
    let (x, y0, y1, bw, n) = (w - 70.0, 0.25 * h, 0.8 * h, 22.0, 64);
    for k in 0..n {
        let ya = y1 - (y1 - y0) * (k + 1) as f32 / n as f32;
        if let Some(r) = Rect::from_xywh(x, ya, bw, (y1 - y0) / n as f32 + 0.5) {
            let c = paint(viridis((k as f32 + 0.5) / n as f32));
            pm.fill_rect(r, &c, Transform::identity(), None);
        }
    }
    let dark = Color::from_rgba8(30, 30, 30, 255);
    let frame = [(x, y0), (x + bw, y0), (x + bw, y1), (x, y1)];
    draw(pm, &frame, true, None, Some((dark, 1.0)));
    let left = |s: &str| (w - 8.0 - 8.0 * s.chars().count() as f32).min(x);
    text(pm, left(&l.high), y0 - 16.0, 2.0, &l.high, dark);
    text(pm, left(&l.low), y1 + 8.0, 2.0, &l.low, dark);
    text(pm, left(&l.title), y0 - 40.0, 2.0, &l.title, dark);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_and_bad_input_do_not_panic() {
        let ortho = Projection::Orthographic { half_height: 1.0 };
        let scene = Scene::new();
        let cam = scene.fit_camera(Vector::NEG_Z, Vector::Y, ortho, 64, 48);
        assert!(scene.render(&cam, 64, 48).is_ok());
        let err = scene.render(&cam, 0, 48);
        assert!(matches!(err, Err(RenderError::InvalidSize(0, 48))));
        let (mut s, style) = (Scene::new(), MeshStyle::default());
        s.add_mesh(&[Vector::ZERO], &[[0, 1, 2]], &style);
        assert!(s
            .add_mesh_scalar(&[Vector::ZERO], &[], &[], (0.0, 1.0), &style)
            .is_err());
        s.add_arrow(Vector::ZERO, Vector::ZERO, Color::BLACK, 2.0);
        s.add_polygon(&[Vector::ZERO], Color::BLACK, Color::BLACK, 1.0);
        s.add_point(Vector::NAN, Color::BLACK, 2.0);
        s.set_title("");
        let cam = Camera::look_at(Vector::Z, Vector::ZERO, Vector::Z);
        assert!(s.render(&cam, 32, 32).is_ok());
    }

    #[test]
    fn a_triangle_is_painted_in_front_of_the_camera() {
        let mut s = Scene::new();
        let v = [Vector::new(-1.0, -1.0, 0.0), Vector::X, Vector::Y].map(|p| p * 2.0);
        let red = Color::from_rgba8(255, 0, 0, 255);
        s.add_mesh(
            &v,
            &[[0, 1, 2]],
            &MeshStyle {
                color: red,
                ..Default::default()
            },
        );
        let persp = Projection::Perspective { fov_y: 0.6 };
        let pm = s.render(
            &s.fit_camera(Vector::NEG_Z, Vector::Y, persp, 40, 40),
            40,
            40,
        );
        let pm = pm.unwrap();
        let px = pm.pixel(20, 22).unwrap();
        assert!(px.red() > 150 && px.green() < 50, "{px:?}");
        assert_eq!(pm.pixel(1, 1).unwrap().green(), 255); // background
        assert!((viridis(0.0).blue() - 0.33).abs() < 0.01 && viridis(1.0).red() > 0.9);
    }
}
