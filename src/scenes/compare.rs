//! The scenes the `penetration_compare` example runs beside the two drops of
//! [`run_drop_side`](super::run_drop_side): a spinning box, a box onto a thin *dynamic* plate, a
//! non-convex TriMesh mover, and the cuboid drop at 1/100 scale ([`CompareScene`]). Each is
//! built by [`compare_world`] and run by [`run_compare_side`], on the same three sides
//! ([`DropSide`]) and into the same [`DropRun`] figures.

use super::{box_depth_below_floor, DropRun, DropSide, DROP_BOX_HALF};
use crate::geometry::generators::extruded_polygon;
use crate::math::{Pose, Real, Rotation, Vector};
use rapier3d::prelude::{
    ActiveHooks, ColliderBuilder, ColliderHandle, IntegrationParameters, PhysicsWorld,
    RigidBodyBuilder, RigidBodyHandle,
};

/// Half extent (x and z) of the fixed cuboid floor of the [`CompareScene`]s at full scale: a
/// 100 m floor, so a spinning box that lands and rolls stays on it. Its top face is at `y = 0`,
/// 1 m thick.
pub const COMPARE_FLOOR_HALF: Real = 50.0;

/// The scale of [`CompareScene::SmallScale`]: every length, speed and gravity of the `cuboid`
/// drop times `1e-2` (a 5 mm box).
pub const SMALL_SCALE: Real = 1.0e-2;

/// Angular velocity (rad/s) of the box of [`CompareScene::Spinning`]: 20 rad/s about the
/// horizontal x axis and 5 rad/s about y.
pub const COMPARE_SPIN: Vector = Vector::new(20.0, 5.0, 0.0);

/// Half extents of the dynamic plate of [`CompareScene::DynamicPlate`]: 4 m wide, 2 cm thick.
pub const PLATE_HALF: Vector = Vector::new(2.0, 0.01, 2.0);

/// Height of the mover's centre above the floor's top when a [`CompareScene`] starts (m, at
/// full scale).
pub const COMPARE_DROP_HEIGHT: Real = 3.0;

/// How deep a cuboid of half extents `half` at `pose` reaches below `y = 0` (0 when above).
fn cuboid_depth_below_floor(pose: &Pose, half: Vector) -> Real {
    let mut lowest = Real::MAX;
    for sx in [-half.x, half.x] {
        for sy in [-half.y, half.y] {
            for sz in [-half.z, half.z] {
                lowest = lowest.min(pose.transform_point(Vector::new(sx, sy, sz)).y);
            }
        }
    }
    (-lowest).max(0.0)
}

/// The scenes of [`compare_world`]. Every one drops a mover from [`COMPARE_DROP_HEIGHT`] at a
/// given speed (straight down) in a rapier world with dt = 1/60, rapier's CCD off and contact
/// clustering off (as [`drop_world`](super::drop_world)); every collider opts into the touch
/// hooks.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum CompareScene {
    /// The 0.5 m box spinning at [`COMPARE_SPIN`] onto a fixed cuboid floor 100 m wide
    /// ([`COMPARE_FLOOR_HALF`]). Depth: how far the rotated box's lowest corner is below
    /// `y = 0`; through: its centre below `y = 0`.
    Spinning,
    /// The 0.5 m box onto a dynamic plate ([`PLATE_HALF`], density 1) lying on the fixed
    /// 100 m cuboid floor. Depth: the deeper of the box's overlap with the plate (parry's
    /// contact query, prediction 0) and the plate's lowest corner below `y = 0` (pushed into
    /// the floor); through: the box's centre below the plate's mid-plane (in the plate's
    /// frame), or the plate's centre below `y = 0`.
    DynamicPlate,
    /// A non-convex ∩-shaped TriMesh body ([`u_prism`], density 1: parry's mass properties of
    /// the closed mesh), tilted, onto the fixed 100 m cuboid floor. rapier's CCD never sweeps a
    /// TriMesh mover. Depth: how far its lowest vertex (world coordinates) is below `y = 0`;
    /// through: its centre below `y = 0`.
    TrimeshMover,
    /// The `cuboid` drop of [`drop_world`](super::drop_world) with every length, speed and the
    /// gravity scaled by [`SMALL_SCALE`] (a 5 mm box onto a 10 cm wide, 5 mm thick floor, from
    /// 3 cm), and rapier's `IntegrationParameters::length_unit` set to [`SMALL_SCALE`] on every
    /// side (rapier: the size of a typical object in world units, relative to a metre). rapier's
    /// run is then the `cuboid` run in other units, and so is the touch pipeline's (its slops
    /// are in that unit too). Depth and through as in the `cuboid` drop.
    SmallScale,
}

