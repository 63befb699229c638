//! Six rigid tools pressing and dragging on a soft organ surface of 788 nodes in a rapier scene.
//!
//! **The organ.** `paper_organ_outline()` meshed with its own target edge (5.28 mm) as in
//! `constrained_790`: 788 nodes, a kidney about 0.14 m × 0.10 m in the plane y = 0, lifted into
//! a dome: the height solves the mesh's Poisson problem `L h = 1` with `h = 0` on the outer
//! boundary (a membrane inflated from below: smooth, without the crease a plain
//! distance-to-boundary profile has along the middle line), scaled to a 30 mm peak. The 111
//! outer-boundary vertices (`PlanarMesh::boundary`) are pinned: the organ's base. The outline's
//! internal constraint polyline is left free. The paper's linear springs, k = 10 N/m and
//! c = 0.1 N·s/m per edge, masses lumped from 15 kg/m² (a tissue layer about 15 mm thick,
//! 0.21 kg in all), no gravity. The damping is heavy enough that the organ stops ringing within
//! about 0.1 s of a tool coming down or lifting off (with c = 0.03 the quasi-static force
//! balance below is off by up to 12 %).
//!
//! **Attachment.** `SurfaceSet::insert` on a fixed body with 17 substeps: the surface runs at
//! 1020 Hz, the rate of a haptic device, so each tool's force is what a device would read, and
//! a tool moves at most about 0.15 mm per substep (3 % of the edge length), so a vertex a tool
//! meets is walked back to the tool's boundary over a short, well-resolved motion. The exact
//! filter: here the immediate-neighbour filter's error bound is 0.64 (s up to 3.9), far above
//! its 5 % limit, so it would fall back to the exact filter anyway. About 0.6 s for the run.
//!
//! **Tools**: five balls (radius 7 to 12 mm) and a cuboid (16 × 8 × 12 mm), kinematic
//! position-based bodies driven with `set_next_kinematic_translation` every 60 Hz step. Each
//! waits 20 mm above the organ, comes down in 0.3 s until its lowest point is 6 mm below the
//! home surface, presses 0.35 s, is dragged 23 to 40 mm sideways in 1.5 s (following the dome's
//! home height), holds 0.35 s and lifts off in 0.3 s. They start 0.5 s apart, so up to five
//! press at once; 0.4 to 0.5 s after each start no tool has come down or lifted off for 0.1 s
//! (the quasi-static steps). The cuboid is pitched 23° about the axis across its drag, leading
//! edge up, like a sled: with frictionless vertex contact and the linear springs, an upright
//! cuboid's vertical leading face ploughs the vertices it meets ahead of it instead of letting
//! them slide under (tried: vertices carried 15 to 24 mm, a 0.7 to 0.9 N horizontal force).
//! There is no convex polyhedron: its force still fluctuates from step to step (see the
//! `SurfaceSet` limitations; capsules and cylinders are steady, `tests/it/coupling.rs`).
//!
//! **Printed** every 0.25 s (at t = 0.2, 0.45, 0.7, ... s): per tool the vertices it holds and
//! its force magnitude (N), the organ's largest displacement (mm), the magnitudes of the tools'
//! total force and of the pins' reaction (the sum of `internal_force` over the pinned
//! vertices) and their imbalance `|Σ F_tools + Σ F_pins| / Σ |F_tool|`, marked `(moving)` when
//! a tool came down or lifted off in the last 0.1 s. The rest of the balance is the free
//! vertices' own (inertial and damping) forces and the tangential parts of the held vertices'
//! forces, which frictionless contact does not pass on. Then the largest values over the run,
//! each tool's mean force along the surface normal and against its drag while dragged, the
//! contact checks and a closing `summary:` line.
//!
//! **Checks** (asserts): every tool force, torque and the pins' reaction is finite; the base
//! never moves; while a tool presses, drags or holds, it holds vertices and its force points
//! out of the surface (positive dot product with the home normal under it); the largest
//! displacement stays between 0.8 and 1.5 times the press depth (dents, no ploughing); a
//! dragged ball is held back by less than 10 % of its normal force (measured 1.6 to 5.4 %;
//! the sled's tilted bottom, 36 %); no vertex is inside a tool by more than 1 µm and every held
//! vertex lies on a tool's boundary within 1 µm (measured: 4 nm); straight above every tool's
//! centre there is no surface, and straight below it the deformed surface is no nearer than
//! the tool's own boundary less 1.5 mm (the flat triangles between held vertices cut into a
//! ball by up to L²/8r for an edge L: measured 0.96 mm, under the 9 mm ball on the flank); at
//! the quasi-static steps the tools' forces and the pins' reaction balance within 10 % (measured
//! 7.3 %, at the sled's sharp edges; 3.0 % with a ball in its place); 2 s after the last
//! lift-off the organ is home within 0.01 mm.
//!
//! Run with `cargo run --release --example multi_tool`.

