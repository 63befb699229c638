//! Closed triangle-mesh generators: subdivided boxes, icospheres and extruded polygons.
//!
//! All meshes are closed, edge-manifold, welded, and wound counter-clockwise seen from outside.

use crate::math::{Real, Vector};
use parry3d::utils::hashmap::HashMap;

/// A vertex and an index buffer.
pub type MeshBuffers = (Vec<Vector>, Vec<[u32; 3]>);

/// A box of the given half extents whose six faces are each split into `n × n` quads (two
/// triangles each). `n = 1` gives the 12-triangle box.
///
/// ```
/// let (v, i) = rapier_touch::geometry::generators::subdivided_box(rapier_touch::math::Vector::ONE, 4);
/// assert_eq!(i.len(), 6 * 4 * 4 * 2);
/// assert_eq!(v.len(), 6 * 4 * 4 + 2); // Euler: V = F/2 + 2
/// ```
pub fn subdivided_box(half_extents: Vector, n: u32) -> MeshBuffers {
    let n = n.max(1) as i32;
    let mut map: HashMap<[i32; 3], u32> = HashMap::default();
    let mut verts = Vec::new();
    let mut idx = Vec::new();
    let mut vid = |g: [i32; 3], verts: &mut Vec<Vector>| -> u32 {
        *map.entry(g).or_insert_with(|| {
            let p = Vector::new(g[0] as Real, g[1] as Real, g[2] as Real) / n as Real;
            verts.push(p * half_extents);
            (verts.len() - 1) as u32
        })
    };
    // Integer grid coordinates in [-n, n] on each axis, stepping 2.
    for axis in 0..3 {
        for side in [-1i32, 1] {
            let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
            for i in 0..n {
                for j in 0..n {
                    let corner = |di: i32, dj: i32| {
                        let mut g = [0; 3];
                        g[axis] = side * n;
                        g[a1] = -n + 2 * (i + di);
                        g[a2] = -n + 2 * (j + dj);
                        g
                    };
                    let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
                        .map(|g| vid(g, &mut verts));
                    // (a1, a2, axis) is right-handed, so (0,0)->(1,0)->(1,1) is CCW seen from
                    // +axis; flip for the -axis side.
                    if side > 0 {
                        idx.push([q[0], q[1], q[2]]);
                        idx.push([q[0], q[2], q[3]]);
                    } else {
                        idx.push([q[0], q[2], q[1]]);
                        idx.push([q[0], q[3], q[2]]);
                    }
                }
            }
        }
    }
    (verts, idx)
}

/// An icosphere: an icosahedron whose triangles are split `subdivisions` times (each split
/// multiplies the triangle count by 4), projected on the sphere.
pub fn icosphere(radius: Real, subdivisions: u32) -> MeshBuffers {
    let t = (1.0 + Real::sqrt(5.0)) / 2.0;
    let mut verts: Vec<Vector> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vector::from(*p).normalize())
    .collect();
    let mut idx: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::default();
        let mut midpoint = |a: u32, b: u32, verts: &mut Vec<Vector>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                verts.push(((verts[a as usize] + verts[b as usize]) * 0.5).normalize());
                (verts.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(idx.len() * 4);
        for [a, b, c] in idx {
            let ab = midpoint(a, b, &mut verts);
            let bc = midpoint(b, c, &mut verts);
            let ca = midpoint(c, a, &mut verts);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        idx = next;
    }
    (verts.into_iter().map(|v| v * radius).collect(), idx)
}

/// A prism: the simple polygon `outline` (in the xy-plane, counter-clockwise, no repeated
/// closing point) extruded along z from `-depth/2` to `depth/2`. Non-convex outlines are
/// triangulated by ear clipping. Returns `None` if the outline has fewer than three points or
/// cannot be triangulated (self-intersecting or clockwise).
pub fn extruded_polygon(outline: &[[Real; 2]], depth: Real) -> Option<MeshBuffers> {
    let n = outline.len();
    if n < 3 {
        return None;
    }
    let cap = ear_clip(outline)?;
    let h = depth / 2.0;
    let mut verts: Vec<Vector> = outline
        .iter()
        .map(|p| Vector::new(p[0], p[1], -h))
        .collect();
    verts.extend(outline.iter().map(|p| Vector::new(p[0], p[1], h)));
    let n32 = n as u32;
    let mut idx = Vec::with_capacity(cap.len() * 2 + n * 2);
    for [a, b, c] in &cap {
        idx.push([*a + n32, *b + n32, *c + n32]); // top, CCW seen from +z
        idx.push([*a, *c, *b]); // bottom, CCW seen from -z
    }
    for i in 0..n32 {
        let j = (i + 1) % n32;
        idx.push([i, j, j + n32]);
        idx.push([i, j + n32, i + n32]);
    }
    Some((verts, idx))
}

fn ear_clip(poly: &[[Real; 2]]) -> Option<Vec<[u32; 3]>> {
    let cross = |o: [Real; 2], a: [Real; 2], b: [Real; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut rest: Vec<u32> = (0..poly.len() as u32).collect();
    let mut tris = Vec::with_capacity(poly.len() - 2);
    while rest.len() > 3 {
        let m = rest.len();
        let ear = (0..m).find(|&i| {
            let (a, b, c) = (rest[(i + m - 1) % m], rest[i], rest[(i + 1) % m]);
            let (pa, pb, pc) = (poly[a as usize], poly[b as usize], poly[c as usize]);
            if cross(pa, pb, pc) <= 0.0 {
                return false;
            }
            !rest.iter().any(|&k| {
                if k == a || k == b || k == c {
                    return false;
                }
                let p = poly[k as usize];
                cross(pa, pb, p) >= 0.0 && cross(pb, pc, p) >= 0.0 && cross(pc, pa, p) >= 0.0
            })
        })?;
        let m = rest.len();
        tris.push([rest[(ear + m - 1) % m], rest[ear], rest[(ear + 1) % m]]);
        rest.remove(ear);
    }
    let [a, b, c] = [rest[0], rest[1], rest[2]];
    if cross(poly[a as usize], poly[b as usize], poly[c as usize]) <= 0.0 {
        return None;
    }
    tris.push([a, b, c]);
    Some(tris)
}
