//! [`ToolTouchEvent`]: a tool starting or stopping to touch a surface, as rapier's
//! `CollisionEvent` reports colliders starting or stopping to touch.

use super::surface_set::SurfaceHandle;
use crate::touch_diff::TouchDiff;
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

/// The tool-surface pairs touching at the end of the last step, and their events.
pub(super) type TouchTracker = TouchDiff<(ColliderHandle, SurfaceHandle), ToolTouchEvent>;

/// Records the tool-surface pairs touching now ([`TouchDiff::update`], by tool then surface).
pub(super) fn update(tracker: &mut TouchTracker, now: HashSet<(ColliderHandle, SurfaceHandle)>) {
    tracker.update(
        now,
        |(t, s)| (t.into_raw_parts(), s.raw()),
        |(tool, surface)| ToolTouchEvent::Stopped { tool, surface },
        |(tool, surface)| ToolTouchEvent::Started { tool, surface },
    );
}
