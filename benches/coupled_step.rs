//! The coupled step (issue 5): a soft plate pinned on its rim, on a fixed rapier body, pressed
//! by kinematic ball tools that circle while pressed in, so vertices enter, slide and leave.
//!
//! Timed per scene, in the same run:
//! - `rapier_step`: vanilla `PhysicsWorld::step` of the same world (the narrow phase sees the
//!   surface's TriMesh collider and the tools): the reference the ratios are quoted against;
//! - `full`: one coupled step without rapier's own step — `SurfaceSet::step_with` with a rigid
//!   step that only moves the tools: tool contacts, every surface substep, tool reactions,
//!   the dynamic tools' motion and the collider update (`TriMesh::set_vertices`, a BVH refit);
//! - `haptic`: the haptic path, `SurfaceSet::haptic_step` for one tool (tool contacts, one
//!   surface step, tool forces; no collider update);
//! - `collider_update`: the collider update alone (`set_vertices` on the surface's TriMesh).
//!
//! Scenes (0.3 m plates, 10 N/m springs, 2 g per node, tools of 2 cm radius): 784 nodes
//! (28 x 28, about the paper's 790) with 6 tools in a 60 Hz world with 1 surface step per
//! rigid step (s up to about 15: the neighbour filter falls back to the exact one) and with 17
//! (a 1 kHz surface, s ≤ 0.24, neighbour filter), the 60 Hz scene with six 4 cm cubes in place
//! of the balls (face, edge and corner contacts: the cubes' vertices and edges press between
//! the surface's vertices), the 60 Hz ball scene with Coulomb friction on every tool (μs 0.5,
//! μd 0.4: the circling balls stick and slip), and 10,000 nodes (100 x 100) with 2 tools
//! in a 1 kHz world, 1 substep, neighbour filter. The set-up prints each scene's filter. Targets (one core): 790 nodes and 6 tools ≤ 300 µs per full
//! step, the haptic path ≤ 50 µs, 10,000 nodes with 2 tools ≤ 1 ms.
//!
//! `256n_dynamic_ball_17sub`: a dynamic ball resting on a plate, coupled implicitly
//! (`bench_dynamic`), against rapier's step of the same world with the ball rigid on the
//! plate's collider.
//!
//! `100kn_6cubes_1khz` and `10kn_6cubes_1khz`: the contact search alone on a 100,000- and a
//! 10,000-node plate of the 784-node plate's spacing pressed by the six cubes
//! (`bench_search_100k`), against the linear scans it replaced, and the full step there.
//!
//! Run with `cargo bench --bench coupled_step`.

use criterion::{criterion_group, criterion_main, Criterion};
use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::scenes::attach_fixed;
use rapier_touch::surface::meshing::{plate, plate_rim};
use std::time::Duration;

const SIZE: f32 = 0.3;
const R: f32 = 0.02;

struct Scene {
    world: PhysicsWorld,
    set: SurfaceSet,
    soft: SurfaceHandle,
    tools: Vec<(ColliderHandle, RigidBodyHandle, Vector)>,
    t: f32,
}

/// Where tool `k` of `n` sits at time `t`: pressed 6 mm in, circling 5 mm around its spot.
fn tool_pose(k: usize, n: usize, centre: Vector, t: f32) -> Pose {
    let a = t * 6.0 + k as f32 * std::f32::consts::TAU / n as f32;
    Pose::from_translation(centre + Vector::new(0.005 * a.cos(), R - 0.006, 0.005 * a.sin()))
}

fn scene(side: u32, tools: usize, substeps: u32, dt: f32, cubes: bool, friction: bool) -> Scene {
    scene_sized(SIZE, side, tools, substeps, dt, cubes, friction)
}

