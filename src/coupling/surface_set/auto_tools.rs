//! Any body as a tool: surfaces that treat every dynamic body coming at them as a tool, with
//! no registration ([`SurfaceSet::set_auto_tools`]).

use super::*;
use crate::hooks::pair_filter::rapier_solves_pair;
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::dynamics::{ImpulseJointSet, MultibodyJointSet, RigidBodySet};
use rapier3d::pipeline::PhysicsHooks;

impl SurfaceSet {
    /// Makes surface `h` treat every dynamic body that comes at its collider as a tool (`on`),
    /// or only the tools you register ([`SurfaceSet::add_tool`], the default).
    ///
    /// Before each rigid step ([`SurfaceSet::step`]), a collider of an awake dynamic body whose
    /// bounds over the coming step (its pose now and where its velocity takes it) meet the
    /// surface's collider's becomes a tool, as [`SurfaceSet::add_tool`] would make it: rapier
    /// stops solving its contact with the surfaces' colliders, and the surfaces press it
    /// instead, coupled implicitly (a dropped box dents the surface). rapier's rules for the
    /// pair are kept, asked as the step guard asks them: a sensor, a disabled collider, one
    /// whose collision groups leave the surface's collider out, one whose
    /// `ActiveCollisionTypes` and the surface collider's both leave its pair out, one on a
    /// joint with contacts disabled to the surface's body, or one whose solver groups leave
    /// out [`SURFACE_SOLVER_GROUP`] (no rigid response wanted from surfaces) is not taken;
    /// nor, when the surfaces are stepped through
    /// [`crate::hooks::TouchPipeline::step_with_surfaces`], is a pair the pipeline's user
    /// hooks refuse in `PhysicsHooks::filter_contact_pair` ([`SurfaceSet::step`] has no user
    /// hooks; the bevy plugin does not ask bevy_rapier's). A tool taken this way is given back
    /// (as [`SurfaceSet::remove_tool`]) once its bounds are clear of every such surface and it
    /// touches none; one you register yourself is yours.
    ///
    /// # Errors
    /// [`CouplingError::NoSuchSurface`]; [`CouplingError::NoCollider`] for a surface attached
    /// without a collider (`AttachOptions::collider`: nothing of it is in rapier's world to
    /// come at).
    ///
    /// # Example
    /// A box dropped on a plate, never registered, dents it and is carried by it:
    /// ```
    /// use rapier_touch::prelude::*;
    /// use rapier_touch::rapier3d::prelude::*;
    /// use rapier_touch::surface::meshing::{plate, plate_rim};
    ///
    /// let mut world = PhysicsWorld::default();
    /// let fixed = world.insert_body(RigidBodyBuilder::fixed());
    /// let surface = MassSpringSurfaceBuilder::from_mesh(&plate(1.0, 1.0, 10, 10))
    ///     .stiffness(200.0)
    ///     .damping(5.0)
    ///     .pinned(plate_rim(10, 10))
    ///     .build()
    ///     .unwrap();
    /// let mut set = SurfaceSet::new();
    /// let options = AttachOptions { substeps: 4, collider: true };
    /// let plate = set.insert(surface, fixed, &mut world, options).unwrap();
    /// set.set_auto_tools(plate, true).unwrap();
    /// let body = world.insert_body(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 0.3, 0.0)));
    /// let cube = world.insert_collider(ColliderBuilder::cuboid(0.1, 0.1, 0.1).density(100.0), Some(body));
    /// for _ in 0..120 {
    ///     set.step(&mut world);
    /// }
    /// let weight = world.bodies[body].mass() * 9.81;
    /// let reaction = set.tool_reaction(cube).unwrap();
    /// assert!((reaction.mean_force.y - weight).abs() < 0.05 * weight);
    /// assert!(set.get(plate).unwrap().surface.max_displacement() > 1e-3);
    /// ```
    pub fn set_auto_tools(&mut self, h: SurfaceHandle, on: bool) -> Result<(), CouplingError> {
        let s = self.get_mut(h).ok_or(CouplingError::NoSuchSurface)?;
        if on && s.collider.is_none() {
            return Err(CouplingError::NoCollider);
        }
        s.auto_tools = on;
        Ok(())
    }

