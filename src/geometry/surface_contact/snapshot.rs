//! The surface over one substep ([`SurfaceSnapshot`]: its positions at the start and the end,
//! its triangles) and the filters that pick a tool's candidate triangles from it by their
//! bounds.

use crate::math::{Real, Vector};
use glamx::DVec3;
use parry3d::bounding_volume::{Aabb, BoundingVolume};
/// The surface over one substep: positions at its start and end, and its triangles.
#[derive(Copy, Clone, Debug)]
pub struct SurfaceSnapshot<'a> {
    /// Vertex positions at the start of the substep.
    pub before: &'a [Vector],
    /// Vertex positions now (end of the substep).
    pub now: &'a [Vector],
    /// The triangles (vertex indices).
    pub triangles: &'a [[u32; 3]],
}

impl SurfaceSnapshot<'_> {
    /// Triangle `t`'s vertices in `pos` (`None` for a triangle or vertex out of range).
    pub(super) fn tri(&self, pos: &[Vector], t: u32) -> Option<[DVec3; 3]> {
        let idx = self.triangles.get(t as usize)?;
        let mut out = [DVec3::ZERO; 3];
        for (o, &v) in out.iter_mut().zip(idx) {
            *o = pos.get(v as usize)?.as_dvec3();
        }
        Some(out)
    }

    /// The triangles whose bounds over the substep (start and end) meet `aabb`: the candidates
    /// for [`super::tool_surface_contacts`]. A linear scan; a surface stepped over and over keeps a
    /// [`crate::geometry::SurfaceBvh`] instead, whose cost does not grow with the mesh.
    pub fn triangles_near(&self, aabb: &Aabb, out: &mut Vec<u32>) {
        let mut bounds = Vec::new();
        self.triangle_bounds(&mut bounds);
        triangles_in(&bounds, aabb, out);
    }

    /// Each triangle's bounds over the substep (its vertices at the start and at the end), in
    /// `out` (cleared first).
    pub fn triangle_bounds(&self, out: &mut Vec<Aabb>) {
        out.clear();
        out.extend(self.triangles.iter().map(|idx| self.bounds_of(idx)));
    }

    /// Triangle `t`'s bounds over the substep (its vertices at the start and at the end);
    /// `None` for a triangle out of range.
    pub fn swept_bounds(&self, t: u32) -> Option<Aabb> {
        self.triangles
            .get(t as usize)
            .map(|idx| self.bounds_of(idx))
    }

    /// The `candidates` whose bounds over the substep ([`Self::swept_bounds`]) meet `query`, in
    /// `out` (cleared first), in their order; a candidate out of range is left out.
    ///
    /// Right after a surface step the candidates' vertices are out of cache (a 100,000-node
    /// surface's positions are megabytes), and asked a triangle at a time the reads wait on
    /// each other. So the candidates go by in chunks: their triangles' indices are fetched
    /// ahead, then their vertices', then the bounds are tested. Measured on `cargo bench
    /// --bench coupled_step -- 100kn_6cubes_1khz` (six cubes on a 100,000-node plate, timed
    /// right after each step): this filter 24-29 µs a substep as a `swept_bounds` per
    /// candidate, 15-17 µs so.
    ///
    /// # Example
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::geometry::SurfaceSnapshot;
    /// use rapier_touch::parry3d::bounding_volume::Aabb;
    ///
    /// // Two triangles side by side: x from 0 to 1, and from 1 to 2.
    /// let strip = [
    ///     Vector::new(0.0, 0.0, 0.0), Vector::new(1.0, 0.0, 0.0),
    ///     Vector::new(1.0, 0.0, 1.0), Vector::new(2.0, 0.0, 0.0),
    ///     Vector::new(2.0, 0.0, 1.0),
    /// ];
    /// let triangles = [[0, 1, 2], [1, 3, 4]];
    /// let surface = SurfaceSnapshot { before: &strip, now: &strip, triangles: &triangles };
    /// // A box round (0.5, 0, 0.5): only the first triangle's bounds reach there (triangle 7
    /// // does not exist).
    /// let query = Aabb::new(Vector::new(0.4, -0.1, 0.4), Vector::new(0.6, 0.1, 0.6));
    /// let mut out = Vec::new();
    /// surface.triangles_meeting(&[0, 1, 7], &query, &mut out);
    /// assert_eq!(out, [0]);
    /// ```
    pub fn triangles_meeting(&self, candidates: &[u32], query: &Aabb, out: &mut Vec<u32>) {
        const CHUNK: usize = 32;
        out.clear();
        let mut idx = [[0u32; 3]; CHUNK];
        for chunk in candidates.chunks(CHUNK) {
            for &t in chunk {
                prefetch(self.triangles, t as usize);
            }
            let mut n = 0;
            let mut kept = [0u32; CHUNK];
            for &t in chunk {
                if let Some(i) = self.triangles.get(t as usize) {
                    (idx[n], kept[n]) = (*i, t);
                    n += 1;
                }
            }
            for i in &idx[..n] {
                for &v in i {
                    prefetch(self.before, v as usize);
                    prefetch(self.now, v as usize);
                }
            }
            for (i, &t) in idx[..n].iter().zip(&kept[..n]) {
                if self.bounds_of(i).intersects(query) {
                    out.push(t);
                }
            }
        }
    }

    fn bounds_of(&self, idx: &[u32; 3]) -> Aabb {
        let mut lo = Vector::splat(Real::MAX);
        let mut hi = Vector::splat(Real::MIN);
        for &v in idx {
            for pos in [self.before, self.now] {
                if let Some(p) = pos.get(v as usize) {
                    lo = lo.min(*p);
                    hi = hi.max(*p);
                }
            }
        }
        Aabb::new(lo, hi)
    }
}

/// Asks the processor to bring `slice[i]` into its cache (nothing when `i` is out of range or
/// on other processors than x86-64). Hand-written for [`SurfaceSnapshot::triangles_meeting`],
/// where the bench its docs cite shows it winning: neither std nor the crates this one uses offer a
/// prefetch on stable Rust.
#[inline(always)]
fn prefetch<T>(slice: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(x) = slice.get(i) {
        // SAFETY: a prefetch is a hint that reads nothing into the program and cannot fault,
        // and the pointer is to an element of the slice.
        unsafe {
            core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(
                (x as *const T).cast(),
            )
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (slice, i);
}

/// The triangles whose `bounds` ([`SurfaceSnapshot::triangle_bounds`]) meet `aabb`, in `out`
/// (cleared first).
pub fn triangles_in(bounds: &[Aabb], aabb: &Aabb, out: &mut Vec<u32>) {
    out.clear();
    for (t, b) in bounds.iter().enumerate() {
        if b.mins.cmple(aabb.maxs).all() && b.maxs.cmpge(aabb.mins).all() {
            out.push(t as u32);
        }
    }
}
