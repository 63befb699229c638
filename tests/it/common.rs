//! Shared helpers: brute-force geometric checks independent of the code under test.

use parry3d::shape::Triangle;
use rapier_touch::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim};

/// At rest the force at the step's last substep is its mean over the step within 1 %: a tool
/// held still gets the same force at every substep. (Rounding once made it swing: a needle
/// 0.46-0.54 N for 0.50 N, a cube corner 0.466 and 0.535 N for 0.503 N, jaws 8.84-10.15 N for
/// 9.55 N.)
pub fn steady(r: &ToolReaction) -> bool {
    (r.force - r.mean_force).length() <= 0.01 * r.mean_force.length()
}

/// The inner shape and the border radius of a round shape.
pub fn round_parts(
    shape: &dyn parry3d::shape::Shape,
) -> Option<(&dyn parry3d::shape::Shape, Real)> {
    use parry3d::shape::TypedShape;
    match shape.as_typed_shape() {
        TypedShape::RoundCuboid(r) => Some((&r.inner_shape, r.border_radius)),
        TypedShape::RoundTriangle(r) => Some((&r.inner_shape, r.border_radius)),
        TypedShape::RoundCylinder(r) => Some((&r.inner_shape, r.border_radius)),
        TypedShape::RoundCone(r) => Some((&r.inner_shape, r.border_radius)),
        TypedShape::RoundConvexPolyhedron(r) => Some((&r.inner_shape, r.border_radius)),
        _ => None,
    }
}

/// Translates a pose.
pub fn shifted(p: &Pose, v: Vector) -> Pose {
    Pose::from_parts(p.translation + v, p.rotation)
}

/// Do the two surfaces meet (touching included)? Their brute-force distance is zero. (parry's
/// GJK `intersection_test` on flat triangles answers `true` for gaps of ~1e-4, so the exact
/// distance is used instead.)
pub fn surfaces_intersect(a: &TouchMesh, pa: &Pose, b: &TouchMesh, pb: &Pose) -> bool {
    surface_distance(a, pa, b, pb) <= 0.0
}

/// Smallest distance between the two surfaces (brute force over triangle pairs).
pub fn surface_distance(a: &TouchMesh, pa: &Pose, b: &TouchMesh, pb: &Pose) -> f32 {
    let mut best = f32::MAX;
    for t in a.indices() {
        let [x, y, z] = t.map(|i| pa.transform_point(a.vertices()[i as usize]));
        let t1 = Triangle::new(x, y, z);
        for s in b.indices() {
            let [x, y, z] = s.map(|i| pb.transform_point(b.vertices()[i as usize]));
            let t2 = Triangle::new(x, y, z);
            best = best.min(triangle_distance(&t1, &t2));
        }
    }
    best
}

/// The distance between two triangles, by their features: zero when an edge of one crosses
/// the other, else the least of each vertex's distance to the other triangle and of the nine
/// edge pairs' (parry's projections by Voronoi regions and Ericson's segment-segment closest
/// points, no iteration). parry's GJK distance read separated triangles 3e-4 apart on a 3 m
/// pair as touching at some poses and not at others a tenth of that further out.
pub fn triangle_distance(t1: &Triangle, t2: &Triangle) -> f32 {
    use parry3d::query::details::closest_points_segment_segment_with_locations_nD as seg_seg;
    use parry3d::query::{PointQuery, Ray, RayCast};
    let edges = |t: &Triangle| [(t.a, t.b), (t.b, t.c), (t.c, t.a)];
    let crosses =
        |t: &Triangle, (a, b): (Vector, Vector)| t.intersects_local_ray(&Ray::new(a, b - a), 1.0);
    if edges(t1).into_iter().any(|e| crosses(t2, e))
        || edges(t2).into_iter().any(|e| crosses(t1, e))
    {
        return 0.0;
    }
    let mut best = f32::MAX;
    for (t, other) in [(t1, t2), (t2, t1)] {
        for p in [t.a, t.b, t.c] {
            best = best.min(other.distance_to_local_point(p, true));
        }
    }
    for (a1, b1) in edges(t1) {
        for (a2, b2) in edges(t2) {
            let (l1, l2) = seg_seg((&a1, &b1), (&a2, &b2));
            let p1 = parry3d::shape::Segment::new(a1, b1).point_at(&l1);
            let p2 = parry3d::shape::Segment::new(a2, b2).point_at(&l2);
            best = best.min((p1 - p2).length());
        }
    }
    best
}

