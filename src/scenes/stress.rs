//! rapier's own stress-test scenes (its repository's `examples3d/stress_tests/`), scaled down
//! to a few hundred bodies, and the sides that step them (vanilla rapier, the touch pipeline
//! in either opt-in mode); [`super::stress_run`] runs and measures them.
//!
//! The scenes follow rapier's files: `pyramid3.rs` (brick-laid shrunken cubes), `keva3.rs`
//! (a plank tower), `ragdolls3.rs` (10-body ragdolls with limited joints, contacts off
//! between jointed parts), `trimesh3.rs` (cubes and balls on a TriMesh made from a height
//! field), `convex_polyhedron3.rs` (rounded random hulls) and `ccd3.rs` (five shapes shot down
//! at 1000 m/s with CCD enabled). Sizes and counts are reduced; shapes, spacings and
//! parameters are rapier's.

use crate::hooks::TouchPipeline;
use crate::math::{Real, Vector};
use rapier3d::prelude::*;

/// One of rapier's stress-test scenes.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum StressScene {
    /// `pyramid3.rs`: a brick-laid pyramid of shrunken 1.95 m cubes on a 2.25 m pitch, 8
    /// layers (204 boxes), on a fixed ground box.
    Pyramid,
    /// `keva3.rs`: a plank tower (0.2 × 1 × 4 m planks in crossed layers), the two smallest
    /// blocks of rapier's five.
    PlankTower,
    /// `ragdolls3.rs`: 18 ragdolls (180 capsules and balls, 162 limited joints) dropped in a
    /// pile.
    Ragdolls,
    /// `trimesh3.rs`: layers of 1 m cubes and balls (4 × 4 × 10) dropped on a fixed TriMesh
    /// made from a `sin x + cos z` height field.
    TriMeshFloor,
    /// `convex_polyhedron3.rs`: rounded convex hulls of 10 random points (4 × 4 × 10).
    ConvexHulls,
    /// `ccd3.rs`: cuboids, balls, rounded cylinders, cones and capsules (4 × 4 × 10) shot down
    /// at 1000 m/s with `ccd_enabled`, onto a 0.2 m ground box.
    Ccd,
}

impl StressScene {
    /// Every scene, in rapier's order above.
    pub const ALL: [StressScene; 6] = [
        StressScene::Pyramid,
        StressScene::PlankTower,
        StressScene::Ragdolls,
        StressScene::TriMeshFloor,
        StressScene::ConvexHulls,
        StressScene::Ccd,
    ];

    /// The scene's name in tables.
    pub fn name(self) -> &'static str {
        match self {
            StressScene::Pyramid => "pyramid",
            StressScene::PlankTower => "plank_tower",
            StressScene::Ragdolls => "ragdolls",
            StressScene::TriMeshFloor => "trimesh_floor",
            StressScene::ConvexHulls => "convex_hulls",
            StressScene::Ccd => "ccd",
        }
    }
}

/// Who steps a stress scene.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum StressSide {
    /// `PhysicsWorld::step` with rapier's default integration parameters (CCD on, contact
    /// clustering on): rapier as users run it.
    Rapier,
    /// [`TouchPipeline::step`], every collider given `ActiveHooks::MODIFY_SOLVER_CONTACTS`,
    /// contact clustering off ([`TouchPipeline::configure`]).
    TouchHooks,
    /// [`TouchPipeline::step`], every collider given to [`TouchPipeline::track_collider`],
    /// contact clustering off.
    TouchTracked,
}

impl StressSide {
    /// The side's name in tables.
    pub fn name(self) -> &'static str {
        match self {
            StressSide::Rapier => "rapier",
            StressSide::TouchHooks => "touch_hooks",
            StressSide::TouchTracked => "touch_tracked",
        }
    }

    /// Sets `world` up for this side, every collider in it opted in as the side says (the
    /// pipeline's integration parameters on the touch sides), and the pipeline to step it
    /// with ([`StressSide::step`]; unused by vanilla rapier).
    pub fn pipeline(self, world: &mut PhysicsWorld) -> TouchPipeline {
        let mut touch = TouchPipeline::default();
        if self != StressSide::Rapier {
            TouchPipeline::configure(&mut world.integration_parameters);
        }
        let handles: Vec<ColliderHandle> = world.colliders.iter().map(|(h, _)| h).collect();
        for h in handles {
            match self {
                StressSide::Rapier => {}
                StressSide::TouchHooks => {
                    if let Some(co) = world.colliders.get_mut(h) {
                        co.set_active_hooks(
                            co.active_hooks() | ActiveHooks::MODIFY_SOLVER_CONTACTS,
                        );
                    }
                }
                StressSide::TouchTracked => touch.track_collider(h),
            }
        }
        // The touch meshes are built with the scene, as rapier builds its shapes (a rounded
        // hull's convex hull) when the scene's colliders are built: neither is in the timed
        // steps.
        touch.prepare_meshes(&world.colliders);
        touch
    }

    /// One step of `world` on this side: rapier's own, or through `touch`.
    pub fn step(self, world: &mut PhysicsWorld, touch: &mut TouchPipeline) {
        match self {
            StressSide::Rapier => world.step(),
            _ => touch.step(world),
        }
    }
}

