//! Six rigid tools pressing and dragging on a soft organ dome: the scene of the `multi_tool`
//! example, with its scripted tool paths.

use super::{attach_fixed, paper_organ};
use crate::coupling::{SurfaceHandle, SurfaceSet, ToolReaction};
use crate::math::{Pose, Real, Rotation, Vector};
use crate::surface::meshing::SurfaceMesh;
use crate::surface::{Integrator, MassDistribution, MassSpringSurface, MassSpringSurfaceBuilder};
use rapier3d::prelude::*;

/// The shape of one of the [`MultiToolScene`] tools.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum ToolShape {
    /// A ball of this radius (m).
    Ball(Real),
    /// A cuboid with these half extents (m).
    Cuboid(Real, Real, Real),
}

impl ToolShape {
    /// A rapier collider of this shape.
    pub fn collider(self) -> ColliderBuilder {
        match self {
            ToolShape::Ball(r) => ColliderBuilder::ball(r),
            ToolShape::Cuboid(x, y, z) => ColliderBuilder::cuboid(x, y, z),
        }
    }

    /// A short description in millimetres, e.g. `ball r = 10 mm`.
    pub fn describe(self) -> String {
        match self {
            ToolShape::Ball(r) => format!("ball r = {:.0} mm", r * 1e3),
            ToolShape::Cuboid(x, y, z) => format!(
                "cuboid {:.0} x {:.0} x {:.0} mm, pitched 23 deg",
                2e3 * x,
                2e3 * y,
                2e3 * z
            ),
        }
    }
}

/// One tool of the [`MultiToolScene`]: its shape, orientation and drag path in plan.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ToolSpec {
    /// The tool's shape.
    pub shape: ToolShape,
    /// Its orientation (scaled axis, rad).
    pub tilt: Vector,
    /// Where it comes down, `(u, v) = (x, z)` (m).
    pub from: [Real; 2],
    /// Where its drag ends, `(u, v) = (x, z)` (m).
    pub to: [Real; 2],
}

/// The six tools of the [`MultiToolScene`], in the order they come down: five balls (radius 7
/// to 12 mm) and a 16 × 8 × 12 mm cuboid pitched 23° about the axis across its drag, leading
/// edge up, like a sled.
pub fn multi_tool_specs() -> [ToolSpec; 6] {
    let ball = |r: Real, from: [Real; 2], to: [Real; 2]| ToolSpec {
        shape: ToolShape::Ball(r),
        tilt: Vector::ZERO,
        from,
        to,
    };
    [
        ball(0.010, [0.045, 0.022], [0.045, -0.018]),
        ball(0.008, [-0.035, 0.022], [-0.005, 0.025]),
        ToolSpec {
            shape: ToolShape::Cuboid(0.008, 0.004, 0.006),
            // Pitched about z: the +x (leading) bottom edge up.
            tilt: Vector::new(0.0, 0.0, 0.4),
            from: [-0.012, 0.0],
            to: [0.018, 0.002],
        },
        ball(0.012, [-0.03, -0.025], [0.0, -0.03]),
        ball(0.007, [0.012, 0.028], [0.035, 0.025]),
        ball(0.009, [0.062, 0.018], [0.062, -0.005]),
    ]
}

/// Where a [`MultiToolScene`] tool is in its script.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum ToolPhase {
    /// Above the organ, before its start.
    Waiting,
    /// Coming down.
    Descending,
    /// Pressed in at its first spot.
    Pressing,
    /// Dragged sideways, pressed in.
    Dragging,
    /// Pressed in at the end of its drag.
    Holding,
    /// Lifting off.
    Lifting,
    /// Lifted off, above the organ.
    Done,
}

impl ToolPhase {
    /// Pressing, dragging or holding: the tool is pressed in at full depth.
    pub fn is_pressed(self) -> bool {
        matches!(
            self,
            ToolPhase::Pressing | ToolPhase::Dragging | ToolPhase::Holding
        )
    }
}

