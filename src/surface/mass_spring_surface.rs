//! [`MassSpringSurface`]: the paper's deformable surface (section 3, eq. 3-4): lumped masses on
//! the vertices of a triangle mesh, a linear spring and a damper in parallel on every edge,
//! displacements measured from the rest (home) positions.

use super::filter::{
    dense_weights, neighbour_error_bound, Filter, FilterError, FilterKind, System,
};
use crate::math::{Real, Vector};
use glamx::DVec3;
use std::collections::HashMap;

mod active_set;
mod baraff_witkin;
mod blocks;
mod builder;
mod changes;
mod constraints;
mod dynamics;
mod motion_watch;
mod point_hold;
mod press_reports;
mod presses;
mod rigid_holder;
use baraff_witkin::CgScratch;
use builder::check_spring;
pub use builder::MassSpringSurfaceBuilder;
use constraints::constrain;
pub use motion_watch::Escaped;
use motion_watch::MotionWatch;
use point_hold::{ActiveMemory, PointHold};
pub use presses::{PointPress, Tangential};
use rigid_holder::HolderState;
pub use rigid_holder::RigidHolder;

/// Why a surface could not be built or changed. Each variant says how to fix the input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceError {
    /// No vertex or no triangle. Give at least one non-degenerate triangle.
    #[error("the surface mesh is empty")]
    EmptyMesh,
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {0} is not finite")]
    NonFiniteVertex(u32),
    /// A triangle, pin, force or edge names a vertex that does not exist.
    #[error("vertex index {index} is out of range ({num_vertices} vertices)")]
    VertexOutOfRange {
        /// The index given.
        index: u32,
        /// The number of vertices.
        num_vertices: u32,
    },
    /// Every triangle is degenerate (repeated index or zero area).
    #[error("all {0} triangles are degenerate")]
    AllTrianglesDegenerate(u32),
    /// A mass is zero, negative or not finite. Masses must be positive.
    #[error("mass {0} is not positive and finite")]
    NonPositiveMass(f64),
    /// A stiffness is not positive and finite, or a damping is negative or not finite.
    #[error("stiffness must be > 0 and damping >= 0 (got k = {stiffness}, c = {damping})")]
    InvalidSpring {
        /// The stiffness given.
        stiffness: f64,
        /// The damping given.
        damping: f64,
    },
    /// The time step is zero, negative or not finite.
    #[error("time step {0} must be positive and finite")]
    InvalidTimeStep(f64),
    /// A force or gravity is NaN or infinite.
    #[error("a force is not finite")]
    NonFiniteForce,
    /// The named edge is not an edge of the mesh.
    #[error("({0}, {1}) is not an edge of the mesh")]
    NotAnEdge(u32, u32),
    /// A force profile's start, end or ramp duration is NaN or infinite, its duration is
    /// negative or its end comes before its start.
    #[error("a force profile's times must be finite, its duration >= 0 and its end >= its start")]
    InvalidForceProfile,
    /// A point hold ([`MassSpringSurface::press_point`]) has no vertex or more than three, a
    /// negative or non-finite weight, weights summing to zero, a zero or non-finite normal, or
    /// a non-finite depth or velocity.
    #[error("invalid point hold (1-3 vertices, weights >= 0 summing > 0, finite unit normal)")]
    InvalidPointHold,
    /// A rigid holder ([`MassSpringSurface::set_holders`]) has a non-finite entry, or an
    /// inverse mass or inertia with a negative diagonal entry.
    #[error("invalid rigid holder (finite, inverse mass and inertia >= 0 on the diagonal)")]
    InvalidHolder,
    /// The implicit filter could not be built.
    #[error(transparent)]
    Filter(#[from] FilterError),
}

/// How the springs pull.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum SpringModel {
    /// The paper's linear model (eq. 3): each spring pulls on the difference of its two
    /// vertices' displacements from home, `f = k (u_b - u_a)`, the same in every direction. The
    /// surface resists being pushed out of its plane as much as being stretched: a tissue
    /// anchored to its rest shape. The filter's `K` is then the exact Jacobian.
    #[default]
    Linear,
    /// Physical springs along the edges, `f = k (l - L) d̂`: nonlinear, they rotate with the
    /// edge. A flat plate then has no linear stiffness out of its plane. The filter uses the
    /// paper's constant `K` as an approximation of the Jacobian; Baraff-Witkin re-linearizes it
    /// each step.
    Length,
}

