//! Changing a built surface: integrator, time step, springs, pins, applied forces, vertex
//! states, and the holds tools put on vertices.

use super::*;

impl MassSpringSurface {
    // ----- Changes -----

    /// Switches the integrator (the mesh is kept; a filter is built if needed).
    ///
    /// # Errors
    /// [`SurfaceError::Filter`].
    pub fn set_integrator(&mut self, integrator: Integrator) -> Result<(), SurfaceError> {
        self.integrator = integrator;
        self.ensure_filter()
    }
    /// Changes the time step (the filter is refactored).
    ///
    /// # Errors
    /// [`SurfaceError::InvalidTimeStep`], [`SurfaceError::Filter`].
    pub fn set_dt(&mut self, dt: Real) -> Result<(), SurfaceError> {
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(SurfaceError::InvalidTimeStep(dt as f64));
        }
        self.dt = dt as f64;
        self.filter = None;
        self.ensure_filter()
    }
    /// Sets the stiffness and damping of every edge (the filter is refactored).
    ///
    /// # Errors
    /// [`SurfaceError::InvalidSpring`], [`SurfaceError::Filter`].
    pub fn set_spring(&mut self, k: Real, c: Real) -> Result<(), SurfaceError> {
        check_spring(k, c)?;
        self.k.iter_mut().for_each(|x| *x = k as f64);
        self.c.iter_mut().for_each(|x| *x = c as f64);
        self.filter = None;
        self.ensure_filter()
    }
    /// Pins or releases vertex `i`.
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::Filter`].
    pub fn set_pinned(&mut self, i: u32, pinned: bool) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        if self.pinned[i as usize] != pinned {
            self.pinned[i as usize] = pinned;
            self.rebuild_free();
            self.ensure_filter()?;
        }
        Ok(())
    }
    /// Sets the persistent external force on vertex `i` (until changed or cleared).
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::NonFiniteForce`].
    pub fn set_force(&mut self, i: u32, f: Vector) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        if !f.is_finite() {
            return Err(SurfaceError::NonFiniteForce);
        }
        self.ext[i as usize] = f.as_dvec3();
        Ok(())
    }
    /// Removes all persistent external forces (not the scheduled ones).
    pub fn clear_forces(&mut self) {
        self.ext.iter_mut().for_each(|f| *f = DVec3::ZERO);
    }
    /// Applies `profile` to each of `vertices` from now on; returns an id for
    /// [`MassSpringSurface::remove_force_schedule`].
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::NonFiniteForce`],
    /// [`SurfaceError::InvalidForceProfile`].
    pub fn add_force_schedule(
        &mut self,
        vertices: Vec<u32>,
        profile: ForceProfile,
    ) -> Result<usize, SurfaceError> {
        for &v in &vertices {
            self.check_vertex(v)?;
        }
        profile.check()?;
        self.schedules.push((vertices, profile));
        Ok(self.schedules.len() - 1)
    }
    /// Stops a force schedule (ids of the others stay valid).
    pub fn remove_force_schedule(&mut self, id: usize) {
        if let Some(s) = self.schedules.get_mut(id) {
            s.0.clear();
        }
    }
    /// Moves free vertex `i` to `p` with velocity `v` (a tool holding it). Pinned vertices do
    /// not move.
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::NonFiniteVertex`].
    pub fn set_state(&mut self, i: u32, p: Vector, v: Vector) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        if !(p.is_finite() && v.is_finite()) {
            return Err(SurfaceError::NonFiniteVertex(i));
        }
        if !self.pinned[i as usize] {
            self.pos[i as usize] = p.as_dvec3();
            motion_watch::note(&mut self.watch, i as usize, self.pos[i as usize]);
            self.vel[i as usize] = v.as_dvec3();
        }
        Ok(())
    }

    /// Marks vertex `i` as held by something outside the surface (a tool) for the following
    /// steps, until [`MassSpringSurface::release_all`]: a moving pin. It keeps the velocity
    /// given by [`MassSpringSurface::set_state`], and the rest of the surface responds to it as
    /// to a pin: the filtered integrators solve for the holders' impulses through the columns
    /// of the filter (`S⁻¹ = W M⁻¹`) at the held vertices (a small dense system per step, one
    /// extra solve per newly held vertex for the exact filter, cached), Baraff-Witkin projects
    /// its CG. A held vertex's
    /// [`MassSpringSurface::internal_force`] is what it pushes the holder with.
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`].
    pub fn hold(&mut self, i: u32) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        if !self.held[i as usize] {
            self.held_list.push(i);
        }
        self.held[i as usize] = true;
        self.held_normal[i as usize] = DVec3::ZERO;
        Ok(())
    }

    /// Holds vertex `i` along `normal` only, until [`MassSpringSurface::release_all`]: a
    /// frictionless contact. The holder balances the normal part of the vertex's force and
    /// velocity change; the tangential part moves it as usual, so it slides along the holder.
    /// A zero or non-finite `normal` gives a full [`MassSpringSurface::hold`].
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`].
    pub fn hold_sliding(&mut self, i: u32, normal: Vector) -> Result<(), SurfaceError> {
        self.hold(i)?;
        if let Some(n) = normal.as_dvec3().try_normalize() {
            self.held_normal[i as usize] = n;
        }
        Ok(())
    }

    /// A sliding hold ([`MassSpringSurface::hold_sliding`]) whose holder also pulls vertex `i`
    /// with `friction` (N) along the surface until released: kinetic friction of a vertex
    /// slipping over a tool. The part of `friction` along `normal` is dropped (the hold takes
    /// it).
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::NonFiniteForce`].
    pub fn hold_sliding_with_friction(
        &mut self,
        i: u32,
        normal: Vector,
        friction: Vector,
    ) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        if !friction.is_finite() {
            return Err(SurfaceError::NonFiniteForce);
        }
        self.hold_sliding(i, normal)?;
        self.held_forces.retain(|h| h.0 != i);
        let f = self.unheld_part(i as usize, friction.as_dvec3());
        if f != DVec3::ZERO {
            self.held_forces.push((i, f));
        }
        Ok(())
    }

    /// The part of `v` (a force or a velocity change of vertex `i`) its holder leaves free.
    pub(super) fn unheld_part(&self, i: usize, v: DVec3) -> DVec3 {
        if !self.held[i] {
            return v;
        }
        let n = self.held_normal[i];
        if n == DVec3::ZERO {
            return DVec3::ZERO;
        }
        v - n * v.dot(n)
    }
    /// Releases vertex `i` if held.
    pub fn release(&mut self, i: u32) {
        if let Some(h) = self.held.get_mut(i as usize) {
            if *h {
                self.held_list.retain(|&v| v != i);
            }
            *h = false;
        }
        self.held_forces.retain(|h| h.0 != i);
    }
    /// Releases every held vertex and every held point.
    pub fn release_all(&mut self) {
        self.point_holds.clear();
        self.held_forces.clear();
        for &v in &self.held_list {
            self.held[v as usize] = false;
        }
        self.held_list.clear();
    }
    /// Is vertex `i` held?
    pub fn is_held(&self, i: u32) -> bool {
        self.held.get(i as usize).copied().unwrap_or(false)
    }
    /// The impulse (N·s) the holder of vertex `i` gave it over the last step: the part of its
    /// force the hold took (all of it for a full hold, the part along the normal for a sliding
    /// one) and the constraint solve's impulse that kept its held velocity. Summed over what a
    /// tool held, it is what the tool gave the surface through its vertex holds (its point
    /// presses' is [`Self::point_momentum`]). Zero for a vertex not held in the last step or
    /// out of range; under the Baraff-Witkin integrator, only the force's part.
    ///
    /// # Example
    /// A free plate (no pins, no gravity) with one vertex held moving down: the plate's
    /// momentum changes by what the hold gave it.
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::surface::meshing::plate;
    ///
    /// let mut surface = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 4, 4))
    ///     .stiffness(50.0)
    ///     .build()
    ///     .unwrap();
    /// let v = 12; // the middle vertex
    /// surface.set_state(v, surface.position(v), Vector::new(0.0, -0.5, 0.0)).unwrap();
    /// let before = surface.momentum();
    /// surface.hold(v).unwrap();
    /// surface.step();
    /// let given = surface.hold_impulse(v);
    /// // It kept the vertex going down against its springs, which pulled the plate after it.
    /// assert!(given.y < 0.0);
    /// assert!((surface.momentum() - before - given).length() < 1e-5);
    /// ```
    pub fn hold_impulse(&self, i: u32) -> Vector {
        self.hold_impulse_f64(i).as_vec3()
    }
    /// [`MassSpringSurface::hold_impulse`] as the surface keeps it (double precision), for
    /// books that sum many of them ([`crate::coupling`]: a tool twisting a plate holds vertices
    /// with impulses tens of times the plate's net momentum change).
    pub(crate) fn hold_impulse_f64(&self, i: u32) -> glamx::DVec3 {
        self.hold_impulse
            .get(i as usize)
            .copied()
            .unwrap_or(glamx::DVec3::ZERO)
    }
    /// The normal a sliding hold on vertex `i` supports; zero for a full hold, a vertex not
    /// held, or one out of range.
    pub(crate) fn held_normal(&self, i: u32) -> Vector {
        match self.held.get(i as usize) {
            Some(true) => self.held_normal[i as usize].as_vec3(),
            _ => Vector::ZERO,
        }
    }
    /// The normal vertex `i` was last held along by a sliding hold, held now or not (kept
    /// through [`MassSpringSurface::release_all`]: what a tool that held it in the last substep
    /// held it along); zero for a full hold, or a vertex never held or out of range.
    pub(crate) fn last_held_normal(&self, i: u32) -> Vector {
        self.held_normal
            .get(i as usize)
            .map_or(Vector::ZERO, |n| n.as_vec3())
    }

    pub(super) fn check_vertex(&self, i: u32) -> Result<(), SurfaceError> {
        if (i as usize) < self.home.len() {
            Ok(())
        } else {
            Err(SurfaceError::VertexOutOfRange {
                index: i,
                num_vertices: self.home.len() as u32,
            })
        }
    }
}
