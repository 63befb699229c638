//! [`MassSpringSurfaceBuilder`]: a surface's mesh, springs, masses, pins and integrator,
//! checked and built.

use super::*;

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
    /// A surface on a mesh from [`crate::surface::meshing`] (planar meshing, OBJ files, generators).
    pub fn from_mesh(mesh: &crate::surface::meshing::SurfaceMesh) -> Self {
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
            held_list: Vec::new(),
            hold_impulse: vec![DVec3::ZERO; n],
            hold_impulse_at: Vec::new(),
            point_holds: Vec::new(),
            holders: Vec::new(),
            pushing: ActiveMemory::default(),
            watch: None,
        };
        s.build_vertex_edges();
        s.rebuild_free();
        s.ensure_filter()?;
        Ok(s)
    }
}

pub(super) fn check_spring(k: Real, c: Real) -> Result<(), SurfaceError> {
    if k > 0.0 && k.is_finite() && c >= 0.0 && c.is_finite() {
        Ok(())
    } else {
        Err(SurfaceError::InvalidSpring {
            stiffness: k as f64,
            damping: c as f64,
        })
    }
}