/// The default surface density of a triangle-mesh surface (kg/m²): a 1 cm layer of
/// water-dense tissue.
pub const DEFAULT_AREA_DENSITY: Real = 10.0;

/// How the vertex masses are lumped.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum MassDistribution {
    /// Every vertex has this mass (kg).
    PerVertex(Real),
    /// The total mass (kg) is split evenly over the vertices.
    Total(Real),
    /// Surface density (kg/m²): each vertex gets a third of the area of its triangles.
    /// Vertices with no area (isolated) get the mean mass.
    AreaDensity(Real),
}

/// The time integrator of a surface (switchable without rebuilding the mesh).
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Integrator {
    /// Symplectic (semi-implicit) Euler, eq. 4: `v += dt F/m; x += dt v`. Stable only below the
    /// Courant limit `dt < 2/ω_max`.
    ExplicitEuler,
    /// Implicit Euler through the paper's global filter, eq. 8.
    Filtered(FilterKind),
    /// Baraff-Witkin implicit Euler: the full `3N × 3N` Jacobian of the springs re-linearized
    /// every step and solved by conjugate gradients, warm-started with the last step's `Δv`.
    /// The accuracy reference when springs rotate ([`SpringModel::Length`]).
    BaraffWitkin {
        /// Conjugate-gradient iteration cap.
        max_iterations: u32,
        /// Relative residual at which CG stops.
        tolerance: Real,
    },
}

impl Integrator {
    /// The exact prefactored filter.
    pub const EXACT: Integrator = Integrator::Filtered(FilterKind::Exact);
    /// The paper's immediate-neighbour filter.
    pub const NEIGHBOUR: Integrator = Integrator::Filtered(FilterKind::Neighbour { rings: 1 });
    /// Baraff-Witkin with 200 iterations and a 1e-8 relative residual.
    pub const BARAFF_WITKIN: Integrator = Integrator::BaraffWitkin {
        max_iterations: 200,
        tolerance: 1e-8,
    };
}

/// A force applied over time to a set of vertices (each vertex receives `force`).
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum ForceProfile {
    /// `force` from `start` on, until `end` if given (a step function).
    Step {
        /// Force on each vertex (N).
        force: Vector,
        /// Time it switches on (s).
        start: Real,
        /// Time it switches off (s), if ever.
        end: Option<Real>,
    },
    /// Rising linearly from zero at `start` to `force` at `start + duration`, then constant.
    Ramp {
        /// Final force on each vertex (N).
        force: Vector,
        /// Time the ramp starts (s).
        start: Real,
        /// Ramp duration (s).
        duration: Real,
    },
}

impl ForceProfile {
    /// The force on each vertex at time `t` (s).
    ///
    /// ```
    /// use rapier_touch::prelude::*;
    /// let ramp = ForceProfile::Ramp { force: Vector::Y, start: 1.0, duration: 2.0 };
    /// assert_eq!(ramp.force_at(0.5), Vector::ZERO);
    /// assert_eq!(ramp.force_at(2.0), Vector::new(0.0, 0.5, 0.0));
    /// assert_eq!(ramp.force_at(9.0), Vector::Y);
    /// ```
    pub fn force_at(&self, t: Real) -> Vector {
        self.at(t as f64).as_vec3()
    }

    /// Finite force and times, a duration ≥ 0, an end not before the start.
    fn check(&self) -> Result<(), SurfaceError> {
        let (force, times_ok) = match *self {
            ForceProfile::Step { force, start, end } => (
                force,
                start.is_finite() && end.is_none_or(|e| e.is_finite() && e >= start),
            ),
            ForceProfile::Ramp {
                force,
                start,
                duration,
            } => (
                force,
                start.is_finite() && duration.is_finite() && duration >= 0.0,
            ),
        };
        if !force.is_finite() {
            return Err(SurfaceError::NonFiniteForce);
        }
        if !times_ok {
            return Err(SurfaceError::InvalidForceProfile);
        }
        Ok(())
    }

    fn at(&self, t: f64) -> DVec3 {
        match *self {
            ForceProfile::Step { force, start, end } => {
                if t >= start as f64 && end.is_none_or(|e| t < e as f64) {
                    force.as_dvec3()
                } else {
                    DVec3::ZERO
                }
            }
            ForceProfile::Ramp {
                force,
                start,
                duration,
            } => {
                let a = if duration > 0.0 {
                    ((t - start as f64) / duration as f64).clamp(0.0, 1.0)
                } else if t >= start as f64 {
                    1.0
                } else {
                    0.0
                };
                force.as_dvec3() * a
            }
        }
    }
}

