//! Mouse-driven tools.

use super::*;

/// A see-through ghost: a dynamic, collision-free body the testbed's mouse grab can move (it
/// only grabs dynamic bodies). The kinematic tool it leads follows it.
pub(crate) struct Ghost {
    pub(crate) body: RigidBodyHandle,
    pub(crate) collider: ColliderHandle,
    /// Grabbed once: the tool left its script and follows its ghost.
    pub(crate) manual: bool,
}

impl Ghost {
    /// A ghost for a tool of `shape` at `pose` (slightly larger than the tool).
    pub(crate) fn insert(world: &mut PhysicsWorld, shape: &SharedShape, pose: Pose) -> Self {
        let body = world.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(pose)
                .gravity_scale(0.0)
                .linear_damping(10.0)
                .lock_rotations()
                .additional_mass(0.1),
        );
        let collider = world.insert_collider(
            ColliderBuilder::new(ghost_shape(shape))
                .density(0.0)
                .collision_groups(InteractionGroups::none()),
            Some(body),
        );
        Self {
            body,
            collider,
            manual: false,
        }
    }

    /// Whether the mouse holds the ghost (the testbed ties it to the cursor with a joint).
    pub(crate) fn grabbed(&self, world: &PhysicsWorld) -> bool {
        world
            .impulse_joints
            .attached_joints(self.body)
            .next()
            .is_some()
    }

    /// The ghost's position: where the mouse wants the tool.
    pub(crate) fn device(&self, world: &PhysicsWorld) -> Pose {
        *world.bodies[self.body].position()
    }

    /// Where the tool goes: the script (`Some(target)`, the ghost is moved there) until the
    /// ghost is first grabbed, then the ghost.
    pub(crate) fn lead(&mut self, world: &mut PhysicsWorld, scripted: Option<Vector>) -> Vector {
        if self.grabbed(world) {
            self.manual = true;
        }
        match scripted {
            Some(at) if !self.manual => {
                let ghost = &mut world.bodies[self.body];
                ghost.set_translation(at, true);
                ghost.set_linvel(Vector::ZERO, true);
                at
            }
            _ => self.device(world).translation,
        }
    }
}

/// A kinematic tool and its ghost.
pub(crate) struct Tool {
    pub(crate) body: RigidBodyHandle,
    pub(crate) collider: ColliderHandle,
    pub(crate) ghost: Ghost,
}

impl Tool {
    pub(crate) fn insert(world: &mut PhysicsWorld, tool: ColliderBuilder, pose: Pose) -> Self {
        let shape = tool.shape.clone();
        let body = world.insert_body(RigidBodyBuilder::kinematic_position_based().pose(pose));
        let collider = world.insert_collider(tool, Some(body));
        let ghost = Ghost::insert(world, &shape, pose);
        Self {
            body,
            collider,
            ghost,
        }
    }

    /// Steel tool, see-through ghost.
    pub(crate) fn colors(&self, viewer: &mut TestbedViewer) {
        tool_colors(viewer, self.collider, &self.ghost);
    }

    /// Follows the script (`Some(target)`) until first grabbed, then the ghost.
    pub(crate) fn drive(&mut self, world: &mut PhysicsWorld, scripted: Option<Vector>) {
        let target = self.ghost.lead(world, scripted);
        world.bodies[self.body].set_next_kinematic_translation(target);
    }
}

pub(crate) fn tool_colors(viewer: &mut TestbedViewer, tool: ColliderHandle, ghost: &Ghost) {
    viewer.set_initial_collider_color(tool, STEEL);
    viewer.set_initial_collider_color(ghost.collider, GHOST);
}

/// A slightly larger copy of a tool's shape for its ghost.
pub(crate) fn ghost_shape(shape: &SharedShape) -> SharedShape {
    const GROW: Real = 1.2;
    if let Some(b) = shape.as_ball() {
        return SharedShape::ball(b.radius * GROW);
    }
    if let Some(c) = shape.as_cuboid() {
        let h = c.half_extents * GROW;
        return SharedShape::cuboid(h.x, h.y, h.z);
    }
    if let Some(m) = shape.as_trimesh() {
        let centre = m.local_aabb().center();
        let v: Vec<Vector> = m
            .vertices()
            .iter()
            .map(|p| centre + (*p - centre) * 1.05)
            .collect();
        if let Ok(s) = SharedShape::trimesh(v, m.indices().to_vec()) {
            return s;
        }
    }
    SharedShape::ball(shape.compute_local_bounding_sphere().radius * GROW)
}

pub(crate) fn mesh_collider(mesh: &TouchMesh) -> ColliderBuilder {
    ColliderBuilder::trimesh(mesh.vertices().to_vec(), mesh.indices().to_vec())
        .expect("a touch mesh is a valid TriMesh")
}
