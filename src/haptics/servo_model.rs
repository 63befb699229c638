//! The local contact model a world step hands to a servo loop, and how the servo loop reads it
//! at device rate.

use crate::geometry::tool_boundary::boundary_point;
use crate::math::{Matrix, Pose, Real, Vector};
use parry3d::math::MatExt;
use rapier3d::geometry::SharedShape;

/// A surface vertex near a tool that was not in contact with it at the last world step (world
/// frame, as that step left it), and the stiffness it resists a first touch with.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PatchVertex {
    /// Its position (world) at the last world step.
    pub position: Vector,
    /// How hard it pushes back per metre it is pushed in (N/m).
    pub stiffness: Real,
}

/// A surface vertex a smooth tool (a ball, a capsule, a rounded shape) held at the last world
/// step, for the contact's turning normals between world steps (see [`ServoModel`]).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct HeldVertex {
    /// Its position (world) at the last world step.
    pub position: Vector,
    /// The normal force it put on the tool there (N, at least 0).
    pub load: Real,
    /// The tool's outward normal at it then (unit, world).
    pub normal: Vector,
    /// Its share of the contact's normal stiffness (N/m): the load grows by this much per
    /// metre its anchor lies deeper in the tool. 0: its load is kept as it turns.
    pub stiffness: Real,
    /// How deep behind the tool's surface its anchor lies (m, along `-normal`): where its
    /// springs would take it without the tool (`load / stiffness`), but no deeper than a
    /// quarter of the tool's smallest half extent (an anchor near the tool's middle would
    /// change sides as the tool moves).
    pub depth: Real,
}

/// What one tool's servo loop needs between two world steps: the full surface solution's force
/// at the tool pose the world stepped to, the contact's stiffness around it, and, while the
/// tool touches nothing, the surface vertices near it (for contacts that start between world
/// steps). Its size depends on the contact and the tool's neighbourhood, not on the mesh.
///
/// Between world updates the servo loop renders
/// - in contact (`force` not zero): `force - stiffness · (x - x₀)` for the tool's reference
///   point at `x` (`x₀` the pose the world stepped to), the linearisation of the surface's
///   force around the last full solution; the contact lets go (no force at all) where the
///   part along `force` would turn into a pull, unless the tool grasps.
/// - in contact, on a smooth tool (a ball, a capsule, a rounded shape: `held` not empty):
///   each [`HeldVertex`] pushes along the tool's normal at the boundary point nearest its
///   *anchor* (a point `depth` behind the surface at the world step, where its springs would
///   take it without the tool), its load growing with its stiffness as the anchor lies
///   deeper; the part of `stiffness` the held normals do not carry stays linear. A vertex held
///   on a ball's side slides round it as the ball slides past, its force turning and easing
///   off: a stiffness that is not positive and that no symmetric positive matrix holds (a
///   capsule dragged over a coarse stiff plate: the linear model alone got the force's change
///   at right angles to the true one). A [`PatchVertex`] the tool reaches meanwhile (one it
///   did not hold at the world step) pushes as at a first touch, from zero at the tool's
///   surface, so a vertex captured between world updates does not arrive as a jump at the
///   next one;
/// - out of contact: the deepest [`PatchVertex`] the tool's shape contains at `x` (turned as at
///   the world step) pushes the tool out with its stiffness times its depth. One point, not a
///   sum over the vertices inside: a membrane's stiffness under a tool does not grow with the
///   number of vertices the tool covers (it is about `2πT / ln(R/a)` for tension `T`, span `R`
///   and contact radius `a`), so a sum would make a fine mesh feel as many times stiffer.
///
/// Rotation is not rendered: the model is for the tool's translation (a 3-DoF device); a
/// 6-DoF device gets no torque from it. The contact's tangential (friction) force is carried
/// in `force` and in `stiffness` like the normal one.
///
/// # Example
/// A contact pushing up with 2 N at the origin, 100 N/m stiff along y:
/// ```
/// use rapier_touch::haptics::ServoModel;
/// use rapier_touch::prelude::{Pose, Vector};
/// use rapier_touch::rapier3d::math::Matrix;
///
/// let model = ServoModel {
///     sequence: 1,
///     tool_pose: Pose::IDENTITY,
///     force: Vector::new(0.0, 2.0, 0.0),
///     stiffness: Matrix::from_diagonal(Vector::new(0.0, 100.0, 0.0)),
///     ..ServoModel::default()
/// };
/// // 1 cm deeper: 3 N; 3 cm out: contact lost, no force.
/// assert!((model.force_at(Vector::new(0.0, -0.01, 0.0)).y - 3.0).abs() < 1e-4);
/// assert_eq!(model.force_at(Vector::new(0.0, 0.03, 0.0)), Vector::ZERO);
/// ```
#[derive(Clone, Debug)]
pub struct ServoModel {
    /// How many world updates the link has published (0: none yet; a new model, a new number).
    pub sequence: u64,
    /// The tool's pose at the world step (its reference point is `tool_pose.translation`).
    pub tool_pose: Pose,
    /// The surfaces' force on the tool at `tool_pose` (world, N) if it stays there: the full
    /// solution less what the held vertices' dampers put on the tool's last move (they let go
    /// when it stops; on a heavily damped surface most of a moving press's force).
    pub force: Vector,
    /// The contact's stiffness around `tool_pose` (N/m, symmetric positive semi-definite): what
    /// the next world update meets a move with, dampers included; no coupling between the
    /// normal (along `force`) and the tangent directions.
    pub stiffness: Matrix,
    /// Whether the tool grasps: its contact may pull.
    pub grasping: bool,
    /// The tool's shape, for contacts that start between world steps.
    pub shape: Option<SharedShape>,
    /// Surface vertices near the tool that it did not touch at the world step: every one out
    /// of contact; in contact, those near a smooth tool holding a few vertices (`held` not
    /// empty), and none otherwise.
    pub patch: Vec<PatchVertex>,
    /// The surface vertices a smooth tool holds (empty for other tools, and out of contact).
    pub held: Vec<HeldVertex>,
    /// `false` when the world side has let the tool go (removed, disconnected, or dropped):
    /// nothing is rendered.
    pub attached: bool,
}

