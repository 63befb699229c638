//! A BVH over a deformable surface whose leaves are fattened by a slack: the candidates for
//! the tool-surface contacts ([`super::tool_surface_contacts`] and the surface vertices inside
//! a tool) without a pass over the whole mesh.
//!
//! Each leaf holds a triangle (or a vertex in no triangle) and bounds it wherever its vertices
//! are within `slack` of their reference positions. The surface reports the vertices that went
//! farther ([`crate::surface::MassSpringSurface::take_escaped`], noted as its integrator moves
//! them); only the leaves around those are recomputed, and parry's BVH refits only their paths
//! to the root ([`Bvh::refit_partial`]). A query then costs the tree's depth and the candidates
//! it returns, not the mesh: at 100,000 nodes and six cubes, 52-59 µs per substep for every
//! cube's candidates where the scans over every vertex and every triangle's bounds took 2.9 ms
//! (`cargo bench --bench coupled_step -- 100kn`).

use crate::math::{Real, Vector};
use parry3d::bounding_volume::Aabb;
use parry3d::partitioning::{Bvh, BvhBuildStrategy};

/// Triangles per leaf. At 100,000 nodes and six cubes the candidates cost 52-59 µs per
/// substep with a leaf per triangle, right after a surface step (24 µs with the tree still in
/// cache); runs of eight triangles in Morton order, a tree eight times smaller, measured 62 µs:
/// their larger candidate sets cost more than the smaller walk saved (`cargo bench --bench
/// coupled_step -- 100kn`). Runs longer than one need the triangles in a spatial order first.
const CLUSTER: usize = 1;

/// A BVH over a surface's triangles with leaves fattened by a slack (module docs).
#[derive(Clone)]
pub struct SurfaceBvh {
    bvh: Bvh,
    /// The triangles: leaf `c < clusters` holds `CLUSTER` of them from `c * CLUSTER`.
    triangles: Vec<[u32; 3]>,
    /// The caller's index of each of `triangles`.
    order: Vec<u32>,
    clusters: usize,
    /// Vertices in no triangle: leaf `clusters + k` is `lone[k]`.
    lone: Vec<u32>,
    /// For each vertex, its leaves (CSR: `leaves[leaf_ptr[v]..leaf_ptr[v + 1]]`).
    leaf_ptr: Vec<u32>,
    leaves: Vec<u32>,
    reference: Vec<Vector>,
    slack: Real,
    /// Query scratch: a vertex is listed once per query (`marks[v] == stamp`).
    marks: Vec<u32>,
    stamp: u32,
    changed: Vec<u32>,
}

impl std::fmt::Debug for SurfaceBvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SurfaceBvh")
            .field("triangles", &self.triangles.len())
            .field("vertices", &self.reference.len())
            .field("slack", &self.slack)
            .finish_non_exhaustive()
    }
}

