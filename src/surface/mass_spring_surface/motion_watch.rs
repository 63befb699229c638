//! Which vertices moved far: the surface notes, as it moves each vertex (its integrators, the
//! constraint solve, [`MassSpringSurface::set_state`]), those that went farther than a radius
//! from where they were when last reported. A spatial index over the surface with leaves
//! fattened by that radius ([`crate::geometry::SurfaceBvh`]) then needs updating only there: no
//! pass over the whole mesh to find out what moved.

use super::MassSpringSurface;
use crate::math::Real;
use glamx::DVec3;

/// The watch's state: each vertex's position when last reported, and the vertices that have
/// left the ball of `radius` around it since.
#[derive(Clone, Debug)]
pub(super) struct MotionWatch {
    reference: Vec<DVec3>,
    radius2: f64,
    flagged: Vec<bool>,
    escaped: Vec<u32>,
    /// Positions changed in a way not noted vertex by vertex (pins reset to their home).
    lost: bool,
}

impl MotionWatch {
    /// Notes that vertex `i` is now at `p`.
    #[inline]
    pub(super) fn note(&mut self, i: usize, p: DVec3) {
        if let (Some(r), Some(f)) = (self.reference.get(i), self.flagged.get_mut(i)) {
            if !*f && (p - *r).length_squared() > self.radius2 {
                *f = true;
                self.escaped.push(i as u32);
            }
        }
    }
    /// Every position may have changed.
    pub(super) fn lose(&mut self) {
        self.lost = true;
    }
}

/// Notes vertex `i` at `p` in `watch`, if the surface is watched.
#[inline]
pub(super) fn note(watch: &mut Option<Box<MotionWatch>>, i: usize, p: DVec3) {
    if let Some(w) = watch {
        w.note(i, p);
    }
}

/// What [`MassSpringSurface::take_escaped`] found.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Escaped {
    /// The vertices written out are all those that moved farther than the radius.
    Listed,
    /// The watch had just started or lost track (the surface was not watched, or its pins were
    /// reset to their rest positions): any vertex may have moved; start over from the
    /// current positions.
    All,
}

impl MassSpringSurface {
    /// Starts (or restarts) watching which vertices move farther than `radius` from their
    /// current positions ([`Self::take_escaped`]). A non-finite or negative radius watches
    /// every motion (radius zero).
    pub fn watch_motion(&mut self, radius: Real) {
        let r = if radius.is_finite() {
            radius.max(0.0) as f64
        } else {
            0.0
        };
        self.watch = Some(Box::new(MotionWatch {
            reference: self.pos.clone(),
            radius2: r * r,
            flagged: vec![false; self.pos.len()],
            escaped: Vec::new(),
            lost: false,
        }));
    }

    /// Writes into `out` (cleared first) the vertices that moved farther than the watch's
    /// radius since the watch started or since they were last reported, and measures them
    /// from where they are now from then on. Returns [`Escaped::All`] (and restarts the watch
    /// at the current positions, with the same radius) when that is not known: the surface
    /// is not watched ([`Self::watch_motion`] starts it at radius zero), or it lost track.
    pub fn take_escaped(&mut self, out: &mut Vec<u32>) -> Escaped {
        out.clear();
        let Some(w) = self.watch.as_mut() else {
            self.watch_motion(0.0);
            return Escaped::All;
        };
        if w.lost {
            let r = w.radius2.sqrt() as Real;
            self.watch_motion(r);
            return Escaped::All;
        }
        for &i in &w.escaped {
            let i = i as usize;
            w.reference[i] = self.pos[i];
            w.flagged[i] = false;
        }
        out.append(&mut w.escaped);
        Escaped::Listed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vector;
    use crate::surface::MassSpringSurfaceBuilder;

    fn strip() -> MassSpringSurface {
        let v = [
            Vector::new(0.0, 0.0, 0.0),
            Vector::new(1.0, 0.0, 0.0),
            Vector::new(0.0, 0.0, 1.0),
            Vector::new(1.0, 0.0, 1.0),
        ];
        MassSpringSurfaceBuilder::new(v.to_vec(), vec![[0, 2, 1], [1, 2, 3]])
            .dt(1e-3)
            .gravity(Vector::new(0.0, -9.81, 0.0))
            .build()
            .unwrap()
    }

    #[test]
    fn reports_exactly_the_vertices_that_moved_farther_than_the_radius() {
        let mut s = strip();
        let mut out = Vec::new();
        assert_eq!(s.take_escaped(&mut out), Escaped::All);
        s.watch_motion(0.1);
        s.set_state(1, Vector::new(1.0, 0.05, 0.0), Vector::ZERO)
            .unwrap();
        s.set_state(2, Vector::new(0.0, 0.2, 1.0), Vector::ZERO)
            .unwrap();
        assert_eq!(s.take_escaped(&mut out), Escaped::Listed);
        assert_eq!(out, vec![2]);
        // Vertex 2 is measured from y = 0.2 now; vertex 1 still from y = 0.
        s.set_state(2, Vector::new(0.0, 0.25, 1.0), Vector::ZERO)
            .unwrap();
        s.set_state(1, Vector::new(1.0, 0.11, 0.0), Vector::ZERO)
            .unwrap();
        assert_eq!(s.take_escaped(&mut out), Escaped::Listed);
        assert_eq!(out, vec![1]);
    }

    #[test]
    fn a_falling_surface_reports_every_vertex_once_it_fell_the_radius() {
        let mut s = strip();
        s.watch_motion(1e-3);
        let mut out = Vec::new();
        let mut fallen = 0.0;
        let mut steps = 0;
        while s.take_escaped(&mut out) == Escaped::Listed && out.is_empty() {
            s.step();
            steps += 1;
            fallen = -s.position(0).y;
            assert!(steps < 10_000);
        }
        out.sort();
        assert_eq!(out, vec![0, 1, 2, 3]);
        // Free fall: it took the step that first passed 1 mm.
        assert!(fallen > 1e-3 && fallen < 1e-3 + 9.81 * 1e-3 * 1e-3 * steps as f32);
    }
}
