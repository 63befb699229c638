//! [`MassSpringSurface`]: the paper's deformable surface (section 3, eq. 3-4): lumped masses on
//! the vertices of a triangle mesh, a linear spring and a damper in parallel on every edge,
//! displacements measured from the rest (home) positions.

use super::filter::{
    dense_weights, neighbour_error_bound, Filter, FilterError, FilterKind, System,
};
use crate::math::{Real, Vector};
use glamx::DVec3;
use std::collections::HashMap;

mod baraff_witkin;
mod constraints;
use baraff_witkin::CgScratch;
pub use constraints::PointPress;
use constraints::{constrain, PointHold};

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

/// Builds a [`MassSpringSurface`].
///
/// # Example
/// A 5 × 5 plate pinned on one side, sagging under gravity with the paper's neighbour filter:
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::surface::meshing::plate;
///
/// let mesh = plate(1.0, 1.0, 4, 4);
/// let pinned: Vec<u32> = (0..mesh.vertices.len() as u32)
///     .filter(|&i| mesh.vertices[i as usize].x < -0.49)
///     .collect();
/// let mut surface = MassSpringSurfaceBuilder::new(mesh.vertices, mesh.triangles)
///     .stiffness(200.0)
///     .damping(2.0)
///     .mass(MassDistribution::Total(1.0))
///     .pinned(pinned)
///     .gravity(Vector::new(0.0, -9.81, 0.0))
///     .dt(1.0 / 60.0)
///     .integrator(Integrator::NEIGHBOUR)
///     .build()
///     .unwrap();
/// for _ in 0..120 {
///     surface.step();
/// }
/// assert!(surface.max_displacement() > 0.0);
/// assert!(surface.total_energy().is_finite());
/// ```
#[derive(Clone, Debug)]
pub struct MassSpringSurfaceBuilder {
    vertices: Vec<Vector>,
    triangles: Vec<[u32; 3]>,
    extra_edges: Vec<[u32; 2]>,
    stiffness: Real,
    damping: Real,
    edge_overrides: Vec<([u32; 2], Option<Real>, Option<Real>)>,
    mass: MassDistribution,
    pinned: Vec<u32>,
    gravity: Vector,
    spring_model: SpringModel,
    integrator: Integrator,
    dt: Real,
    neighbour_max_error: Real,
}