fn smooth(x: Real) -> Real {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Tool `k`'s script at time `t` (s): its spot `(u, v)`, the depth of its lowest point below
/// the home surface (negative: above) and its phase. Tool `k` starts at
/// `k` × [`MultiToolScene::STAGGER`].
pub fn tool_script(spec: &ToolSpec, k: usize, t: Real) -> ([Real; 2], Real, ToolPhase) {
    type S = MultiToolScene;
    let s = t - k as Real * S::STAGGER;
    let lerp = |x: Real| {
        [
            spec.from[0] + (spec.to[0] - spec.from[0]) * x,
            spec.from[1] + (spec.to[1] - spec.from[1]) * x,
        ]
    };
    let t1 = S::DESCEND;
    let t2 = t1 + S::PRESS;
    let t3 = t2 + S::DRAG;
    let t4 = t3 + S::HOLD;
    if s < 0.0 {
        (spec.from, -S::CLEARANCE, ToolPhase::Waiting)
    } else if s < t1 {
        let d = -S::CLEARANCE + (S::DEPTH + S::CLEARANCE) * smooth(s / S::DESCEND);
        (spec.from, d, ToolPhase::Descending)
    } else if s < t2 {
        (spec.from, S::DEPTH, ToolPhase::Pressing)
    } else if s < t3 {
        (
            lerp(smooth((s - t2) / S::DRAG)),
            S::DEPTH,
            ToolPhase::Dragging,
        )
    } else if s < t4 {
        (spec.to, S::DEPTH, ToolPhase::Holding)
    } else if s < S::ACTIVE {
        let d = S::DEPTH - (S::DEPTH + S::CLEARANCE) * smooth((s - t4) / S::LIFT);
        (spec.to, d, ToolPhase::Lifting)
    } else {
        (spec.to, -S::CLEARANCE, ToolPhase::Done)
    }
}

/// The paper's 788-node organ raised into a dome ([`MultiToolScene::DOME_HEIGHT`], edges of
/// [`MultiToolScene::K`] and [`MultiToolScene::C`], [`MultiToolScene::DENSITY`], the exact
/// filter), pinned on its outer boundary and attached to a fixed body in a world with no
/// gravity (dt = 1/60 s): the organ of the multi-tool and surgery scenes.
pub struct OrganDome {
    /// The rapier world.
    pub world: PhysicsWorld,
    /// The organ in a set of its own.
    pub set: SurfaceSet,
    /// The organ in [`Self::set`].
    pub organ: SurfaceHandle,
    /// The TriMesh collider that follows the deformed organ.
    pub organ_collider: ColliderHandle,
    /// The planar mesh (the home in plan).
    pub flat: SurfaceMesh,
    /// The home height at each vertex (m).
    pub heights: Vec<Real>,
    /// The pinned outer-boundary vertices.
    pub base: Vec<u32>,
    /// Upward unit normals of the home surface at the vertices.
    pub normals: Vec<Vector>,
}

/// Builds an [`OrganDome`] with `substeps` surface steps per rigid step.
fn organ_dome(substeps: u32) -> OrganDome {
    type S = MultiToolScene;
    let (height, k, c, density) = (S::DOME_HEIGHT, S::K, S::C, S::DENSITY);
    let planar = paper_organ();
    let flat = planar.mesh;
    let base = planar.boundary;
    let heights: Vec<Real> = dome(&flat, &base).iter().map(|h| h * height).collect();
    let vertices: Vec<Vector> = flat
        .vertices
        .iter()
        .zip(&heights)
        .map(|(v, h)| Vector::new(v.x, *h, v.z))
        .collect();
    let normals = vertex_normals(&vertices, &flat.triangles);
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    world.integration_parameters.dt = 1.0 / 60.0;
    let surface = MassSpringSurfaceBuilder::new(vertices, flat.triangles.clone())
        .stiffness(k)
        .damping(c)
        .mass(MassDistribution::AreaDensity(density))
        .pinned(base.iter().copied())
        .integrator(Integrator::EXACT)
        .build()
        .expect("valid organ mesh");
    let (set, organ, organ_collider) = attach_fixed(&mut world, surface, substeps);
    OrganDome {
        world,
        set,
        organ,
        organ_collider,
        flat,
        heights,
        base,
        normals,
    }
}

impl std::fmt::Debug for OrganDome {
    /// The world's sizes, the set and the handles; the meshes as counts.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OrganDome")
            .field("world", &super::WorldSummary(&self.world))
            .field("set", &self.set)
            .field("organ", &self.organ)
            .field("flat_vertices", &self.flat.vertices.len())
            .finish_non_exhaustive()
    }
}

