//! What the point presses and the rigid holders gave the surface, read after a step: each
//! press's impulse along its normal and its tangent plane, the momentum it gave the vertices,
//! and each rigid holder's impulse; and the holders themselves.

use super::rigid_holder::{HolderState, RigidHolder};
use super::{MassSpringSurface, SurfaceError};
use crate::math::{Real, Vector};

impl MassSpringSurface {
    /// The impulse (N·s, along its normal; positive when pushing) hold `id` of
    /// [`MassSpringSurface::press_points`] has given the surface: the press's own velocity
    /// change, plus the constraint impulse of the filtered step after it (all the momentum the
    /// holder gave the surface from the press to the end of that step). The share of a vertex
    /// that was held when it was pressed is left out: that vertex's holder keeps it where it
    /// is, taking that share itself (a tool pressing a triangle beside a vertex it holds gives
    /// the surface the rest; its hold of the vertex gives the vertex's own force). `None` for
    /// no such hold.
    pub fn point_impulse(&self, id: usize) -> Option<Real> {
        self.point_holds
            .get(id)
            .map(|h| (h.impulse * (1.0 - h.held_share)) as Real)
    }

    /// The momentum (N·s) hold `id` of [`MassSpringSurface::press_points`] has given the
    /// surface's vertices: the press's own velocity change and the filtered step's impulses
    /// on the vertices that moved with it, along its normal and (with friction or a grasp)
    /// its tangent plane. Where [`MassSpringSurface::point_impulse`] leaves out the share of
    /// a vertex held when it was pressed, this is what the vertices took, as the holds'
    /// [`MassSpringSurface::hold_impulse`] is: the two sum to the momentum the holders gave
    /// the surface. `None` for no such hold.
    ///
    /// # Example
    /// A point pressed into a free plate at 0.2 m/s: the plate's momentum changes by the
    /// press's, then by the step's impulses on it.
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::surface::meshing::plate;
    ///
    /// let mut surface = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 4, 4))
    ///     .build()
    ///     .unwrap();
    /// let [a, b, c] = surface.triangles()[10];
    /// let down = Vector::new(0.0, -1.0, 0.0);
    /// let third = 1.0 / 3.0;
    /// let weights = [(a, third), (b, third), (c, third)];
    /// let id = surface.press_point(&weights, down, 0.01, 0.2).unwrap().unwrap();
    /// let pressed = surface.point_momentum(id).unwrap();
    /// assert!((surface.momentum() - pressed).length() < 1e-6);
    /// surface.step();
    /// let given = surface.point_momentum(id).unwrap();
    /// assert!((surface.momentum() - given).length() < 1e-5);
    /// assert!(given.y < pressed.y); // it kept pushing the point down through the step
    /// ```
    pub fn point_momentum(&self, id: usize) -> Option<Vector> {
        self.point_momentum_f64(id).map(|m| m.as_vec3())
    }

    /// [`MassSpringSurface::point_momentum`] in double precision (as
    /// [`MassSpringSurface::hold_impulse_f64`]).
    pub(crate) fn point_momentum_f64(&self, id: usize) -> Option<glamx::DVec3> {
        self.point_holds.get(id).map(|h| h.momentum)
    }

    /// The impulse (N·s, in its tangent plane) the holder of hold `id` of
    /// [`MassSpringSurface::press_points`] gave the surface along the point's tangent plane
    /// (friction, [`Tangential`](super::Tangential)) in the filtered step after the press, less a held vertex's
    /// share as [`MassSpringSurface::point_impulse`]; zero for a frictionless press, `None` for
    /// no such hold.
    pub fn point_tangent_impulse(&self, id: usize) -> Option<Vector> {
        self.point_holds
            .get(id)
            .map(|h| (h.tangent_impulse * (1.0 - h.held_share)).as_vec3())
    }

    /// The impulse (N·s) the filtered step after the press of hold `id` gave, through the
    /// point's rows, the vertices a sliding hold holds, across that hold's normal: the hold
    /// takes only the part along its normal (what its holder reads there is the vertex's
    /// springs along it), so this part is the point's holder's to feel. A tool pressing a
    /// triangle beside a vertex it holds on a face tilted 10° from the triangle left 0.56 N
    /// of a 6.4 N press out of its reaction without it. Zero where no such vertex moved with
    /// the point; `None` for no such hold.
    pub fn point_held_across(&self, id: usize) -> Option<Vector> {
        self.point_holds.get(id).map(|h| h.held_across.as_vec3())
    }

    /// Replaces the rigid holders that presses may name ([`PointPress::holder`](super::PointPress::holder), index into
    /// `holders`): bodies whose mass enters the filtered step's solve (implicit coupling,
    /// [`RigidHolder`]). Points already pressed keep their holder's index and follow the
    /// velocity given here from the next step on: a caller moving a body between steps sets
    /// its new velocity here. The surface never moves a holder: after a step, read what it
    /// gave each one with [`MassSpringSurface::holder_impulse`] and move the body. The
    /// explicit and Baraff-Witkin integrators do not hold points, nor couple holders.
    ///
    /// # Errors
    /// [`SurfaceError::InvalidHolder`]; the holders are then left as they were.
    pub fn set_holders(&mut self, holders: &[RigidHolder]) -> Result<(), SurfaceError> {
        let checked = holders
            .iter()
            .map(HolderState::new)
            .collect::<Result<Vec<_>, _>>()?;
        self.holders = checked;
        Ok(())
    }

    /// The impulse (N·s) the surface gave rigid holder `k` ([`MassSpringSurface::set_holders`])
    /// in the last filtered step, and its moment about the holder's centre (N·m·s); surface
    /// frame. The holder's velocity after the step is its velocity before plus its inverse
    /// mass and inertia times these. `None` for no such holder.
    pub fn holder_impulse(&self, k: usize) -> Option<(Vector, Vector)> {
        self.holders
            .get(k)
            .map(|h| (h.impulse.as_vec3(), h.angular_impulse.as_vec3()))
    }
}