fn scene_sized(
    size: f32,
    side: u32,
    tools: usize,
    substeps: u32,
    dt: f32,
    cubes: bool,
    friction: bool,
) -> Scene {
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    world.integration_parameters.dt = dt;
    let surface = MassSpringSurfaceBuilder::from_mesh(&plate(size, size, side, side))
        .stiffness(10.0)
        .damping(0.05)
        .mass(MassDistribution::PerVertex(2e-3))
        .pinned(plate_rim(side, side))
        .integrator(Integrator::NEIGHBOUR)
        .build()
        .expect("valid plate");
    let (mut set, soft, _) = attach_fixed(&mut world, surface, substeps);
    let spots: Vec<Vector> = (0..tools)
        .map(|k| {
            let a = k as f32 * std::f32::consts::TAU / tools as f32;
            let r = if tools == 1 { 0.0 } else { 0.07 };
            Vector::new(r * a.cos(), 0.0, r * a.sin())
        })
        .collect();
    let mut handles = Vec::new();
    for (k, c) in spots.iter().enumerate() {
        let start = tool_pose(k, tools, *c, 0.0).translation + Vector::Y * 0.05;
        let b = world.insert_body(RigidBodyBuilder::kinematic_position_based().translation(start));
        let shape = if cubes {
            ColliderBuilder::cuboid(R, R, R)
        } else {
            ColliderBuilder::ball(R)
        };
        let h = world.insert_collider(shape, Some(b));
        set.add_tool(h, &mut world).unwrap();
        if friction {
            set.set_tool_friction(h, Friction::new(0.5, 0.4).unwrap())
                .unwrap();
        }
        handles.push((h, b, *c));
    }
    // Press the tools in through real rapier steps.
    let press_steps = (0.5 / dt) as usize;
    for s in 0..2 * press_steps {
        let a = ((s + 1) as f32 / press_steps as f32).min(1.0);
        for (k, (_, b, c)) in handles.iter().enumerate() {
            let to = tool_pose(k, tools, *c, 0.0).translation;
            world.bodies[*b].set_next_kinematic_translation(to + Vector::Y * 0.05 * (1.0 - a));
        }
        set.step(&mut world);
    }
    let surface = &set.get(soft).unwrap().surface;
    println!(
        "{} nodes, {tools} tools, {substeps} substeps of {:.3} ms: {:?}, fell back to exact: {}, s max {:.2}",
        surface.num_vertices(),
        surface.dt() * 1e3,
        surface.integrator(),
        surface.filter_fallback(),
        surface.s_values().iter().cloned().fold(0.0, f32::max)
    );
    if friction {
        let sticking: usize = handles
            .iter()
            .map(|(h, _, _)| set.tool_reaction(*h).unwrap().sticking_vertices)
            .sum();
        println!("friction: {sticking} vertices stick to the tools");
    }
    for (h, _, _) in &handles {
        let r = set.tool_reaction(*h).unwrap();
        assert!(
            r.held_vertices + r.pressed_points > 0 && r.force.y > 0.0,
            "tool pressing: {r:?} at {:?}",
            world.colliders[*h].position().translation
        );
    }
    Scene {
        world,
        set,
        soft,
        tools: handles,
        t: 0.0,
    }
}

impl Scene {
    /// One coupled step with a rigid step that only moves the tools (their colliders'
    /// `set_position`, the bodies left where the pressing put them: the coupling starts each
    /// tool where its collider ended the last step, `tests/it/circling_tools.rs`).
    fn full_step(&mut self) {
        self.t += self.world.integration_parameters.dt;
        let (t, n) = (self.t, self.tools.len());
        let tools = &self.tools;
        self.set.step_with(&mut self.world, |w| {
            for (k, (h, _, c)) in tools.iter().enumerate() {
                w.colliders[*h].set_position(tool_pose(k, n, *c, t));
            }
        });
    }

    /// Vanilla rapier's step of the same world, the tools driven along their paths.
    fn rapier_step(&mut self) {
        self.t += self.world.integration_parameters.dt;
        let n = self.tools.len();
        for (k, (_, b, c)) in self.tools.iter().enumerate() {
            self.world.bodies[*b].set_next_kinematic_position(tool_pose(k, n, *c, self.t));
        }
        self.world.step();
    }
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("coupled_step");
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    for (name, side, tools, substeps, dt, cubes, friction) in [
        (
            "784n_6tools_60hz",
            27u32,
            6usize,
            1u32,
            1.0 / 60.0,
            false,
            false,
        ),
        (
            "784n_6tools_60hz_friction",
            27,
            6,
            1,
            1.0 / 60.0,
            false,
            true,
        ),
        ("784n_6cubes_60hz", 27, 6, 1, 1.0 / 60.0, true, false),
        (
            "784n_6cubes_60hz_friction",
            27,
            6,
            1,
            1.0 / 60.0,
            true,
            true,
        ),
        (
            "784n_6tools_60hz_17sub",
            27,
            6,
            17,
            1.0 / 60.0,
            false,
            false,
        ),
        ("10kn_2tools_1khz", 99, 2, 1, 1.0 / 1000.0, false, false),
    ] {
        let mut s = scene(side, tools, substeps, dt, cubes, friction);
        g.bench_function(format!("{name}/rapier_step"), |b| {
            b.iter(|| s.rapier_step())
        });
        g.bench_function(format!("{name}/full"), |b| b.iter(|| s.full_step()));
        for (h, _, _) in &s.tools {
            let r = s.set.tool_reaction(*h).unwrap();
            assert!(
                r.force.is_finite() && r.held_vertices + r.pressed_points > 0,
                "{name}: still pressing"
            );
        }
        {
            let (tool, _, centre) = s.tools[0];
            let mut t = 0.0f32;
            g.bench_function(format!("{name}/haptic"), |b| {
                b.iter(|| {
                    t += 1e-3;
                    s.set
                        .haptic_step(&s.world, tool, tool_pose(0, tools, centre, t))
                        .unwrap()
                })
            });
        }
        let collider = s.set.get(s.soft).unwrap().collider().unwrap();
        let mut verts = Vec::new();
        s.set
            .get(s.soft)
            .unwrap()
            .surface
            .positions_into(&mut verts);
        g.bench_function(format!("{name}/collider_update"), |b| {
            b.iter(|| {
                let c = &mut s.world.colliders[collider];
                c.shape_mut().as_trimesh_mut().unwrap().set_vertices(&verts);
            })
        });
        assert!(s.set.get(s.soft).unwrap().surface.is_finite());
    }
    g.finish();
}

