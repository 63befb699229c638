//! The servo loop's scenes (issue 14): a surface of a chosen size in a world at 60 Hz with
//! kinematic ball tools above press points, each ready to be linked to a servo loop, and the
//! scripted press-drag-lift a simulated hand follows.

use super::OrganDome;
use crate::coupling::{AttachOptions, SurfaceHandle, SurfaceSet};
use crate::haptics::{haptic_link, ServoLink};
use crate::math::{Pose, Real, Vector};
use crate::surface::meshing::{box_surface, plate, plate_rim};
use crate::surface::{Integrator, MassDistribution, MassSpringSurfaceBuilder};
use rapier3d::prelude::*;

/// A surface and ball tools over it (see the module docs).
pub struct HapticScene {
    /// The world (no gravity, dt = 1/60 s).
    pub world: PhysicsWorld,
    /// The surface in its set.
    pub set: SurfaceSet,
    /// The surface.
    pub surface: SurfaceHandle,
    /// The tools' colliders (kinematic balls of [`HapticScene::radius`]).
    pub tools: Vec<ColliderHandle>,
    /// Each tool's press point on the surface and the surface's outward normal there.
    pub press: Vec<(Vector, Vector)>,
    /// The tools' radius (m).
    pub radius: Real,
    /// How deep the script presses (m).
    pub depth: Real,
    /// How far the script drags along the surface (m).
    pub drag: Real,
}

impl std::fmt::Debug for HapticScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("HapticScene")
            .field("vertices", &self.vertices())
            .field("tools", &self.tools)
            .finish_non_exhaustive()
    }
}

impl HapticScene {
    /// The seconds the script lasts.
    pub const SCRIPT_SECONDS: Real = 5.0;

    /// The 788-node organ dome ([`OrganDome`], 4 substeps) with `tools` (1 or 2) 1 cm balls,
    /// pressed 8 mm at its peak and 3 cm beside it.
    pub fn organ(tools: usize) -> Self {
        let dome = OrganDome::new(4);
        let peak = (0..dome.heights.len())
            .max_by(|&a, &b| dome.heights[a].total_cmp(&dome.heights[b]))
            .unwrap_or(0);
        let point = |i: usize| {
            let v = dome.flat.vertices[i];
            (Vector::new(v.x, dome.heights[i], v.z), dome.normals[i])
        };
        let (top, _) = point(peak);
        let beside = (0..dome.heights.len())
            .min_by(|&a, &b| {
                let d = |i: usize| ((point(i).0 - top).length() - 0.03).abs();
                d(a).total_cmp(&d(b))
            })
            .unwrap_or(0);
        let press: Vec<(Vector, Vector)> = [peak, beside]
            .into_iter()
            .take(tools.clamp(1, 2))
            .map(point)
            .collect();
        Self::with_tools(dome.world, dome.set, dome.organ, press, 0.01, 0.008, 0.015)
    }

    /// A 0.3 m plate of `cells²` cells (`(cells + 1)²` nodes, rim pinned, 100 N/m edges,
    /// 0.1 kg, the exact filter, one substep) with `tools` (1 or 2) 1.5 cm balls, pressed
    /// 1 cm either side of its centre.
    pub fn plate(cells: u32, tools: usize) -> Self {
        let size = 0.3;
        let surface = MassSpringSurfaceBuilder::from_mesh(&plate(size, size, cells, cells))
            .stiffness(100.0)
            .damping(1.0)
            .mass(MassDistribution::Total(0.1))
            .pinned(plate_rim(cells, cells))
            .integrator(Integrator::EXACT)
            .build()
            .expect("a valid plate");
        let press = [-0.05, 0.05]
            .into_iter()
            .take(tools.clamp(1, 2))
            .map(|x| (Vector::new(x, 0.0, 0.0), Vector::Y))
            .collect();
        let (world, set, handle) = attached(surface);
        Self::with_tools(world, set, handle, press, 0.015, 0.01, 0.02)
    }