impl Default for ServoModel {
    /// No world update yet: no force anywhere.
    fn default() -> Self {
        ServoModel {
            sequence: 0,
            tool_pose: Pose::IDENTITY,
            force: Vector::ZERO,
            stiffness: Matrix::ZERO,
            grasping: false,
            shape: None,
            patch: Vec::new(),
            held: Vec::new(),
            attached: true,
        }
    }
}

/// Most patch vertices the world hands to a servo loop (the nearest are kept); the servo
/// reserves this much so that it never allocates while running.
pub(crate) const MAX_PATCH: usize = 4096;

/// Newton iterations of the proxy solve (the force is piecewise linear: a few settle it).
const PROXY_ITERATIONS: usize = 8;

impl ServoModel {
    /// Whether the tool was in contact at the world step.
    pub fn in_contact(&self) -> bool {
        self.force != Vector::ZERO
    }

    /// The surfaces' force on the tool with its reference point at `x` (world), and its
    /// stiffness there (`-∂f/∂x`). Not finite inputs give no force.
    pub fn force_and_stiffness_at(&self, x: Vector) -> (Vector, Matrix) {
        if !self.attached || !x.is_finite() {
            return (Vector::ZERO, Matrix::ZERO);
        }
        if self.in_contact() {
            let (f, k) = match self.shape.as_deref() {
                Some(shape) if !self.held.is_empty() => self.smooth_contact(shape, x),
                _ => (
                    self.force - self.stiffness * (x - self.tool_pose.translation),
                    self.stiffness,
                ),
            };
            let along = self.force.normalize_or_zero();
            if !f.is_finite() || !k.is_finite() || (!self.grasping && f.dot(along) < 0.0) {
                return (Vector::ZERO, Matrix::ZERO);
            }
            return (f, k);
        }
        let Some(shape) = &self.shape else {
            return (Vector::ZERO, Matrix::ZERO);
        };
        let pose = Pose::from_parts(x, self.tool_pose.rotation);
        match deepest_inside(shape.as_ref(), &pose, &self.patch) {
            Some((n, depth, k)) if (n * (k * depth)).is_finite() => {
                (n * (k * depth), outer(n, n) * k)
            }
            _ => (Vector::ZERO, Matrix::ZERO),
        }
    }

