//! A BVH over a deformable surface whose leaves are fattened by a slack: the candidates for
//! the tool-surface contacts ([`super::tool_surface_contacts`] and the surface vertices inside
//! a tool) without a pass over the whole mesh.
//!
//! Each leaf holds a triangle (or a vertex in no triangle) and bounds it wherever its vertices
//! are within `slack` of their reference positions. The surface reports the vertices that went
//! farther ([`crate::surface::MassSpringSurface::take_escaped`], noted as its integrator moves
//! them); only the leaves around those are recomputed, and parry's BVH refits only their paths
//! to the root ([`Bvh::refit_partial`]). A query then costs the tree's depth and the candidates
//! it returns, not the mesh. A tool asks about much the same place substep after substep:
//! [`SurfaceBvh::near_cached`] walks a grown box once and then only looks at the leaves changed
//! since. At 100,000 nodes and six cubes, 27-49 µs per substep for every cube's candidates
//! over four runs (22-36 µs at 10,000 nodes) where the scans over every vertex and every
//! triangle's bounds took 3.2 ms (`cargo bench --bench coupled_step -- 6cubes_1khz`).

use crate::math::{Real, Vector};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};

/// A BVH over a surface's triangles with leaves fattened by a slack (module docs).
///
/// A leaf per triangle. Runs of eight triangles in Morton order per leaf (a tree eight times
/// smaller, fewer cache misses on the walk right after a surface step) measured slower at
/// 100,000 nodes and six cubes, 62 µs against 52-59 µs per substep for the candidates
/// (`cargo bench --bench coupled_step -- 100kn`): their larger candidate sets cost more than
/// the smaller walk saved.
#[derive(Clone)]
pub struct SurfaceBvh {
    bvh: Bvh,
    /// The triangles kept (indices in range): leaf `l < triangles.len()` is `triangles[l]`.
    triangles: Vec<[u32; 3]>,
    /// The caller's index of each of `triangles`.
    ids: Vec<u32>,
    /// Vertices in no triangle: leaf `triangles.len() + k` is `lone[k]`.
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
    /// Bumped by every rebuild: a [`NearCache`] from an older tree is walked again.
    generation: u64,
    /// The leaves changed since the log was last trimmed; `log[0]` is the `log_base`-th change.
    log: Vec<u32>,
    log_base: usize,
}

/// Leaves changed before a cache's walk are kept in the log for it up to this many; past
/// that, a cached query walks the tree again.
const LOG_MAX: usize = 4096;