    /// A sphere of 10 cm radius meshed with about `nodes` nodes (a subdivided cube pushed onto
    /// the sphere: `6 n² + 2`), its lower half pinned, with `tools` (1 or 2) 1.5 cm balls
    /// pressed 1 cm into its top.
    pub fn sphere(nodes: usize, tools: usize) -> Self {
        let n = (((nodes.max(8) - 2) as f64 / 6.0).sqrt().round() as u32).max(1);
        let mut mesh = box_surface(Vector::ONE, n);
        let radius = 0.1;
        for v in &mut mesh.vertices {
            *v = v.normalize() * radius;
        }
        let pinned: Vec<u32> = (0..mesh.vertices.len() as u32)
            .filter(|&i| mesh.vertices[i as usize].y < 0.0)
            .collect();
        let surface = MassSpringSurfaceBuilder::from_mesh(&mesh)
            .stiffness(100.0)
            .damping(1.0)
            .mass(MassDistribution::Total(0.2))
            .pinned(pinned)
            .integrator(Integrator::EXACT)
            .build()
            .expect("a valid sphere");
        let press = [-0.3f32, 0.3]
            .into_iter()
            .take(tools.clamp(1, 2))
            .map(|a| {
                let n = Vector::new(a.sin(), a.cos(), 0.0);
                (n * radius, n)
            })
            .collect();
        let (world, set, handle) = attached(surface);
        Self::with_tools(world, set, handle, press, 0.015, 0.01, 0.02)
    }

    fn with_tools(
        mut world: PhysicsWorld,
        set: SurfaceSet,
        surface: SurfaceHandle,
        press: Vec<(Vector, Vector)>,
        radius: Real,
        depth: Real,
        drag: Real,
    ) -> Self {
        let tools = press
            .iter()
            .map(|(p, n)| {
                let start = *p + *n * (radius + 0.01);
                let body = world
                    .insert_body(RigidBodyBuilder::kinematic_position_based().translation(start));
                world.insert_collider(ColliderBuilder::ball(radius), Some(body))
            })
            .collect();
        HapticScene {
            world,
            set,
            surface,
            tools,
            press,
            radius,
            depth,
            drag,
        }
    }

    /// The surface's node count.
    pub fn vertices(&self) -> usize {
        self.set
            .get(self.surface)
            .map_or(0, |s| s.surface.num_vertices())
    }

    /// Links tool `k` to a new servo loop end.
    pub fn link(&mut self, k: usize) -> ServoLink {
        let (world_end, servo_end) = haptic_link();
        self.set
            .connect_haptic(self.tools[k], world_end, &mut self.world)
            .expect("a kinematic tool");
        servo_end
    }

    /// Tool `k`'s script (world = device frame), [`Self::SCRIPT_SECONDS`] long: hovers 1 cm
    /// over its press point, presses [`Self::depth`] in over 1.5 s, drags [`Self::drag`]
    /// along the surface over 1.5 s, lifts off over 1 s, hovers.
    pub fn script(&self, k: usize) -> impl Fn(Real) -> Pose + Send + 'static {
        let (p, n) = self.press[k];
        let (r, depth, drag) = (self.radius, self.depth, self.drag);
        let along = (Vector::X - n * n.x).normalize_or_zero();
        move |t: Real| {
            let smooth = |a: Real| {
                let a = a.clamp(0.0, 1.0);
                a * a * (3.0 - 2.0 * a)
            };
            let press = smooth((t - 0.5) / 1.5) - smooth((t - 3.5) / 1.0);
            let height = r + 0.01 - (0.01 + depth) * press;
            let aside = drag * smooth((t - 2.0) / 1.5);
            Pose::from_translation(p + n * height + along * aside)
        }
    }
}

/// `surface` on a fixed body in a world with no gravity at 60 Hz, one substep, with a collider.
fn attached(
    surface: crate::surface::MassSpringSurface,
) -> (PhysicsWorld, SurfaceSet, SurfaceHandle) {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    world.integration_parameters.dt = 1.0 / 60.0;
    let body = world.insert_body(RigidBodyBuilder::fixed());
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: 1,
        collider: true,
    };
    let handle = set
        .insert(surface, body, &mut world, options)
        .expect("attached");
    (world, set, handle)
}