/// The contact search per surface substep on plates of 100,000 and 10,000 nodes (316 and 99
/// cells of 11 mm a side: the 784-node plate's mesh spacing over 3.5 m and 1.1 m) pressed by
/// the six 4 cm cubes of the `784n_6cubes` scene, near the middle, in a 1 kHz world: what the
/// coupling does to find the contacts, timed alone while the real coupled step runs (untimed)
/// between samples.
///
/// - `search_bvh`: the crate's search: the [`SurfaceBvh`] brought up to date with the vertices
///   that moved farther than its slack (found here by a scan, untimed; the surface notes them
///   as its integrator moves them), then per cube one walk (reused through a [`NearCache`]
///   while the cube stays in the grown box it walked) for the vertices near it (each tested
///   against the cube, as the vertex holds do) and the triangles its sweep may meet, filtered
///   by their own bounds, and the cube's vertex-face and edge-edge contacts with them;
/// - `search_scan`: the same contacts from linear scans (every vertex against each cube's box,
///   every triangle's bounds once and against each cube's sweep): what the coupling did before;
/// - `candidates_bvh`: `search_bvh` without the tests against the cube: the candidates alone.
fn bench_search_100k(c: &mut Criterion) {
    // The same search on a 10,000-node plate of the same spacing: what does not grow with
    // the mesh takes the same time there.
    for (label, side) in [("10kn", 99u32), ("100kn", 316)] {
        bench_search(c, label, side);
    }
}