/// The paper's deformable surface: a mass-spring-damper mesh integrated by explicit Euler, the
/// global filter (exact or immediate-neighbour) or Baraff-Witkin implicit Euler.
///
/// Built by [`MassSpringSurfaceBuilder`]; needs no rapier pipeline.
///
/// # Example
/// One spring (k = 100 N/m, critically damped) from a pinned vertex to a free 1 kg one pulled
/// by 2 N settles at the static stretch `F / k` = 2 cm:
/// ```
/// use rapier_touch::prelude::*;
///
/// let mut surface = MassSpringSurfaceBuilder::network(vec![Vector::ZERO, Vector::X], vec![[0, 1]])
///     .stiffness(100.0)
///     .damping(20.0)
///     .pinned([0])
///     .build()
///     .unwrap();
/// surface.set_force(1, Vector::new(2.0, 0.0, 0.0)).unwrap();
/// for _ in 0..300 {
///     surface.step(); // 5 s at the default 60 Hz
/// }
/// assert!((surface.displacement(1) - Vector::new(0.02, 0.0, 0.0)).length() < 1e-4);
/// assert_eq!(surface.position(0), Vector::ZERO); // pinned
/// // At rest the spring's pull balances the applied force.
/// assert!((surface.internal_force(1) + Vector::new(2.0, 0.0, 0.0)).length() < 1e-2);
/// ```
pub struct MassSpringSurface {
    home: Vec<DVec3>,
    pos: Vec<DVec3>,
    vel: Vec<DVec3>,
    mass: Vec<f64>,
    pinned: Vec<bool>,
    edges: Vec<[u32; 2]>,
    rest: Vec<f64>,
    k: Vec<f64>,
    c: Vec<f64>,
    ext: Vec<DVec3>,
    schedules: Vec<(Vec<u32>, ForceProfile)>,
    gravity: DVec3,
    model: SpringModel,
    integrator: Integrator,
    dt: f64,
    time: f64,
    neighbour_max_error: f64,
    dropped: Vec<u32>,
    triangles: Vec<[u32; 3]>,
    isolated: Vec<u32>,
    free: Vec<u32>,
    free_index: Vec<u32>,
    filter: Option<Filter>,
    fallback: bool,
    /// The fallback was reported through `log` (once per surface).
    fallback_logged: bool,
    force: Vec<DVec3>,
    disp: Vec<[DVec3; 2]>,
    rhs: Vec<DVec3>,
    dv: Vec<DVec3>,
    cg: CgScratch,
    last_cg_iterations: u32,
    diverged: bool,
    vertex_edge_ptr: Vec<usize>,
    vertex_edges: Vec<u32>,
    held: Vec<bool>,
    /// For a sliding hold, the unit normal the holder supports; zero for a full hold.
    held_normal: Vec<DVec3>,
    /// Forces the holders add on held vertices (friction on a sliding hold), until released.
    held_forces: Vec<(u32, DVec3)>,
    /// The held vertices (`held` true), each once.
    held_list: Vec<u32>,
    /// Each held vertex's hold impulse over the last step ([`Self::hold_impulse`]); zero
    /// elsewhere but at `hold_impulse_at` (the vertices held then).
    hold_impulse: Vec<DVec3>,
    hold_impulse_at: Vec<u32>,
    point_holds: Vec<PointHold>,
    /// The rigid holders the point holds may name ([`Self::set_holders`]).
    holders: Vec<HolderState>,
    /// Which constraint rows pushed in the last filtered step's solve (its warm start).
    pushing: ActiveMemory,
    /// Which vertices moved far ([`Self::watch_motion`]); `None` until watched.
    watch: Option<Box<MotionWatch>>,
}

const NOT_FREE: u32 = u32::MAX;

impl MassSpringSurface {
    fn build_vertex_edges(&mut self) {
        let n = self.home.len();
        let mut ptr = vec![0usize; n + 1];
        for e in &self.edges {
            ptr[e[0] as usize + 1] += 1;
            ptr[e[1] as usize + 1] += 1;
        }
        for i in 0..n {
            ptr[i + 1] += ptr[i];
        }
        let mut fill = ptr.clone();
        let mut list = vec![0u32; ptr[n]];
        for (ei, e) in self.edges.iter().enumerate() {
            for &v in e {
                list[fill[v as usize]] = ei as u32;
                fill[v as usize] += 1;
            }
        }
        self.vertex_edge_ptr = ptr;
        self.vertex_edges = list;
    }