/// The stiffness Laplacian `k L` of a mesh's unique edges (`n` vertices): the static reference
/// for linear springs, built independently of the crate.
pub fn edge_laplacian(triangles: &[[u32; 3]], n: usize, k: f64) -> nalgebra::DMatrix<f64> {
    let mut lap = nalgebra::DMatrix::<f64>::zeros(n, n);
    let mut edges = std::collections::BTreeSet::new();
    for tri in triangles {
        for j in 0..3 {
            let (a, b) = (tri[j].min(tri[(j + 1) % 3]), tri[j].max(tri[(j + 1) % 3]));
            edges.insert((a as usize, b as usize));
        }
    }
    for &(a, b) in &edges {
        lap[(a, a)] += k;
        lap[(b, b)] += k;
        lap[(a, b)] -= k;
        lap[(b, a)] -= k;
    }
    lap
}

/// Static equilibrium `L u = 0` on the vertices not `known`, with `u` given on the known ones:
/// fills in the free entries of `u`.
pub fn dirichlet_solve(lap: &nalgebra::DMatrix<f64>, known: &[bool], u: &mut [f64]) {
    let n = u.len();
    let free: Vec<usize> = (0..n).filter(|&i| !known[i]).collect();
    let a = nalgebra::DMatrix::from_fn(free.len(), free.len(), |r, c| lap[(free[r], free[c])]);
    let rhs = nalgebra::DVector::from_fn(free.len(), |r, _| {
        -(0..n)
            .filter(|&j| known[j])
            .map(|j| lap[(free[r], j)] * u[j])
            .sum::<f64>()
    });
    let x = a
        .lu()
        .solve(&rhs)
        .expect("a connected mesh with pins is solvable");
    for (r, &i) in free.iter().enumerate() {
        u[i] = x[r];
    }
}

/// `G = Wᵀ K⁻¹ W`: how far each of `points` (a point `Σ wⱼ xⱼ` each, `(vertex, weight)`)
/// moves under a unit load on each, for linear springs (Laplacian `lap`) with the `pinned`
/// vertices held at zero, per axis. A point displaced by `u` alone takes the load `u / G₀₀`;
/// weights on pinned vertices carry nothing.
pub fn point_compliance(
    lap: &nalgebra::DMatrix<f64>,
    pinned: &[bool],
    points: &[&[(usize, f64)]],
) -> nalgebra::DMatrix<f64> {
    let free: Vec<usize> = (0..pinned.len()).filter(|&i| !pinned[i]).collect();
    let mut slot = vec![usize::MAX; pinned.len()];
    for (s, &i) in free.iter().enumerate() {
        slot[i] = s;
    }
    let kff = nalgebra::DMatrix::from_fn(free.len(), free.len(), |r, c| lap[(free[r], free[c])]);
    let mut w = nalgebra::DMatrix::<f64>::zeros(free.len(), points.len());
    for (c, point) in points.iter().enumerate() {
        for &(i, wt) in point.iter() {
            if slot[i] != usize::MAX {
                w[(slot[i], c)] += wt;
            }
        }
    }
    let kinv_w = kff
        .lu()
        .solve(&w)
        .expect("a connected mesh with pins is solvable");
    w.transpose() * kinv_w
}

/// A square plate clamped at its rim: its size (m), edge stiffness (N/m) and mass per vertex
/// (kg), edge damping `sqrt(k m)`.
#[derive(Copy, Clone, Debug)]
pub struct ClampedPlate {
    pub size: f32,
    pub k: f32,
    pub mass: f32,
}

impl ClampedPlate {
    /// The surface, `cells` × `cells` cells, its rim pinned.
    pub fn surface(&self, cells: u32) -> MassSpringSurface {
        MassSpringSurfaceBuilder::from_mesh(&plate(self.size, self.size, cells, cells))
            .stiffness(self.k)
            .damping((self.k * self.mass).sqrt())
            .mass(MassDistribution::PerVertex(self.mass))
            .pinned(plate_rim(cells, cells))
            .build()
            .unwrap()
    }

    /// The springs' Laplacian and which vertices are pinned (linear springs: the size does
    /// not enter the static solve).
    pub fn statics(&self, cells: u32) -> (nalgebra::DMatrix<f64>, Vec<bool>) {
        let mesh = plate(1.0, 1.0, cells, cells);
        let n = mesh.vertices.len();
        let rim = plate_rim(cells, cells);
        let pinned = (0..n as u32).map(|i| rim.contains(&i)).collect();
        (edge_laplacian(&mesh.triangles, n, self.k as f64), pinned)
    }
}

