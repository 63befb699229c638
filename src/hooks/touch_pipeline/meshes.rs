//! The touch meshes of the opted-in colliders: built when a collider opts in or changes its
//! shape, shared between colliders of one shape, dropped when it leaves.

use super::*;

impl<H: PhysicsHooks> TouchPipeline<H> {
    /// Builds (or drops) the touch meshes of opted-in colliders.
    pub(super) fn refresh_meshes(&mut self, colliders: &ColliderSet) {
        self.tracked.retain(|h| colliders.contains(*h));
        self.hooked.retain(|h| colliders.contains(*h));
        if self.options.hook_flags_on_demand {
            for (h, co) in colliders.iter() {
                if co
                    .active_hooks()
                    .contains(ActiveHooks::MODIFY_SOLVER_CONTACTS)
                {
                    self.hooked.insert(h);
                }
            }
        }
        let (tracked, hooked) = (&self.tracked, &self.hooked);
        let opted_in = |h: &ColliderHandle, co: &rapier3d::geometry::Collider| {
            co.active_hooks()
                .contains(ActiveHooks::MODIFY_SOLVER_CONTACTS)
                || tracked.contains(h)
                || hooked.contains(h)
        };
        self.refused
            .retain(|h, _| colliders.get(*h).is_some_and(|co| opted_in(h, co)));
        let meshes = &mut self.hooks.meshes;
        meshes.retain(|h, _| colliders.contains(*h));
        // Colliders sharing one shape (rapier's `SharedShape` is an `Arc`) share one mesh;
        // equal primitives in separate `Arc`s share one mesh too. Indexed only once a collider
        // needs a mesh (most steps none does).
        let mut index: Option<MeshIndex> = None;
        for (h, co) in colliders.iter() {
            if !opted_in(&h, co) {
                meshes.remove(&h);
                continue;
            }
            let ptr = Arc::as_ptr(&co.shared_shape().0) as *const u8 as usize;
            if meshes.get(&h).is_some_and(|m| m.shape_ptr == ptr)
                || self.refused.get(&h).is_some_and(|r| r.0 == ptr)
            {
                continue;
            }
            let (by_shape, by_key) = index.get_or_insert_with(|| {
                (
                    meshes
                        .values()
                        .map(|m| (m.shape_ptr, m.mesh.clone()))
                        .collect(),
                    meshes
                        .values()
                        .filter_map(|m| Some((m.key.clone()?, m.mesh.clone())))
                        .collect(),
                )
            });
            let key = shape_key(co.shape());
            let built = match by_shape
                .get(&ptr)
                .or_else(|| key.as_ref().and_then(|k| by_key.get(k)))
            {
                Some(mesh) => Ok(mesh.clone()),
                None => TouchMesh::from_shape(co.shape()).map(Arc::new),
            };
            match built {
                Ok(mesh) => {
                    self.refused.remove(&h);
                    by_shape.insert(ptr, mesh.clone());
                    if let Some(k) = &key {
                        by_key.insert(k.clone(), mesh.clone());
                    }
                    meshes.insert(
                        h,
                        CachedMesh {
                            shape_ptr: ptr,
                            mesh,
                            exact: meshed_exactly(co.shape()),
                            key,
                            reach: shape_reach(co.shape()),
                        },
                    );
                }
                Err(e) => {
                    meshes.remove(&h);
                    self.refused.insert(h, (ptr, e));
                }
            }
        }
    }
}

/// The touch meshes built so far, by shape address and by primitive key (sharing).
type MeshIndex = (
    HashMap<usize, Arc<TouchMesh>>,
    HashMap<ShapeKey, Arc<TouchMesh>>,
);