    fn rebuild_free(&mut self) {
        self.free = (0..self.home.len() as u32)
            .filter(|&i| !self.pinned[i as usize])
            .collect();
        self.free_index = vec![NOT_FREE; self.home.len()];
        for (fi, &v) in self.free.iter().enumerate() {
            self.free_index[v as usize] = fi as u32;
        }
        let nf = self.free.len();
        self.rhs = vec![DVec3::ZERO; nf];
        self.dv = vec![DVec3::ZERO; nf];
        self.filter = None;
        for (i, p) in self.pinned.iter().enumerate() {
            if *p {
                self.pos[i] = self.home[i];
                self.vel[i] = DVec3::ZERO;
                if let Some(w) = self.watch.as_mut() {
                    w.lose();
                }
            }
        }
    }

    /// The implicit system of the free vertices (eq. 7).
    fn system(&self) -> System {
        let mut pairs = Vec::new();
        let mut anchors = Vec::new();
        for (e, &[a, b]) in self.edges.iter().enumerate() {
            let (fa, fb) = (self.free_index[a as usize], self.free_index[b as usize]);
            match (fa != NOT_FREE, fb != NOT_FREE) {
                (true, true) => pairs.push((fa, fb, self.k[e], self.c[e])),
                (true, false) => anchors.push((fa, self.k[e], self.c[e])),
                (false, true) => anchors.push((fb, self.k[e], self.c[e])),
                (false, false) => {}
            }
        }
        System {
            mass: self.free.iter().map(|&v| self.mass[v as usize]).collect(),
            pairs,
            anchors,
        }
    }

    fn ensure_filter(&mut self) -> Result<(), SurfaceError> {
        let Integrator::Filtered(kind) = self.integrator else {
            self.filter = None;
            return Ok(());
        };
        if self.free.is_empty() {
            return Ok(());
        }
        let mut kind = kind;
        self.fallback = false;
        if let FilterKind::Neighbour { rings } = kind {
            let bound = neighbour_error_bound(&self.system().s_values(self.dt), rings.max(1));
            if bound > self.neighbour_max_error {
                kind = FilterKind::Exact;
                self.fallback = true;
                if !self.fallback_logged {
                    self.fallback_logged = true;
                    log::warn!(
                        "rapier_touch: the neighbour filter's error bound {bound:.3} exceeds \
                         {:.3} on this {}-vertex surface (largest s = {:.3}); using the exact \
                         filter (MassSpringSurface::filter_fallback)",
                        self.neighbour_max_error,
                        self.home.len(),
                        self.system()
                            .s_values(self.dt)
                            .into_iter()
                            .fold(0.0, f64::max)
                    );
                }
            }
        }
        if self.filter.as_ref().map(|f| f.kind()) != Some(kind) {
            self.filter = Some(Filter::precompute(&self.system(), self.dt, kind)?);
        }
        Ok(())
    }

