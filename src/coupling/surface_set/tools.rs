//! A set's tools: registering and removing them, their friction and grasp, their touch events
//! and reactions.

use super::*;

impl SurfaceSet {
    /// Registers collider `tool` as a tool pressing into every surface of the set.
    ///
    /// Its solver-group filter loses [`SURFACE_SOLVER_GROUP`] (the group of the surfaces'
    /// colliders), so rapier's rigid contact with a surface's collider does not fight the
    /// surface's own response (rapier still reports the pair; it only stops solving it);
    /// [`SurfaceSet::remove_tool`] gives it back. A dynamic tool's body is moved by the
    /// surfaces' impulses in the same step (see the type's docs); no force is added to it.
    ///
    /// Adding a tool twice changes nothing more (a tool registered by
    /// [`SurfaceSet::set_auto_tools`] becomes yours: it stays a tool when it leaves).
    ///
    /// # Errors
    /// [`CouplingError::NoSuchCollider`] when `tool` is not in the world;
    /// [`CouplingError::ZeroSizeTool`] for a shape of no size (a ball of radius zero, a cuboid
    /// of zero half-extents: its bounding box has no extent, or a non-finite one), which could
    /// hold nothing. Nothing changes then.
    pub fn add_tool(
        &mut self,
        tool: ColliderHandle,
        world: &mut PhysicsWorld,
    ) -> Result<(), CouplingError> {
        self.auto.remove(&tool);
        self.add_tool_in(tool, &mut world.colliders)
    }

    /// [`SurfaceSet::add_tool`] on the collider set.
    pub(super) fn add_tool_in(
        &mut self,
        tool: ColliderHandle,
        colliders: &mut ColliderSet,
    ) -> Result<(), CouplingError> {
        if self.tools.contains_key(&tool) {
            return Ok(());
        }
        let c = colliders
            .get_mut(tool)
            .ok_or(CouplingError::NoSuchCollider)?;
        let extent = c.shape().compute_local_aabb().extents().max_element();
        if !(extent > 0.0 && extent.is_finite()) {
            return Err(CouplingError::ZeroSizeTool);
        }
        let shape = Arc::new(ToolShape::of(c.shape()));
        let g = c.solver_groups();
        let had_surface_group = g.filter.contains(SURFACE_SOLVER_GROUP);
        c.set_solver_groups(InteractionGroups::new(
            g.memberships,
            g.filter & !SURFACE_SOLVER_GROUP,
            g.test_mode,
        ));
        self.tools.insert(
            tool,
            ToolState {
                prev: None,
                seen_on_body: None,
                reaction: ToolReaction::default(),
                haptic_prev: None,
                had_surface_group,
                shape,
                friction: Friction::NONE,
                grasp: false,
                held: Vec::new(),
                feed: (Vector::ZERO, Vector::ZERO),
            },
        );
        Ok(())
    }

    /// Stops treating `tool` as a tool: the vertices it held are released, and its
    /// solver-group filter gets
    /// [`SURFACE_SOLVER_GROUP`] back if it had it before [`SurfaceSet::add_tool`] (so rapier
    /// solves its contacts with the surfaces' colliders again). A tool whose collider left the
    /// world is simply forgotten.
    pub fn remove_tool(&mut self, tool: ColliderHandle, world: &mut PhysicsWorld) {
        self.remove_tool_in(tool, &mut world.colliders);
    }

    /// [`SurfaceSet::remove_tool`] on the collider set.
    pub(super) fn remove_tool_in(&mut self, tool: ColliderHandle, colliders: &mut ColliderSet) {
        self.auto.remove(&tool);
        let Some(state) = self.tools.remove(&tool) else {
            return;
        };
        self.links.remove(&tool);
        for s in self.entries.iter_mut().filter_map(|e| e.1.as_mut()) {
            s.sticks.retain(|_, st| st.0 != tool);
            s.pair_friction.remove(&tool);
        }
        let Some(c) = colliders.get_mut(tool) else {
            return;
        };
        if state.had_surface_group {
            let g = c.solver_groups();
            c.set_solver_groups(InteractionGroups::new(
                g.memberships,
                g.filter | SURFACE_SOLVER_GROUP,
                g.test_mode,
            ));
        }
    }