impl SurfaceBvh {
    /// The BVH of `triangles` over `positions`, its leaves fattened by `slack` (a negative or
    /// non-finite slack counts as zero). Triangle indices out of range are left out.
    ///
    /// # Example
    /// ```
    /// use rapier_touch::geometry::SurfaceBvh;
    /// use rapier_touch::parry3d::bounding_volume::Aabb;
    /// use rapier_touch::prelude::*;
    ///
    /// // Two triangles a metre apart.
    /// let vertices = [
    ///     Vector::new(0.0, 0.0, 0.0), Vector::new(1.0, 0.0, 0.0), Vector::new(0.0, 0.0, 1.0),
    ///     Vector::new(2.0, 0.0, 0.0), Vector::new(3.0, 0.0, 0.0), Vector::new(2.0, 0.0, 1.0),
    /// ];
    /// let mut bvh = SurfaceBvh::new(&vertices, &[[0, 2, 1], [3, 5, 4]], 0.01);
    /// let (mut tris, mut verts) = (Vec::new(), Vec::new());
    /// let near_second = Aabb::new(Vector::new(2.4, -0.1, 0.0), Vector::new(2.6, 0.1, 0.1));
    /// bvh.triangles_in(&near_second, &mut tris);
    /// assert!(tris.contains(&1));
    /// bvh.vertices_in(&near_second, &mut verts);
    /// assert!([3, 4, 5].iter().all(|v| verts.contains(v)));
    /// // Nothing a metre above.
    /// let above = Aabb::new(Vector::new(2.4, 0.95, 0.0), Vector::new(2.6, 1.05, 0.1));
    /// bvh.triangles_in(&above, &mut tris);
    /// assert!(tris.is_empty());
    /// // The second triangle moved up a metre: after `update` the box above finds it.
    /// let mut moved = vertices;
    /// for p in &mut moved[3..] {
    ///     p.y += 1.0;
    /// }
    /// bvh.update(&[3, 4, 5], &moved, &vertices);
    /// bvh.triangles_in(&above, &mut tris);
    /// assert!(tris.contains(&1));
    /// ```
    pub fn new(positions: &[Vector], triangles: &[[u32; 3]], slack: Real) -> Self {
        let n = positions.len();
        let triangles: Vec<[u32; 3]> = triangles
            .iter()
            .filter(|t| t.iter().all(|&v| (v as usize) < n))
            .copied()
            .collect();
        let order: Vec<u32> = (0..triangles.len() as u32).collect();
        let clusters = triangles.len().div_ceil(CLUSTER);
        let mut used = vec![false; n];
        let mut count = vec![0u32; n + 1];
        // Each vertex's leaves, each once: a cluster's triangles come together, so a repeat is
        // the last one written.
        let mut last = vec![u32::MAX; n];
        for (i, t) in triangles.iter().enumerate() {
            let c = (i / CLUSTER) as u32;
            for v in dedup3(*t) {
                used[v as usize] = true;
                if last[v as usize] != c {
                    last[v as usize] = c;
                    count[v as usize + 1] += 1;
                }
            }
        }
        let lone: Vec<u32> = (0..n as u32).filter(|&v| !used[v as usize]).collect();
        for &v in &lone {
            count[v as usize + 1] = 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut leaves = vec![0u32; count[n] as usize];
        last.iter_mut().for_each(|l| *l = u32::MAX);
        for (i, t) in triangles.iter().enumerate() {
            let c = (i / CLUSTER) as u32;
            for v in dedup3(*t) {
                if last[v as usize] != c {
                    last[v as usize] = c;
                    leaves[fill[v as usize] as usize] = c;
                    fill[v as usize] += 1;
                }
            }
        }
        for (k, &v) in lone.iter().enumerate() {
            leaves[fill[v as usize] as usize] = (clusters + k) as u32;
        }
        let mut out = Self {
            bvh: Bvh::new(),
            triangles,
            order,
            clusters,
            lone,
            leaf_ptr: count,
            leaves,
            reference: positions.to_vec(),
            slack: if slack.is_finite() {
                slack.max(0.0)
            } else {
                0.0
            },
            marks: vec![0; n],
            stamp: 0,
            changed: Vec::new(),
        };
        out.rebuild(positions, None);
        out
    }

    /// The slack the leaves are fattened by.
    pub fn slack(&self) -> Real {
        self.slack
    }

    /// Every leaf recomputed around `now` (the new references) and, if given, the positions
    /// `before` (where the vertices were at the start of the substep), and the tree rebuilt.
    pub fn rebuild(&mut self, now: &[Vector], before: Option<&[Vector]>) {
        self.reference.clear();
        self.reference.extend_from_slice(now);
        self.reference.resize(self.marks.len(), Vector::ZERO);
        let boxes: Vec<Aabb> = (0..self.num_leaves())
            .map(|l| self.leaf_box(l, before))
            .collect();
        self.bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes);
    }

    /// The vertices in `moved` are at `now` and were at `before` at the start of the substep
    /// (full position arrays): they become the references of those vertices, and the leaves
    /// around them bound their triangles both there and within `slack` of the new references.
    /// Every other vertex must still be within `slack` of its reference (what
    /// [`crate::surface::MassSpringSurface::take_escaped`] guarantees).
    pub fn update(&mut self, moved: &[u32], now: &[Vector], before: &[Vector]) {
        if moved.is_empty() {
            return;
        }
        // A partial refit walks each changed leaf's path to the root: past a fraction of the
        // leaves, one rebuild is cheaper.
        if moved.len() * 8 > self.reference.len() {
            self.rebuild(now, Some(before));
            return;
        }
        for &v in moved {
            if let (Some(r), Some(p)) = (self.reference.get_mut(v as usize), now.get(v as usize)) {
                *r = *p;
            }
        }
        self.changed.clear();
        for &v in moved {
            let v = v as usize;
            if v + 1 < self.leaf_ptr.len() {
                let range = self.leaf_ptr[v] as usize..self.leaf_ptr[v + 1] as usize;
                self.changed.extend_from_slice(&self.leaves[range]);
            }
        }
        self.changed.sort_unstable();
        self.changed.dedup();
        for &leaf in &self.changed {
            let b = self.leaf_box(leaf as usize, Some(before));
            self.bvh.insert_or_update_partially(b, leaf, 0.0);
        }
        self.bvh.refit_partial(&[], &self.changed);
    }

