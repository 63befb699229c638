//! [`PairTouchEvent`]: two colliders starting or stopping to touch, as the touch pipeline sees
//! it (rapier's contacts, and the touches the step guard restores).

use crate::touch_diff::TouchDiff;
use rapier3d::geometry::ColliderHandle;

/// Two colliders, at least one of them opted in to the touch pipeline, started or stopped
/// touching at a [`TouchPipeline`](super::TouchPipeline) step. They touch at the end of a step
/// when rapier has an active contact between them (as for its own `CollisionEvent`), or when
/// the pipeline reported the pair ([`PairReport`](super::PairReport): a body the guard walked
/// back to first touch touches, though rapier saw it past or through). Drained with
/// [`TouchPipeline::drain_touch_events`](super::TouchPipeline::drain_touch_events);
/// `collider1 < collider2` (handle order).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum PairTouchEvent {
    /// The pair touches, and did not at the end of the previous step.
    Started {
        /// The first collider (lower handle).
        collider1: ColliderHandle,
        /// The second collider.
        collider2: ColliderHandle,
    },
    /// The pair no longer touches (it separated, or a collider was removed).
    Stopped {
        /// The first collider (lower handle).
        collider1: ColliderHandle,
        /// The second collider.
        collider2: ColliderHandle,
    },
}

impl PairTouchEvent {
    /// The two colliders, lower handle first.
    pub fn pair(&self) -> (ColliderHandle, ColliderHandle) {
        match *self {
            PairTouchEvent::Started {
                collider1,
                collider2,
            }
            | PairTouchEvent::Stopped {
                collider1,
                collider2,
            } => (collider1, collider2),
        }
    }

    /// `true` for [`PairTouchEvent::Started`].
    pub fn started(&self) -> bool {
        matches!(self, PairTouchEvent::Started { .. })
    }
}

/// The touching pairs of the last step and their events.
pub(super) type PairTracker = TouchDiff<(ColliderHandle, ColliderHandle), PairTouchEvent>;

/// The pair `(a, b)` in handle order.
pub(super) fn ordered(a: ColliderHandle, b: ColliderHandle) -> (ColliderHandle, ColliderHandle) {
    if a.into_raw_parts() <= b.into_raw_parts() {
        (a, b)
    } else {
        (b, a)
    }
}

/// Records the pairs touching now, listed in an order kept from step to step.
pub(super) fn update(tracker: &mut PairTracker, now: Vec<(ColliderHandle, ColliderHandle)>) {
    tracker.update_listed(
        now,
        |(a, b)| (a.into_raw_parts(), b.into_raw_parts()),
        |(collider1, collider2)| PairTouchEvent::Stopped {
            collider1,
            collider2,
        },
        |(collider1, collider2)| PairTouchEvent::Started {
            collider1,
            collider2,
        },
    );
}