/// A built stress scene: its world and its floor collider.
pub struct StressWorld {
    /// The rapier world (dt = 1/60, rapier's default integration parameters).
    pub world: PhysicsWorld,
    /// The fixed floor every body ends on.
    pub floor: ColliderHandle,
}

impl std::fmt::Debug for StressWorld {
    /// The world's sizes (a `PhysicsWorld` has no `Debug`) and the floor.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StressWorld")
            .field("world", &super::WorldSummary(&self.world))
            .field("floor", &self.floor)
            .finish()
    }
}

/// Builds `scene` with rapier's default integration parameters.
pub fn stress_world(scene: StressScene) -> StressWorld {
    let mut world = PhysicsWorld::default();
    let floor = match scene {
        StressScene::Pyramid => pyramid(&mut world),
        StressScene::PlankTower => plank_tower(&mut world),
        StressScene::Ragdolls => ragdolls(&mut world),
        StressScene::TriMeshFloor => trimesh_floor(&mut world),
        StressScene::ConvexHulls => convex_hulls(&mut world),
        StressScene::Ccd => ccd(&mut world),
    };
    StressWorld { world, floor }
}

fn ground_box(world: &mut PhysicsWorld, half: Vector, y: Real) -> ColliderHandle {
    let body = world.insert_body(RigidBodyBuilder::fixed().translation(Vector::new(0.0, y, 0.0)));
    world.insert_collider(ColliderBuilder::cuboid(half.x, half.y, half.z), Some(body))
}

fn dynamic(world: &mut PhysicsWorld, at: Vector, collider: ColliderBuilder) -> RigidBodyHandle {
    let body = world.insert_body(RigidBodyBuilder::dynamic().translation(at));
    world.insert_collider(collider, Some(body));
    body
}

fn pyramid(world: &mut PhysicsWorld) -> ColliderHandle {
    let floor = ground_box(world, Vector::new(100.0, 1.0, 100.0), -1.0);
    let height = 8i32;
    let (size, separation) = (2.0, 0.5);
    let half = 0.5 * size;
    let h = half - 0.025;
    for i in 0..height {
        let brick = if i & 1 != 0 { half } else { 0.0 };
        let y = 1.0 + (size + separation) * i as Real;
        for j in i / 2..height - (i + 1) / 2 {
            for k in i / 2..height - (i + 1) / 2 {
                let x = -(height as Real) + (size + 0.25) * j as Real + brick;
                let z = -(height as Real) + (size + 0.25) * k as Real + brick;
                dynamic(
                    world,
                    Vector::new(x, y, z),
                    ColliderBuilder::cuboid(h, h, h).density(1000.0),
                );
            }
        }
    }
    floor
}

/// One block of `keva3.rs`'s tower.
fn keva_block(
    world: &mut PhysicsWorld,
    half: Vector,
    shift: Vector,
    (mut numx, numy, mut numz): (usize, usize, usize),
) {
    let dims = [half, Vector::new(half.z, half.y, half.x)];
    let width = 2.0 * half.z * numx as Real;
    let height = 2.0 * half.y * numy as Real;
    let spacing = (half.z * numx as Real - half.x) / (numz as Real - 1.0);
    for i in 0..numy {
        std::mem::swap(&mut numx, &mut numz);
        let dim = dims[i % 2];
        let y = dim.y * i as Real * 2.0;
        for j in 0..numx {
            let x = if i % 2 == 0 {
                spacing * j as Real * 2.0
            } else {
                dim.x * j as Real * 2.0
            };
            for k in 0..numz {
                let z = if i % 2 == 0 {
                    dim.z * k as Real * 2.0
                } else {
                    spacing * k as Real * 2.0
                };
                dynamic(
                    world,
                    Vector::new(x + dim.x, y + dim.y, z + dim.z) + shift,
                    ColliderBuilder::cuboid(dim.x, dim.y, dim.z),
                );
            }
        }
    }
    // Close the top.
    let dim = Vector::new(half.z, half.x, half.y);
    for i in 0..(width / (dim.x * 2.0)) as usize {
        for j in 0..(width / (dim.z * 2.0)) as usize {
            dynamic(
                world,
                Vector::new(
                    i as Real * dim.x * 2.0 + dim.x + shift.x,
                    dim.y + shift.y + height,
                    j as Real * dim.z * 2.0 + dim.z + shift.z,
                ),
                ColliderBuilder::cuboid(dim.x, dim.y, dim.z),
            );
        }
    }
}