/// Exact first touch walking `moving` back from `now` along `-u` (world unit `u`) over
/// `[0, len]`: the largest `s` at which a vertex of either mesh meets a triangle of the other
/// or an edge meets an edge, by brute force over every pair, in `f64`. Written here from the
/// definition, independently of the crate's search. `None` if the surfaces never meet.
pub fn reference_first_touch(
    fixed: &TouchMesh,
    pf: &Pose,
    moving: &TouchMesh,
    now: &Pose,
    u: Vector,
    len: f64,
) -> Option<f64> {
    use glamx::DVec3;
    let world = |p: &Pose, v: Vector| -> DVec3 {
        p.rotation.as_dquat().normalize() * v.as_dvec3() + p.translation.as_dvec3()
    };
    let fv: Vec<DVec3> = fixed.vertices().iter().map(|&v| world(pf, v)).collect();
    let mv: Vec<DVec3> = moving.vertices().iter().map(|&v| world(now, v)).collect();
    let u = u.as_dvec3().normalize();
    let scale = fixed.scale().max(moving.scale()) as f64;
    let eps = 1e-12;
    let in_range = |s: f64| s >= -1e-9 * scale && s <= len + 1e-9 * scale;
    // Solve a + x e1 + y e2 = o + s d for (x, y, s) by Cramer's rule.
    let solve = |o: DVec3, d: DVec3, a: DVec3, e1: DVec3, e2: DVec3| -> Option<(f64, f64, f64)> {
        // x e1 + y e2 - s d = o - a
        let det = e1.dot(e2.cross(-d));
        if det.abs() < 1e-14 * e1.length() * e2.length() {
            return None;
        }
        let r = o - a;
        let x = r.dot(e2.cross(-d)) / det;
        let y = e1.dot(r.cross(-d)) / det;
        let s = e1.dot(e2.cross(r)) / det;
        Some((x, y, s))
    };
    let mut best: Option<f64> = None;
    let mut take = |s: f64| {
        if in_range(s) {
            best = Some(best.map_or(s, |b: f64| b.max(s)));
        }
    };
    let tris = |m: &TouchMesh, v: &[DVec3]| -> Vec<[DVec3; 3]> {
        m.indices()
            .iter()
            .map(|t| t.map(|i| v[i as usize]))
            .collect()
    };
    let (ft, mt) = (tris(fixed, &fv), tris(moving, &mv));
    // Moving vertex p at p - s u on a fixed triangle.
    for &p in &mv {
        for t in &ft {
            if let Some((x, y, s)) = solve(p, -u, t[0], t[1] - t[0], t[2] - t[0]) {
                if x >= -eps && y >= -eps && x + y <= 1.0 + eps {
                    take(s);
                }
            }
        }
    }
    // Fixed vertex q on a moving triangle walked back by s: q + s u on the triangle now.
    for &q in &fv {
        for t in &mt {
            if let Some((x, y, s)) = solve(q, u, t[0], t[1] - t[0], t[2] - t[0]) {
                if x >= -eps && y >= -eps && x + y <= 1.0 + eps {
                    take(s);
                }
            }
        }
    }
    // Moving edge (p0, p1) walked back meets fixed edge (q0, q1):
    // p0 + x (p1 - p0) - s u = q0 + y (q1 - q0)  <=>  q0 + y f + x (-e) = p0 - s u.
    let edges = |t: &[[DVec3; 3]]| -> Vec<(DVec3, DVec3)> {
        t.iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .collect()
    };
    let (fe, me) = (edges(&ft), edges(&mt));
    for &(p0, p1) in &me {
        for &(q0, q1) in &fe {
            if let Some((y, x, s)) = solve(p0, -u, q0, q1 - q0, p0 - p1) {
                if (-eps..=1.0 + eps).contains(&x) && (-eps..=1.0 + eps).contains(&y) {
                    take(s);
                }
            }
        }
    }
    best
}

/// A mesh scaled by `k` about the origin.
pub fn scaled_mesh(m: &TouchMesh, k: f32) -> TouchMesh {
    TouchMesh::new(
        m.vertices().iter().map(|&v| v * k).collect(),
        m.indices().to_vec(),
    )
    .unwrap()
}

/// A pose whose translation is scaled by `k`.
pub fn scaled_pose(p: &Pose, k: f32) -> Pose {
    Pose::from_parts(p.translation * k, p.rotation)
}

