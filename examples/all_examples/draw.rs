//! Drawing (immediate mode: drawn on the next frame only, so every frame).

use super::*;

pub(crate) fn line(viewer: &mut TestbedViewer, a: Vector, b: Vector, color: Color, width: f32) {
    viewer.window_mut().draw_line(a, b, color, width, false);
}

pub(crate) fn point(viewer: &mut TestbedViewer, p: Vector, color: Color, size: f32) {
    viewer.window_mut().draw_point(p, color, size);
}

/// A line with a small head at `to`.
pub(crate) fn arrow(
    viewer: &mut TestbedViewer,
    from: Vector,
    to: Vector,
    color: Color,
    width: f32,
) {
    line(viewer, from, to, color, width);
    let d = to - from;
    let len = d.length();
    if len.is_nan() || len <= 1e-9 {
        return;
    }
    let dir = d / len;
    let side = dir.any_orthonormal_vector();
    let up = dir.cross(side);
    let head = 0.25 * len;
    for s in [side, -side, up, -up] {
        line(viewer, to, to - dir * head + s * (0.4 * head), color, width);
    }
}

/// The edges of `mesh` at `pose`.
pub(crate) fn wireframe(
    viewer: &mut TestbedViewer,
    mesh: &TouchMesh,
    pose: &Pose,
    color: Color,
    w: f32,
) {
    for [a, b] in mesh.edges() {
        let pa = pose.transform_point(mesh.vertices()[*a as usize]);
        let pb = pose.transform_point(mesh.vertices()[*b as usize]);
        line(viewer, pa, pb, color, w);
    }
}

/// The touching vertices and edges of one mesh, yellow (touching faces show as the patch).
pub(crate) fn features(
    viewer: &mut TestbedViewer,
    mesh: &TouchMesh,
    pose: &Pose,
    list: &[Feature],
) {
    let at = |v: u32| pose.transform_point(mesh.vertices()[v as usize]);
    for f in list {
        match *f {
            Feature::Vertex(v) => point(viewer, at(v), YELLOW, 12.0),
            Feature::Edge([a, b]) => line(viewer, at(a), at(b), YELLOW, 4.0),
            Feature::Face(_) => {}
        }
    }
}

/// A contact patch at first touch: the polygon, segment or point in red with its points, and
/// the reversing vector `rv` as a green arrow ending at the patch centre.
pub(crate) fn patch(viewer: &mut TestbedViewer, p: &ContactPatch, rv: Vector) {
    match p.kind {
        ContactKind::Face => {
            let n = p.polygon.len();
            for k in 0..n {
                line(viewer, p.polygon[k], p.polygon[(k + 1) % n], RED, 4.0);
            }
        }
        ContactKind::Edge => {
            if let (Some(a), Some(b)) = (p.polygon.first(), p.polygon.last()) {
                line(viewer, *a, *b, RED, 6.0);
            }
        }
        ContactKind::Vertex => {}
    }
    for q in &p.points {
        point(viewer, q.point, RED, 9.0);
    }
    if rv.length() > 0.0 {
        let c = p.center();
        arrow(viewer, c - rv, c, GREEN, 3.0);
    }
}

/// Points the camera from `eye` at `at`, aimed left of `at` so the scene shows right of the
/// testbed's panels (which cover the left of the window), and shows the scene's first label
/// in the example settings.
pub(crate) fn look(
    viewer: &mut TestbedViewer,
    [eye, at]: [Vector; 2],
    label: &'static str,
    text: impl Into<String>,
) {
    let right = (at - eye).cross(Vector::Y).normalize_or_zero();
    let shift = right * (0.25 * (at - eye).length());
    viewer.look_at(eye - shift, at - shift);
    viewer.example_settings_mut().set_label(label, text);
}

pub(crate) fn mm(v: Vector) -> String {
    format!("({:.1}, {:.1}, {:.1}) mm", v.x * 1e3, v.y * 1e3, v.z * 1e3)
}

pub(crate) fn kinds(patches: &[ContactPatch]) -> String {
    if patches.is_empty() {
        return "none".into();
    }
    let k: Vec<String> = patches.iter().map(|p| format!("{:?}", p.kind)).collect();
    k.join(", ")
}
