//! Shared helpers: brute-force geometric checks independent of the code under test.

use parry3d::query;
use parry3d::shape::Triangle;
use rapier_touch::prelude::*;

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
    let id = Pose::IDENTITY;
    let mut best = f32::MAX;
    for t in a.indices() {
        let [x, y, z] = t.map(|i| pa.transform_point(a.vertices()[i as usize]));
        let t1 = Triangle::new(x, y, z);
        for s in b.indices() {
            let [x, y, z] = s.map(|i| pb.transform_point(b.vertices()[i as usize]));
            let t2 = Triangle::new(x, y, z);
            best = best.min(query::distance(&id, &t1, &id, &t2).map_or(f32::MAX, |d| d.distance));
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
