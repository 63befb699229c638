//! The reusable storage of a reconstruction query: candidate pairs, events, stamps and the
//! convex path's warm starts.

use super::super::classify::Event;
use super::super::touch_mesh::TouchMesh;
use glamx::DVec3;
use std::collections::HashSet;
use std::hash::{BuildHasherDefault, Hasher};

#[derive(Default, Clone)]
pub(super) struct Workspace {
    /// Candidate triangle pairs `(fixed, moving)`, internal numbering.
    pub(super) pairs: Vec<(u32, u32)>,
    pub(super) events: Vec<Event>,
    pub(super) m_pts: Vec<DVec3>,
    pub(super) m_pt_stamp: Vec<u32>,
    pub(super) v_stamp_m: Vec<u32>,
    pub(super) v_stamp_f: Vec<u32>,
    pub(super) e_stamp_m: Vec<u32>,
    pub(super) e_stamp_f: Vec<u32>,
    pub(super) tm_range: Vec<(u32, u32)>,
    pub(super) tm_range_stamp: Vec<u32>,
    pub(super) counter: u32,
    /// Convex path: triangles near the witness points, visited triangle pairs, the touches
    /// found near the witnesses, touching pairs still to grow from, and the last support
    /// vertices (warm starts).
    pub(super) near_f: Vec<u32>,
    pub(super) near_m: Vec<u32>,
    pub(super) visited: HashSet<u64, BuildHasherDefault<PairHasher>>,
    pub(super) near_touches: Vec<(u32, u32, f64)>,
    pub(super) grow: Vec<(u32, u32)>,
    pub(super) warm: [u32; 2],
    /// A small moving mesh's triangles in the fixed frame and their loosened boxes
    /// (`penetrating_at`).
    pub(super) m_tris: Vec<([DVec3; 3], parry3d::bounding_volume::Aabb)>,
    /// A small moving mesh's triangles' boxes in the fixed frame, centre and half extents
    /// (`collect_first_touch`).
    pub(super) m_boxes: Vec<(crate::math::Vector, crate::math::Vector)>,
}

/// Hashes a packed triangle pair with one multiplication (the keys are already well spread).
#[derive(Default)]
pub(super) struct PairHasher(u64);

impl Hasher for PairHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ b as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (x ^ (x >> 29)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

impl Workspace {
    pub(super) fn prepare(&mut self, f: &TouchMesh, m: &TouchMesh) {
        fn fit<T: Clone + Default>(v: &mut Vec<T>, n: usize) {
            if v.len() < n {
                v.resize(n, T::default());
            }
        }
        fit(&mut self.m_pts, m.num_vertices());
        fit(&mut self.m_pt_stamp, m.num_vertices());
        fit(&mut self.v_stamp_m, m.num_vertices());
        fit(&mut self.v_stamp_f, f.num_vertices());
        fit(&mut self.e_stamp_m, m.num_edges());
        fit(&mut self.e_stamp_f, f.num_edges());
        fit(&mut self.tm_range, m.num_triangles());
        fit(&mut self.tm_range_stamp, m.num_triangles());
        self.pairs.clear();
        self.events.clear();
    }

    /// A fresh stamp value; stamp arrays are cleared when the counter wraps.
    pub(super) fn stamp(&mut self) -> u32 {
        self.counter = self.counter.wrapping_add(1);
        if self.counter == 0 {
            for v in [
                &mut self.m_pt_stamp,
                &mut self.v_stamp_m,
                &mut self.v_stamp_f,
                &mut self.e_stamp_m,
                &mut self.e_stamp_f,
                &mut self.tm_range_stamp,
            ] {
                v.iter_mut().for_each(|x| *x = 0);
            }
            self.counter = 1;
        }
        self.counter
    }
}
