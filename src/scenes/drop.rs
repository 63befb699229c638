//! Rigid drops and piles: a box dropped on a floor at a given speed by vanilla rapier, rapier
//! with CCD, or the touch pipeline ([`run_drop_side`]), and boxes resting on a TriMesh floor
//! ([`boxes_on_trimesh_floor`]).

use super::*;

/// The floors of [`drop_world`].
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum DropFloor {
    /// A fixed 10 m × 1 m × 10 m cuboid, top face at `y = 0`.
    Cuboid,
    /// A fixed two-triangle TriMesh of zero thickness at `y = 0`, 10 m square.
    ThinTriMesh,
}

/// Half extent of the box [`drop_world`] drops.
pub const DROP_BOX_HALF: Real = 0.25;

/// A rapier world (dt = 1/60, rapier's CCD off, contact clustering off) with `floor` and a
/// 0.5 m dynamic box 3 m above it falling at `speed` m/s. Every collider opts into the touch
/// hooks. Returns the world and the box.
pub fn drop_world(
    speed: Real,
    floor: DropFloor,
) -> (
    rapier3d::pipeline::PhysicsWorld,
    rapier3d::dynamics::RigidBodyHandle,
) {
    use rapier3d::prelude::*;
    let hooks = ActiveHooks::MODIFY_SOLVER_CONTACTS;
    let mut w = PhysicsWorld::default();
    w.integration_parameters.dt = 1.0 / 60.0;
    w.integration_parameters.max_ccd_substeps = 0;
    w.integration_parameters.contact_clustering = false;
    let floor = match floor {
        DropFloor::Cuboid => {
            ColliderBuilder::cuboid(5.0, 0.5, 5.0).translation(Vector::new(0.0, -0.5, 0.0))
        }
        DropFloor::ThinTriMesh => ColliderBuilder::trimesh(
            vec![
                Vector::new(-5.0, 0.0, -5.0),
                Vector::new(5.0, 0.0, -5.0),
                Vector::new(5.0, 0.0, 5.0),
                Vector::new(-5.0, 0.0, 5.0),
            ],
            vec![[0, 2, 1], [0, 3, 2]],
        )
        .expect("a valid quad"),
    };
    w.insert_collider(floor.active_hooks(hooks), None);
    let b = w.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 3.0, 0.0))
            .linvel(Vector::new(0.0, -speed, 0.0)),
    );
    let h = DROP_BOX_HALF;
    w.insert_collider(
        ColliderBuilder::cuboid(h, h, h).active_hooks(hooks),
        Some(b),
    );
    (w, b)
}

/// How deep a box of half extent `half` at `pose` reaches below `y = 0` (0 when above).
pub fn box_depth_below_floor(pose: &Pose, half: Real) -> Real {
    let mut lowest = Real::MAX;
    for sx in [-half, half] {
        for sy in [-half, half] {
            for sz in [-half, half] {
                lowest = lowest.min(pose.transform_point(Vector::new(sx, sy, sz)).y);
            }
        }
    }
    (-lowest).max(0.0)
}

/// One run of a [`drop_world`]: the box's penetration after every step and the figures the
/// `penetration_compare` example reports.
#[derive(Clone, Debug, PartialEq)]
pub struct DropRun {
    /// How deep the box reaches below `y = 0` after each step (m; 0 above the floor). A box
    /// that went through keeps its depth counted as it falls.
    pub depth: Vec<Real>,
    /// The first step (counted from 1) after which the box's centre was below the floor, if
    /// it went through.
    pub tunneled_at: Option<usize>,
    /// The largest penetration at the steps the box's centre was above the floor (m).
    pub max_penetration: Real,
    /// The penetration after the last step (m; NaN if the box went through).
    pub resting_penetration: Real,
    /// The step from which the box rested to the end (speed below 1 cm/s, centre above the
    /// floor); `None` if it never did or went through.
    pub steps_to_rest: Option<usize>,
    /// Wall-clock time of the whole run (s).
    pub seconds: f64,
}

impl DropRun {
    /// The box went through the floor.
    pub fn tunneled(&self) -> bool {
        self.tunneled_at.is_some()
    }
}

/// Drops the box of [`drop_world`] at `speed` m/s onto `floor` for `steps` steps, stepped by
/// rapier alone (`with_crate == false`: `PhysicsWorld::step`, CCD off) or by
/// [`TouchPipeline::step`](crate::hooks::TouchPipeline::step).
///
/// ```
/// use rapier_touch::scenes::{run_drop, DropFloor};
/// let vanilla = run_drop(100.0, DropFloor::ThinTriMesh, false, 30);
/// let touch = run_drop(100.0, DropFloor::ThinTriMesh, true, 30);
/// assert!(vanilla.tunneled() && !touch.tunneled());
/// assert!(touch.max_penetration < 1e-3);
/// ```
pub fn run_drop(speed: Real, floor: DropFloor, with_crate: bool, steps: usize) -> DropRun {
    let side = if with_crate {
        DropSide::Touch
    } else {
        DropSide::Rapier
    };
    run_drop_side(speed, floor, side, steps)
}

