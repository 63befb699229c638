//! The crate's prelude and rapier's glob-import together: every name the crate's prelude
//! exports resolves without ambiguity next to `rapier3d::prelude::*` (an ambiguous glob name
//! is an error only where it is used, so each one is used below).
#![deny(ambiguous_glob_imports)]

use rapier3d::prelude::*;
use rapier_touch::prelude::*;

/// Names both preludes export (the math types and parry shapes rapier re-exports) are the very
/// same items: a cube built with them is touched exactly on its face by a falling cube.
#[test]
fn both_preludes_glob_import_without_ambiguity() {
    let half: Real = 0.5;
    let floor = TouchMesh::from_shape(&Cuboid::new(Vector::new(2.0, half, 2.0))).unwrap();
    let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(half))).unwrap();
    // `Cuboid` is rapier's alias of parry's struct: the very type parry's functions take.
    let _: rapier_touch::parry3d::shape::Cuboid = Cuboid::new(Vector::splat(half));
    let floor_pose = Pose::from_translation(Vector::new(0.0, -half, 0.0));
    let now = Pose::from_translation(Vector::new(0.0, 0.4, 0.0));
    let before = Pose::from_translation(Vector::new(0.0, 0.9, 0.0));
    let mut rec = Reconstructor::default();
    let c: ContactConfiguration = rec
        .reconstruct(&floor, &floor_pose, &cube, &now, &before)
        .unwrap();
    assert_eq!(c.state, TouchState::Penetrating);
    assert!((c.reversing_vector - Vector::new(0.0, 0.1, 0.0)).length() < 1e-5);
    let patch: &ContactPatch = &c.patches[0];
    assert_eq!(patch.kind, ContactKind::Face);
    let _: Option<&ContactPoint> = patch.points.first();
    let _: Option<(Feature, DirectionSource)> = None;
    let _: Rotation = Rotation::IDENTITY;
    let motion = RigidMotion::new(before, now, Vector::ZERO);
    assert!((motion.pose_at(0.5).translation - Vector::new(0.0, 0.65, 0.0)).length() < 1e-6);
    let _: ReconstructionOptions = ReconstructionOptions::default();
    let _: Option<(ReconstructionError, TouchMeshError)> = None;
    assert_eq!(safe_step_length(&floor, &cube), 1.0);

    // Parry shapes rapier's prelude also exports (`ConvexPolyhedron`, `TriMesh`).
    let hull = ConvexPolyhedron::from_convex_hull(&[Vector::ZERO, Vector::X, Vector::Y, Vector::Z])
        .unwrap();
    assert_eq!(hull.points().len(), 4);
    let tri = TriMesh::new(vec![Vector::ZERO, Vector::X, Vector::Y], vec![[0, 1, 2]]).unwrap();
    assert_eq!(tri.num_triangles(), 1);

    // rapier's own names next to the crate's.
    let mut world = PhysicsWorld::default();
    TouchPipeline::configure(&mut world.integration_parameters);
    let body = world.insert_body(RigidBodyBuilder::dynamic());
    let collider = world.insert_collider(ColliderBuilder::cuboid(0.5, 0.5, 0.5), Some(body));
    let mut touch: TouchPipeline = TouchPipeline::default();
    touch.track_collider(collider);
    touch.step(&mut world);
    let _: &[PairReport] = touch.reports();
    let _: Option<ToolFeedback> = touch.tool_feedback(body);
    let _: HookCounters = touch.hooks.counters();
    let _: &TouchHooks = &touch.hooks;
    let _: TouchOptions = touch.options;

    // The soft-surface and coupling names.
    let _: Option<(SurfaceHandle, ToolReaction, CouplingError)> = None;
    let _: Option<&AttachedSurface> = None;
    let _: AttachOptions = AttachOptions::default();
    let _: SurfaceSet = SurfaceSet::new();
    let _: Option<(FilterKind, ForceProfile, Integrator, MassDistribution)> = None;
    let _: Option<(SpringModel, SurfaceError)> = None;
    let _: Option<(MassSpringSurface, MassSpringSurfaceBuilder)> = None;
}
