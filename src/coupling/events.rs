//! [`ToolTouchEvent`]: a tool starting or stopping to touch a surface, as rapier's
//! `CollisionEvent` reports colliders starting or stopping to touch.

use super::surface_set::SurfaceHandle;
use parry3d::utils::hashset::HashSet;
use rapier3d::geometry::ColliderHandle;

/// A tool started or stopped touching a surface of a [`SurfaceSet`](super::SurfaceSet): holding
/// at least one of its vertices at the end of a [`SurfaceSet::step`](super::SurfaceSet::step).
/// Drained with [`SurfaceSet::drain_touch_events`](super::SurfaceSet::drain_touch_events).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum ToolTouchEvent {
    /// `tool` holds vertices of `surface`, and did not at the end of the previous step.
    Started {
        /// The tool's collider.
        tool: ColliderHandle,
        /// The surface it touches.
        surface: SurfaceHandle,
    },
    /// `tool` no longer holds any vertex of `surface` (it left, it was removed with
    /// [`SurfaceSet::remove_tool`](super::SurfaceSet::remove_tool), or the surface was removed).
    Stopped {
        /// The tool's collider.
        tool: ColliderHandle,
        /// The surface it touched.
        surface: SurfaceHandle,
    },
}

impl ToolTouchEvent {
    /// The tool and the surface of the event.
    pub fn pair(&self) -> (ColliderHandle, SurfaceHandle) {
        match *self {
            ToolTouchEvent::Started { tool, surface }
            | ToolTouchEvent::Stopped { tool, surface } => (tool, surface),
        }
    }

    /// `true` for [`ToolTouchEvent::Started`].
    pub fn started(&self) -> bool {
        matches!(self, ToolTouchEvent::Started { .. })
    }
}

/// The pairs touching at the end of the last step, and the events not drained yet.
#[derive(Clone, Debug, Default)]
pub(super) struct TouchTracker {
    touching: HashSet<(ColliderHandle, SurfaceHandle)>,
    events: Vec<ToolTouchEvent>,
}

impl TouchTracker {
    /// Compares the pairs touching now with those of the last step, and records the changes
    /// (in a deterministic order: by tool, then by surface).
    pub(super) fn update(&mut self, now: HashSet<(ColliderHandle, SurfaceHandle)>) {
        let key = |(t, s): &(ColliderHandle, SurfaceHandle)| (t.into_raw_parts(), s.raw());
        let mut started: Vec<_> = now.difference(&self.touching).copied().collect();
        let mut stopped: Vec<_> = self.touching.difference(&now).copied().collect();
        started.sort_unstable_by_key(key);
        stopped.sort_unstable_by_key(key);
        self.events.extend(
            stopped
                .into_iter()
                .map(|(tool, surface)| ToolTouchEvent::Stopped { tool, surface }),
        );
        self.events.extend(
            started
                .into_iter()
                .map(|(tool, surface)| ToolTouchEvent::Started { tool, surface }),
        );
        self.touching = now;
    }

    /// The events since the last drain, oldest first.
    pub(super) fn drain(&mut self) -> std::vec::Drain<'_, ToolTouchEvent> {
        self.events.drain(..)
    }
}
