//! Reference scenes shared by the examples, tests and benchmarks (fixed, deterministic).
//!
//! Test fixtures, not API: compiled only with the `fixtures` feature, which this crate's own
//! examples, tests and benches turn on through a dev-dependency on the crate itself. Their
//! helpers may panic on impossible input (they build fixed scenes).
//!
//! - Rigid contact: [`fig4_scenes`], [`table1_scenes`], [`drop_world`] (with [`run_drop`]) and
//!   [`boxes_on_trimesh_floor`].
//! - Soft surfaces: [`Fig7Organ`] (the paper's Fig. 7 under six forces), [`MultiToolScene`]
//!   (an organ dome pressed and dragged by six scripted tools) and [`BallOnPlateScene`] (a
//!   dynamic ball dropped on a soft plate). Each scene owns its world and steps itself, so the
//!   examples, the pictures and a viewer run the very same scene.

use crate::coupling::{AttachOptions, SurfaceHandle, SurfaceSet};
use crate::geometry::generators::{extruded_polygon, icosphere, subdivided_box};
use crate::geometry::{ContactKind, TouchMesh};
use crate::math::{Pose, Real, Rotation, Vector};
use crate::surface::meshing::{paper_organ_outline, triangulate_planar, PlanarMesh};
use crate::surface::MassSpringSurface;
use rapier3d::prelude::{ColliderHandle, PhysicsWorld, RigidBodyBuilder};

/// What the stepped soft scenes share: `Default` (their `new`), their timing (60 Hz rigid steps
/// with 17 surface substeps, a run of `$end_time` s) and their step count. The scene type has
/// a private `steps: usize` field that its `step` increments.
macro_rules! stepped_soft_scene {
    ($scene:ty, $end_time:expr) => {
        impl Default for $scene {
            fn default() -> Self {
                Self::new()
            }
        }

        impl $scene {
            /// Rigid time step (s).
            pub const DT: Real = 1.0 / 60.0;
            /// Surface substeps per rigid step.
            pub const SUBSTEPS: u32 = 17;
            /// Length of the run (s).
            pub const END_TIME: Real = $end_time;

            /// Rigid steps taken so far.
            pub fn steps(&self) -> usize {
                self.steps
            }

            /// Rigid steps of the whole run ([`Self::END_TIME`] / [`Self::DT`]).
            pub fn total_steps() -> usize {
                (Self::END_TIME / Self::DT).round() as usize
            }

            /// Time at the end of the last step (s).
            pub fn time(&self) -> Real {
                self.steps as Real * Self::DT
            }
        }
    };
}

mod ball_on_plate;
mod compare;
mod drop;
mod haptic;
mod multi_tool;
mod organ;
mod stress;
mod stress_run;
mod surgery;

pub use ball_on_plate::BallOnPlateScene;
pub use compare::{
    compare_world, run_compare_side, u_prism, CompareMeasure, CompareScene, CompareWorld,
    COMPARE_DROP_HEIGHT, COMPARE_FLOOR_HALF, COMPARE_SPIN, PLATE_HALF, SMALL_SCALE,
};
use drop::DropRecorder;
pub use drop::{
    box_depth_below_floor, boxes_on_trimesh_floor, drop_world, run_drop, run_drop_side, DropFloor,
    DropRun, DropSide, DROP_BOX_HALF,
};
pub use haptic::HapticScene;
pub use multi_tool::{
    multi_tool_specs, tool_script, MultiTool, MultiToolScene, OrganDome, ToolPhase, ToolShape,
    ToolSpec,
};
pub use organ::{diverged, Fig7Organ, COMPARED_INTEGRATORS};
pub use stress::{stress_world, StressScene, StressSide, StressWorld};
pub use stress_run::{
    deepest_solved_overlap, run_stress, run_stress_with_gravity, run_stress_with_options,
    StressRun, StressRunner,
};
pub use surgery::{SurgeryScene, SurgeryTool};

/// `Debug` of a [`PhysicsWorld`] (which has none): its sizes, time step and gravity, not its
/// contents. The scenes' `Debug` impls show their world through it.
pub(crate) struct WorldSummary<'a>(pub(crate) &'a PhysicsWorld);