fn plank_tower(world: &mut PhysicsWorld) -> ColliderHandle {
    let floor = ground_box(world, Vector::new(50.0, 0.1, 50.0), -0.1);
    let half = Vector::new(0.02, 0.1, 0.4) / 2.0 * 10.0;
    let numy = [0, 13, 17];
    let mut block_height = 0.0;
    for i in (1..=2).rev() {
        let numx = i * 2;
        let numz = numx * 3 + 1;
        let width = numx as Real * half.z * 2.0;
        keva_block(
            world,
            half,
            Vector::new(-width / 2.0, block_height, -width / 2.0),
            (numx, numy[i], numz),
        );
        block_height += numy[i] as Real * half.y * 2.0 + half.x * 2.0;
    }
    floor
}

/// `ragdolls3.rs`'s ragdoll: torso, head, two-link arms and legs, limited joints with contacts
/// off between jointed parts.
fn ragdoll(world: &mut PhysicsWorld, origin: Vector) {
    let part = |world: &mut PhysicsWorld, offset: Vector, co: ColliderBuilder| {
        (dynamic(world, origin + offset, co), offset)
    };
    type Part = (RigidBodyHandle, Vector);
    let spherical = |p: Part, c: Part, anchor: Vector, limit: Real| {
        SphericalJointBuilder::new()
            .local_anchor1(anchor - p.1)
            .local_anchor2(anchor - c.1)
            .limits(JointAxis::AngX, [-limit, limit])
            .limits(JointAxis::AngY, [-limit, limit])
            .limits(JointAxis::AngZ, [-limit, limit])
            .contacts_enabled(false)
    };
    let revolute = |p: Part, c: Part, anchor: Vector, limits: [Real; 2]| {
        RevoluteJointBuilder::new(Vector::Z)
            .local_anchor1(anchor - p.1)
            .local_anchor2(anchor - c.1)
            .limits(limits)
            .contacts_enabled(false)
    };
    let torso = part(world, Vector::ZERO, ColliderBuilder::capsule_y(0.3, 0.15));
    let head = part(
        world,
        Vector::new(0.0, 0.55, 0.0),
        ColliderBuilder::ball(0.15),
    );
    let neck = spherical(torso, head, Vector::new(0.0, 0.42, 0.0), 0.5);
    world.insert_impulse_joint(torso.0, head.0, neck);
    for side in [-1.0, 1.0] {
        let capsule_x = || ColliderBuilder::capsule_x(0.14, 0.06);
        let upper = part(world, Vector::new(side * 0.36, 0.25, 0.0), capsule_x());
        let fore = part(world, Vector::new(side * 0.70, 0.25, 0.0), capsule_x());
        let capsule_y = || ColliderBuilder::capsule_y(0.16, 0.07);
        let thigh = part(world, Vector::new(side * 0.09, -0.52, 0.0), capsule_y());
        let shin = part(world, Vector::new(side * 0.09, -0.92, 0.0), capsule_y());
        let shoulder = spherical(torso, upper, Vector::new(side * 0.19, 0.25, 0.0), 1.2);
        world.insert_impulse_joint(torso.0, upper.0, shoulder);
        let elbow = revolute(upper, fore, Vector::new(side * 0.53, 0.25, 0.0), [0.0, 2.5]);
        world.insert_impulse_joint(upper.0, fore.0, elbow);
        let hip = spherical(torso, thigh, Vector::new(side * 0.09, -0.33, 0.0), 1.0);
        world.insert_impulse_joint(torso.0, thigh.0, hip);
        let knee = revolute(
            thigh,
            shin,
            Vector::new(side * 0.09, -0.72, 0.0),
            [0.0, 2.3],
        );
        world.insert_impulse_joint(thigh.0, shin.0, knee);
    }
}