fn bench_search(c: &mut Criterion, label: &str, side: u32) {
    use rapier_touch::geometry::{
        tool_surface_contacts_with_rings, triangles_in, NearCache, SurfaceBvh, SurfaceSnapshot,
    };
    use rapier_touch::parry3d::bounding_volume::BoundingVolume;
    use rapier_touch::parry3d::query::PointQuery;
    use std::time::Instant;

    let dt = 1.0 / 1000.0;
    let mut s = scene_sized(SIZE * side as f32 / 27.0, side, 6, 1, dt, true, false);
    let cube = TouchMesh::from_shape(&Cuboid::new(Vector::splat(R))).unwrap();
    let shape = Cuboid::new(Vector::splat(R));
    let positions = |s: &Scene| {
        let mut p = Vec::new();
        s.set.get(s.soft).unwrap().surface.positions_into(&mut p);
        p
    };
    let triangles = s.set.get(s.soft).unwrap().surface.triangles().to_vec();
    let mut now = positions(&s);
    let edge = {
        let t = triangles[0];
        (now[t[0] as usize] - now[t[1] as usize]).length()
    };
    // The coupling's slack: a quarter of an edge.
    let slack = 0.25 * edge;
    let mut bvh = SurfaceBvh::new(&now, &triangles, slack);
    let mut reference = now.clone();
    let (mut moved, mut verts, mut tris, mut near_tris, mut contacts) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut bounds = Vec::new();
    let mut caches = vec![NearCache::default(); 6];
    let (mut candidates_seen, mut moved_seen, mut contacts_seen, mut samples) = (0, 0, 0, 0);
    let mut g = c.benchmark_group("coupled_step");
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(3));
    for (name, scan, tests) in [
        ("search_bvh", false, true),
        ("search_scan", true, true),
        ("candidates_bvh", false, false),
    ] {
        g.bench_function(format!("{label}_6cubes_1khz/{name}"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let t0 = s.t;
                    s.full_step();
                    let before = std::mem::replace(&mut now, positions(&s));
                    moved.clear();
                    for (v, (p, r)) in now.iter().zip(reference.iter_mut()).enumerate() {
                        if (*p - *r).length() > slack {
                            *r = *p;
                            moved.push(v as u32);
                        }
                    }
                    let n = s.tools.len();
                    let poses: Vec<(Pose, Pose)> = s
                        .tools
                        .iter()
                        .enumerate()
                        .map(|(k, (_, _, c))| (tool_pose(k, n, *c, t0), tool_pose(k, n, *c, s.t)))
                        .collect();
                    let snapshot = SurfaceSnapshot {
                        before: &before,
                        now: &now,
                        triangles: &triangles,
                    };
                    let start = Instant::now();
                    contacts.clear();
                    let mut near = 0usize;
                    if !scan {
                        bvh.update(&moved, &now, &before);
                    } else {
                        snapshot.triangle_bounds(&mut bounds);
                    }
                    for (k, (from, to)) in poses.iter().enumerate() {
                        let aabb = cube.local_aabb().transform_by(to);
                        let box_ = aabb.loosened(1e-4 * edge);
                        let swept = aabb.merged(&cube.local_aabb().transform_by(from));
                        let query = swept.loosened(2e-4 * edge);
                        if scan {
                            verts.clear();
                            verts.extend(
                                (0..now.len() as u32)
                                    .filter(|&v| box_.contains_local_point(now[v as usize])),
                            );
                            triangles_in(&bounds, &query, &mut tris);
                        } else {
                            // One walk of the tree for both, reused while the cube stays
                            // inside the grown box it walked, as the coupling does.
                            let q = query.merged(&box_);
                            let grow = 0.2 * q.extents().max_element();
                            bvh.near_cached(&mut caches[k], &q, grow, &mut near_tris, &mut verts);
                            snapshot.triangles_meeting(&near_tris, &query, &mut tris);
                        }
                        for &v in verts.iter().filter(|_| tests) {
                            let p = now[v as usize];
                            if box_.contains_local_point(p) {
                                near +=
                                    (shape.distance_to_point(to, p, true) <= 1e-4 * edge) as usize;
                            }
                        }
                        if tests {
                            // With each vertex's ring from the BVH, as the coupling
                            // asks for a kinematic tool.
                            tool_surface_contacts_with_rings(
                                &snapshot,
                                &tris,
                                &|v, out| bvh.triangles_of(&[v], out),
                                &cube,
                                from,
                                to,
                                1e-4 * edge,
                                &mut contacts,
                            );
                        }
                    }
                    total += start.elapsed();
                    candidates_seen += verts.len() + tris.len() + near;
                    moved_seen += moved.len();
                    contacts_seen += contacts.len();
                    samples += 1;
                }
                total
            })
        });
        println!(
            "{name}: per substep {:.0} vertices moved past the slack ({slack:.2e} m), {:.0} contacts",
            moved_seen as f64 / samples.max(1) as f64,
            contacts_seen as f64 / samples.max(1) as f64,
        );
        println!(
            "{name}: {:.0} candidates (vertices, triangles, vertices in a cube) per substep",
            candidates_seen as f64 / samples.max(1) as f64
        );
        (candidates_seen, moved_seen, contacts_seen, samples) = (0, 0, 0, 0);
    }
    g.bench_function(format!("{label}_6cubes_1khz/full"), |b| {
        b.iter(|| s.full_step())
    });
    g.finish();
}

/// A dynamic tool: `scenes::BallOnPlateScene` (a 0.1 kg ball on a 256-node plate, 17 substeps,
/// the exact filter) at rest after 2 s, stepped through `SurfaceSet::step` (rapier's step, then
/// the plate's substeps with the ball's mass in each solve), against rapier's own step of the
/// same world with the ball's solver groups restored (a rigid ball on the plate's collider).
fn bench_dynamic(c: &mut Criterion) {
    use rapier_touch::scenes::BallOnPlateScene;
    let mut g = c.benchmark_group("coupled_step");
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    let mut scene = BallOnPlateScene::new();
    for _ in 0..120 {
        scene.step();
    }
    assert!(scene.ball_velocity().length() < 1e-3, "the ball rests");
    g.bench_function("256n_dynamic_ball_17sub/full", |b| b.iter(|| scene.step()));
    let mut rigid = BallOnPlateScene::new();
    for _ in 0..120 {
        rigid.step();
    }
    let (ball, body, mut world) = (rigid.ball_collider, rigid.ball, rigid.world);
    rigid.set.remove_tool(ball, &mut world);
    // Kept awake: asleep on the rigid plate, rapier's step would do nothing.
    g.bench_function("256n_dynamic_ball_17sub/rapier_step", |b| {
        b.iter(|| {
            world.bodies[body].wake_up(true);
            world.step()
        })
    });
    g.finish();
}

criterion_group!(benches, bench, bench_search_100k, bench_dynamic);
criterion_main!(benches);