/// One caller's last walk of a [`SurfaceBvh`] ([`SurfaceBvh::near_cached`]): the box it
/// walked and what it found, brought up to date with the leaves changed since.
#[derive(Clone, Debug, Default)]
pub struct NearCache {
    generation: u64,
    log_at: usize,
    walked: Option<Aabb>,
    triangles: Vec<u32>,
    vertices: Vec<u32>,
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
        let mut out = Self::unbuilt(positions, triangles, slack);
        out.rebuild(positions, None);
        out
    }

    /// [`Self::new`] with the leaves also bounding `before` (the positions at the start of the
    /// substep that ended at `now`), as [`Self::rebuild`] with `Some(before)`: one build.
    pub fn new_swept(
        now: &[Vector],
        before: &[Vector],
        triangles: &[[u32; 3]],
        slack: Real,
    ) -> Self {
        let mut out = Self::unbuilt(now, triangles, slack);
        out.rebuild(now, Some(before));
        out
    }

    /// Everything but the tree: the kept triangles, the lone vertices, each vertex's leaves.
    fn unbuilt(positions: &[Vector], triangles: &[[u32; 3]], slack: Real) -> Self {
        let n = positions.len();
        let (ids, triangles): (Vec<u32>, Vec<[u32; 3]>) = triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| t.iter().all(|&v| (v as usize) < n))
            .map(|(i, t)| (i as u32, *t))
            .unzip();
        let mut count = vec![0u32; n + 1];
        for t in &triangles {
            for v in dedup3(*t) {
                count[v as usize + 1] += 1;
            }
        }
        let lone: Vec<u32> = (0..n as u32)
            .filter(|&v| count[v as usize + 1] == 0)
            .collect();
        for &v in &lone {
            count[v as usize + 1] = 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut leaves = vec![0u32; count[n] as usize];
        let lone_leaves = lone
            .iter()
            .enumerate()
            .map(|(k, &v)| (triangles.len() + k, [v; 3]));
        for (leaf, t) in triangles.iter().copied().enumerate().chain(lone_leaves) {
            for v in dedup3(t) {
                leaves[fill[v as usize] as usize] = leaf as u32;
                fill[v as usize] += 1;
            }
        }
        Self {
            bvh: Bvh::new(),
            triangles,
            ids,
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
            generation: 0,
            log: Vec::new(),
            log_base: 0,
        }
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
        self.forget_changes();
    }

    /// Every leaf may have changed: the tools' cached answers ([`Self::near_cached`]) are
    /// dropped with the log of changed leaves.
    fn forget_changes(&mut self) {
        self.generation += 1;
        self.log_base += self.log.len();
        self.log.clear();
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
        for &v in moved {
            if let (Some(r), Some(p)) = (self.reference.get_mut(v as usize), now.get(v as usize)) {
                *r = *p;
            }
        }
        // A partial refit walks each changed leaf's path to the root: past a fraction of the
        // leaves, one pass over every leaf and node is cheaper. The tree keeps its structure,
        // as parry's `TriMesh::set_vertices` keeps a deforming mesh's; a binned rebuild here
        // (what this did before) cost 1.4 ms on a 3,025-vertex plate, a step's worth several
        // times over, each time the pressed plate's vertices moved past the slack together.
        // Only the moved vertices take new references, so every other vertex stays within
        // the slack of its reference, as the caller's motion watch measures it.
        if moved.len() * 8 > self.reference.len() {
            for l in 0..self.num_leaves() {
                let b = self.leaf_box(l, Some(before));
                self.bvh.insert_or_update_partially(b, l as u32, 0.0);
            }
            self.bvh.refit_without_opt();
            self.forget_changes();
            return;
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
        if self.log.len() + self.changed.len() > LOG_MAX {
            self.log_base += self.log.len();
            self.log.clear();
        }
        self.log.extend_from_slice(&self.changed);
    }

    /// [`Self::near`] for a caller that asks about much the same place again and again (a
    /// tool, substep after substep): the tree is walked with `aabb` grown by `grow` on every
    /// side, and while later boxes stay inside that one, the answer is the walk's, plus the
    /// leaves changed since that now meet the walked box (kept in `cache`). Triangles in
    /// increasing order, vertices each once; a superset of [`Self::near`]'s.
    pub fn near_cached(
        &mut self,
        cache: &mut NearCache,
        aabb: &Aabb,
        grow: Real,
        triangles: &mut Vec<u32>,
        vertices: &mut Vec<u32>,
    ) {
        let walked = cache.walked.filter(|w| {
            cache.generation == self.generation && cache.log_at >= self.log_base && w.contains(aabb)
        });
        match walked {
            Some(w) => {
                // The leaves changed since: those that now meet the walked box join it.
                let pending = &self.log[cache.log_at - self.log_base..];
                let mut grew = false;
                for &leaf in pending {
                    let meets = self
                        .bvh
                        .leaf_node(leaf)
                        .is_some_and(|n| n.aabb().intersects(&w));
                    if meets {
                        grew = true;
                        cache.triangles.extend(self.id_of(leaf));
                        cache.vertices.extend(self.leaf_vertices(leaf as usize));
                    }
                }
                if grew {
                    cache.triangles.sort_unstable();
                    cache.triangles.dedup();
                    cache.vertices.sort_unstable();
                    cache.vertices.dedup();
                }
            }
            None => {
                let grown = aabb.loosened(grow.max(0.0));
                self.near(&grown, &mut cache.triangles, &mut cache.vertices);
                cache.vertices.sort_unstable();
                cache.walked = Some(grown);
                cache.generation = self.generation;
            }
        }
        cache.log_at = self.log_base + self.log.len();
        triangles.clone_from(&cache.triangles);
        vertices.clone_from(&cache.vertices);
    }

    /// The triangles whose leaves meet `aabb`, in `out` (cleared first), in increasing order:
    /// every triangle that meets `aabb` (anywhere within the slack of its references), and
    /// some that do not.
    pub fn triangles_in(&self, aabb: &Aabb, out: &mut Vec<u32>) {
        out.clear();
        out.extend(self.bvh.intersect_aabb(aabb).filter_map(|l| self.id_of(l)));
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
        let mut marks = std::mem::take(&mut self.marks);
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
            triangles.extend(self.id_of(leaf));
            self.leaf_vertices(leaf as usize).for_each(&mut add);
        }
        self.marks = marks;
        triangles.sort_unstable();
    }

    /// Appends to `out` the triangles that use any of `vertices`.
    pub fn triangles_of(&self, vertices: &[u32], out: &mut Vec<u32>) {
        for &v in vertices {
            let v = v as usize;
            if v + 1 < self.leaf_ptr.len() {
                let range = self.leaf_ptr[v] as usize..self.leaf_ptr[v + 1] as usize;
                out.extend(self.leaves[range].iter().filter_map(|&l| self.id_of(l)));
            }
        }
    }

    /// The caller's index of leaf `l`'s triangle (`None` for a lone vertex's leaf).
    fn id_of(&self, l: u32) -> Option<u32> {
        self.ids.get(l as usize).copied()
    }

    /// Leaf `l`'s vertices (a vertex may repeat).
    fn leaf_vertices(&self, l: usize) -> impl Iterator<Item = u32> + '_ {
        let nt = self.triangles.len();
        let verts = match self.triangles.get(l) {
            Some(t) => Some(*t),
            None => self.lone.get(l - nt).map(|&v| [v; 3]),
        };
        verts.into_iter().flatten()
    }

    fn num_leaves(&self) -> usize {
        self.triangles.len() + self.lone.len()
    }

    /// Leaf `l`'s box: its vertices' references fattened by the slack, and their positions in
    /// `before` if given.
    fn leaf_box(&self, l: usize, before: Option<&[Vector]>) -> Aabb {
        let mut lo = Vector::splat(Real::MAX);
        let mut hi = Vector::splat(Real::MIN);
        for v in self.leaf_vertices(l) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangles_keep_the_callers_indices_when_some_are_left_out() {
        let v = [
            Vector::new(0.0, 0.0, 0.0),
            Vector::new(1.0, 0.0, 0.0),
            Vector::new(0.0, 0.0, 1.0),
            Vector::new(5.0, 0.0, 0.0),
            Vector::new(6.0, 0.0, 0.0),
            Vector::new(5.0, 0.0, 1.0),
            Vector::new(9.0, 9.0, 9.0),
        ];
        // Triangle 1 names a vertex that does not exist; vertex 6 is in no triangle.
        let mut bvh = SurfaceBvh::new(&v, &[[0, 2, 1], [0, 1, 99], [3, 5, 4]], 0.0);
        let (mut tris, mut verts) = (Vec::new(), Vec::new());
        let far = Aabb::new(Vector::new(4.9, -0.1, -0.1), Vector::new(6.1, 0.1, 1.1));
        bvh.near(&far, &mut tris, &mut verts);
        verts.sort();
        assert_eq!(
            (tris.as_slice(), verts.as_slice()),
            (&[2][..], &[3, 4, 5][..])
        );
        let mut around = Vec::new();
        bvh.triangles_of(&[4, 6], &mut around);
        assert_eq!(around, [2]);
        let lone = Aabb::new(Vector::splat(8.9), Vector::splat(9.1));
        bvh.near(&lone, &mut tris, &mut verts);
        assert_eq!((tris.len(), verts.as_slice()), (0, &[6][..]));
        // Through a cache: the lone vertex moves next to the second triangle and is found.
        let mut cache = NearCache::default();
        bvh.near_cached(&mut cache, &far, 0.5, &mut tris, &mut verts);
        assert_eq!(tris, [2]);
        let mut moved = v;
        moved[6] = Vector::new(5.5, 0.0, 0.5);
        bvh.update(&[6], &moved, &v);
        bvh.near_cached(&mut cache, &far, 0.5, &mut tris, &mut verts);
        assert!(verts.contains(&6) && tris == [2]);
    }
}