    // ----- Accessors -----

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.home.len()
    }
    /// The unique edges (vertex pairs, smallest first).
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }
    /// Home (rest) position of vertex `i`.
    pub fn home(&self, i: u32) -> Vector {
        self.home[i as usize].as_vec3()
    }
    /// Current position of vertex `i`.
    pub fn position(&self, i: u32) -> Vector {
        self.pos[i as usize].as_vec3()
    }
    /// Current velocity of vertex `i`.
    pub fn velocity(&self, i: u32) -> Vector {
        self.vel[i as usize].as_vec3()
    }
    /// Displacement of vertex `i` from home.
    pub fn displacement(&self, i: u32) -> Vector {
        (self.pos[i as usize] - self.home[i as usize]).as_vec3()
    }
    /// Writes all current positions into `out` (cleared first).
    pub fn positions_into(&self, out: &mut Vec<Vector>) {
        out.clear();
        out.extend(self.pos.iter().map(|p| p.as_vec3()));
    }
    /// The sum of the stiffnesses of vertex `i`'s edges (N/m; 0 out of range): how hard it
    /// resists being moved while its neighbours stay put.
    pub fn vertex_stiffness(&self, i: u32) -> Real {
        let i = i as usize;
        if i + 1 >= self.vertex_edge_ptr.len() {
            return 0.0;
        }
        let edges = &self.vertex_edges[self.vertex_edge_ptr[i]..self.vertex_edge_ptr[i + 1]];
        edges.iter().map(|&e| self.k[e as usize]).sum::<f64>() as Real
    }
    /// The held vertices (each once, whatever holds them).
    pub(crate) fn held_list(&self) -> &[u32] {
        &self.held_list
    }
    /// The force the dampers of held vertex `i`'s edges to vertices not held put on it
    /// (`Σ c (v_j - v_i)`, surface frame, N): the part of what it pushes its holder with that
    /// comes from the last step's velocities. Edges between held vertices are left out (over
    /// a holder's vertices they cancel). `O(degree)`; zero out of range.
    pub(crate) fn held_damper_force(&self, i: u32) -> Vector {
        let i = i as usize;
        if i + 1 >= self.vertex_edge_ptr.len() {
            return Vector::ZERO;
        }
        let mut f = DVec3::ZERO;
        for &e in &self.vertex_edges[self.vertex_edge_ptr[i]..self.vertex_edge_ptr[i + 1]] {
            let [a, b] = self.edges[e as usize];
            let j = if a as usize == i { b } else { a } as usize;
            if !self.held[j] {
                f += (self.vel[j] - self.vel[i]) * self.c[e as usize];
            }
        }
        f.as_vec3()
    }
    /// Mass of vertex `i`.
    pub fn mass(&self, i: u32) -> Real {
        self.mass[i as usize] as Real
    }
    /// Is vertex `i` pinned?
    pub fn is_pinned(&self, i: u32) -> bool {
        self.pinned[i as usize]
    }
    /// The triangles kept (degenerate ones dropped), for rendering and colliders.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    /// User triangles dropped as degenerate.
    pub fn dropped_triangles(&self) -> &[u32] {
        &self.dropped
    }
    /// Vertices on no edge (they move freely under their own forces).
    pub fn isolated_vertices(&self) -> &[u32] {
        &self.isolated
    }
    /// Simulated time (s).
    pub fn time(&self) -> Real {
        self.time as Real
    }
    /// The time step (s).
    pub fn dt(&self) -> Real {
        self.dt as Real
    }
    /// The integrator in use.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }
    /// `true` when the neighbour filter was asked for but its error bound exceeded the limit,
    /// so the exact filter runs instead. The first fallback of a surface is also reported as a
    /// `log` warning (the application's logger decides where it goes).
    pub fn filter_fallback(&self) -> bool {
        self.fallback
    }
    /// CG iterations of the last Baraff-Witkin step.
    pub fn last_cg_iterations(&self) -> u32 {
        self.last_cg_iterations
    }

    /// The paper's `s = dt² Σk/m + dt Σc/m` of each vertex (0 for pinned vertices): the
    /// neighbour filter is close to the exact one only where `s` is small.
    pub fn s_values(&self) -> Vec<Real> {
        let s = self.system().s_values(self.dt);
        let mut out = vec![0.0; self.home.len()];
        for (fi, &v) in self.free.iter().enumerate() {
            out[v as usize] = s[fi] as Real;
        }
        out
    }

    /// The neighbour filter's truncation-error bound `max (s/(1+s))^(rings+1)`.
    pub fn neighbour_error_bound(&self, rings: u32) -> Real {
        neighbour_error_bound(&self.system().s_values(self.dt), rings.max(1)) as Real
    }

    /// The dense exact filter `W = S⁻¹ M` over the free vertices, as `(free vertex ids, rows)`.
    /// `O(N²)`: for analysis of small meshes (Table II).
    ///
    /// # Errors
    /// [`SurfaceError::Filter`] if the system cannot be factored.
    pub fn dense_filter(&self) -> Result<(Vec<u32>, Vec<Vec<f64>>), SurfaceError> {
        Ok((self.free.clone(), dense_weights(&self.system(), self.dt)?))
    }
}

impl std::fmt::Debug for MassSpringSurface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MassSpringSurface")
            .field("vertices", &self.home.len())
            .field("edges", &self.edges.len())
            .field("pinned", &(self.home.len() - self.free.len()))
            .field("integrator", &self.integrator)
            .field("dt", &self.dt)
            .finish()
    }
}