impl std::fmt::Debug for WorldSummary<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhysicsWorld")
            .field("bodies", &self.0.bodies.len())
            .field("colliders", &self.0.colliders.len())
            .field("dt", &self.0.integration_parameters.dt)
            .field("gravity", &self.0.gravity)
            .finish_non_exhaustive()
    }
}

/// Attaches `surface` (positions in world coordinates) to a new fixed body at the origin of
/// `world`, in a new [`SurfaceSet`], with `substeps` surface steps per rigid step and a TriMesh
/// collider that follows the deformed surface. Returns the set, the surface's handle and its
/// collider. Panics if `substeps` is 0 or the surface cannot be a collider.
///
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::rapier3d::prelude::PhysicsWorld;
/// use rapier_touch::scenes::attach_fixed;
/// use rapier_touch::surface::meshing::{plate, plate_rim};
/// let mut world = PhysicsWorld::default();
/// let surface = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 4, 4))
///     .pinned(plate_rim(4, 4))
///     .build()
///     .unwrap();
/// let (set, plate, collider) = attach_fixed(&mut world, surface, 17);
/// assert_eq!(set.get(plate).unwrap().collider(), Some(collider));
/// assert_eq!(set.get(plate).unwrap().substeps(), 17);
/// ```
pub fn attach_fixed(
    world: &mut PhysicsWorld,
    surface: MassSpringSurface,
    substeps: u32,
) -> (SurfaceSet, SurfaceHandle, ColliderHandle) {
    let body = world.insert_body(RigidBodyBuilder::fixed());
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps,
        collider: true,
    };
    let handle = set.insert(surface, body, world, options).expect("attached");
    let collider = set
        .get(handle)
        .and_then(|a| a.collider())
        .expect("collider");
    (set, handle, collider)
}

/// [`paper_organ_outline`] meshed with its own target edge (5.28 mm): the 788-node organ of
/// [`Fig7Organ`] and [`MultiToolScene`].
fn paper_organ() -> PlanarMesh {
    let (outline, target_edge) = paper_organ_outline();
    triangulate_planar(&outline, target_edge).expect("the organ meshes")
}

/// A fixed and a moving mesh with the moving one's pose before and after a step, and what is
/// known about the pair (`T`): [`Fig4Expected`] for the [`fig4_scenes`], [`Table1Sizes`] for
/// the [`table1_scenes`].
#[derive(Clone, Debug)]
pub struct ContactScene<T = Fig4Expected> {
    /// Short name.
    pub name: &'static str,
    /// What the scene shows.
    pub description: &'static str,
    /// The fixed object.
    pub fixed: TouchMesh,
    /// Its pose.
    pub fixed_pose: Pose,
    /// The moving object.
    pub moving: TouchMesh,
    /// Its pose after the step (penetrating).
    pub pose: Pose,
    /// Its pose before the step.
    pub prev_pose: Pose,
    /// What is known about the pair.
    pub known: T,
}

/// What the reconstruction should find in one of the [`fig4_scenes`].
#[derive(Clone, Debug, PartialEq)]
pub struct Fig4Expected {
    /// The contact kind of every patch, in no particular order.
    pub kinds: Vec<ContactKind>,
    /// The reversing vector.
    pub reversing: Vector,
}

fn cuboid(half: Vector) -> TouchMesh {
    let (v, i) = subdivided_box(half, 1);
    TouchMesh::new(v, i).expect("a box is a valid mesh")
}