use rapier_touch::prelude::*;
use rapier_touch::rapier3d::prelude::*;
use rapier_touch::surface::meshing::{paper_organ_outline, triangulate_planar, SurfaceMesh};
use std::time::Instant;

const DT: Real = 1.0 / 60.0;
const SUBSTEPS: u32 = 17;
const END_TIME: Real = 7.5;
const PRINT_EVERY: usize = 15; // 0.25 s, at t = 0.2, 0.45, 0.7, ... s
const DOME_HEIGHT: Real = 0.03;
const K: Real = 10.0;
const C: Real = 0.1;
const DENSITY: Real = 15.0;
const DEPTH: Real = 0.006;
const CLEARANCE: Real = 0.02;
const STAGGER: Real = 0.5;

// A tool's path, in seconds from its start.
const DESCEND: Real = 0.3;
const PRESS: Real = 0.35;
const DRAG: Real = 1.5;
const HOLD: Real = 0.35;
const LIFT: Real = 0.3;
const ACTIVE: Real = DESCEND + PRESS + DRAG + HOLD + LIFT;

#[derive(Copy, Clone, Debug)]
enum Shape {
    Ball(Real),
    /// Half extents.
    Cuboid(Real, Real, Real),
}

impl Shape {
    fn collider(self) -> ColliderBuilder {
        match self {
            Shape::Ball(r) => ColliderBuilder::ball(r),
            Shape::Cuboid(x, y, z) => ColliderBuilder::cuboid(x, y, z),
        }
    }
    fn describe(self) -> String {
        match self {
            Shape::Ball(r) => format!("ball r = {:.0} mm", r * 1e3),
            Shape::Cuboid(x, y, z) => format!(
                "cuboid {:.0} x {:.0} x {:.0} mm, pitched 23 deg",
                2e3 * x,
                2e3 * y,
                2e3 * z
            ),
        }
    }
}

struct ToolSpec {
    shape: Shape,
    /// Orientation (scaled axis, rad).
    tilt: Vector,
    /// Where it comes down and where the drag ends (u, v) = (x, z).
    from: [Real; 2],
    to: [Real; 2],
}