impl MassSpringSurfaceBuilder {
    /// A surface on this triangle mesh, with stiffness 100 N/m, damping 1 N·s/m, a surface
    /// density of [`DEFAULT_AREA_DENSITY`] (10 kg/m²: a 1 cm layer of water-dense tissue, lumped
    /// a third of each triangle's area per vertex), no gravity, no pins, dt = 1/60 s, the exact
    /// filter and the linear spring model.
    pub fn new(vertices: Vec<Vector>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            vertices,
            triangles,
            extra_edges: Vec::new(),
            stiffness: 100.0,
            damping: 1.0,
            edge_overrides: Vec::new(),
            mass: MassDistribution::AreaDensity(DEFAULT_AREA_DENSITY),
            pinned: Vec::new(),
            gravity: Vector::ZERO,
            spring_model: SpringModel::Linear,
            integrator: Integrator::EXACT,
            dt: 1.0 / 60.0,
            neighbour_max_error: 0.05,
        }
    }
    /// A surface on a mesh from [`super::meshing`] (planar meshing, OBJ files, generators).
    pub fn from_mesh(mesh: &super::meshing::SurfaceMesh) -> Self {
        Self::new(mesh.vertices.clone(), mesh.triangles.clone())
    }
    /// A spring network with no triangles (a chain, a lattice): the same model on explicit
    /// edges, 1 kg per vertex by default (with no area, a density has nothing to act on).
    /// [`MassDistribution::AreaDensity`] needs triangles and is an error here.
    pub fn network(vertices: Vec<Vector>, edges: Vec<[u32; 2]>) -> Self {
        let mut b = Self::new(vertices, Vec::new());
        b.extra_edges = edges;
        b.mass = MassDistribution::PerVertex(1.0);
        b
    }
    /// Spring stiffness of every edge (N/m).
    pub fn stiffness(mut self, k: Real) -> Self {
        self.stiffness = k;
        self
    }
    /// Damping of every edge (N·s/m).
    pub fn damping(mut self, c: Real) -> Self {
        self.damping = c;
        self
    }
    /// Overrides the stiffness of edge `(a, b)`.
    pub fn edge_stiffness(mut self, a: u32, b: u32, k: Real) -> Self {
        self.edge_overrides.push(([a, b], Some(k), None));
        self
    }
    /// Overrides the damping of edge `(a, b)`.
    pub fn edge_damping(mut self, a: u32, b: u32, c: Real) -> Self {
        self.edge_overrides.push(([a, b], None, Some(c)));
        self
    }
    /// How masses are lumped (default: [`MassDistribution::AreaDensity`] of
    /// [`DEFAULT_AREA_DENSITY`] for a triangle mesh, 1 kg per vertex for a network).
    pub fn mass(mut self, m: MassDistribution) -> Self {
        self.mass = m;
        self
    }
    /// Vertices held at their home position (boundary pins, the paper's constrained internal
    /// boundaries).
    pub fn pinned(mut self, vertices: impl IntoIterator<Item = u32>) -> Self {
        self.pinned.extend(vertices);
        self
    }
    /// Gravity (m/s²).
    pub fn gravity(mut self, g: Vector) -> Self {
        self.gravity = g;
        self
    }
    /// The spring model.
    pub fn spring_model(mut self, m: SpringModel) -> Self {
        self.spring_model = m;
        self
    }
    /// The integrator.
    pub fn integrator(mut self, i: Integrator) -> Self {
        self.integrator = i;
        self
    }
    /// The time step (s).
    pub fn dt(mut self, dt: Real) -> Self {
        self.dt = dt;
        self
    }
    /// Largest truncation-error bound `(s/(1+s))^(rings+1)` the neighbour filter may have
    /// before the surface falls back to the exact filter (default 0.05; see
    /// [`MassSpringSurface::filter_fallback`]).
    pub fn neighbour_max_error(mut self, e: Real) -> Self {
        self.neighbour_max_error = e;
        self
    }

    /// Builds the surface: edges and adjacency once, masses, and the filter if the integrator
    /// needs one.
    ///
    /// # Errors
    /// See [`SurfaceError`]. Degenerate triangles are dropped (and listed by
    /// [`MassSpringSurface::dropped_triangles`]); vertices on no edge are kept and move freely
    /// under their forces ([`MassSpringSurface::isolated_vertices`]).
    pub fn build(self) -> Result<MassSpringSurface, SurfaceError> {
        let n = self.vertices.len();
        if n == 0 || (self.triangles.is_empty() && self.extra_edges.is_empty()) {
            return Err(SurfaceError::EmptyMesh);
        }
        if let Some(i) = self.vertices.iter().position(|v| !v.is_finite()) {
            return Err(SurfaceError::NonFiniteVertex(i as u32));
        }
        let check = |i: u32| {
            if (i as usize) < n {
                Ok(())
            } else {
                Err(SurfaceError::VertexOutOfRange {
                    index: i,
                    num_vertices: n as u32,
                })
            }
        };
        for t in &self.triangles {
            for &i in t {
                check(i)?;
            }
        }
        for e in &self.extra_edges {
            check(e[0])?;
            check(e[1])?;
        }
        for &p in &self.pinned {
            check(p)?;
        }
        check_spring(self.stiffness, self.damping)?;
        if !(self.dt > 0.0 && self.dt.is_finite()) {
            return Err(SurfaceError::InvalidTimeStep(self.dt as f64));
        }
        if !self.gravity.is_finite() {
            return Err(SurfaceError::NonFiniteForce);
        }

        let home: Vec<DVec3> = self.vertices.iter().map(|v| v.as_dvec3()).collect();
        let mut edges: Vec<[u32; 2]> = Vec::new();
        let mut edge_map: HashMap<[u32; 2], usize> = HashMap::new();
        let mut area = vec![0.0f64; n];
        let mut dropped = Vec::new();
        let mut kept_triangles = Vec::with_capacity(self.triangles.len());
        for (ti, t) in self.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|i| home[i as usize]);
            let ar = 0.5 * (b - a).cross(c - a).length();
            let scale = (b - a).length().max((c - a).length()).max(1e-30);
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || ar <= 1e-12 * scale * scale {
                dropped.push(ti as u32);
                continue;
            }
            kept_triangles.push(*t);
            for &v in t {
                area[v as usize] += ar / 3.0;
            }
            for k in 0..3 {
                let (x, y) = (t[k], t[(k + 1) % 3]);
                let key = [x.min(y), x.max(y)];
                edge_map.entry(key).or_insert_with(|| {
                    edges.push(key);
                    edges.len() - 1
                });
            }
        }
        for e in &self.extra_edges {
            let key = [e[0].min(e[1]), e[0].max(e[1])];
            if key[0] != key[1] {
                edge_map.entry(key).or_insert_with(|| {
                    edges.push(key);
                    edges.len() - 1
                });
            }
        }
        if edges.is_empty() {
            return Err(SurfaceError::AllTrianglesDegenerate(
                self.triangles.len() as u32
            ));
        }
        let mut k = vec![self.stiffness as f64; edges.len()];
        let mut c = vec![self.damping as f64; edges.len()];
        for (e, ko, co) in &self.edge_overrides {
            let key = [e[0].min(e[1]), e[0].max(e[1])];
            let &i = edge_map
                .get(&key)
                .ok_or(SurfaceError::NotAnEdge(e[0], e[1]))?;
            if let Some(kv) = ko {
                check_spring(*kv, 0.0)?;
                k[i] = *kv as f64;
            }
            if let Some(cv) = co {
                check_spring(1.0, *cv)?;
                c[i] = *cv as f64;
            }
        }
        let mass: Vec<f64> = match self.mass {
            MassDistribution::PerVertex(m) => vec![m as f64; n],
            MassDistribution::Total(m) => vec![m as f64 / n as f64; n],
            MassDistribution::AreaDensity(rho) => {
                let with_area: Vec<f64> = area.iter().map(|a| a * rho as f64).collect();
                let positive: Vec<f64> = with_area.iter().copied().filter(|m| *m > 0.0).collect();
                let mean = positive.iter().sum::<f64>() / positive.len().max(1) as f64;
                with_area
                    .into_iter()
                    .map(|m| if m > 0.0 { m } else { mean })
                    .collect()
            }
        };
        if let Some(&m) = mass.iter().find(|m| !(**m > 0.0 && m.is_finite())) {
            return Err(SurfaceError::NonPositiveMass(m));
        }
        let mut used = vec![false; n];
        for e in &edges {
            used[e[0] as usize] = true;
            used[e[1] as usize] = true;
        }
        let isolated = (0..n as u32).filter(|&i| !used[i as usize]).collect();
        let mut pinned = vec![false; n];
        for &p in &self.pinned {
            pinned[p as usize] = true;
        }
        let rest = edges
            .iter()
            .map(|e| (home[e[1] as usize] - home[e[0] as usize]).length())
            .collect();
        let mut s = MassSpringSurface {
            pos: home.clone(),
            vel: vec![DVec3::ZERO; n],
            home,
            mass,
            pinned,
            edges,
            rest,
            k,
            c,
            ext: vec![DVec3::ZERO; n],
            schedules: Vec::new(),
            gravity: self.gravity.as_dvec3(),
            model: self.spring_model,
            integrator: self.integrator,
            dt: self.dt as f64,
            time: 0.0,
            neighbour_max_error: self.neighbour_max_error as f64,
            dropped,
            triangles: kept_triangles,
            isolated,
            free: Vec::new(),
            free_index: Vec::new(),
            filter: None,
            fallback: false,
            fallback_logged: false,
            force: vec![DVec3::ZERO; n],
            disp: Vec::with_capacity(n),
            rhs: Vec::new(),
            dv: Vec::new(),
            cg: CgScratch::default(),
            last_cg_iterations: 0,
            diverged: false,
            vertex_edge_ptr: Vec::new(),
            vertex_edges: Vec::new(),
            held: vec![false; n],
            held_normal: vec![DVec3::ZERO; n],
            held_forces: Vec::new(),
            any_held: false,
            point_holds: Vec::new(),
        };
        s.build_vertex_edges();
        s.rebuild_free();
        s.ensure_filter()?;
        Ok(s)
    }
}