/// The four test cases of the paper's Fig. 4: a line (edge) contact, a face contact, a vertex
/// contact, and multiple point contacts of two non-convex objects.
pub fn fig4_scenes() -> Vec<ContactScene> {
    let floor = cuboid(Vector::new(2.0, 0.5, 2.0));
    let floor_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
    let cube = cuboid(Vector::splat(0.5));
    let half_diag = 0.5 * Real::sqrt(2.0);
    let rot_edge = Rotation::from_rotation_z(std::f32::consts::FRAC_PI_4);
    let rot_vertex = Rotation::from_rotation_arc(Vector::NEG_ONE.normalize(), Vector::NEG_Y);
    let corner = 0.5 * Real::sqrt(3.0);

    // (d): a fixed U-shaped block with two plateaus, and a moving bar with two V-shaped tips,
    // tilted so each tip touches with a single corner.
    let u_block = extruded_polygon(
        &[
            [-2.0, -1.0],
            [2.0, -1.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 0.0],
            [-1.0, 0.0],
            [-1.0, 1.0],
            [-2.0, 1.0],
        ],
        2.0,
    )
    .expect("valid outline");
    let tips = extruded_polygon(
        &[
            [-1.5, 0.0],
            [-1.2, 0.5],
            [1.2, 0.5],
            [1.5, 0.0],
            [1.8, 0.5],
            [1.8, 1.0],
            [-1.8, 1.0],
            [-1.8, 0.5],
        ],
        1.0,
    )
    .expect("valid outline");
    let tilt: Real = 0.2;
    let tip_drop = 0.5 * tilt.sin();

    vec![
        ContactScene {
            name: "line",
            description: "a cube standing on an edge sinks 0.1 m into a slab: line (edge) contact",
            fixed: floor.clone(),
            fixed_pose: floor_pose,
            moving: cube.clone(),
            pose: Pose::from_parts(Vector::new(0.2, half_diag - 0.1, 0.1), rot_edge),
            prev_pose: Pose::from_parts(Vector::new(0.2, half_diag + 0.3, 0.1), rot_edge),
            known: Fig4Expected {
                kinds: vec![ContactKind::Edge],
                reversing: Vector::new(0.0, 0.1, 0.0),
            },
        },
        ContactScene {
            name: "face",
            description: "a cube falling at a slant sinks 0.15 m flat into a slab: face contact",
            fixed: floor.clone(),
            fixed_pose: floor_pose,
            moving: cube.clone(),
            pose: Pose::from_translation(Vector::new(0.0, 0.35, 0.0)),
            prev_pose: Pose::from_translation(Vector::new(-0.2, 0.85, 0.1)),
            // |D| along y is 0.5 of |D| = 0.5477: walking back 0.15 in y walks back 0.2 in x
            // times 0.15/0.5 = 0.06 and 0.03 in z.
            known: Fig4Expected {
                kinds: vec![ContactKind::Face],
                reversing: Vector::new(-0.06, 0.15, 0.03),
            },
        },
        ContactScene {
            name: "vertex",
            description: "a cube falling corner first sinks 0.05 m into a slab: vertex contact",
            fixed: floor,
            fixed_pose: floor_pose,
            moving: cube,
            pose: Pose::from_parts(Vector::new(-0.4, corner - 0.05, 0.3), rot_vertex),
            prev_pose: Pose::from_parts(Vector::new(-0.4, corner + 0.45, 0.3), rot_vertex),
            known: Fig4Expected {
                kinds: vec![ContactKind::Vertex],
                reversing: Vector::new(0.0, 0.05, 0.0),
            },
        },
        ContactScene {
            name: "multi_point",
            description: "a tilted two-tipped bar lands on the two plateaus of a U block: \
                          two point contacts between non-convex objects",
            fixed: TouchMesh::new(u_block.0, u_block.1).expect("valid mesh"),
            fixed_pose: Pose::IDENTITY,
            moving: TouchMesh::new(tips.0, tips.1).expect("valid mesh"),
            pose: Pose::from_parts(
                Vector::new(0.0, 1.0 + tip_drop - 0.05, 0.0),
                Rotation::from_rotation_x(tilt),
            ),
            prev_pose: Pose::from_parts(
                Vector::new(0.0, 1.0 + tip_drop + 0.25, 0.0),
                Rotation::from_rotation_x(tilt),
            ),
            known: Fig4Expected {
                kinds: vec![ContactKind::Vertex, ContactKind::Vertex],
                reversing: Vector::new(0.0, 0.05, 0.0),
            },
        },
    ]
}

/// One of the four pairs whose sizes reproduce the paper's Table I (benchmarked in
/// `benches/reconstruction.rs`).
pub type Table1Scene = ContactScene<Table1Sizes>;

/// The sizes of a [`Table1Scene`]: "colliding edges / colliding vertices" as a collision
/// detector like RAPID reports them (see [`colliding_features`]), the paper's and this scene's.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct Table1Sizes {
    /// The paper's colliding-edge count for this row of Table I.
    pub paper_edges: usize,
    /// The paper's colliding-vertex count for this row of Table I.
    pub paper_vertices: usize,
    /// The colliding edges of this scene, measured by [`colliding_features`] at `pose`.
    pub colliding_edges: usize,
    /// The colliding vertices of this scene, measured by [`colliding_features`] at `pose`.
    pub colliding_vertices: usize,
}