    /// The triangles whose leaves meet `aabb`, in `out` (cleared first), in increasing order:
    /// every triangle that meets `aabb` (anywhere within the slack of its references), and
    /// some that do not.
    pub fn triangles_in(&self, aabb: &Aabb, out: &mut Vec<u32>) {
        out.clear();
        for leaf in self.bvh.intersect_aabb(aabb) {
            out.extend_from_slice(self.cluster_ids(leaf as usize));
        }
        out.sort_unstable();
    }

    /// The vertices of the leaves that meet `aabb`, each once, in `out` (cleared first): every
    /// vertex inside `aabb` is among them.
    pub fn vertices_in(&mut self, aabb: &Aabb, out: &mut Vec<u32>) {
        let mut triangles = Vec::new();
        self.near(aabb, &mut triangles, out);
    }

    /// [`Self::triangles_in`] and [`Self::vertices_in`] from one walk of the tree: the
    /// triangles in increasing order, the vertices each once.
    pub fn near(&mut self, aabb: &Aabb, triangles: &mut Vec<u32>, vertices: &mut Vec<u32>) {
        triangles.clear();
        vertices.clear();
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.marks.iter_mut().for_each(|m| *m = 0);
            self.stamp = 1;
        }
        let marks = &mut self.marks;
        let stamp = self.stamp;
        let mut add = |v: u32| {
            if let Some(m) = marks.get_mut(v as usize) {
                if *m != stamp {
                    *m = stamp;
                    vertices.push(v);
                }
            }
        };
        for leaf in self.bvh.intersect_aabb(aabb) {
            let l = leaf as usize;
            if l >= self.clusters {
                if let Some(&v) = self.lone.get(l - self.clusters) {
                    add(v);
                }
                continue;
            }
            let range = l * CLUSTER..((l + 1) * CLUSTER).min(self.triangles.len());
            triangles.extend_from_slice(&self.order[range.clone()]);
            for t in &self.triangles[range] {
                t.iter().for_each(|&v| add(v));
            }
        }
        triangles.sort_unstable();
    }

    /// Appends to `out` the triangles of the leaves around `vertices`: every triangle that
    /// uses one of them, and their neighbours in the leaves.
    pub fn triangles_of(&self, vertices: &[u32], out: &mut Vec<u32>) {
        for &v in vertices {
            let v = v as usize;
            if v + 1 < self.leaf_ptr.len() {
                let range = self.leaf_ptr[v] as usize..self.leaf_ptr[v + 1] as usize;
                for &leaf in &self.leaves[range] {
                    out.extend_from_slice(self.cluster_ids(leaf as usize));
                }
            }
        }
    }

    /// The caller's indices of leaf `l`'s triangles (none for a lone vertex's leaf).
    fn cluster_ids(&self, l: usize) -> &[u32] {
        if l >= self.clusters {
            return &[];
        }
        &self.order[l * CLUSTER..((l + 1) * CLUSTER).min(self.order.len())]
    }

    fn num_leaves(&self) -> usize {
        self.clusters + self.lone.len()
    }

    /// Leaf `l`'s box: its vertices' references fattened by the slack, and their positions in
    /// `before` if given.
    fn leaf_box(&self, l: usize, before: Option<&[Vector]>) -> Aabb {
        let lone;
        let tris: &[[u32; 3]] = if l < self.clusters {
            &self.triangles[l * CLUSTER..((l + 1) * CLUSTER).min(self.triangles.len())]
        } else {
            lone = [[self.lone[l - self.clusters]; 3]];
            &lone
        };
        let mut lo = Vector::splat(Real::MAX);
        let mut hi = Vector::splat(Real::MIN);
        for &v in tris.iter().flatten() {
            let v = v as usize;
            let r = self.reference[v];
            lo = lo.min(r);
            hi = hi.max(r);
            if let Some(p) = before.and_then(|b| b.get(v)) {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        // The references are single precision: a hair more than the slack covers rounding.
        let s = Vector::splat(self.slack) + (hi.abs().max(lo.abs())) * 4.0 * Real::EPSILON;
        Aabb::new(lo - s, hi + s)
    }
}

/// A triangle's distinct vertices.
fn dedup3(t: [u32; 3]) -> impl Iterator<Item = u32> {
    let [a, b, c] = t;
    [
        Some(a),
        (b != a).then_some(b),
        (c != a && c != b).then_some(c),
    ]
    .into_iter()
    .flatten()
}
