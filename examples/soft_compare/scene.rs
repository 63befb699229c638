//! The scene both engines run: the plate, the tools' paths and the tracker of what a run
//! measures.

use super::*;

/// The plate mesh and its pinned rim.
pub(crate) struct Plate {
    pub(crate) mesh: SurfaceMesh,
    pub(crate) rim: Vec<u32>,
}

impl Plate {
    pub(crate) fn new(cells: u32) -> Self {
        let mesh = plate(SIZE, SIZE, cells, cells);
        let rim = plate_rim(cells, cells);
        Self { mesh, rim }
    }

    pub(crate) fn nodes(&self) -> usize {
        self.mesh.num_vertices()
    }

    /// Mass of one vertex (kg).
    pub(crate) fn vertex_mass(&self) -> Real {
        TOTAL_MASS / self.nodes() as Real
    }

    /// The crate's surface on this plate.
    pub(crate) fn surface(&self, dt: Real, integrator: Integrator) -> MassSpringSurface {
        MassSpringSurfaceBuilder::from_mesh(&self.mesh)
            .stiffness(K)
            .damping(C)
            .mass(MassDistribution::Total(TOTAL_MASS))
            .pinned(self.rim.iter().copied())
            .dt(dt)
            .integrator(integrator)
            .build()
            .expect("valid plate")
    }
}

/// rapier's edge softness `(f Hz, ζ)` for the crate's k and c on an edge between two free
/// particles of mass m (effective mass m/2).
pub(crate) fn rapier_softness(m: Real) -> (Real, Real) {
    let m_eff = 0.5 * m;
    let f = (K / m_eff).sqrt() / std::f32::consts::TAU;
    let zeta = C / (2.0 * (K * m_eff).sqrt());
    (f, zeta)
}

/// The tools' (x, z) sites.
pub(crate) fn tool_sites(n: usize) -> Vec<[Real; 2]> {
    if n == 1 {
        return vec![[0.0, 0.0]];
    }
    let six = [
        [-0.07, -0.05],
        [0.0, -0.05],
        [0.07, -0.05],
        [-0.07, 0.05],
        [0.0, 0.05],
        [0.07, 0.05],
    ];
    six[..n.min(6)].to_vec()
}

/// Height of a tool's bottom at time t (m, y up; the plate lies at y = 0).
pub(crate) fn tool_bottom(t: Real) -> Real {
    START_GAP - (START_GAP + PRESS_DEPTH) * (t / DESCENT).clamp(0.0, 1.0)
}

pub(crate) fn tool_centre(site: [Real; 2], t: Real, lift: Real) -> Vector {
    Vector::new(site[0], tool_bottom(t) + TOOL_RADIUS + lift, site[1])
}

/// Kinematic ball tools at their starting poses, `lift` above the crate's path, with friction
/// `mu` (combined with the other collider's by `Min`).
pub(crate) fn insert_tools(
    world: &mut PhysicsWorld,
    sites: &[[Real; 2]],
    lift: Real,
    mu: Real,
) -> Vec<ColliderHandle> {
    sites
        .iter()
        .map(|site| {
            let body = world.insert_body(
                RigidBodyBuilder::kinematic_position_based()
                    .translation(tool_centre(*site, 0.0, lift)),
            );
            world.insert_collider(
                ColliderBuilder::ball(TOOL_RADIUS)
                    .friction(mu)
                    .friction_combine_rule(CoefficientCombineRule::Min),
                Some(body),
            )
        })
        .collect()
}

/// Sets every tool's target: its pose at time t (the end of the coming step).
pub(crate) fn drive_tools(
    world: &mut PhysicsWorld,
    tools: &[ColliderHandle],
    sites: &[[Real; 2]],
    t: Real,
    lift: Real,
) {
    for (h, site) in tools.iter().zip(sites) {
        let body = world.colliders[*h].parent().expect("tool body");
        world.bodies[body].set_next_kinematic_translation(tool_centre(*site, t, lift));
    }
}

/// A world with no gravity stepping at `dt`.
pub(crate) fn empty_world(dt: Real) -> PhysicsWorld {
    PhysicsWorld {
        gravity: Vector::ZERO,
        integration_parameters: IntegrationParameters {
            dt,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// What a run records.
pub(crate) struct Tracker {
    pub(crate) cfg: Config,
    pub(crate) times: Vec<f64>,
    pub(crate) max_displacement: Real,
    pub(crate) finite: bool,
    /// Hold steps with a finite nonzero force, per tool.
    pub(crate) hits: Vec<usize>,
    pub(crate) hold_steps: usize,
    pub(crate) nonfinite_force: bool,
    pub(crate) force_y_sum: f64,
}

impl Tracker {
    pub(crate) fn new(cfg: Config) -> Self {
        Self {
            cfg,
            times: Vec::with_capacity(cfg.steps),
            max_displacement: 0.0,
            finite: true,
            hits: vec![0; cfg.tools],
            hold_steps: 0,
            nonfinite_force: false,
            force_y_sum: 0.0,
        }
    }

    pub(crate) fn displacement(&mut self, d: Real) {
        if d.is_finite() {
            self.max_displacement = self.max_displacement.max(d);
        } else {
            self.finite = false;
        }
    }

    /// The tools' forces at the end of a step ending at time t.
    pub(crate) fn forces(&mut self, t: Real, forces: &[Vector]) {
        if forces.iter().any(|f| !f.is_finite()) {
            self.nonfinite_force = true;
        }
        if t < DESCENT - 1e-6 {
            return;
        }
        self.hold_steps += 1;
        for (hits, f) in self.hits.iter_mut().zip(forces) {
            if f.is_finite() && f.length() > 0.0 {
                *hits += 1;
                self.force_y_sum += f.y as f64;
            }
        }
    }

    pub(crate) fn row(self, engine: &'static str, nodes: usize) -> Row {
        let tail = &self.times[self.times.len() / 10..];
        let samples = (self.hold_steps * self.cfg.tools).max(1) as f64;
        Row {
            engine,
            nodes,
            cfg: self.cfg,
            ms_per_step: tail.iter().sum::<f64>() / tail.len() as f64 * 1e3,
            max_displacement: self.max_displacement,
            stable: self.finite && self.max_displacement < STABLE_BOUND,
            force_available: !self.nonfinite_force && self.hits.iter().all(|&h| h > 0),
            force_share: self.hits.iter().sum::<usize>() as f64 / samples,
            mean_force_y: self.force_y_sum / samples,
        }
    }
}