    /// How much the held vertices' normal forces change when their normals turn, the tool's
    /// reference point at `x` instead of `x₀` (each load kept).
    pub(crate) fn turning(&self, x: Vector) -> Vector {
        let Some(shape) = self.shape.as_deref().filter(|_| !self.held.is_empty()) else {
            return Vector::ZERO;
        };
        let pose = Pose::from_parts(x, self.tool_pose.rotation);
        let mut df = Vector::ZERO;
        for v in &self.held {
            let n = normal_at(shape, &pose, v.position).unwrap_or(v.normal);
            df += (v.normal - n) * v.load;
        }
        if df.is_finite() {
            df
        } else {
            Vector::ZERO
        }
    }

    /// A smooth tool's contact with its reference point at `x`: each held vertex pushes along
    /// the tool's normal at the boundary point nearest its anchor, its load changed by its
    /// stiffness times how much deeper the anchor lies than at the world step; the part of
    /// `stiffness` the held vertices' normals do not carry (friction, the vertices' coupling)
    /// stays linear. Force and the stiffness the proxy's steps go by (the linear one), as
    /// [`ServoModel::force_and_stiffness_at`].
    fn smooth_contact(&self, shape: &dyn parry3d::shape::Shape, x: Vector) -> (Vector, Matrix) {
        let pose = Pose::from_parts(x, self.tool_pose.rotation);
        let mut f = self.force;
        let mut carried = Matrix::ZERO;
        for v in &self.held {
            let (n, load) = if v.stiffness > 0.0 {
                carried += outer(v.normal, v.normal) * v.stiffness;
                let anchor = v.position - v.normal * v.depth;
                let (depth, n) = boundary_offset(shape, &pose, anchor).unwrap_or((0.0, v.normal));
                (n, (v.load + v.stiffness * (depth - v.depth)).max(0.0))
            } else {
                (
                    normal_at(shape, &pose, v.position).unwrap_or(v.normal),
                    v.load,
                )
            };
            f += v.normal * v.load - n * load;
        }
        // A vertex the tool reaches between world steps pushes as a first touch does, from
        // zero at the tool's surface: the deepest one only, as out of contact.
        let mut captured = Matrix::ZERO;
        if let Some((n, depth, k)) = deepest_inside(shape, &pose, &self.patch) {
            f += n * (k * depth);
            captured = outer(n, n) * k;
        }
        (
            f - (self.stiffness - carried) * (x - self.tool_pose.translation),
            self.stiffness + captured,
        )
    }

    /// [`ServoModel::force_and_stiffness_at`]'s force.
    pub fn force_at(&self, x: Vector) -> Vector {
        self.force_and_stiffness_at(x).0
    }

    /// The proxy of a device at `device` (world) held to it by a spring of
    /// `coupling_stiffness` (N/m): where a massless tool rests between that spring and the
    /// surfaces (`k (device - proxy) + f(proxy) = 0`), and the surfaces' force there. Newton
    /// steps on the piecewise linear force, from the device's position.
    pub fn proxy(&self, device: Vector, coupling_stiffness: Real) -> (Vector, Vector) {
        rest_proxy(device, coupling_stiffness, |x| {
            self.force_and_stiffness_at(x)
        })
    }

    /// Copies `other` into `self`, reusing `self`'s patch storage (no allocation once the
    /// patch has room: the servo thread keeps its models this way).
    pub fn copy_from(&mut self, other: &ServoModel) {
        self.sequence = other.sequence;
        self.tool_pose = other.tool_pose;
        self.force = other.force;
        self.stiffness = other.stiffness;
        self.grasping = other.grasping;
        self.shape.clone_from(&other.shape);
        self.patch.clear();
        self.patch.extend_from_slice(&other.patch);
        self.held.clear();
        self.held.extend_from_slice(&other.held);
        self.attached = other.attached;
    }
}