fn ragdolls(world: &mut PhysicsWorld) -> ColliderHandle {
    let floor = ground_box(world, Vector::new(100.0, 1.0, 100.0), -1.0);
    for layer in 0..2 {
        for row in 0..3 {
            for col in 0..3 {
                let origin = Vector::new(
                    col as Real * 2.2,
                    1.5 + layer as Real * 2.6,
                    row as Real * 2.2,
                );
                ragdoll(world, origin);
            }
        }
    }
    floor
}

/// The columns of rapier's grid scenes: `num × num` bodies per layer, `layers` layers.
fn grid(
    world: &mut PhysicsWorld,
    (num, layers): (usize, usize),
    shift: Real,
    drift: Real,
    mut body: impl FnMut(usize, usize, usize, Vector) -> (RigidBodyBuilder, ColliderBuilder),
) {
    let center = shift * (num / 2) as Real;
    let mut offset = -(num as Real) * shift * 0.5;
    for j in 0..layers {
        for i in 0..num {
            for k in 0..num {
                let at = Vector::new(
                    i as Real * shift - center + offset,
                    j as Real * shift + shift / 2.0 + 3.0,
                    k as Real * shift - center + offset,
                );
                let (rb, co) = body(i, j, k, at);
                let h = world.insert_body(rb.translation(at));
                world.insert_collider(co, Some(h));
            }
        }
        offset -= drift * (num as Real - 1.0);
    }
}

fn trimesh_floor(world: &mut PhysicsWorld) -> ColliderHandle {
    let size = Vector::new(60.0, 1.0, 60.0);
    let n = 20;
    let mut heights = parry3d::utils::Array2::repeat(n + 1, n + 1, 0.0);
    for i in 0..=n {
        for j in 0..=n {
            heights[(i, j)] = if i == 0 || i == n || j == 0 || j == n {
                10.0
            } else {
                let x = i as Real * size.x / n as Real;
                let z = j as Real * size.z / n as Real;
                x.sin() + z.cos()
            };
        }
    }
    let (vertices, indices) = parry3d::shape::HeightField::new(heights, size).to_trimesh();
    let body = world.insert_body(RigidBodyBuilder::fixed());
    let floor = world.insert_collider(
        ColliderBuilder::trimesh(vertices, indices).expect("a height field's triangles"),
        Some(body),
    );
    // rapier's grid is centred on its first rows, not on the floor: keep it within the rim.
    grid(world, (4, 10), 3.0, 0.0, |_, j, _, _| {
        let co = if j % 2 == 0 {
            ColliderBuilder::cuboid(1.0, 1.0, 1.0)
        } else {
            ColliderBuilder::ball(1.0)
        };
        (RigidBodyBuilder::dynamic(), co)
    });
    floor
}

fn convex_hulls(world: &mut PhysicsWorld) -> ColliderHandle {
    let floor = ground_box(world, Vector::new(200.1, 0.1, 200.1), -0.1);
    let (scale, border) = (2.0, 0.1);
    // rapier draws its points with `StdRng::seed_from_u64(0)`; a fixed LCG keeps this crate
    // free of `rand` (the points are a fixture, not a distribution).
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut unit = move || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 40) as Real / (1u64 << 24) as Real
    };
    let shapes: Vec<SharedShape> = (0..5)
        .map(|_| {
            let points: Vec<Vector> = (0..10)
                .map(|_| Vector::new(unit(), unit(), unit()) * scale)
                .collect();
            SharedShape::round_convex_hull(&points, border).expect("ten points in general position")
        })
        .collect();
    grid(world, (4, 10), border * 2.0 + scale, 0.05, |i, _, k, _| {
        (
            RigidBodyBuilder::dynamic(),
            ColliderBuilder::new(shapes[(i + k) % 5].clone()),
        )
    });
    floor
}

fn ccd(world: &mut PhysicsWorld) -> ColliderHandle {
    let floor = ground_box(world, Vector::new(100.1, 0.1, 100.1), -0.1);
    let rad = 1.0;
    grid(world, (4, 10), rad * 3.0, 0.05 * rad, |_, j, _, _| {
        let co = match j % 5 {
            0 => ColliderBuilder::cuboid(rad, rad, rad),
            1 => ColliderBuilder::ball(rad),
            2 => ColliderBuilder::round_cylinder(rad, rad, rad / 10.0),
            3 => ColliderBuilder::cone(rad, rad),
            _ => ColliderBuilder::capsule_y(rad, rad),
        };
        (
            RigidBodyBuilder::dynamic()
                .linvel(Vector::new(0.0, -1000.0, 0.0))
                .ccd_enabled(true),
            co,
        )
    });
    floor
}