impl CompareScene {
    /// Every scene, in the example's order.
    pub const ALL: [CompareScene; 4] = [
        CompareScene::Spinning,
        CompareScene::DynamicPlate,
        CompareScene::TrimeshMover,
        CompareScene::SmallScale,
    ];

    /// The name in the example's `scene` column.
    pub fn name(self) -> &'static str {
        match self {
            CompareScene::Spinning => "spinning",
            CompareScene::DynamicPlate => "dynamic_plate",
            CompareScene::TrimeshMover => "trimesh_mover",
            CompareScene::SmallScale => "small_scale",
        }
    }

    /// The length scale: [`SMALL_SCALE`] for [`CompareScene::SmallScale`], 1 otherwise.
    pub fn scale(self) -> Real {
        match self {
            CompareScene::SmallScale => SMALL_SCALE,
            _ => 1.0,
        }
    }

    /// The drop speeds the example runs (m/s, actual): 5, 20 and 100 m/s times [`Self::scale`]
    /// (0.05, 0.2 and 1 m/s for [`CompareScene::SmallScale`]).
    pub fn speeds(self) -> [Real; 3] {
        match self {
            CompareScene::SmallScale => [0.05, 0.2, 1.0],
            _ => [5.0, 20.0, 100.0],
        }
    }
}

/// The non-convex mover of [`CompareScene::TrimeshMover`]: a ∩ (an outline 0.6 m wide and
/// 0.5 m tall with two 0.15 m legs 0.3 m long pointing down) extruded 0.3 m along z, centred on
/// its bounding box. A closed, outward-oriented TriMesh.
pub fn u_prism() -> (Vec<Vector>, Vec<[u32; 3]>) {
    extruded_polygon(
        &[
            [-0.3, -0.25],
            [-0.15, -0.25],
            [-0.15, 0.05],
            [0.15, 0.05],
            [0.15, -0.25],
            [0.3, -0.25],
            [0.3, 0.25],
            [-0.3, 0.25],
        ],
        0.3,
    )
    .expect("a valid outline")
}

/// A [`CompareScene`]'s world and what [`CompareWorld::measure`] needs.
pub struct CompareWorld {
    /// The scene.
    pub scene: CompareScene,
    /// The rapier world.
    pub world: PhysicsWorld,
    /// The dropped body.
    pub mover: RigidBodyHandle,
    /// Its collider.
    pub mover_collider: ColliderHandle,
    /// The fixed floor (top face at `y = 0`).
    pub floor: ColliderHandle,
    /// The dynamic plate and its collider ([`CompareScene::DynamicPlate`] only).
    pub plate: Option<(RigidBodyHandle, ColliderHandle)>,
    /// The mover's vertices in its body's frame ([`CompareScene::TrimeshMover`] only).
    mover_vertices: Vec<Vector>,
}

impl std::fmt::Debug for CompareWorld {
    /// The scene, the world's sizes and the handles; the mover's vertices as a count.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CompareWorld")
            .field("scene", &self.scene)
            .field("world", &super::WorldSummary(&self.world))
            .field("mover", &self.mover)
            .field("mover_collider", &self.mover_collider)
            .field("floor", &self.floor)
            .field("plate", &self.plate)
            .field("mover_vertices", &self.mover_vertices.len())
            .finish()
    }
}

