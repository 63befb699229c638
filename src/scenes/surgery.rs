//! Surgery on the organ dome (the 788-node organ of the multi-tool scene): a grasper lifts a
//! fold while a scalpel blade presses and slides and a needle pokes, with friction; the scene
//! of the `surgery` example and of the `frames` example's surgery frames.

use super::multi_tool::{home_height_of, home_normal_of, OrganDome};
use crate::coupling::{Friction, ToolReaction};
use crate::math::{Real, Rotation, Vector};
use crate::surface::MassSpringSurface;
use rapier3d::prelude::*;

/// One tool of the [`SurgeryScene`] in its world.
#[derive(Copy, Clone, Debug)]
pub struct SurgeryTool {
    /// `grasper`, `blade` or `needle`.
    pub name: &'static str,
    /// Its kinematic body.
    pub body: RigidBodyHandle,
    /// Its collider (a registered tool).
    pub collider: ColliderHandle,
    /// Its site in plan `(u, v) = (x, z)` (m).
    pub site: [Real; 2],
    /// Its lowest point below its body's origin (m, turned as placed).
    pub lowest: Real,
}

/// The organ dome with three tools on a script (no gravity, dt = 1/60 s):
/// - a grasper (closed jaws, an 8 mm cube; friction 0.8 / 0.6) comes down 3 mm into the organ
///   by 0.5 s, grasps, lifts a fold to 10 mm above the home surface by 1.5 s, holds it, lets
///   go at 3.5 s and leaves;
/// - a scalpel blade (24 × 12 × 0.8 mm, edge down; friction 0.3 / 0.2) comes down 2 mm by
///   0.8 s and slides 20 mm along its edge from 1 s to 3 s, then leaves;
/// - a needle (a slim pyramid, tip down; frictionless) pokes 4 mm in from 1 s to 1.6 s, holds,
///   and leaves.
///
/// All tools are up again from 4 s; the run ends at 5 s.
///
/// # Example
/// ```
/// use rapier_touch::scenes::SurgeryScene;
/// let mut scene = SurgeryScene::new();
/// for _ in 0..90 {
///     scene.step(); // 1.5 s: the fold is up
/// }
/// let (normal, _) = scene.normal_and_tangential(0);
/// assert!(normal < 0.0); // the grasper is pulled down by the fold
/// ```
pub struct SurgeryScene {
    /// The rapier world, the organ and its set, and the organ's home.
    pub dome: OrganDome,
    /// The grasper, the blade and the needle.
    pub tools: Vec<SurgeryTool>,
    steps: usize,
}

stepped_soft_scene!(SurgeryScene, 5.0);

impl std::fmt::Debug for SurgeryScene {
    /// The world's sizes, the set, the handles and the tools; the meshes as counts.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SurgeryScene")
            .field("dome", &self.dome)
            .field("tools", &self.tools)
            .field("steps", &self.steps)
            .finish_non_exhaustive()
    }
}

/// How high a waiting tool's lowest point is above the home surface (m).
const CLEARANCE: Real = 0.015;

/// A point of a piecewise-linear script: at `t` (s), the lowest point `h` (m) above the home
/// surface and `s` (m) along the tool's slide.
type Key = (Real, Real, Real);

