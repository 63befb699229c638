//! A dynamic ball dropped on a soft plate: the scene of the `ball_on_plate` example.

use super::attach_fixed;
use crate::coupling::{SurfaceHandle, SurfaceSet, ToolReaction};
use crate::math::{Real, Vector};
use crate::surface::meshing::{plate, plate_rim, SurfaceMesh};
use crate::surface::{Integrator, MassDistribution, MassSpringSurface, MassSpringSurfaceBuilder};
use rapier3d::prelude::*;

/// A dynamic ball dropped on a soft plate, two-way coupled: the plate's force is all that
/// stops it (the `ball_on_plate` example).
///
/// **Plate.** `plate(0.3, 0.3, 15, 15)`: 256 nodes 20 mm apart at y = 0, its 60 rim vertices
/// pinned ([`Self::rim`]), attached to a fixed body with [`SurfaceSet::insert`]. The paper's
/// linear springs, k = 30 N/m and c = 1 N·s/m per edge, 0.05 kg spread evenly, the exact
/// filter, 17 substeps (the surface at 1020 Hz). The plate's own weight is left out, so its
/// pins carry the ball alone.
///
/// **Ball.** A rapier dynamic ball, r = 30 mm and 0.1 kg, registered with
/// [`SurfaceSet::add_tool`], released at rest with its centre 100 mm above the plate (4 mm and
/// 3 mm off its centre) under gravity (9.81 m/s², 60 Hz rigid steps). The ball's mass meets
/// the plate's in each substep's constraint solve (implicit coupling, [`SurfaceSet`]'s docs).
/// The run lasts 5 s ([`Self::END_TIME`]).
///
/// ```
/// use rapier_touch::scenes::BallOnPlateScene;
/// let mut scene = BallOnPlateScene::new();
/// for _ in 0..12 {
///     scene.step(); // SurfaceSet::step: rapier's step, then the plate's substeps
/// }
/// assert!(scene.ball_position().y < BallOnPlateScene::START.y); // falling
/// ```
pub struct BallOnPlateScene {
    /// The rapier world (gravity, dt = 1/60 s).
    pub world: PhysicsWorld,
    /// The plate surface and the ball as its tool.
    pub set: SurfaceSet,
    /// The plate in [`Self::set`].
    pub plate: SurfaceHandle,
    /// The TriMesh collider that follows the deformed plate.
    pub plate_collider: ColliderHandle,
    /// The ball's dynamic body.
    pub ball: RigidBodyHandle,
    /// The ball's collider (registered with [`SurfaceSet::add_tool`]).
    pub ball_collider: ColliderHandle,
    /// The plate's home mesh.
    pub mesh: SurfaceMesh,
    /// The pinned rim vertices.
    pub rim: Vec<u32>,
    steps: usize,
}

stepped_soft_scene!(BallOnPlateScene, 5.0);

impl std::fmt::Debug for BallOnPlateScene {
    /// The world's sizes, the set and the handles; the meshes as counts.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BallOnPlateScene")
            .field("world", &super::WorldSummary(&self.world))
            .field("set", &self.set)
            .field("plate", &self.plate)
            .field("plate_collider", &self.plate_collider)
            .field("ball", &self.ball)
            .field("ball_collider", &self.ball_collider)
            .field("mesh_vertices", &self.mesh.vertices.len())
            .field("rim", &self.rim.len())
            .field("steps", &self.steps)
            .finish()
    }
}

impl BallOnPlateScene {
    /// Side of the square plate (m).
    pub const SIZE: Real = 0.3;
    /// Cells along each side of the plate.
    pub const CELLS: u32 = 15;
    /// Stiffness of every edge (N/m).
    pub const K: Real = 30.0;
    /// Damping of every edge (N·s/m).
    pub const C: Real = 1.0;
    /// Mass of the whole plate (kg).
    pub const PLATE_MASS: Real = 0.05;
    /// The ball's radius (m).
    pub const RADIUS: Real = 0.03;
    /// The ball's mass (kg).
    pub const BALL_MASS: Real = 0.1;
    /// Where the ball's centre is released, at rest (m).
    pub const START: Vector = Vector::new(0.004, 0.1, -0.003);
    /// Gravity (m/s², downward).
    pub const G: Real = 9.81;

    /// Builds the world, the plate and the ball at its release point (t = 0).
    pub fn new() -> Self {
        let mut world = PhysicsWorld {
            gravity: Vector::new(0.0, -Self::G, 0.0),
            ..Default::default()
        };
        world.integration_parameters.dt = Self::DT;
        let mesh = plate(Self::SIZE, Self::SIZE, Self::CELLS, Self::CELLS);
        let rim = plate_rim(Self::CELLS, Self::CELLS);
        let surface = MassSpringSurfaceBuilder::from_mesh(&mesh)
            .stiffness(Self::K)
            .damping(Self::C)
            .mass(MassDistribution::Total(Self::PLATE_MASS))
            .pinned(rim.iter().copied())
            .integrator(Integrator::EXACT)
            .build()
            .expect("valid plate");
        let (mut set, plate, plate_collider) = attach_fixed(&mut world, surface, Self::SUBSTEPS);

        let volume = 4.0 / 3.0 * std::f32::consts::PI * Self::RADIUS.powi(3);
        let ball = world.insert_body(RigidBodyBuilder::dynamic().translation(Self::START));
        let ball_collider = world.insert_collider(
            ColliderBuilder::ball(Self::RADIUS).density(Self::BALL_MASS / volume),
            Some(ball),
        );
        set.add_tool(ball_collider, &mut world)
            .expect("a ball of positive radius is a tool");
        BallOnPlateScene {
            world,
            set,
            plate,
            plate_collider,
            ball,
            ball_collider,
            mesh,
            rim,
            steps: 0,
        }
    }

    /// One rigid step: [`SurfaceSet::step`] (rapier's step, then the plate's substeps).
    pub fn step(&mut self) {
        self.steps += 1;
        self.set.step(&mut self.world);
    }

    /// The plate's deformable model (positions in world coordinates: its body is fixed at the
    /// origin).
    pub fn surface(&self) -> &MassSpringSurface {
        &self.set.get(self.plate).expect("the plate").surface
    }

    /// The ball's mass as rapier computed it from its density (kg).
    pub fn ball_mass(&self) -> Real {
        self.world.bodies[self.ball].mass()
    }

    /// The ball's weight (N).
    pub fn weight(&self) -> Real {
        self.ball_mass() * Self::G
    }

    /// The ball centre's position (m).
    pub fn ball_position(&self) -> Vector {
        self.world.bodies[self.ball].translation()
    }

    /// The ball's linear velocity (m/s).
    pub fn ball_velocity(&self) -> Vector {
        self.world.bodies[self.ball].linvel()
    }

    /// What the plate pushes back on the ball with after the last step.
    pub fn reaction(&self) -> ToolReaction {
        self.set
            .tool_reaction(self.ball_collider)
            .expect("a registered tool")
    }

    /// The pins' reaction: the sum of the spring and damper forces on the rim vertices (N).
    pub fn pins_reaction(&self) -> Vector {
        let s = self.surface();
        self.rim.iter().map(|&i| s.internal_force(i)).sum()
    }
}