/// A plate `size` wide in the xz-plane (`cells` per side, rim pinned) of edge stiffness `k`
/// and damping `0.02 √k`, `mass` in all (`None`: the builder's default areal density), on a
/// fixed body of `world`, with its collider, stepped in `substeps`.
pub fn pinned_plate(
    world: &mut rapier_touch::rapier3d::prelude::PhysicsWorld,
    size: f32,
    cells: u32,
    k: f32,
    mass: Option<f32>,
    substeps: u32,
) -> (SurfaceSet, SurfaceHandle) {
    use rapier_touch::rapier3d::prelude::*;
    let fixed = world.insert_body(RigidBodyBuilder::fixed());
    let mut builder = MassSpringSurfaceBuilder::from_mesh(&plate(size, size, cells, cells))
        .stiffness(k)
        .damping(0.02 * k.sqrt())
        .pinned(plate_rim(cells, cells));
    if let Some(mass) = mass {
        builder = builder.mass(MassDistribution::Total(mass));
    }
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps,
        collider: true,
    };
    let h = set
        .insert(builder.build().unwrap(), fixed, world, options)
        .unwrap();
    (set, h)
}

/// [`pinned_plate`] with no gravity, and a kinematic tool of `shape` above it.
pub fn plate_scene(
    size: f32,
    cells: u32,
    k: f32,
    mass: f32,
    substeps: u32,
    shape: rapier_touch::rapier3d::prelude::SharedShape,
) -> (
    rapier_touch::rapier3d::prelude::PhysicsWorld,
    SurfaceSet,
    rapier_touch::rapier3d::prelude::ColliderHandle,
    SurfaceHandle,
) {
    use rapier_touch::rapier3d::prelude::*;
    let mut world = PhysicsWorld {
        gravity: Vector::ZERO,
        ..Default::default()
    };
    let (set, h) = pinned_plate(&mut world, size, cells, k, Some(mass), substeps);
    let body = world.insert_body(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.0, size, 0.0)),
    );
    let tool = world.insert_collider(ColliderBuilder::new(shape), Some(body));
    (world, set, tool, h)
}

/// How far below its centre `shape` reaches when turned by `rotation` (negative: the height
/// of its lowest point over its centre).
pub fn lowest_point(shape: &dyn parry3d::shape::Shape, rotation: Rotation) -> f32 {
    shape
        .compute_aabb(&Pose::from_parts(Vector::ZERO, rotation))
        .mins
        .y
}

/// A cube of half-size `half` as a convex hull of its corners (parry's `ConvexPolyhedron`,
/// whose point queries take another path than a cuboid's).
pub fn cube_hull(half: f32) -> rapier_touch::rapier3d::prelude::SharedShape {
    let corners: Vec<Vector> = (0..8)
        .map(|c| {
            Vector::new(
                if c & 1 == 0 { -half } else { half },
                if c & 2 == 0 { -half } else { half },
                if c & 4 == 0 { -half } else { half },
            )
        })
        .collect();
    rapier_touch::rapier3d::prelude::SharedShape::convex_hull(&corners).expect("a cube's hull")
}

/// Proptest strategies shared by the property tests.
pub mod strategies {
    use proptest::prelude::*;
    use rapier_touch::prelude::*;

    /// A vector in the cube `[-1, 1]³`.
    pub fn vec3() -> impl Strategy<Value = Vector> {
        (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0).prop_map(|(x, y, z)| Vector::new(x, y, z))
    }

    /// A rotation about a random axis by up to π.
    pub fn rotation() -> impl Strategy<Value = Rotation> {
        (vec3(), 0.0f32..std::f32::consts::PI).prop_map(|(axis, angle)| {
            Rotation::from_axis_angle(axis.try_normalize().unwrap_or(Vector::X), angle)
        })
    }

    /// A unit direction.
    pub fn direction() -> impl Strategy<Value = Vector> {
        vec3().prop_filter_map("non-zero", |v| v.try_normalize())
    }
}

/// The U of the drop tests as a collider shape, and its volume: a TriMesh, legs down, `2 r`
/// wide and `1.25 r` tall, legs `r / 2` wide, extruded `2 r` (its origin where the legs' inner
/// walls meet the bridge's underside, `r` above the legs' bottoms).
pub fn u_collider(r: f32) -> (rapier_touch::rapier3d::prelude::ColliderBuilder, f32) {
    let outline = [
        [-r, -r],
        [-0.5 * r, -r],
        [-0.5 * r, 0.0],
        [0.5 * r, 0.0],
        [0.5 * r, -r],
        [r, -r],
        [r, 0.25 * r],
        [-r, 0.25 * r],
    ];
    let (v, i) = rapier_touch::geometry::generators::extruded_polygon(&outline, 2.0 * r).unwrap();
    let volume = (2.0 * r * 1.25 * r - r * r) * 2.0 * r;
    let mesh = rapier_touch::rapier3d::prelude::ColliderBuilder::trimesh(v, i).unwrap();
    (mesh, volume)
}