    /// The tools that started or stopped touching a surface, step by step, since the last
    /// drain (oldest first): a tool touches a surface while it holds at least one of its
    /// vertices at the end of a [`SurfaceSet::step`]. [`SurfaceSet::haptic_step`] does not
    /// record events; a removed tool or surface gets its `Stopped` at the next step.
    ///
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    /// use rapier_touch::surface::meshing::{plate, plate_rim};
    ///
    /// let mut world = PhysicsWorld { gravity: Vector::ZERO, ..Default::default() };
    /// let fixed = world.insert_body(RigidBodyBuilder::fixed());
    /// let surface = MassSpringSurfaceBuilder::from_mesh(&plate(0.4, 0.4, 4, 4))
    ///     .pinned(plate_rim(4, 4))
    ///     .build()
    ///     .unwrap();
    /// let mut set = SurfaceSet::new();
    /// let plate = set.insert(surface, fixed, &mut world, AttachOptions::default()).unwrap();
    /// let ball = world.insert_body(
    ///     RigidBodyBuilder::kinematic_velocity_based().translation(Vector::new(0.0, 0.1, 0.0)),
    /// );
    /// let tool = world.insert_collider(ColliderBuilder::ball(0.05), Some(ball));
    /// set.add_tool(tool, &mut world).unwrap();
    /// // Down through the plate's plane for half a second, then back up.
    /// world.bodies[ball].set_linvel(Vector::new(0.0, -0.15, 0.0), true);
    /// for _ in 0..30 {
    ///     set.step(&mut world);
    /// }
    /// world.bodies[ball].set_linvel(Vector::new(0.0, 0.3, 0.0), true);
    /// for _ in 0..30 {
    ///     set.step(&mut world);
    /// }
    /// let events: Vec<ToolTouchEvent> = set.drain_touch_events().collect();
    /// assert_eq!(
    ///     events,
    ///     [
    ///         ToolTouchEvent::Started { tool, surface: plate },
    ///         ToolTouchEvent::Stopped { tool, surface: plate },
    ///     ]
    /// );
    /// assert_eq!(set.drain_touch_events().count(), 0);
    /// ```
    pub fn drain_touch_events(&mut self) -> impl Iterator<Item = ToolTouchEvent> + '_ {
        self.touch.drain()
    }

    /// Sets the Coulomb friction of registered tool `tool` on every surface (that has no
    /// friction of its own for it, [`SurfaceSet::set_pair_friction`]). Tools start
    /// frictionless. Friction acts where the tool holds surface vertices (see
    /// [`super::Friction`]) and at the points a polyhedral tool presses between vertices
    /// (solved with the surface's constraints, [`crate::surface::Tangential::Coulomb`]).
    ///
    /// # Errors
    /// [`CouplingError::NoSuchCollider`] when `tool` is not a registered tool,
    /// [`CouplingError::InvalidFriction`] for bad coefficients; nothing changes then.
    pub fn set_tool_friction(
        &mut self,
        tool: ColliderHandle,
        friction: Friction,
    ) -> Result<(), CouplingError> {
        friction.check()?;
        let t = self
            .tools
            .get_mut(&tool)
            .ok_or(CouplingError::NoSuchCollider)?;
        t.friction = friction;
        Ok(())
    }

    /// Sets the friction of registered tool `tool` on surface `surface` only, in place of the
    /// tool's own ([`SurfaceSet::set_tool_friction`]).
    ///
    /// # Errors
    /// [`CouplingError::NoSuchSurface`] for a removed surface, [`CouplingError::NoSuchCollider`]
    /// when `tool` is not a registered tool, [`CouplingError::InvalidFriction`].
    pub fn set_pair_friction(
        &mut self,
        surface: SurfaceHandle,
        tool: ColliderHandle,
        friction: Friction,
    ) -> Result<(), CouplingError> {
        friction.check()?;
        if !self.tools.contains_key(&tool) {
            return Err(CouplingError::NoSuchCollider);
        }
        let s = self.get_mut(surface).ok_or(CouplingError::NoSuchSurface)?;
        s.pair_friction.insert(tool, friction);
        Ok(())
    }

    /// Makes registered tool `tool` grasp (`true`) or let go (`false`). While it grasps, every
    /// surface vertex it holds, or comes to hold, sticks to its material point whether the
    /// surface pushes or pulls it (a bilateral contact): lifting the tool lifts a fold of the
    /// surface, and the tool's reaction includes the springs' pull. Let go, the vertices the
    /// springs pull off the tool are released at the next substep. A kinematic tool (or one with
    /// no body) carries what it grasps; a dynamic tool is not chased by the vertices. A
    /// polyhedral tool also grasps the points it presses between the surface's vertices (a
    /// corner in a triangle, an edge across an edge): each is held, in every direction, on the
    /// tool's material point it touched until the tool lets go (one grasped point per set of
    /// surface vertices: two on the same vertices would fight).
    ///
    /// # Example
    /// A ball pressed 1 cm into a clamped plate, made to grasp, and lifted 3 cm: it pulls the
    /// plate's centre up with it and feels the springs pull it down.
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    /// use rapier_touch::surface::meshing::{plate, plate_rim};
    ///
    /// let mut world = PhysicsWorld { gravity: Vector::ZERO, ..Default::default() };
    /// let fixed = world.insert_body(RigidBodyBuilder::fixed());
    /// let surface = MassSpringSurfaceBuilder::from_mesh(&plate(0.4, 0.4, 4, 4))
    ///     .pinned(plate_rim(4, 4))
    ///     .build()
    ///     .unwrap();
    /// let mut set = SurfaceSet::new();
    /// let options = AttachOptions { substeps: 4, collider: true };
    /// let plate = set.insert(surface, fixed, &mut world, options).unwrap();
    /// let ball = world.insert_body(
    ///     RigidBodyBuilder::kinematic_position_based().translation(Vector::new(0.0, 0.05, 0.0)),
    /// );
    /// let tool = world.insert_collider(ColliderBuilder::ball(0.02), Some(ball));
    /// set.add_tool(tool, &mut world).unwrap();
    /// let mut go = |world: &mut PhysicsWorld, set: &mut SurfaceSet, y: f32| {
    ///     for _ in 0..30 {
    ///         world.bodies[ball].set_next_kinematic_translation(Vector::new(0.0, y, 0.0));
    ///         set.step(world);
    ///     }
    /// };
    /// go(&mut world, &mut set, 0.01); // its bottom 1 cm into the plate
    /// set.set_grasp(tool, true).unwrap();
    /// go(&mut world, &mut set, 0.05); // lifted: its bottom 3 cm above the plate
    /// assert!(set.get(plate).unwrap().surface.displacement(12).y > 0.029);
    /// assert!(set.tool_reaction(tool).unwrap().force.y < 0.0); // pulled down
    /// set.set_grasp(tool, false).unwrap();
    /// go(&mut world, &mut set, 0.05);
    /// assert_eq!(set.tool_reaction(tool).unwrap().held_vertices, 0); // let go
    /// ```
    ///
    /// # Errors
    /// [`CouplingError::NoSuchCollider`] when `tool` is not a registered tool.
    pub fn set_grasp(&mut self, tool: ColliderHandle, grasp: bool) -> Result<(), CouplingError> {
        let t = self
            .tools
            .get_mut(&tool)
            .ok_or(CouplingError::NoSuchCollider)?;
        t.grasp = grasp;
        Ok(())
    }

    /// Whether `tool` grasps ([`SurfaceSet::set_grasp`]).
    pub fn is_grasping(&self, tool: ColliderHandle) -> bool {
        self.tools.get(&tool).is_some_and(|t| t.grasp)
    }

    /// The friction of `tool` on `surface`: the pair's own, else the tool's
    /// ([`Friction::NONE`] for an unknown tool).
    pub fn friction(&self, surface: SurfaceHandle, tool: ColliderHandle) -> Friction {
        self.get(surface)
            .and_then(|s| s.pair_friction.get(&tool).copied())
            .or_else(|| self.tools.get(&tool).map(|t| t.friction))
            .unwrap_or(Friction::NONE)
    }

    /// The reaction on `tool` after the last step.
    pub fn tool_reaction(&self, tool: ColliderHandle) -> Option<ToolReaction> {
        self.tools.get(&tool).map(|t| t.reaction)
    }
}