/// The moving object's translation over the step in every [`table1_scenes`] scene: 5 cm
/// down, slightly slanted (so `D` is not axis-aligned).
const TABLE1_STEP: Vector = Vector::new(0.01, -0.05, -0.005);

/// Four penetrating pairs whose sizes reproduce the rows of the paper's Table I: about
/// 32/22, 54/31, 409/205 and 1062/502 colliding edges / colliding vertices (see
/// [`colliding_features`]; each scene stores the paper's numbers and its own measured ones).
///
/// Every fixed object is a box of 1 m × 0.5 m × 1 m whose top face lies at `y = 0`, split
/// into `n × n` quads per face; every moving object is closed and moved by
/// `D = (0.01, -0.05, -0.005)` m over the step, ending a few centimetres deep.
///
/// 1. `comb_3pt`: a three-tipped comb (extruded polygon, 40 triangles), tilted so each tip
///    touches with one corner, 1 cm deep in a box split 4 × 4 per face (192 triangles): three
///    vertex contacts.
/// 2. `cube_face`: a 0.2 m cube split 3 × 3 per face (108 triangles), lying flat (turned
///    about `y`), 2 cm deep in the same 192-triangle box: a face contact.
/// 3. `ball_192`: a 0.2 m-radius icosphere (20480 triangles), 3 cm deep in a box split 4 × 4
///    per face (192 triangles).
/// 4. `ball_49k`: a 0.35 m-radius icosphere (20480 triangles), 3.5 cm deep in a box split
///    64 × 64 per face (49152 triangles).
///
/// Deterministic: no randomness.
pub fn table1_scenes() -> Vec<Table1Scene> {
    let block = |n: u32| {
        let (v, i) = subdivided_box(Vector::new(0.5, 0.25, 0.5), n);
        TouchMesh::new(v, i).expect("a box is a valid mesh")
    };
    let block_pose = Pose::from_translation(Vector::new(0.0, -0.25, 0.0));
    let ball = |r: Real| {
        let (v, i) = icosphere(r, 5);
        TouchMesh::new(v, i).expect("an icosphere is a valid mesh")
    };
    let ball_rot = Rotation::from_rotation_x(0.3)
        * Rotation::from_rotation_y(0.2)
        * Rotation::from_rotation_z(0.1);

    // A comb with three V-shaped tips at x = -0.25, 0, 0.25 (tips at y = 0), 0.2 m deep in z.
    let (cv, ci) = extruded_polygon(
        &[
            [-0.25, 0.0],
            [-0.2, 0.1],
            [-0.05, 0.1],
            [0.0, 0.0],
            [0.05, 0.1],
            [0.2, 0.1],
            [0.25, 0.0],
            [0.3, 0.1],
            [0.3, 0.2],
            [-0.3, 0.2],
            [-0.3, 0.1],
        ],
        0.2,
    )
    .expect("valid outline");
    let comb = TouchMesh::new(cv, ci).expect("valid mesh");
    // Tilted about x: the z = +0.1 end of each tip is the lowest point, 0.1 sin(tilt) below
    // the tip line.
    let tilt: Real = 0.3;
    let comb_low = 0.1 * tilt.sin();

    let (qv, qi) = subdivided_box(Vector::splat(0.1), 3);
    let cube = TouchMesh::new(qv, qi).expect("a box is a valid mesh");

    // Measures the scene's colliding features and fills in the previous pose.
    let scene = |name: &'static str,
                 description: &'static str,
                 fixed: TouchMesh,
                 moving: TouchMesh,
                 pose: Pose,
                 (paper_edges, paper_vertices): (usize, usize)| {
        let (colliding_edges, colliding_vertices) =
            colliding_features(&fixed, &block_pose, &moving, &pose);
        Table1Scene {
            name,
            description,
            fixed,
            fixed_pose: block_pose,
            moving,
            pose,
            prev_pose: Pose::from_parts(pose.translation - TABLE1_STEP, pose.rotation),
            known: Table1Sizes {
                paper_edges,
                paper_vertices,
                colliding_edges,
                colliding_vertices,
            },
        }
    };

    vec![
        scene(
            "comb_3pt",
            "a tilted three-tipped comb sinks 1 cm into a box: three vertex contacts",
            block(4),
            comb,
            Pose::from_parts(
                Vector::new(0.03, comb_low - 0.01, -0.02),
                Rotation::from_rotation_x(tilt),
            ),
            (32, 22),
        ),
        scene(
            "cube_face",
            "a finely split cube lying flat sinks 2 cm into a split box: face contact",
            block(4),
            cube,
            Pose::from_parts(
                Vector::new(0.11, 0.1 - 0.02, 0.07),
                Rotation::from_rotation_y(0.5),
            ),
            (54, 31),
        ),
        scene(
            "ball_192",
            "a 20480-triangle icosphere sinks 3 cm into a 192-triangle box",
            block(4),
            ball(0.2),
            Pose::from_parts(Vector::new(0.013, 0.2 - 0.03, -0.021), ball_rot),
            (409, 205),
        ),
        scene(
            "ball_49k",
            "a 20480-triangle icosphere sinks 3.5 cm into a 49152-triangle box",
            block(64),
            ball(0.35),
            Pose::from_parts(Vector::new(0.013, 0.35 - 0.035, -0.021), ball_rot),
            (1062, 502),
        ),
    ]
}