impl OrganDome {
    /// The organ with `substeps` surface steps per rigid step.
    pub fn new(substeps: u32) -> Self {
        organ_dome(substeps)
    }
}

/// A dome over the planar mesh: the solution of the graph Poisson problem `L h = 1` with
/// `h = 0` on `boundary` (SOR), scaled to a peak of 1.
fn dome(mesh: &SurfaceMesh, boundary: &[u32]) -> Vec<Real> {
    let n = mesh.num_vertices();
    let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); n];
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            if !adjacent[a].contains(&b) {
                adjacent[a].push(b);
                adjacent[b].push(a);
            }
        }
    }
    let mut fixed = vec![false; n];
    for &b in boundary {
        fixed[b as usize] = true;
    }
    let mut h = vec![0.0f64; n];
    for _ in 0..20_000 {
        let mut change = 0.0f64;
        for i in (0..n).filter(|&i| !fixed[i]) {
            let sum: f64 = adjacent[i].iter().map(|&j| h[j]).sum();
            let delta = 1.8 * ((sum + 1.0) / adjacent[i].len() as f64 - h[i]);
            h[i] += delta;
            change = change.max(delta.abs());
        }
        if change < 1e-12 {
            break;
        }
    }
    let top = h.iter().copied().fold(0.0, f64::max);
    h.iter().map(|x| (x / top) as Real).collect()
}

/// Upward unit normals at the vertices: area-weighted sums of the triangle normals.
fn vertex_normals(vertices: &[Vector], triangles: &[[u32; 3]]) -> Vec<Vector> {
    let mut n = vec![Vector::ZERO; vertices.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let f = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += f;
        }
    }
    n.into_iter()
        .map(|v| {
            let v = v.normalize();
            if v.y < 0.0 {
                -v
            } else {
                v
            }
        })
        .collect()
}

/// One tool of a [`MultiToolScene`] in its world.
#[derive(Copy, Clone, Debug)]
pub struct MultiTool {
    /// Its shape, orientation and path.
    pub spec: ToolSpec,
    /// Its kinematic position-based body.
    pub body: RigidBodyHandle,
    /// Its collider (registered with [`SurfaceSet::add_tool`]).
    pub collider: ColliderHandle,
    /// Its lowest point relative to its centre (world axes).
    pub lowest: Vector,
    /// How far its own boundary is straight below its centre (m).
    pub reach_down: Real,
}