#[cfg(test)]
mod bad_input {
    use super::*;

    #[test]
    fn empty_degenerate_and_non_finite_input_gives_no_panic_and_no_candidates_from_nowhere() {
        let big = Aabb::new(Vector::splat(-1e3), Vector::splat(1e3));
        let (mut tris, mut verts) = (Vec::new(), Vec::new());
        // Empty.
        let mut empty = SurfaceBvh::new(&[], &[], 0.1);
        empty.near(&big, &mut tris, &mut verts);
        assert!(tris.is_empty() && verts.is_empty());
        empty.update(&[0, 7], &[], &[]);
        // A degenerate triangle (one point) and a NaN slack: the vertex is still found.
        let p = [Vector::new(1.0, 2.0, 3.0)];
        let mut point = SurfaceBvh::new(&p, &[[0, 0, 0]], Real::NAN);
        assert_eq!(point.slack(), 0.0);
        point.near(&big, &mut tris, &mut verts);
        assert_eq!((tris.as_slice(), verts.as_slice()), (&[0][..], &[0][..]));
        // A NaN vertex: no panic; the finite triangle is still found where it is.
        let v = [
            Vector::ZERO,
            Vector::X,
            Vector::Z,
            Vector::new(Real::NAN, 0.0, 0.0),
        ];
        let mut nan = SurfaceBvh::new(&v, &[[0, 2, 1], [1, 2, 3]], 0.01);
        let near_origin = Aabb::new(Vector::splat(-0.1), Vector::splat(0.1));
        nan.near(&near_origin, &mut tris, &mut verts);
        assert!(tris.contains(&0));
        nan.update(&[3], &v, &v);
    }
}