/// The deepest of `patch`'s vertices inside `shape` at `pose`: the direction from the boundary
/// point nearest it to it (the way it pushes the tool), its depth and its stiffness. Vertices
/// outside the shape's bounding sphere are skipped before the point query.
fn deepest_inside(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    patch: &[PatchVertex],
) -> Option<(Vector, Real, Real)> {
    if patch.is_empty() {
        return None;
    }
    let sphere = shape.compute_local_bounding_sphere();
    let (centre, r2) = (
        pose.transform_point(sphere.center),
        sphere.radius * sphere.radius,
    );
    let mut deepest: Option<(Vector, Real, Real)> = None;
    for v in patch {
        if (v.position - centre).length_squared() > r2 {
            continue;
        }
        if let Some((depth, n)) = boundary_offset(shape, pose, v.position) {
            if depth > 0.0 && deepest.is_none_or(|d| depth > d.1) {
                deepest = Some((-n, depth, v.stiffness));
            }
        }
    }
    deepest
}

/// `a bᵀ`.
pub(crate) fn outer(a: Vector, b: Vector) -> Matrix {
    Matrix::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Where `p` lies from the boundary of `shape` at `pose`: how deep inside (negative: how far
/// outside) and the outward normal at the boundary point nearest it (along `p`'s offset from
/// that point). `None` on the boundary itself (the offset gives no direction) or when not
/// finite.
fn boundary_offset(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    p: Vector,
) -> Option<(Real, Vector)> {
    // The coupling's own boundary query (exact on rounded shapes and inside polyhedra, where
    // parry's projection is iterative), so the model and the full solution agree on it.
    let (near, inside) = boundary_point(shape, pose, p);
    let d = near - p;
    let len = d.length();
    let n = d.try_normalize()?;
    let (depth, n) = if inside { (len, n) } else { (-len, -n) };
    (len > 0.0 && n.is_finite()).then_some((depth, n))
}

/// The outward normal (world) of `shape` at `pose` at the boundary point nearest `p`, along
/// `p`'s offset from that point. `None` when `p` lies on the boundary (within 1e-5 of the
/// shape's size: the offset gives no direction there) or the answer is not finite.
pub(crate) fn normal_at(
    shape: &dyn parry3d::shape::Shape,
    pose: &Pose,
    p: Vector,
) -> Option<Vector> {
    let size = shape.compute_local_aabb().half_extents().max_element();
    boundary_offset(shape, pose, p)
        .filter(|(depth, _)| depth.abs() > 1e-5 * size)
        .map(|(_, n)| n)
}

/// Whether `shape`'s normals turn smoothly over its whole boundary (a ball, a capsule, a
/// rounded shape): no edge or rim where a held vertex's normal would jump.
pub(crate) fn is_smooth(shape: &dyn parry3d::shape::Shape) -> bool {
    use parry3d::shape::ShapeType;
    matches!(
        shape.shape_type(),
        ShapeType::Ball
            | ShapeType::Capsule
            | ShapeType::RoundCuboid
            | ShapeType::RoundCylinder
            | ShapeType::RoundCone
            | ShapeType::RoundConvexPolyhedron
    )
}

/// [`ServoModel::proxy`] for any piecewise linear force `model(x) = (f, -∂f/∂x)`.
pub(crate) fn rest_proxy(
    device: Vector,
    coupling_stiffness: Real,
    model: impl Fn(Vector) -> (Vector, Matrix),
) -> (Vector, Vector) {
    rest_proxy_from(None, device, coupling_stiffness, model)
}

/// [`rest_proxy`], also searched from `start` (the last tick's proxy): the answer with the
/// smaller residual. The force is piecewise linear with kinks where contacts begin and end, so
/// Newton's steps from the device alone may land on the far side of a kink and stop there: a
/// hand lifting off the 100,000-node sphere had the proxy thrown from its last rest to the
/// device (0.46 N of a 1.7 N press within one tick), and a new model's rest, eased in to agree
/// with the last tick at the last proxy, was found 40 µm away from it (0.39 N).
pub(crate) fn rest_proxy_from(
    start: Option<Vector>,
    device: Vector,
    coupling_stiffness: Real,
    model: impl Fn(Vector) -> (Vector, Matrix),
) -> (Vector, Vector) {
    let kc = coupling_stiffness.max(0.0);
    let (f, k) = model(device);
    if f == Vector::ZERO || kc == 0.0 || !device.is_finite() {
        return (device, f);
    }
    let residual = |x: Vector, f: Vector| (device - x) * kc + f;
    let solve = |mut x: Vector, mut f: Vector, mut k: Matrix| {
        let mut r = residual(x, f);
        for _ in 0..PROXY_ITERATIONS {
            // The contact's positive part: a stiffness that falls along the motion (a
            // deformed surface pushing the tool on) does not steer the steps.
            let jac = Matrix::from_diagonal(Vector::splat(kc)) + positive_part(&k);
            let Some(mut step) = Some(jac.inverse() * r).filter(|s| s.is_finite()) else {
                break;
            };
            // Halved while it does not bring the residual down (a kink crossed).
            let mut better = None;
            for _ in 0..BACKTRACKS {
                let x_new = x + step;
                let (f_new, k_new) = model(x_new);
                let r_new = residual(x_new, f_new);
                if r_new.length() < r.length() {
                    better = Some((x_new, f_new, k_new, r_new));
                    break;
                }
                step *= 0.5;
            }
            let Some(b) = better else {
                break;
            };
            (x, f, k, r) = b;
            if r.length() <= 1e-6 * (f.length() + kc * 1e-6) {
                break;
            }
        }
        let converged = r.length() <= 1e-6 * (f.length() + kc * 1e-6);
        (x, f, r.length(), converged)
    };
    let (mut x, mut f, r, converged) = solve(device, f, k);
    // From the last proxy only where the device's start stopped short (a kink).
    if let Some(p) = start.filter(|p| p.is_finite() && !converged) {
        let (fp, kp) = model(p);
        let (xp, fp, rp, _) = solve(p, fp, kp);
        if rp < r {
            (x, f) = (xp, fp);
        }
    }
    (x, f)
}

/// Tries of a proxy step that does not reduce the residual: the step, then halved twice.
const BACKTRACKS: usize = 3;

/// The positive semi-definite part of a symmetric matrix (negative eigenvalues dropped).
pub(crate) fn positive_part(m: &Matrix) -> Matrix {
    let eig = m.symmetric_eigen();
    let v = eig.eigenvectors;
    let psd = v * Matrix::from_diagonal(eig.eigenvalues.max(Vector::ZERO)) * v.transpose();
    if psd.is_finite() {
        psd
    } else {
        Matrix::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A constant push into a surface (an eased-in offset) beside a stiff contact below y = 0,
    /// the device just over the surface: the first Newton step from the device lands deep in
    /// the contact, where the residual is larger. The rest, solved by hand on the contact's
    /// piece: `kc (y_d - y) - a - k y = 0`.
    #[test]
    fn the_proxy_rests_across_a_kink_the_first_step_overshoots() {
        let (kc, k, a, y_d) = (1.0e4, 1.0e5, 0.5, 1.0e-5);
        let model = |x: Vector| {
            let contact = if x.y < 0.0 { -k * x.y } else { 0.0 };
            let stiff = if x.y < 0.0 { k } else { 0.0 };
            (
                Vector::new(0.0, contact - a, 0.0),
                Matrix::from_diagonal(Vector::new(0.0, stiff, 0.0)),
            )
        };
        let device = Vector::new(0.0, y_d, 0.0);
        let expect = (kc * y_d - a) / (kc + k);
        for start in [None, Some(Vector::new(0.0, 0.01, 0.0)), Some(device)] {
            let (proxy, f) = rest_proxy_from(start, device, kc, model);
            assert!(
                (proxy.y - expect).abs() < 1e-9,
                "{start:?}: {proxy} against {expect}"
            );
            assert!(((device - proxy) * kc + f).length() < 1e-6);
        }
        // From the last rest, it stays there.
        let last = Vector::new(0.0, expect, 0.0);
        let (proxy, _) = rest_proxy_from(Some(last), device, kc, model);
        assert!((proxy - last).length() < 1e-9);
    }
}