/// The paper's 788-node organ, lifted into a dome and pinned at its base, pressed and dragged
/// by six scripted tools in a rapier world (the `multi_tool` example).
///
/// **The organ.** [`paper_organ_outline`] meshed with its own target edge (5.28 mm): 788
/// nodes, a kidney about 0.14 m × 0.10 m in the plane y = 0, lifted into a dome: the height
/// solves the mesh's Poisson problem `L h = 1` with `h = 0` on the outer boundary (a membrane
/// inflated from below), scaled to a 30 mm peak ([`Self::DOME_HEIGHT`]). The 111
/// outer-boundary vertices are pinned ([`Self::base`]); the outline's internal constraint
/// polyline is left free. The paper's linear springs, k = 10 N/m and c = 0.1 N·s/m per edge,
/// masses lumped from 15 kg/m² (0.21 kg in all), no gravity.
///
/// **Attachment.** [`SurfaceSet::insert`] on a fixed body with 17 substeps (the surface runs
/// at 1020 Hz, the rate of a haptic device) and the exact filter.
///
/// **Tools** ([`multi_tool_specs`]): kinematic position-based bodies driven with
/// `set_next_kinematic_translation` every 60 Hz step ([`tool_script`]). Each waits 20 mm above
/// the organ, comes down in 0.3 s until its lowest point is 6 mm below the home surface,
/// presses 0.35 s, is dragged 23 to 40 mm sideways in 1.5 s (following the dome's home
/// height), holds 0.35 s and lifts off in 0.3 s. They start 0.5 s apart, so up to five press
/// at once. The run lasts 7.5 s ([`Self::END_TIME`]).
///
/// ```
/// use rapier_touch::scenes::MultiToolScene;
/// let mut scene = MultiToolScene::new();
/// for _ in 0..30 {
///     scene.step(); // drives the tools for the step's end time, then steps the SurfaceSet
/// }
/// assert!(scene.tool_reaction(0).force.y > 0.0); // the first tool presses from t = 0.3 s
/// assert!(scene.surface().max_displacement() > 0.0);
/// ```
///
/// [`paper_organ_outline`]: crate::surface::meshing::paper_organ_outline
pub struct MultiToolScene {
    /// The rapier world (no gravity, dt = 1/60 s).
    pub world: PhysicsWorld,
    /// The organ surface and the tools.
    pub set: SurfaceSet,
    /// The organ in [`Self::set`].
    pub organ: SurfaceHandle,
    /// The TriMesh collider that follows the deformed organ.
    pub organ_collider: ColliderHandle,
    /// The six tools, in the order of [`multi_tool_specs`].
    pub tools: Vec<MultiTool>,
    /// The organ's planar mesh (its home positions in plan, y = 0).
    pub flat: SurfaceMesh,
    /// The dome's home height at each vertex (m).
    pub heights: Vec<Real>,
    /// The pinned outer-boundary vertices (the organ's base).
    pub base: Vec<u32>,
    /// Upward unit normals of the home surface at the vertices.
    pub normals: Vec<Vector>,
    /// Where [`Self::set_tool_target`] drives each tool instead of its script.
    targets: Vec<Option<Vector>>,
    steps: usize,
}

stepped_soft_scene!(MultiToolScene, 7.5);

impl std::fmt::Debug for MultiToolScene {
    /// The world's sizes, the set, the handles and the tools; the meshes as counts.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MultiToolScene")
            .field("world", &super::WorldSummary(&self.world))
            .field("set", &self.set)
            .field("organ", &self.organ)
            .field("organ_collider", &self.organ_collider)
            .field("tools", &self.tools)
            .field("flat_vertices", &self.flat.vertices.len())
            .field("base", &self.base.len())
            .field("targets", &self.targets)
            .field("steps", &self.steps)
            .finish_non_exhaustive()
    }
}

impl MultiToolScene {
    /// Peak height of the dome (m).
    pub const DOME_HEIGHT: Real = 0.03;
    /// Stiffness of every edge (N/m).
    pub const K: Real = 10.0;
    /// Damping of every edge (N·s/m).
    pub const C: Real = 0.1;
    /// Area density of the organ (kg/m²).
    pub const DENSITY: Real = 15.0;
    /// How deep a pressed tool's lowest point is below the home surface (m).
    pub const DEPTH: Real = 0.006;
    /// How high a waiting tool's lowest point is above the home surface (m).
    pub const CLEARANCE: Real = 0.02;
    /// Time between two tools' starts (s).
    pub const STAGGER: Real = 0.5;
    /// Time a tool takes to come down (s).
    pub const DESCEND: Real = 0.3;
    /// Time a tool presses at its first spot (s).
    pub const PRESS: Real = 0.35;
    /// Time a tool is dragged (s).
    pub const DRAG: Real = 1.5;
    /// Time a tool holds at the end of its drag (s).
    pub const HOLD: Real = 0.35;
    /// Time a tool takes to lift off (s).
    pub const LIFT: Real = 0.3;
    /// A tool's whole script, from its start to its lift-off (s).
    pub const ACTIVE: Real = Self::DESCEND + Self::PRESS + Self::DRAG + Self::HOLD + Self::LIFT;