fn check_spring(k: Real, c: Real) -> Result<(), SurfaceError> {
    if k > 0.0 && k.is_finite() && c >= 0.0 && c.is_finite() {
        Ok(())
    } else {
        Err(SurfaceError::InvalidSpring {
            stiffness: k as f64,
            damping: c as f64,
        })
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
    any_held: bool,
    point_holds: Vec<PointHold>,
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

    // ----- Changes -----

    /// Switches the integrator (the mesh is kept; a filter is built if needed).
    ///
    /// # Errors
    /// [`SurfaceError::Filter`].
    pub fn set_integrator(&mut self, integrator: Integrator) -> Result<(), SurfaceError> {
        self.integrator = integrator;
        self.ensure_filter()
    }
    /// Changes the time step (the filter is refactored).
    ///
    /// # Errors
    /// [`SurfaceError::InvalidTimeStep`], [`SurfaceError::Filter`].
    pub fn set_dt(&mut self, dt: Real) -> Result<(), SurfaceError> {
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(SurfaceError::InvalidTimeStep(dt as f64));
        }
        self.dt = dt as f64;
        self.filter = None;
        self.ensure_filter()
    }
    /// Sets the stiffness and damping of every edge (the filter is refactored).
    ///
    /// # Errors
    /// [`SurfaceError::InvalidSpring`], [`SurfaceError::Filter`].
    pub fn set_spring(&mut self, k: Real, c: Real) -> Result<(), SurfaceError> {
        check_spring(k, c)?;
        self.k.iter_mut().for_each(|x| *x = k as f64);
        self.c.iter_mut().for_each(|x| *x = c as f64);
        self.filter = None;
        self.ensure_filter()
    }
    /// Pins or releases vertex `i`.
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::Filter`].
    pub fn set_pinned(&mut self, i: u32, pinned: bool) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        if self.pinned[i as usize] != pinned {
            self.pinned[i as usize] = pinned;
            self.rebuild_free();
            self.ensure_filter()?;
        }
        Ok(())
    }
    /// Sets the persistent external force on vertex `i` (until changed or cleared).
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::NonFiniteForce`].
    pub fn set_force(&mut self, i: u32, f: Vector) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        if !f.is_finite() {
            return Err(SurfaceError::NonFiniteForce);
        }
        self.ext[i as usize] = f.as_dvec3();
        Ok(())
    }
    /// Removes all persistent external forces (not the scheduled ones).
    pub fn clear_forces(&mut self) {
        self.ext.iter_mut().for_each(|f| *f = DVec3::ZERO);
    }
    /// Applies `profile` to each of `vertices` from now on; returns an id for
    /// [`MassSpringSurface::remove_force_schedule`].
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::NonFiniteForce`],
    /// [`SurfaceError::InvalidForceProfile`].
    pub fn add_force_schedule(
        &mut self,
        vertices: Vec<u32>,
        profile: ForceProfile,
    ) -> Result<usize, SurfaceError> {
        for &v in &vertices {
            self.check_vertex(v)?;
        }
        profile.check()?;
        self.schedules.push((vertices, profile));
        Ok(self.schedules.len() - 1)
    }
    /// Stops a force schedule (ids of the others stay valid).
    pub fn remove_force_schedule(&mut self, id: usize) {
        if let Some(s) = self.schedules.get_mut(id) {
            s.0.clear();
        }
    }
    /// Moves free vertex `i` to `p` with velocity `v` (a tool holding it). Pinned vertices do
    /// not move.
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::NonFiniteVertex`].
    pub fn set_state(&mut self, i: u32, p: Vector, v: Vector) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        if !(p.is_finite() && v.is_finite()) {
            return Err(SurfaceError::NonFiniteVertex(i));
        }
        if !self.pinned[i as usize] {
            self.pos[i as usize] = p.as_dvec3();
            self.vel[i as usize] = v.as_dvec3();
        }
        Ok(())
    }

    /// Marks vertex `i` as held by something outside the surface (a tool) for the following
    /// steps, until [`MassSpringSurface::release_all`]: a moving pin. It keeps the velocity
    /// given by [`MassSpringSurface::set_state`], and the rest of the surface responds to it as
    /// to a pin: the filtered integrators solve for the holders' impulses through the columns
    /// of the filter (`S⁻¹ = W M⁻¹`) at the held vertices (a small dense system per step, one
    /// extra solve per newly held vertex for the exact filter, cached), Baraff-Witkin projects
    /// its CG. A held vertex's
    /// [`MassSpringSurface::internal_force`] is what it pushes the holder with.
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`].
    pub fn hold(&mut self, i: u32) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        self.held[i as usize] = true;
        self.held_normal[i as usize] = DVec3::ZERO;
        self.any_held = true;
        Ok(())
    }

    /// Holds vertex `i` along `normal` only, until [`MassSpringSurface::release_all`]: a
    /// frictionless contact. The holder balances the normal part of the vertex's force and
    /// velocity change; the tangential part moves it as usual, so it slides along the holder.
    /// A zero or non-finite `normal` gives a full [`MassSpringSurface::hold`].
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`].
    pub fn hold_sliding(&mut self, i: u32, normal: Vector) -> Result<(), SurfaceError> {
        self.hold(i)?;
        if let Some(n) = normal.as_dvec3().try_normalize() {
            self.held_normal[i as usize] = n;
        }
        Ok(())
    }

    /// A sliding hold ([`MassSpringSurface::hold_sliding`]) whose holder also pulls vertex `i`
    /// with `friction` (N) along the surface until released: kinetic friction of a vertex
    /// slipping over a tool. The part of `friction` along `normal` is dropped (the hold takes
    /// it).
    ///
    /// # Errors
    /// [`SurfaceError::VertexOutOfRange`], [`SurfaceError::NonFiniteForce`].
    pub fn hold_sliding_with_friction(
        &mut self,
        i: u32,
        normal: Vector,
        friction: Vector,
    ) -> Result<(), SurfaceError> {
        self.check_vertex(i)?;
        if !friction.is_finite() {
            return Err(SurfaceError::NonFiniteForce);
        }
        self.hold_sliding(i, normal)?;
        self.held_forces.retain(|h| h.0 != i);
        let f = self.unheld_part(i as usize, friction.as_dvec3());
        if f != DVec3::ZERO {
            self.held_forces.push((i, f));
        }
        Ok(())
    }

    /// The part of `v` (a force or a velocity change of vertex `i`) its holder leaves free.
    fn unheld_part(&self, i: usize, v: DVec3) -> DVec3 {
        if !self.held[i] {
            return v;
        }
        let n = self.held_normal[i];
        if n == DVec3::ZERO {
            return DVec3::ZERO;
        }
        v - n * v.dot(n)
    }
    /// Releases vertex `i` if held.
    pub fn release(&mut self, i: u32) {
        if let Some(h) = self.held.get_mut(i as usize) {
            *h = false;
        }
        self.held_forces.retain(|h| h.0 != i);
    }
    /// Releases every held vertex and every held point.
    pub fn release_all(&mut self) {
        self.point_holds.clear();
        self.held_forces.clear();
        if self.any_held {
            self.held.iter_mut().for_each(|h| *h = false);
            self.any_held = false;
        }
    }
    /// Is vertex `i` held?
    pub fn is_held(&self, i: u32) -> bool {
        self.held.get(i as usize).copied().unwrap_or(false)
    }
    /// The normal a sliding hold on vertex `i` supports; zero for a full hold, a vertex not
    /// held, or one out of range.
    pub(crate) fn held_normal(&self, i: u32) -> Vector {
        match self.held.get(i as usize) {
            Some(true) => self.held_normal[i as usize].as_vec3(),
            _ => Vector::ZERO,
        }
    }

    fn check_vertex(&self, i: u32) -> Result<(), SurfaceError> {
        if (i as usize) < self.home.len() {
            Ok(())
        } else {
            Err(SurfaceError::VertexOutOfRange {
                index: i,
                num_vertices: self.home.len() as u32,
            })
        }
    }

    // ----- Forces and energies -----

    /// Spring and damper force of edge `e` on its first vertex (the second gets the opposite).
    #[inline]
    fn edge_force(&self, e: usize) -> DVec3 {
        let [a, b] = self.edges[e];
        let (a, b) = (a as usize, b as usize);
        let spring = match self.model {
            SpringModel::Linear => {
                self.k[e] * ((self.pos[b] - self.home[b]) - (self.pos[a] - self.home[a]))
            }
            SpringModel::Length => {
                let d = self.pos[b] - self.pos[a];
                let l = d.length();
                if l > 0.0 {
                    d * (self.k[e] * (l - self.rest[e]) / l)
                } else {
                    DVec3::ZERO
                }
            }
        };
        spring + self.c[e] * (self.vel[b] - self.vel[a])
    }

    /// The spring and damper force on vertex `i` (what it pushes back with when held).
    /// `O(degree)`.
    pub fn internal_force(&self, i: u32) -> Vector {
        let mut f = DVec3::ZERO;
        let i = i as usize;
        if i + 1 >= self.vertex_edge_ptr.len() {
            return Vector::ZERO;
        }
        for &e in &self.vertex_edges[self.vertex_edge_ptr[i]..self.vertex_edge_ptr[i + 1]] {
            let e = e as usize;
            if self.edges[e][0] as usize == i {
                f += self.edge_force(e);
            } else {
                f -= self.edge_force(e);
            }
        }
        f.as_vec3()
    }

    fn compute_forces(&mut self) {
        self.accumulate_forces(0.0);
    }

    /// `force = ext + m g + schedules + springs + dampers + kv_dt K v` in one pass over the
    /// edges (`kv_dt = dt` adds the filter's `dt K vⁿ` term, with the paper's constant `K`).
    fn accumulate_forces(&mut self, kv_dt: f64) {
        let t = self.time;
        for ((f, e), m) in self.force.iter_mut().zip(&self.ext).zip(&self.mass) {
            *f = *e + self.gravity * *m;
        }
        for (verts, profile) in &self.schedules {
            let f = profile.at(t);
            for &v in verts {
                self.force[v as usize] += f;
            }
        }
        let edges = self.edges.iter().zip(self.k.iter().zip(&self.c));
        match self.model {
            SpringModel::Linear => {
                // Displacement and velocity side by side once per vertex, then one read per
                // edge end.
                self.disp.clear();
                self.disp.extend(
                    self.pos
                        .iter()
                        .zip(&self.home)
                        .zip(&self.vel)
                        .map(|((p, h), v)| [*p - *h, *v]),
                );
                let state = &self.disp;
                let force = &mut self.force;
                for (&[a, b], (&k, &c)) in edges {
                    let (a, b) = (a as usize, b as usize);
                    let [ua, va] = state[a];
                    let [ub, vb] = state[b];
                    let f = (ub - ua) * k + (vb - va) * (c + kv_dt * k);
                    force[a] += f;
                    force[b] -= f;
                }
            }
            SpringModel::Length => {
                for ((&[a, b], (&k, &c)), &rest) in edges.zip(&self.rest) {
                    let (a, b) = (a as usize, b as usize);
                    let d = self.pos[b] - self.pos[a];
                    let l = d.length();
                    let spring = if l > 0.0 {
                        d * (k * (l - rest) / l)
                    } else {
                        DVec3::ZERO
                    };
                    let f = spring + (self.vel[b] - self.vel[a]) * (c + kv_dt * k);
                    self.force[a] += f;
                    self.force[b] -= f;
                }
            }
        }
        for &(i, f) in &self.held_forces {
            self.force[i as usize] += f;
        }
        if self.any_held {
            for i in 0..self.force.len() {
                self.force[i] = self.unheld_part(i, self.force[i]);
            }
        }
    }

    /// Kinetic energy (J).
    pub fn kinetic_energy(&self) -> f64 {
        self.vel
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| 0.5 * m * v.length_squared())
            .sum()
    }
    /// Elastic energy of the springs (J).
    pub fn elastic_energy(&self) -> f64 {
        self.edges
            .iter()
            .enumerate()
            .map(|(e, &[a, b])| {
                let (a, b) = (a as usize, b as usize);
                match self.model {
                    SpringModel::Linear => {
                        let d = (self.pos[b] - self.home[b]) - (self.pos[a] - self.home[a]);
                        0.5 * self.k[e] * d.length_squared()
                    }
                    SpringModel::Length => {
                        let l = (self.pos[b] - self.pos[a]).length();
                        0.5 * self.k[e] * (l - self.rest[e]).powi(2)
                    }
                }
            })
            .sum()
    }
    /// Kinetic + elastic + gravitational energy (relative to home) (J).
    pub fn total_energy(&self) -> f64 {
        let grav: f64 = (0..self.home.len())
            .map(|i| -self.mass[i] * self.gravity.dot(self.pos[i] - self.home[i]))
            .sum();
        self.kinetic_energy() + self.elastic_energy() + grav
    }
    /// Total momentum `Σ m v`.
    pub fn momentum(&self) -> Vector {
        self.vel
            .iter()
            .zip(&self.mass)
            .map(|(v, m)| *v * *m)
            .sum::<DVec3>()
            .as_vec3()
    }
    /// Largest displacement from home over the vertices (m).
    pub fn max_displacement(&self) -> Real {
        self.pos
            .iter()
            .zip(&self.home)
            .map(|(p, h)| (*p - *h).length())
            .fold(0.0, f64::max) as Real
    }
    /// Root-mean-square distance between this surface's positions and `other`'s (m).
    pub fn rms_difference(&self, other: &MassSpringSurface) -> Real {
        let n = self.pos.len().min(other.pos.len()).max(1);
        (self
            .pos
            .iter()
            .zip(&other.pos)
            .map(|(a, b)| (*a - *b).length_squared())
            .sum::<f64>()
            / n as f64)
            .sqrt() as Real
    }
    /// `true` once a step produced a non-finite state (the surface then stops stepping).
    pub fn diverged(&self) -> bool {
        self.diverged
    }
    /// `true` if every position and velocity is finite.
    pub fn is_finite(&self) -> bool {
        self.pos.iter().all(|p| p.is_finite()) && self.vel.iter().all(|v| v.is_finite())
    }

    // ----- Stepping -----

    /// Advances the surface by one time step with its integrator.
    ///
    /// A state that stops being finite (explicit Euler beyond its stability limit) is not
    /// advanced further: check [`MassSpringSurface::is_finite`] or
    /// [`MassSpringSurface::diverged`].
    pub fn step(&mut self) {
        if self.diverged {
            return;
        }
        match self.integrator {
            Integrator::ExplicitEuler => {
                self.compute_forces();
                let dt = self.dt;
                let mut probe = 0.0;
                for &v in &self.free {
                    let i = v as usize;
                    self.vel[i] += self.force[i] * (dt / self.mass[i]);
                    self.pos[i] += self.vel[i] * dt;
                    probe += self.pos[i].element_sum();
                }
                self.check_probe(probe);
            }
            Integrator::Filtered(_) => {
                if self.filter.is_none() && self.ensure_filter().is_err() {
                    return;
                }
                self.filtered_step();
            }
            Integrator::BaraffWitkin {
                max_iterations,
                tolerance,
            } => {
                self.compute_forces();
                self.baraff_witkin_step(max_iterations, tolerance as f64)
            }
        }
        self.time += self.dt;
    }

    /// NaN and infinity propagate into a sum of the new positions (every velocity went into
    /// them): one check per step instead of a scan.
    fn check_probe(&mut self, probe: f64) {
        if !probe.is_finite() {
            self.diverged = true;
        }
    }

    /// Eq. (8): `Δv = W M⁻¹ dt (Fⁿ + dt K vⁿ)`, i.e. `S Δv = dt (Fⁿ + dt K vⁿ)`.
    fn filtered_step(&mut self) {
        let dt = self.dt;
        self.accumulate_forces(dt);
        for (r, &v) in self.rhs.iter_mut().zip(&self.free) {
            *r = self.force[v as usize] * dt;
        }
        let Some(filter) = self.filter.as_mut() else {
            return;
        };
        filter.apply(&self.rhs, &mut self.dv);
        if self.free.len() == self.home.len()
            && matches!(filter.kind(), FilterKind::Neighbour { .. })
        {
            // The truncated filter drifts the rigid mode: add the mean velocity change that
            // makes the momentum change equal the applied impulse (module docs of `filter`).
            let (mut impulse, mut got, mut total) = (DVec3::ZERO, DVec3::ZERO, 0.0);
            for ((b, dv), &v) in self.rhs.iter().zip(&self.dv).zip(&self.free) {
                let m = self.mass[v as usize];
                impulse += *b;
                got += *dv * m;
                total += m;
            }
            let gamma = (impulse - got) / total;
            self.dv.iter_mut().for_each(|dv| *dv += gamma);
        }
        if self.any_held || !self.point_holds.is_empty() {
            constrain(
                filter,
                &self.free,
                &self.free_index,
                &self.held,
                &self.held_normal,
                &mut self.point_holds,
                &self.vel,
                &mut self.dv,
            );
        }
        let mut probe = 0.0;
        for (fi, &v) in self.free.iter().enumerate() {
            let i = v as usize;
            // A held vertex keeps the holder's normal velocity.
            let dv = self.unheld_part(i, self.dv[fi]);
            self.vel[i] += dv;
            self.pos[i] += self.vel[i] * dt;
            probe += self.pos[i].element_sum();
        }
        self.check_probe(probe);
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
