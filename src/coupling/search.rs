//! Where the tools may touch a surface, without a pass over its mesh: a [`SurfaceBvh`] over the
//! surface (the geometry layer's), kept current from the vertices the surface reports as having
//! moved farther than the BVH's slack ([`MassSpringSurface::take_escaped`]). The vertex holds
//! and the sharp features' presses both take their candidates from it.

use crate::geometry::{NearCache, SurfaceBvh};
use crate::math::{Real, Vector};
use crate::surface::{Escaped, MassSpringSurface};
use parry3d::bounding_volume::Aabb;
use rapier3d::geometry::ColliderHandle;

/// The leaves' slack as a fraction of the surface's mean edge length: a vertex is re-bounded
/// once it moved a quarter of an edge.
const SLACK_PER_EDGE: Real = 0.25;
/// A tool's walk of the BVH covers its box grown by this fraction of its size on every side.
const GROW: Real = 0.2;

/// A surface's contact search state (module docs).
#[derive(Clone, Debug, Default)]
pub(super) struct ContactSearch {
    bvh: Option<SurfaceBvh>,
    escaped: Vec<u32>,
    /// The last query's candidate vertices.
    pub vertices: Vec<u32>,
    /// Each tool's candidate triangles, by its index in the substep.
    tools: Vec<Vec<u32>>,
    /// Each tool's last walk of the BVH.
    caches: Vec<(ColliderHandle, NearCache)>,
}

impl ContactSearch {
    /// Brings the BVH up to the surface at `now` (positions; `before`: at the start of the
    /// substep), building it on first use, when the surface lost track of its motion or
    /// changed size.
    pub fn refresh(&mut self, surface: &mut MassSpringSurface, now: &[Vector], before: &[Vector]) {
        let fresh = match &self.bvh {
            Some(_) => surface.take_escaped(&mut self.escaped) == Escaped::All,
            None => true,
        } || now.len() != before.len();
        let Some(bvh) = self.bvh.as_mut().filter(|_| !fresh) else {
            let slack = SLACK_PER_EDGE * mean_edge(now, surface.triangles());
            surface.watch_motion(slack);
            self.bvh = Some(SurfaceBvh::new_swept(
                now,
                before,
                surface.triangles(),
                slack,
            ));
            // Every vertex may have moved.
            self.escaped.clear();
            self.escaped.extend(0..now.len() as u32);
            return;
        };
        bvh.update(&self.escaped, now, before);
    }

    /// The vertices and the triangles that may lie in `aabb`, for tool `k` of the substep
    /// (collider `tool`): the vertices into `self.vertices` in increasing order, the
    /// triangles kept as the tool's ([`Self::triangles_of_tool`]). The BVH is walked with the
    /// box grown by a fifth of its size and the answer reused while the tool stays inside
    /// that ([`SurfaceBvh::near_cached`]).
    pub fn near(&mut self, k: usize, tool: ColliderHandle, aabb: &Aabb) {
        if self.tools.len() <= k {
            self.tools.resize_with(k + 1, Vec::new);
        }
        let triangles = &mut self.tools[k];
        let Some(bvh) = self.bvh.as_mut() else {
            triangles.clear();
            self.vertices.clear();
            return;
        };
        let cache = match self.caches.iter().position(|c| c.0 == tool) {
            Some(i) => &mut self.caches[i].1,
            None => {
                self.caches.push((tool, NearCache::default()));
                &mut self.caches.last_mut().expect("just pushed").1
            }
        };
        let grow = GROW * aabb.extents().max_element();
        bvh.near_cached(cache, aabb, grow, triangles, &mut self.vertices);
    }

    /// The vertices that may lie in `aabb` (the surface's frame) into `out`, from the BVH as
    /// the last [`Self::refresh`] left it (each vertex within the slack of its leaf); `false`,
    /// with `out` untouched, when there is no BVH yet.
    pub fn vertices_in(&mut self, aabb: &Aabb, out: &mut Vec<u32>) -> bool {
        match self.bvh.as_mut() {
            Some(bvh) => {
                bvh.vertices_in(aabb, out);
                true
            }
            None => false,
        }
    }

    /// Forgets the caches of tools not in `tools`.
    pub fn retain_tools(&mut self, tools: impl Fn(ColliderHandle) -> bool) {
        self.caches.retain(|c| tools(c.0));
    }

    /// Forgets the tools' triangles (a tool with no [`Self::near`] in this substep has none).
    pub fn clear_tools(&mut self) {
        self.tools.iter_mut().for_each(Vec::clear);
    }

    /// After a [`Self::refresh`] that followed the [`Self::near`] queries: the triangles
    /// around the vertices that moved farther than the slack in between join every tool's
    /// candidates (their leaves were stale when the tools looked).
    pub fn add_moved_triangles(&mut self) {
        let Some(bvh) = self.bvh.as_ref() else {
            return;
        };
        if self.escaped.is_empty() {
            return;
        }
        for list in &mut self.tools {
            bvh.triangles_of(&self.escaped, list);
            list.sort_unstable();
            list.dedup();
        }
    }

    /// Appends to `out` the triangles round `vertex` (nothing before the tree is built).
    pub fn triangles_round(&self, vertex: u32, out: &mut Vec<u32>) {
        if let Some(bvh) = &self.bvh {
            bvh.triangles_of(&[vertex], out);
        }
    }

    /// Tool `k`'s candidate triangles.
    pub fn triangles_of_tool(&self, k: usize) -> &[u32] {
        self.tools.get(k).map_or(&[], Vec::as_slice)
    }
}

/// The mean length of the triangles' edges at `positions` (zero without triangles).
fn mean_edge(positions: &[Vector], triangles: &[[u32; 3]]) -> Real {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for t in triangles {
        for k in 0..3 {
            if let (Some(a), Some(b)) = (
                positions.get(t[k] as usize),
                positions.get(t[(k + 1) % 3] as usize),
            ) {
                sum += (*a - *b).length() as f64;
                n += 1;
            }
        }
    }
    if n == 0 {
        0.0
    } else {
        (sum / n as f64) as Real
    }
}