    /// Builds the world, the organ and the tools at their waiting poses (t = 0).
    pub fn new() -> Self {
        let d = OrganDome::new(Self::SUBSTEPS);

        let mut scene = MultiToolScene {
            world: d.world,
            set: d.set,
            organ: d.organ,
            organ_collider: d.organ_collider,
            tools: Vec::new(),
            flat: d.flat,
            heights: d.heights,
            base: d.base,
            normals: d.normals,
            targets: Vec::new(),
            steps: 0,
        };
        for spec in multi_tool_specs() {
            let rot = Pose::from_parts(Vector::ZERO, Rotation::from_scaled_axis(spec.tilt));
            let collider = spec.shape.collider().build();
            let map = collider.shape().as_support_map().expect("convex tool");
            let lowest = map.support_point(&rot, -Vector::Y);
            let down = Ray::new(-Vector::Y * 1.0, Vector::Y);
            let toi = collider
                .shape()
                .cast_ray(&rot, &down, 2.0, false)
                .expect("the ray meets the tool");
            // The handles are set below, once `place` (which needs `lowest`) gives the start.
            scene.tools.push(MultiTool {
                spec,
                body: RigidBodyHandle::invalid(),
                collider: ColliderHandle::invalid(),
                lowest,
                reach_down: 1.0 - toi,
            });
        }
        for k in 0..scene.tools.len() {
            let (at, _, _) = scene.place(k, 0.0);
            let spec = scene.tools[k].spec;
            let b = scene.world.insert_body(
                RigidBodyBuilder::kinematic_position_based()
                    .translation(at)
                    .rotation(spec.tilt),
            );
            let c = scene.world.insert_collider(spec.shape.collider(), Some(b));
            scene
                .set
                .add_tool(c, &mut scene.world)
                .expect("the scene's tools have a size");
            scene.tools[k].body = b;
            scene.tools[k].collider = c;
        }
        scene.targets = vec![None; scene.tools.len()];
        scene
    }

    /// One rigid step: every tool's kinematic target is set to its scripted pose at the end
    /// of the step (or to where [`Self::set_tool_target`] put it), then [`SurfaceSet::step`]
    /// runs rapier's step and the organ's substeps.
    pub fn step(&mut self) {
        self.steps += 1;
        let t = self.time();
        for k in 0..self.tools.len() {
            let at = self.targets[k].unwrap_or_else(|| self.place(k, t).0);
            let body = self.tools[k].body;
            self.world.bodies[body].set_next_kinematic_translation(at);
        }
        self.set.step(&mut self.world);
    }

    /// Drives tool `k`'s centre to `target` at the end of every following step instead of
    /// along its script; `None` gives the tool back to its script. For a viewer whose mouse
    /// drags the tools, or that repeats their script.
    pub fn set_tool_target(&mut self, k: usize, target: Option<Vector>) {
        self.targets[k] = target;
    }

    /// When the last tool has lifted off (s).
    pub fn last_lift_off() -> Real {
        (multi_tool_specs().len() - 1) as Real * Self::STAGGER + Self::ACTIVE
    }

    /// The organ's deformable model (positions in world coordinates: its body is fixed at the
    /// origin).
    pub fn surface(&self) -> &MassSpringSurface {
        &self.set.get(self.organ).expect("the organ").surface
    }

