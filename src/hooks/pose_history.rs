//! Where every rigid body was when the step began: the history the hooks and the step guard
//! read a body's motion over the step from.

use crate::math::Pose;
use rapier3d::dynamics::{RigidBodyHandle, RigidBodySet};

/// The bodies' poses at the start of the step, by handle.
///
/// A table indexed by the handle's arena slot (with its generation, so a removed body's slot
/// reused by a new body is not mistaken for it), not a hash map: it is written for every body
/// every step, and filling a hash map was a tenth of the touch pipeline's own time on a
/// sleeping 204-box pyramid.
#[derive(Clone, Debug, Default)]
pub(crate) struct PoseHistory {
    slots: Vec<Option<(u32, Pose)>>,
    len: usize,
}

impl PoseHistory {
    /// Records where every body of `bodies` is now, forgetting what was recorded before.
    pub(crate) fn record(&mut self, bodies: &RigidBodySet) {
        self.slots.clear();
        self.len = 0;
        for (h, b) in bodies.iter() {
            let (index, generation) = h.into_raw_parts();
            let index = index as usize;
            if self.slots.len() <= index {
                self.slots.resize(index + 1, None);
            }
            self.slots[index] = Some((generation, *b.position()));
            self.len += 1;
        }
    }

    /// Where body `h` was when the step began (`None`: it was not in the set then).
    pub(crate) fn get(&self, h: &RigidBodyHandle) -> Option<&Pose> {
        let (index, generation) = h.into_raw_parts();
        match self.slots.get(index as usize)? {
            Some((g, pose)) if *g == generation => Some(pose),
            _ => None,
        }
    }

    /// How many bodies were recorded.
    pub(crate) fn len(&self) -> usize {
        self.len
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vector;
    use rapier3d::dynamics::RigidBodyBuilder;

    #[test]
    fn a_removed_body_has_no_history_and_its_reused_slot_is_the_new_body_s() {
        let mut world = rapier3d::pipeline::PhysicsWorld::default();
        let at = |x: f32| RigidBodyBuilder::dynamic().translation(Vector::new(x, 0.0, 0.0));
        let a = world.insert_body(at(1.0));
        let b = world.insert_body(at(2.0));
        let mut history = PoseHistory::default();
        history.record(&world.bodies);
        assert_eq!(history.len(), 2);
        assert_eq!(history.get(&b).unwrap().translation.x, 2.0);

        world.remove_body(a);
        let c = world.insert_body(at(3.0));
        assert_eq!(
            c.into_raw_parts().0,
            a.into_raw_parts().0,
            "the slot is reused"
        );
        // Not recorded again yet: the new body has no history, the old handle keeps its own.
        assert!(history.get(&c).is_none());
        assert_eq!(history.get(&a).unwrap().translation.x, 1.0);
        history.record(&world.bodies);
        assert!(history.get(&a).is_none());
        assert_eq!(history.get(&c).unwrap().translation.x, 3.0);
        assert_eq!(history.get(&b).unwrap().translation.x, 2.0);
        assert_eq!(history.len(), 2);
    }
}