/// What [`CompareWorld::measure`] finds after a step.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CompareMeasure {
    /// The scene's penetration (m; 0 when nothing overlaps): see [`CompareScene`].
    pub depth: Real,
    /// The mover (or the plate) went through: see [`CompareScene`].
    pub through: bool,
    /// The mover rests: linear speed below 1 cm/s times the scene's scale and angular speed
    /// below 0.1 rad/s.
    pub resting: bool,
}

/// Builds `scene` with the mover falling at `speed` m/s (actual: already scaled for
/// [`CompareScene::SmallScale`]).
///
/// ```
/// use rapier_touch::scenes::{compare_world, CompareScene};
/// let cw = compare_world(CompareScene::TrimeshMover, 20.0);
/// // The TriMesh mover has a mass (parry's mass properties of the closed mesh).
/// assert!(cw.world.bodies[cw.mover].mass() > 0.0);
/// assert!(!cw.measure().through);
/// ```
pub fn compare_world(scene: CompareScene, speed: Real) -> CompareWorld {
    let hooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;
    let k = scene.scale();
    let mut w = PhysicsWorld::default();
    w.integration_parameters.dt = 1.0 / 60.0;
    w.integration_parameters.max_ccd_substeps = 0;
    w.integration_parameters.contact_clustering = false;
    w.integration_parameters.length_unit = k;
    w.gravity *= k;
    let floor_half = match scene {
        // The floor of `drop_world`'s cuboid drop, scaled.
        CompareScene::SmallScale => 5.0 * k,
        _ => COMPARE_FLOOR_HALF,
    };
    let floor = w.insert_collider(
        ColliderBuilder::cuboid(floor_half, 0.5 * k, floor_half)
            .translation(Vector::new(0.0, -0.5 * k, 0.0))
            .active_hooks(hooks),
        None,
    );
    let plate = (scene == CompareScene::DynamicPlate).then(|| {
        let body = w.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(
            0.0,
            PLATE_HALF.y,
            0.0,
        )));
        let collider = w.insert_collider(
            ColliderBuilder::cuboid(PLATE_HALF.x, PLATE_HALF.y, PLATE_HALF.z).active_hooks(hooks),
            Some(body),
        );
        (body, collider)
    });
    let base = plate.map_or(0.0, |_| 2.0 * PLATE_HALF.y);
    let (rotation, angvel) = match scene {
        CompareScene::Spinning => (Rotation::IDENTITY, COMPARE_SPIN),
        CompareScene::TrimeshMover => (
            Rotation::from_rotation_z(0.1) * Rotation::from_rotation_x(0.2),
            Vector::ZERO,
        ),
        _ => (Rotation::IDENTITY, Vector::ZERO),
    };
    let mover = w.insert_body(
        RigidBodyBuilder::dynamic()
            .pose(Pose::from_parts(
                Vector::new(0.0, base + COMPARE_DROP_HEIGHT * k, 0.0),
                rotation,
            ))
            .linvel(Vector::new(0.0, -speed, 0.0))
            .angvel(angvel),
    );
    let (collider, mover_vertices) = match scene {
        CompareScene::TrimeshMover => {
            let (v, i) = u_prism();
            let c = ColliderBuilder::trimesh(v.clone(), i)
                .expect("a valid mesh")
                .density(1.0);
            (c, v)
        }
        _ => {
            let h = DROP_BOX_HALF * k;
            (ColliderBuilder::cuboid(h, h, h), Vec::new())
        }
    };
    let mover_collider = w.insert_collider(collider.active_hooks(hooks), Some(mover));
    CompareWorld {
        scene,
        world: w,
        mover,
        mover_collider,
        floor,
        plate,
        mover_vertices,
    }
}

