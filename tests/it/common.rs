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