/// Counts the colliding features of a pair at the given poses, as `(edges, vertices)`: the
/// distinct edges and vertices, summed over both meshes, of every triangle that intersects a
/// triangle of the other mesh (what a triangle-level collision detector such as RAPID
/// reports).
///
/// Candidates come from a simultaneous traversal of the two parry BVHs; each candidate pair is
/// then checked with parry's exact triangle-triangle intersection test.
///
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::scenes::colliding_features;
/// let slab = TouchMesh::from_shape(&Cuboid::new(Vector::new(2.0, 0.5, 2.0))).unwrap();
/// let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(0.5))).unwrap();
/// let slab_pose = Pose::from_translation(Vector::new(0.0, -0.5, 0.0));
/// // Far apart: nothing collides.
/// let away = Pose::from_translation(Vector::new(0.0, 3.0, 0.0));
/// assert_eq!(colliding_features(&slab, &slab_pose, &cube, &away), (0, 0));
/// // Sinking 0.1 m: some triangles of each mesh cross.
/// let sunk = Pose::from_translation(Vector::new(0.1, 0.4, 0.2));
/// let (edges, vertices) = colliding_features(&slab, &slab_pose, &cube, &sunk);
/// assert!(edges > 0 && vertices > 0);
/// ```
pub fn colliding_features(
    fixed: &TouchMesh,
    fixed_pose: &Pose,
    moving: &TouchMesh,
    pose: &Pose,
) -> (usize, usize) {
    use parry3d::bounding_volume::BoundingVolume;
    use std::collections::BTreeSet;

    // The moving mesh in the fixed mesh's frame.
    let pos12 = fixed_pose.inv_mul(pose);
    let (fbvh, mbvh) = (fixed.bvh(), moving.bvh());
    let mut hit_f = BTreeSet::new();
    let mut hit_m = BTreeSet::new();
    for (tf, tm) in fbvh.leaf_pairs(mbvh, |nf, nm| {
        nm.aabb().transform_by(&pos12).intersects(&nf.aabb())
    }) {
        let tri_f = fixed.trimesh().triangle(tf);
        let tri_m = moving.trimesh().triangle(tm);
        let hit = parry3d::query::intersection_test(&Pose::IDENTITY, &tri_f, &pos12, &tri_m)
            .is_ok_and(|r| r.intersecting);
        if hit {
            hit_f.insert(tf);
            hit_m.insert(tm);
        }
    }
    let count = |mesh: &TouchMesh, tris: &BTreeSet<u32>| -> (usize, usize) {
        let mut edges = BTreeSet::new();
        let mut vertices = BTreeSet::new();
        for &t in tris {
            edges.extend(mesh.triangle_edges(t));
            vertices.extend(mesh.indices()[t as usize]);
        }
        (edges.len(), vertices.len())
    };
    let (ef, vf) = count(fixed, &hit_f);
    let (em, vm) = count(moving, &hit_m);
    (ef + em, vf + vm)
}