    /// Tool `k`'s scripted spot `(u, v)` and phase at time `t`.
    pub fn script(&self, k: usize, t: Real) -> ([Real; 2], ToolPhase) {
        let (spot, _, phase) = tool_script(&self.tools[k].spec, k, t);
        (spot, phase)
    }

    /// Tool `k`'s scripted centre at time `t`: over its spot, its lowest point at its scripted
    /// depth below the home surface there. Also its spot and phase.
    pub fn place(&self, k: usize, t: Real) -> (Vector, [Real; 2], ToolPhase) {
        let tool = &self.tools[k];
        let ([u, v], depth, phase) = tool_script(&tool.spec, k, t);
        let o = tool.lowest;
        let y = self.home_height(u + o.x, v + o.z) - depth - o.y;
        (Vector::new(u, y, v), [u, v], phase)
    }

    /// The home surface's height over `(u, v)`, interpolated in the planar triangle containing
    /// it. Panics if the point is not over the organ.
    pub fn home_height(&self, u: Real, v: Real) -> Real {
        home_height_of(&self.flat, &self.heights, u, v)
    }

    /// The home surface's upward normal at the vertex nearest to `(u, v)` in plan.
    pub fn home_normal(&self, site: [Real; 2]) -> Vector {
        home_normal_of(&self.flat, &self.normals, site)
    }

    /// What the organ pushes back on tool `k` with after the last step.
    pub fn tool_reaction(&self, k: usize) -> ToolReaction {
        self.set
            .tool_reaction(self.tools[k].collider)
            .expect("a registered tool")
    }

    /// The pins' reaction: the sum of the spring and damper forces on the base vertices (N).
    pub fn pins_reaction(&self) -> Vector {
        let s = self.surface();
        self.base.iter().map(|&i| s.internal_force(i)).sum()
    }

    /// No tool has come down or lifted off within the 0.1 s up to `t`: the tools' forces and
    /// the pins' reaction should balance.
    pub fn quasi_static(&self, t: Real) -> bool {
        !self.tools.iter().enumerate().any(|(k, tool)| {
            [t, t - 0.1].iter().any(|&t| {
                matches!(
                    tool_script(&tool.spec, k, t).2,
                    ToolPhase::Descending | ToolPhase::Lifting
                )
            })
        })
    }
}

/// The height over `(u, v)` of the surface with heights `heights` over the planar mesh
/// `flat`, interpolated in the planar triangle containing it. Panics if the point is not over
/// the mesh.
pub(super) fn home_height_of(flat: &SurfaceMesh, heights: &[Real], u: Real, v: Real) -> Real {
    for t in &flat.triangles {
        let [a, b, c] = t.map(|i| flat.vertices[i as usize]);
        let (e1, e2) = ((b.x - a.x, b.z - a.z), (c.x - a.x, c.z - a.z));
        let (px, pz) = (u - a.x, v - a.z);
        let det = e1.0 * e2.1 - e1.1 * e2.0;
        let l1 = (px * e2.1 - pz * e2.0) / det;
        let l2 = (e1.0 * pz - e1.1 * px) / det;
        let l0 = 1.0 - l1 - l2;
        if l0 >= -1e-6 && l1 >= -1e-6 && l2 >= -1e-6 {
            let [ha, hb, hc] = t.map(|i| heights[i as usize]);
            return l0 * ha + l1 * hb + l2 * hc;
        }
    }
    panic!("({u}, {v}) is not over the organ");
}

/// The normal (of `normals`, one per vertex of the planar mesh `flat`) at the vertex nearest
/// to `(u, v)` in plan.
pub(super) fn home_normal_of(flat: &SurfaceMesh, normals: &[Vector], [u, v]: [Real; 2]) -> Vector {
    let d2 = |i: usize| (flat.vertices[i].x - u).powi(2) + (flat.vertices[i].z - v).powi(2);
    let nearest = (0..flat.num_vertices())
        .min_by(|&a, &b| d2(a).total_cmp(&d2(b)))
        .expect("vertices");
    normals[nearest]
}