fn tools() -> [ToolSpec; 6] {
    let ball = |r: Real, from: [Real; 2], to: [Real; 2]| ToolSpec {
        shape: Shape::Ball(r),
        tilt: Vector::ZERO,
        from,
        to,
    };
    [
        ball(0.010, [0.045, 0.022], [0.045, -0.018]),
        ball(0.008, [-0.035, 0.022], [-0.005, 0.025]),
        ToolSpec {
            shape: Shape::Cuboid(0.008, 0.004, 0.006),
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

#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Phase {
    Waiting,
    Descending,
    Pressing,
    Dragging,
    Holding,
    Lifting,
    Done,
}

fn smooth(x: Real) -> Real {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Tool `k`'s spot (u, v), the depth of its lowest point below the home surface (negative:
/// above) and its phase at time `t`.
fn script(spec: &ToolSpec, k: usize, t: Real) -> ([Real; 2], Real, Phase) {
    let s = t - k as Real * STAGGER;
    let lerp = |x: Real| {
        [
            spec.from[0] + (spec.to[0] - spec.from[0]) * x,
            spec.from[1] + (spec.to[1] - spec.from[1]) * x,
        ]
    };
    let t1 = DESCEND;
    let t2 = t1 + PRESS;
    let t3 = t2 + DRAG;
    let t4 = t3 + HOLD;
    if s < 0.0 {
        (spec.from, -CLEARANCE, Phase::Waiting)
    } else if s < t1 {
        let d = -CLEARANCE + (DEPTH + CLEARANCE) * smooth(s / DESCEND);
        (spec.from, d, Phase::Descending)
    } else if s < t2 {
        (spec.from, DEPTH, Phase::Pressing)
    } else if s < t3 {
        (lerp(smooth((s - t2) / DRAG)), DEPTH, Phase::Dragging)
    } else if s < t4 {
        (spec.to, DEPTH, Phase::Holding)
    } else if s < ACTIVE {
        let d = DEPTH - (DEPTH + CLEARANCE) * smooth((s - t4) / LIFT);
        (spec.to, d, Phase::Lifting)
    } else {
        (spec.to, -CLEARANCE, Phase::Done)
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

/// The home surface's height over (u, v): interpolated in the planar triangle containing it.
fn home_height(flat: &SurfaceMesh, heights: &[Real], u: Real, v: Real) -> Real {
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

/// The home vertex nearest to (u, v) in plan.
fn nearest_vertex(flat: &SurfaceMesh, u: Real, v: Real) -> usize {
    let d2 = |i: usize| (flat.vertices[i].x - u).powi(2) + (flat.vertices[i].z - v).powi(2);
    (0..flat.num_vertices())
        .min_by(|&a, &b| d2(a).total_cmp(&d2(b)))
        .expect("vertices")
}

fn main() {
    let wall = Instant::now();
    let (outline, target_edge) = paper_organ_outline();
    let planar = triangulate_planar(&outline, target_edge).expect("meshes");
    let flat = planar.mesh.clone();
    let base = planar.boundary.clone();
    let heights: Vec<Real> = dome(&flat, &base).iter().map(|h| h * DOME_HEIGHT).collect();
    let vertices: Vec<Vector> = flat
        .vertices
        .iter()
        .zip(&heights)
        .map(|(v, h)| Vector::new(v.x, *h, v.z))
        .collect();
    let normals = vertex_normals(&vertices, &flat.triangles);
    let n = vertices.len();

    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    world.integration_parameters.dt = DT;
    let organ_body = world.insert_body(RigidBodyBuilder::fixed());
    let surface = MassSpringSurfaceBuilder::new(vertices, flat.triangles.clone())
        .stiffness(K)
        .damping(C)
        .mass(MassDistribution::AreaDensity(DENSITY))
        .pinned(base.iter().copied())
        .integrator(Integrator::EXACT)
        .build()
        .expect("valid organ mesh");
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: SUBSTEPS,
        collider: true,
    };
    let organ = set
        .insert(surface, organ_body, &mut world, options)
        .expect("attached");
    let organ_collider = set.get(organ).unwrap().collider().expect("collider");
    {
        let s = &set.get(organ).unwrap().surface;
        let s_free: Vec<Real> = s.s_values().into_iter().filter(|&x| x > 0.0).collect();
        let total_mass: Real = (0..n as u32).map(|i| s.mass(i)).sum();
        println!(
            "organ: {n} nodes, {} triangles, {} base vertices pinned, dome {:.0} mm high, \
             {:.3} kg",
            flat.num_triangles(),
            base.len(),
            DOME_HEIGHT * 1e3,
            total_mass
        );
        println!(
            "k = {K} N/m, c = {C} N*s/m per edge, {DENSITY} kg/m^2, exact filter, {SUBSTEPS} \
             substeps (surface dt {:.3} ms); s mean {:.3}, max {:.3}; the neighbour filter's \
             error bound would be {:.3}",
            s.dt() * 1e3,
            s_free.iter().sum::<Real>() / s_free.len() as Real,
            s_free.iter().copied().fold(0.0, Real::max),
            s.neighbour_error_bound(1),
        );
    }

    let specs = tools();
    // Each tool's lowest point relative to its centre (world axes), and how far its own
    // boundary is straight below its centre.
    let mut lowest = Vec::new();
    let mut reach_down = Vec::new();
    for spec in &specs {
        let rot = Pose::from_parts(Vector::ZERO, Rotation::from_scaled_axis(spec.tilt));
        let collider = spec.shape.collider().build();
        let map = collider.shape().as_support_map().expect("convex tool");
        lowest.push(map.support_point(&rot, -Vector::Y));
        let down = Ray::new(-Vector::Y * 1.0, Vector::Y);
        let toi = collider
            .shape()
            .cast_ray(&rot, &down, 2.0, false)
            .expect("the ray meets the tool");
        reach_down.push(1.0 - toi);
    }
    // The tool's centre over its spot, its lowest point `depth` below the home surface there.
    let place = |k: usize, t: Real| -> (Vector, [Real; 2], Phase) {
        let ([u, v], depth, phase) = script(&specs[k], k, t);
        let o = lowest[k];
        let y = home_height(&flat, &heights, u + o.x, v + o.z) - depth - o.y;
        (Vector::new(u, y, v), [u, v], phase)
    };
    let mut bodies = Vec::new();
    let mut colliders = Vec::new();
    for (k, spec) in specs.iter().enumerate() {
        let (at, _, _) = place(k, 0.0);
        let b = world.insert_body(
            RigidBodyBuilder::kinematic_position_based()
                .translation(at)
                .rotation(spec.tilt),
        );
        let c = world.insert_collider(spec.shape.collider(), Some(b));
        set.add_tool(c, &mut world);
        bodies.push(b);
        colliders.push(c);
        let start = k as Real * STAGGER;
        println!(
            "tool {}: {}, down at ({:.3}, {:.3}) from t = {start:.1} s, dragged to ({:.3}, \
             {:.3}), off at t = {:.1} s",
            k + 1,
            spec.shape.describe(),
            spec.from[0],
            spec.from[1],
            spec.to[0],
            spec.to[1],
            start + ACTIVE
        );
    }
    println!();
    print!("{:>5}", "t s");
    for k in 0..specs.len() {
        print!(" | T{} held  |F| N", k + 1);
    }
    println!(" | disp mm | tools N | pins N | imbalance");

    let steps = (END_TIME / DT).round() as usize;
    let last_off = (specs.len() - 1) as Real * STAGGER + ACTIVE;
    let mut positions = Vec::new();
    let (mut max_force, mut max_disp) = (0.0f32, 0.0f32);
    let (mut max_imbalance, mut quasi_static_samples) = (0.0f32, 0usize);
    let (mut min_clearance, mut max_inside, mut max_off_boundary) = (Real::MAX, 0.0f32, 0.0f32);
    let mut pressed_steps = vec![0usize; specs.len()];
    // Per tool while dragged: sums of the force along the home normal and against the drag.
    let mut drag_sums = vec![(0.0f32, 0.0f32, 0usize); specs.len()];
    for step in 1..=steps {
        let t = step as Real * DT;
        let mut phases = Vec::new();
        let mut spots = Vec::new();
        for (k, b) in bodies.iter().enumerate() {
            let (at, spot, phase) = place(k, t);
            world.bodies[*b].set_next_kinematic_translation(at);
            phases.push(phase);
            spots.push(spot);
        }
        set.step(&mut world);

        let s = &set.get(organ).unwrap().surface;
        s.positions_into(&mut positions);
        let disp = s.max_displacement();
        max_disp = max_disp.max(disp);
        let pins: Vector = base.iter().map(|&i| s.internal_force(i)).sum();
        assert!(pins.is_finite(), "pin reaction at t = {t}");
        for &i in &base {
            assert_eq!(s.position(i), s.home(i), "base vertex {i} moved");
        }
        let organ_pose = *world.colliders[organ_collider].position();
        let organ_shape = world.colliders[organ_collider].shape();
        let (mut total, mut sum_abs) = (Vector::ZERO, 0.0);
        let mut row = Vec::new();
        for (k, c) in colliders.iter().enumerate() {
            let r = set.tool_reaction(*c).expect("tool");
            assert!(
                r.force.is_finite() && r.mean_force.is_finite() && r.torque.is_finite(),
                "tool {} at t = {t}: {r:?}",
                k + 1
            );
            total += r.force;
            sum_abs += r.force.length();
            max_force = max_force.max(r.force.length());
            row.push((r.held_vertices, r.force.length()));
            if matches!(
                phases[k],
                Phase::Pressing | Phase::Dragging | Phase::Holding
            ) {
                pressed_steps[k] += 1;
                let normal = normals[nearest_vertex(&flat, spots[k][0], spots[k][1])];
                assert!(
                    r.held_vertices > 0 && r.force.dot(normal) > 0.0,
                    "tool {} ({:?}) at t = {t}: {r:?}",
                    k + 1,
                    phases[k]
                );
                if phases[k] == Phase::Dragging {
                    // The drag direction in the surface's tangent plane.
                    let along = Vector::new(
                        specs[k].to[0] - specs[k].from[0],
                        0.0,
                        specs[k].to[1] - specs[k].from[1],
                    );
                    let along = (along - normal * along.dot(normal)).normalize();
                    let d = &mut drag_sums[k];
                    d.0 += r.force.dot(normal);
                    d.1 -= r.force.dot(along);
                    d.2 += 1;
                }
            }
            // No vertex inside the tool.
            let pose = *world.colliders[*c].position();
            let shape = world.colliders[*c].shape();
            for p in &positions {
                let proj = shape.project_point(&pose, *p, false);
                if proj.is_inside {
                    max_inside = max_inside.max((proj.point - *p).length());
                }
            }
            // The tool's centre stays above the deformed surface.
            let up = Ray::new(pose.translation, Vector::Y);
            assert!(
                organ_shape.cast_ray(&organ_pose, &up, 1.0, false).is_none(),
                "tool {} is under the surface at t = {t}",
                k + 1
            );
            let down = Ray::new(pose.translation, -Vector::Y);
            if let Some(toi) = organ_shape.cast_ray(&organ_pose, &down, 1.0, false) {
                min_clearance = min_clearance.min(toi - reach_down[k]);
            }
        }
        // Held vertices lie on a tool's boundary.
        for (i, p) in positions.iter().enumerate() {
            if s.is_held(i as u32) {
                let off = colliders
                    .iter()
                    .map(|c| {
                        let col = &world.colliders[*c];
                        let proj = col.shape().project_point(col.position(), *p, false);
                        (proj.point - *p).length()
                    })
                    .fold(Real::MAX, Real::min);
                max_off_boundary = max_off_boundary.max(off);
            }
        }
        // Quasi-static: no tool has come down or lifted off in the last 0.1 s.
        let moving = (0..specs.len()).any(|k| {
            [t, t - 0.1].iter().any(|&t| {
                matches!(
                    script(&specs[k], k, t).2,
                    Phase::Descending | Phase::Lifting
                )
            })
        });
        let imbalance = (total + pins).length() / sum_abs.max(Real::MIN_POSITIVE);
        if !moving && sum_abs > 0.0 {
            max_imbalance = max_imbalance.max(imbalance);
            quasi_static_samples += 1;
        }
        if step % PRINT_EVERY == 12 || step == steps {
            print!("{t:>5.2}");
            for (held, f) in &row {
                print!(" | {held:>6} {f:>6.3}");
            }
            let balance = if sum_abs > 0.0 {
                format!("{:>6.1} %", 100.0 * imbalance)
            } else {
                format!("{:>8}", "-")
            };
            println!(
                " | {:>7.3} | {:>7.3} | {:>6.3} | {balance}{}",
                disp * 1e3,
                total.length(),
                pins.length(),
                if moving { " (moving)" } else { "" }
            );
        }
    }
    let final_disp = set.get(organ).unwrap().surface.max_displacement();
    println!();
    println!(
        "largest tool force {max_force:.3} N; largest displacement {:.2} mm; largest imbalance \
         at the {quasi_static_samples} quasi-static steps {:.1} %",
        max_disp * 1e3,
        100.0 * max_imbalance
    );
    for (k, (normal, against, count)) in drag_sums.iter().enumerate() {
        let count = (*count).max(1) as Real;
        println!(
            "tool {} dragged: mean force {:.3} N along the surface normal, {:.3} N against the \
             drag along the surface (frictionless: from the dent's tilted walls only)",
            k + 1,
            normal / count,
            against / count
        );
    }
    println!(
        "deepest vertex inside a tool {:.1e} mm; held vertex farthest from a tool boundary \
         {:.1e} mm; least clearance below a tool centre beyond the tool {:.3} mm",
        max_inside * 1e3,
        max_off_boundary * 1e3,
        min_clearance * 1e3
    );
    println!(
        "{:.1} s after the last lift-off: largest displacement {:.1e} mm",
        END_TIME - last_off,
        final_disp * 1e3
    );
    println!(
        "summary: steps={steps} tools={} nodes={n} max_force_n={max_force:.3} \
         max_disp_mm={:.2} final_disp_mm={:.1e} max_imbalance_pct={:.1} wall_s={:.2}",
        specs.len(),
        max_disp * 1e3,
        final_disp * 1e3,
        100.0 * max_imbalance,
        wall.elapsed().as_secs_f64()
    );

    assert!(pressed_steps.iter().all(|&p| p > 0));
    // Frictionless sliding: a ball dragged at a constant depth is resisted only by the
    // asymmetry of its dent (damping), a few per cent of its normal force.
    for (spec, (normal, against, _)) in specs.iter().zip(&drag_sums) {
        if let Shape::Ball(_) = spec.shape {
            assert!(
                against.abs() < 0.1 * normal,
                "a dragged ball is held back: {against} vs {normal}"
            );
        }
    }
    assert!(
        max_disp > 0.8 * DEPTH && max_disp < 1.5 * DEPTH,
        "the tools dent the organ without ploughing it: {max_disp} m"
    );
    assert!(
        max_inside < 1e-6,
        "a vertex is {max_inside} m inside a tool"
    );
    assert!(
        max_off_boundary < 1e-6,
        "a held vertex is {max_off_boundary} m off its tool"
    );
    assert!(
        min_clearance > -1.5e-3,
        "the surface is {min_clearance} m into a tool"
    );
    assert!(quasi_static_samples > 0);
    assert!(
        max_imbalance < 0.1,
        "tools and pins out of balance by {max_imbalance}"
    );
    assert!(final_disp < 1e-5, "{final_disp} m from home after settling");
}