impl CompareWorld {
    /// The scene's penetration, whether something went through, and whether the mover rests,
    /// from the bodies' poses and velocities now (see [`CompareScene`]).
    pub fn measure(&self) -> CompareMeasure {
        let k = self.scene.scale();
        let body = &self.world.bodies[self.mover];
        let pose = *body.position();
        let resting = body.linvel().length() < 0.01 * k && body.angvel().length() < 0.1;
        let (depth, through) = match (self.scene, self.plate) {
            (CompareScene::DynamicPlate, Some((plate, _))) => {
                use parry3d::shape::Cuboid;
                let plate_pose = *self.world.bodies[plate].position();
                // The box in the plate: parry's contact query (prediction 0).
                let into_plate = parry3d::query::contact(
                    &plate_pose,
                    &Cuboid::new(PLATE_HALF),
                    &pose,
                    &Cuboid::new(Vector::splat(DROP_BOX_HALF)),
                    0.0,
                )
                .ok()
                .flatten()
                .map_or(0.0, |c| (-c.dist).max(0.0));
                // The plate in the fixed floor: its lowest corner below the floor's top. (parry's
                // cuboid-cuboid query, SAT or GJK/EPA, is unreliable for the 4 m plate lying flat
                // on the 100 m floor: it sometimes answers a metre.)
                let into_floor = cuboid_depth_below_floor(&plate_pose, PLATE_HALF);
                let below_plate = plate_pose.inverse_transform_point(pose.translation).y < 0.0;
                (
                    into_plate.max(into_floor),
                    below_plate || plate_pose.translation.y < 0.0,
                )
            }
            (CompareScene::TrimeshMover, _) => {
                let lowest = self
                    .mover_vertices
                    .iter()
                    .map(|&v| pose.transform_point(v).y)
                    .fold(Real::MAX, Real::min);
                ((-lowest).max(0.0), pose.translation.y < 0.0)
            }
            _ => (
                box_depth_below_floor(&pose, DROP_BOX_HALF * k),
                pose.translation.y < 0.0,
            ),
        };
        CompareMeasure {
            depth,
            through,
            resting,
        }
    }
}

/// Runs `scene` with the mover falling at `speed` m/s for `steps` steps on `side` (as
/// [`run_drop_side`](super::run_drop_side): rapier with its CCD off, rapier with its default
/// `max_ccd_substeps` (CCD on), or the touch pipeline with its default options). The figures
/// are those of [`DropRun`] with the scene's depth and through-test ([`CompareWorld::measure`]);
/// `seconds` counts the steps only, not the measuring.
///
/// ```
/// use rapier_touch::scenes::{run_compare_side, CompareScene, DropSide};
/// // rapier's CCD never sweeps a TriMesh mover: at 100 m/s it goes through the floor.
/// let rapier = run_compare_side(CompareScene::TrimeshMover, 100.0, DropSide::RapierDefaults, 40);
/// let touch = run_compare_side(CompareScene::TrimeshMover, 100.0, DropSide::Touch, 40);
/// assert!(rapier.tunneled());
/// assert!(!touch.tunneled() && touch.max_penetration <= 1e-3);
/// ```
pub fn run_compare_side(scene: CompareScene, speed: Real, side: DropSide, steps: usize) -> DropRun {
    let mut cw = compare_world(scene, speed);
    if side == DropSide::RapierDefaults {
        cw.world.integration_parameters.max_ccd_substeps =
            IntegrationParameters::default().max_ccd_substeps;
    }
    let mut touch = crate::hooks::TouchPipeline::default();
    let mut run = super::DropRecorder::new(steps);
    let mut seconds = 0.0;
    for _ in 0..steps {
        let t0 = std::time::Instant::now();
        if side == DropSide::Touch {
            touch.step(&mut cw.world);
        } else {
            cw.world.step();
        }
        seconds += t0.elapsed().as_secs_f64();
        let m = cw.measure();
        run.record(m.depth, m.through, m.resting);
    }
    run.finish(seconds)
}
