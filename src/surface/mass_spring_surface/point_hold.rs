//! The state a filtered step's constraint solve keeps: the points held between the surface's
//! vertices ([`PointHold`]) and what the solve remembers from one step to the next
//! ([`ActiveMemory`]: which rows pushed, how the points with friction ended).

use super::active_set::Scratch;
use super::rigid_holder::HolderState;
use glamx::DVec3;
use parry3d::utils::hashmap::HashMap;
use parry3d::utils::hashset::HashSet;

/// A point of the surface, `Σ wⱼ xⱼ` over up to three vertices, pressed along a normal by
/// something outside it (see [`MassSpringSurface::press_point`]).
#[derive(Copy, Clone, Debug)]
pub(crate) struct PointHold {
    pub(super) vertices: [u32; 3],
    pub(super) weights: [f64; 3],
    pub(super) count: usize,
    /// Unit direction the holder pushes the point in.
    pub(super) normal: DVec3,
    /// The impulse (N·s, along `normal`) the holder gave: the press's velocity change, plus the
    /// constraint impulse of the step after it.
    pub(super) impulse: f64,
    /// The least velocity along `normal` the point may have after the step: the holder's for
    /// a point in contact; less by `gap / dt` for a point `gap` short of its holder (it may
    /// close the gap, not pass the holder).
    pub(super) min_velocity: f64,
    /// The velocity the point keeps along its tangent plane through the step while it pushes
    /// (its holder carries it: static friction), or `None` (it slides freely).
    pub(super) carried: Option<DVec3>,
    /// The static and dynamic friction coefficients that bound the carrying impulse (`None`:
    /// carried whatever it takes, a grasp, with a bilateral normal).
    pub(super) cone: Option<(f64, f64)>,
    /// The impulse (N·s, in the tangent plane) the holder gave carrying it.
    pub(super) tangent_impulse: DVec3,
    /// The momentum its press and the step's impulses gave the vertices that moved with it
    /// ([`MassSpringSurface::point_momentum`]).
    pub(super) momentum: DVec3,
    /// The weight on vertices held when it was pressed: their holders keep them where they
    /// are, so that share of its impulses goes into them, not into the surface.
    pub(super) held_share: f64,
    /// The part of the step's impulses on the vertices a sliding hold holds (their share of
    /// this point's rows, where the row moves them) across that hold's normal. Their holds
    /// take only the part along it, and the tool's force reads their springs along it
    /// ([`MassSpringSurface::point_held_across`]): this part is the point's.
    pub(super) held_across: DVec3,
    /// Its rigid holder ([`super::rigid_holder`]), and the holder's point that presses (from
    /// the holder's centre once pressed; where it was given until then). With a holder, `min_velocity` and `carried` are relative to
    /// the holder's velocity at that point, which the solve takes after the step.
    pub(super) holder: Option<(usize, DVec3)>,
}

impl PointHold {
    /// The hold's key across steps: the surface vertices it loads, sorted.
    pub(super) fn key(&self) -> [u32; 3] {
        let mut v = self.vertices;
        v[self.count.min(3)..]
            .iter_mut()
            .for_each(|x| *x = u32::MAX);
        v.sort_unstable();
        v
    }

    /// Held in every direction, pulled as well as pushed.
    pub(super) fn grasped(&self) -> bool {
        self.carried.is_some() && self.cone.is_none()
    }

    /// The least velocity along its normal after the step, before the holder's own change.
    pub(super) fn normal_target(&self, holders: &[HolderState]) -> f64 {
        self.min_velocity + self.holder_velocity(holders).dot(self.normal)
    }

    /// The velocity it is carried with (static friction, grasp), before the holder's change.
    pub(super) fn carried_target(&self, holders: &[HolderState]) -> Option<DVec3> {
        self.carried.map(|v| v + self.holder_velocity(holders))
    }

    /// Its holder's velocity at the point (zero without a rigid holder).
    fn holder_velocity(&self, holders: &[HolderState]) -> DVec3 {
        self.holder
            .and_then(|(k, arm)| holders.get(k).map(|h| h.velocity_at(arm)))
            .unwrap_or(DVec3::ZERO)
    }

    pub(super) fn entries(&self) -> impl Iterator<Item = (u32, f64)> + '_ {
        self.vertices[..self.count]
            .iter()
            .copied()
            .zip(self.weights[..self.count].iter().copied())
    }
}

/// Which push-only rows of the filtered step's constraint solve pushed at its end, by key
/// ([`PointHold::key`]): the next step's solve starts from them, so a contact that persists
/// costs fewer active-set passes (six cubes on a plate, about 110 rows of which 40 push: from
/// 5-10 passes to mostly 2-5; `cargo bench --bench coupled_step` 0.70 → 0.44 ms). A row not
/// seen last time starts in if it asks for a push.
#[derive(Clone, Debug, Default)]
pub(crate) struct ActiveMemory {
    pub(super) seen: HashSet<[u32; 3]>,
    pub(super) pushing: HashSet<[u32; 3]>,
    /// How the points with friction ended the step: the next step's solve starts from it.
    pub(super) friction: HashMap<[u32; 3], Remembered>,
    /// The solves' dense storage, reused.
    pub(super) scratch: Scratch,
}

impl ActiveMemory {
    pub(super) fn starts_in(&self, key: [u32; 3], b: f64) -> bool {
        if self.seen.contains(&key) {
            self.pushing.contains(&key)
        } else {
            b > 0.0
        }
    }
}

/// How a point with friction ended a step (see [`ActiveMemory`]).
#[derive(Copy, Clone, Debug)]
pub(super) enum Remembered {
    Stuck,
    /// Sliding with its tangential impulse along `direction` (unit, world) and that normal
    /// impulse.
    Sliding {
        direction: DVec3,
        load: f64,
    },
}
