//! Vertex welding: a triangle soup (every triangle with its own vertex copies, as modelling
//! tools and parry's height-field and voxel conversions give it) becomes one connected surface.

use crate::math::{Real, Vector};
use parry3d::utils::hashmap::HashMap;

/// Vertices closer than this fraction of the bounding-box diagonal are welded (see
/// [`TouchMesh::new`](super::TouchMesh::new)).
pub(super) const WELD_RELATIVE_TOLERANCE: Real = 1.0e-6;

/// For each vertex, the vertex that stands for it: itself, or the lowest-numbered earlier
/// vertex within `tol` of it. Only vertices with `used[v]` take part (the others map to
/// themselves). Representatives are never welded further, so each group is the set of vertices
/// within `tol` of its representative.
///
/// A grid hash with cells of `2 tol`: a vertex within `tol` of `v` lies in `v`'s cell or in the
/// neighbouring cell on the side of the nearer cell face, along each axis, so 8 cells are
/// searched per vertex.
pub(super) fn weld_map(vertices: &[Vector], used: &[bool], tol: Real) -> Vec<u32> {
    let mut map: Vec<u32> = (0..vertices.len() as u32).collect();
    let Some(origin) = vertices
        .iter()
        .zip(used)
        .filter(|(_, &u)| u)
        .map(|(v, _)| *v)
        .reduce(Vector::min)
    else {
        return map;
    };
    let cell = (2.0 * tol).max(Real::MIN_POSITIVE) as f64;
    let tol2 = (tol as f64) * (tol as f64);
    // Representatives by cell, as linked lists: `head[cell]` then `next[v]`.
    let mut head: HashMap<[i64; 3], u32> =
        HashMap::with_capacity_and_hasher(vertices.len(), Default::default());
    let mut next = vec![u32::MAX; vertices.len()];
    for (v, p) in vertices.iter().enumerate() {
        if !used[v] {
            continue;
        }
        let q = (*p - origin).as_dvec3() / cell;
        let home = [q.x.floor() as i64, q.y.floor() as i64, q.z.floor() as i64];
        let side = [q.x, q.y, q.z].map(|c| if c - c.floor() < 0.5 { -1 } else { 1 });
        let mut best = u32::MAX;
        for k in 0..8 {
            let key: [i64; 3] =
                std::array::from_fn(|a| home[a] + if (k >> a) & 1 == 1 { side[a] } else { 0 });
            let mut r = head.get(&key).copied().unwrap_or(u32::MAX);
            while r != u32::MAX {
                let d = (vertices[r as usize] - *p).as_dvec3().length_squared();
                if d <= tol2 && r < best {
                    best = r;
                }
                r = next[r as usize];
            }
        }
        if best != u32::MAX {
            map[v] = best;
        } else if let Some(h) = head.get_mut(&home) {
            next[v] = *h;
            *h = v as u32;
        } else {
            head.insert(home, v as u32);
        }
    }
    map
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the same rule, O(n²).
    fn brute(vertices: &[Vector], tol: Real) -> Vec<u32> {
        let mut map: Vec<u32> = (0..vertices.len() as u32).collect();
        for v in 0..vertices.len() {
            let rep = (0..v).find(|&r| {
                map[r] == r as u32
                    && (vertices[r] - vertices[v]).as_dvec3().length_squared()
                        <= (tol as f64).powi(2)
            });
            if let Some(r) = rep {
                map[v] = r as u32;
            }
        }
        map
    }

    #[test]
    fn grid_hash_agrees_with_brute_force() {
        // Points on a coarse lattice with copies jittered around cell boundaries.
        let tol = 0.01;
        let mut pts = Vec::new();
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as Real / (1u64 << 31) as Real) * 2.0 - 1.0
        };
        for i in 0..200 {
            let base = Vector::new(
                (i % 7) as Real * 0.1,
                (i / 7 % 5) as Real * 0.1,
                (i / 35) as Real * 0.1,
            );
            // 0.0199 = just under one cell (2 tol) from base: some pairs straddle cells.
            pts.push(base + Vector::new(rnd(), rnd(), rnd()) * 0.0099);
            pts.push(base + Vector::new(rnd(), rnd(), rnd()) * 0.0099);
        }
        let used = vec![true; pts.len()];
        assert_eq!(weld_map(&pts, &used, tol), brute(&pts, tol));
        // Exact copies weld even with a zero tolerance; unused vertices stay alone.
        let p = vec![Vector::X, Vector::Y, Vector::X, Vector::X];
        assert_eq!(weld_map(&p, &[true; 4], 0.0), vec![0, 1, 0, 0]);
        assert_eq!(
            weld_map(&p, &[false, true, true, true], 0.0),
            vec![0, 1, 2, 2]
        );
    }
}