fn along(keys: &[Key], t: Real) -> (Real, Real) {
    let mut prev = keys[0];
    for &k in keys {
        if t <= k.0 {
            let a = if k.0 > prev.0 {
                ((t - prev.0) / (k.0 - prev.0)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            return (prev.1 + (k.1 - prev.1) * a, prev.2 + (k.2 - prev.2) * a);
        }
        prev = k;
    }
    (prev.1, prev.2)
}

impl SurgeryScene {
    /// When the grasper grasps and lets go (s).
    pub const GRASP: (Real, Real) = (0.5, 3.5);

    /// The tools' scripts: (lowest point above the home surface, slide) against time.
    fn script(k: usize) -> &'static [Key] {
        const C: Real = CLEARANCE;
        match k {
            0 => &[
                (0.0, C, 0.0),
                (0.4, -0.003, 0.0),
                (0.5, -0.003, 0.0),
                (1.5, 0.010, 0.0),
                (3.6, 0.010, 0.0),
                (4.0, C, 0.0),
            ],
            1 => &[
                (0.0, C, 0.0),
                (0.8, -0.002, 0.0),
                (1.0, -0.002, 0.0),
                (3.0, -0.002, 0.020),
                (3.5, -0.002, 0.020),
                (4.0, C, 0.020),
            ],
            _ => &[
                (0.0, C, 0.0),
                (1.0, C, 0.0),
                (1.6, -0.004, 0.0),
                (3.5, -0.004, 0.0),
                (4.0, C, 0.0),
            ],
        }
    }

    /// Builds the organ and the tools at their waiting poses (t = 0).
    pub fn new() -> Self {
        let needle = SharedShape::convex_hull(&[
            Vector::ZERO,
            Vector::new(-0.0015, 0.04, -0.0015),
            Vector::new(0.0015, 0.04, -0.0015),
            Vector::new(0.0015, 0.04, 0.0015),
            Vector::new(-0.0015, 0.04, 0.0015),
        ])
        .expect("a pyramid");
        let specs: [(&str, SharedShape, Rotation, [Real; 2], Friction); 3] = [
            (
                "grasper",
                SharedShape::cuboid(0.004, 0.004, 0.004),
                Rotation::IDENTITY,
                [0.035, 0.01],
                Friction::new(0.8, 0.6).expect("valid"),
            ),
            (
                "blade",
                SharedShape::cuboid(0.012, 0.006, 0.0004),
                Rotation::IDENTITY,
                [-0.04, 0.0],
                Friction::new(0.3, 0.2).expect("valid"),
            ),
            (
                "needle",
                needle,
                Rotation::IDENTITY,
                [0.0, -0.025],
                Friction::NONE,
            ),
        ];
        let mut scene = SurgeryScene {
            dome: OrganDome::new(Self::SUBSTEPS),
            tools: Vec::new(),
            steps: 0,
        };
        for (name, shape, rotation, site, friction) in specs {
            let lowest = shape
                .compute_aabb(&Pose::from_parts(Vector::ZERO, rotation))
                .mins
                .y;
            let at = scene.place(site, 0.0, CLEARANCE, lowest);
            let body = scene.dome.world.insert_body(
                RigidBodyBuilder::kinematic_position_based()
                    .translation(at)
                    .rotation(rotation.to_scaled_axis()),
            );
            let collider = scene
                .dome
                .world
                .insert_collider(ColliderBuilder::new(shape), Some(body));
            scene
                .dome
                .set
                .add_tool(collider, &mut scene.dome.world)
                .expect("the tools have a size");
            scene
                .dome
                .set
                .set_tool_friction(collider, friction)
                .expect("a registered tool");
            scene.tools.push(SurgeryTool {
                name,
                body,
                collider,
                site,
                lowest,
            });
        }
        scene
    }

    /// The body position putting a tool's lowest point `h` above the home surface at `site`
    /// moved `slide` along x.
    fn place(&self, site: [Real; 2], slide: Real, h: Real, lowest: Real) -> Vector {
        let (u, v) = (site[0] + slide, site[1]);
        let y = home_height_of(&self.dome.flat, &self.dome.heights, u, v) + h - lowest;
        Vector::new(u, y, v)
    }

    /// One rigid step: the tools go to their scripted poses at the end of the step, the
    /// grasper grasps or lets go on time, then [`crate::coupling::SurfaceSet::step`].
    pub fn step(&mut self) {
        self.steps += 1;
        let t = self.time();
        for k in 0..self.tools.len() {
            let tool = self.tools[k];
            let (h, slide) = along(Self::script(k), t);
            let at = self.place(tool.site, slide, h, tool.lowest);
            self.dome.world.bodies[tool.body].set_next_kinematic_translation(at);
        }
        let grasping = (Self::GRASP.0..Self::GRASP.1).contains(&t);
        let grasper = self.tools[0].collider;
        if self.dome.set.is_grasping(grasper) != grasping {
            self.dome
                .set
                .set_grasp(grasper, grasping)
                .expect("a registered tool");
        }
        self.dome.set.step(&mut self.dome.world);
    }

    /// The organ surface.
    pub fn surface(&self) -> &MassSpringSurface {
        &self
            .dome
            .set
            .get(self.dome.organ)
            .expect("attached")
            .surface
    }

    /// What the organ pushes back on tool `k` with after the last step.
    pub fn tool_reaction(&self, k: usize) -> ToolReaction {
        self.dome
            .set
            .tool_reaction(self.tools[k].collider)
            .expect("a registered tool")
    }

    /// Tool `k`'s force split along the home surface's normal at its site (positive: pushed
    /// out of the organ) and across it (its size) (N).
    pub fn normal_and_tangential(&self, k: usize) -> (Real, Real) {
        let n = home_normal_of(&self.dome.flat, &self.dome.normals, self.tools[k].site);
        let f = self.tool_reaction(k).force;
        let normal = f.dot(n);
        (normal, (f - n * normal).length())
    }
}