/// Who steps a [`run_drop_side`] world.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum DropSide {
    /// `PhysicsWorld::step`, rapier's CCD off (`max_ccd_substeps = 0`).
    Rapier,
    /// `PhysicsWorld::step` with rapier's default integration parameters: its CCD on
    /// (`max_ccd_substeps = 1`: fast bodies are swept against fixed colliders).
    RapierDefaults,
    /// [`TouchPipeline::step`](crate::hooks::TouchPipeline::step), rapier's CCD off.
    Touch,
}

/// [`run_drop`] with the side named: rapier with its CCD off, rapier with its defaults (CCD
/// on), or the touch pipeline.
pub fn run_drop_side(speed: Real, floor: DropFloor, side: DropSide, steps: usize) -> DropRun {
    let (mut w, b) = drop_world(speed, floor);
    if side == DropSide::RapierDefaults {
        w.integration_parameters.max_ccd_substeps =
            rapier3d::dynamics::IntegrationParameters::default().max_ccd_substeps;
    }
    let with_crate = side == DropSide::Touch;
    let mut touch = crate::hooks::TouchPipeline::default();
    let mut run = DropRecorder::new(steps);
    let t0 = std::time::Instant::now();
    for _ in 0..steps {
        if with_crate {
            touch.step(&mut w);
        } else {
            w.step();
        }
        let body = &w.bodies[b];
        let pose = *body.position();
        run.record(
            box_depth_below_floor(&pose, DROP_BOX_HALF),
            pose.translation.y < 0.0,
            body.linvel().length() < 0.01,
        );
    }
    run.finish(t0.elapsed().as_secs_f64())
}

/// Builds a [`DropRun`] step by step (shared by [`run_drop_side`] and
/// [`run_compare_side`]).
pub(super) struct DropRecorder {
    depth: Vec<Real>,
    tunneled_at: Option<usize>,
    max_penetration: Real,
    rest_since: Option<usize>,
}

impl DropRecorder {
    pub(super) fn new(steps: usize) -> Self {
        Self {
            depth: Vec::with_capacity(steps),
            tunneled_at: None,
            max_penetration: 0.0,
            rest_since: None,
        }
    }

    /// One step: the depth, whether the body was through, whether it was at rest (counted
    /// only above the floor).
    pub(super) fn record(&mut self, depth: Real, through: bool, resting: bool) {
        self.depth.push(depth);
        let step = self.depth.len();
        if through {
            self.tunneled_at.get_or_insert(step);
        } else {
            self.max_penetration = self.max_penetration.max(depth);
        }
        self.rest_since = match (resting && !through, self.rest_since) {
            (true, None) => Some(step),
            (true, s) => s,
            (false, _) => None,
        };
    }

    pub(super) fn finish(self, seconds: f64) -> DropRun {
        let tunneled = self.tunneled_at.is_some();
        DropRun {
            tunneled_at: self.tunneled_at,
            max_penetration: self.max_penetration,
            resting_penetration: if tunneled {
                Real::NAN
            } else {
                self.depth.last().copied().unwrap_or(0.0)
            },
            steps_to_rest: self.rest_since.filter(|_| !tunneled),
            depth: self.depth,
            seconds,
        }
    }
}

/// A rapier world (dt = 1/60, contact clustering off) with `n` dynamic 0.5 m boxes that never
/// sleep, in a square grid 1 m apart just above a fixed 20 m TriMesh floor (32 × 32 quads).
/// With `touch_hooks`, every collider opts into the touch hooks. Used by the `step_overhead`
/// benchmark.
pub fn boxes_on_trimesh_floor(n: usize, touch_hooks: bool) -> rapier3d::pipeline::PhysicsWorld {
    use rapier3d::prelude::*;
    let hooks = if touch_hooks {
        ActiveHooks::MODIFY_SOLVER_CONTACTS
    } else {
        ActiveHooks::empty()
    };
    let mut w = PhysicsWorld::default();
    w.integration_parameters.dt = 1.0 / 60.0;
    w.integration_parameters.contact_clustering = false;
    let q = 32;
    let mut v = Vec::new();
    let mut idx = Vec::new();
    for i in 0..=q {
        for j in 0..=q {
            v.push(Vector::new(
                -10.0 + 20.0 * i as Real / q as Real,
                0.0,
                -10.0 + 20.0 * j as Real / q as Real,
            ));
        }
    }
    for i in 0..q {
        for j in 0..q {
            let a = (i * (q + 1) + j) as u32;
            let b = a + (q + 1) as u32;
            idx.push([a, a + 1, b]);
            idx.push([b, a + 1, b + 1]);
        }
    }
    w.insert_collider(
        ColliderBuilder::trimesh(v, idx)
            .expect("a valid grid")
            .active_hooks(hooks),
        None,
    );
    let side = (n as Real).sqrt().ceil() as usize;
    for k in 0..n {
        let (i, j) = (k / side, k % side);
        let b = w.insert_body(RigidBodyBuilder::dynamic().can_sleep(false).translation(
            Vector::new(
                i as Real - side as Real / 2.0,
                0.26,
                j as Real - side as Real / 2.0,
            ),
        ));
        w.insert_collider(
            ColliderBuilder::cuboid(0.25, 0.25, 0.25).active_hooks(hooks),
            Some(b),
        );
    }
    w
}