    /// Takes the dynamic bodies coming at the surfaces of [`SurfaceSet::set_auto_tools`] as
    /// tools, and gives back those it took that are clear of them (before a rigid step of
    /// `dt`; for engines that own the step, with [`SurfaceSet::step_with`]'s other parts).
    ///
    /// Whether rapier would solve a body's contact with a surface's collider is asked as the
    /// step guard asks it (`crate::hooks::pair_filter::rapier_solves_pair`: sensors, disabled
    /// colliders, joints with contacts disabled, `ActiveCollisionTypes`, collision and solver
    /// groups, and `hooks`' `filter_contact_pair`), for the bodies not yet taken; one taken
    /// stays near while its bounds meet the surface's and its collision groups allow the pair
    /// (its solver groups are the crate's while it is a tool).
    pub(crate) fn take_coming_tools(
        &mut self,
        bodies: &RigidBodySet,
        colliders: &mut ColliderSet,
        joints: (&ImpulseJointSet, &MultibodyJointSet),
        hooks: &dyn PhysicsHooks,
        dt: Real,
    ) {
        let surfaces: Vec<(Aabb, ColliderHandle)> = self
            .entries
            .iter()
            .filter_map(|e| e.1.as_ref())
            .filter(|s| s.auto_tools)
            .filter_map(|s| {
                let handle = s.collider?;
                let aabb = colliders.get(handle)?.compute_aabb();
                let margin = 1e-3 * aabb.extents().max_element();
                Some((aabb.loosened(margin), handle))
            })
            .collect();
        if surfaces.is_empty() && self.auto.is_empty() {
            return;
        }
        let mut near: HashSet<ColliderHandle> = HashSet::default();
        for (_, b) in bodies.iter() {
            if !b.is_dynamic() || b.is_sleeping() {
                continue;
            }
            let next = b.predict_position_using_velocity_and_forces(dt);
            for &ch in b.colliders() {
                let Some(c) = colliders.get(ch) else {
                    continue;
                };
                if c.is_sensor() || !c.is_enabled() {
                    continue;
                }
                let Some(local) = c.position_wrt_parent() else {
                    continue;
                };
                let swept = c
                    .compute_aabb()
                    .merged(&c.shape().compute_aabb(&(next * *local)));
                let taken = self.tools.contains_key(&ch);
                let meets = surfaces.iter().any(|&(aabb, surface)| {
                    aabb.intersects(&swept)
                        && if taken {
                            colliders
                                .get(surface)
                                .is_some_and(|s| c.collision_groups().test(s.collision_groups()))
                        } else {
                            rapier_solves_pair(bodies, colliders, joints, hooks, surface, ch, false)
                        }
                });
                if meets {
                    near.insert(ch);
                }
            }
        }
        // Given back: taken ones clear of every surface (and touching none), or gone.
        let leaving: Vec<ColliderHandle> =
            self.auto
                .iter()
                .copied()
                .filter(|h| {
                    !near.contains(h)
                        && self.tools.get(h).is_none_or(|t| {
                            t.reaction.held_vertices + t.reaction.pressed_points == 0
                        })
                })
                .collect();
        for h in leaving {
            self.remove_tool_in(h, colliders);
        }
        for h in near {
            if self.tools.contains_key(&h) {
                continue;
            }
            // A body that wants no rigid response from the surfaces keeps it that way.
            let wants = colliders
                .get(h)
                .is_some_and(|c| c.solver_groups().filter.contains(SURFACE_SOLVER_GROUP));
            if wants && self.add_tool_in(h, colliders).is_ok() {
                self.auto.insert(h);
            }
        }
    }
}
