//! The paper's Fig. 7 organ under six forces: the scene of the `constrained_790` example.

use super::paper_organ;
use crate::math::{Real, Vector};
use crate::surface::meshing::PlanarMesh;
use crate::surface::{
    ForceProfile, Integrator, MassDistribution, MassSpringSurface, MassSpringSurfaceBuilder,
};
use std::collections::BTreeSet;

/// The integrators the `plate_step_force` and `constrained_790` examples run side by side,
/// with their printed names: explicit Euler, the exact filter, the paper's neighbour filter
/// and Baraff-Witkin.
pub const COMPARED_INTEGRATORS: [(&str, Integrator); 4] = [
    ("explicit Euler", Integrator::ExplicitEuler),
    ("exact filter", Integrator::EXACT),
    ("neighbour filter", Integrator::NEIGHBOUR),
    ("Baraff-Witkin", Integrator::BARAFF_WITKIN),
];

/// A run has diverged: the surface's f64 state is no longer finite, or too large for the f32
/// accessors (explicit Euler spends a few steps between the two).
pub fn diverged(s: &MassSpringSurface) -> bool {
    !s.is_finite() || !s.max_displacement().is_finite() || !s.total_energy().is_finite()
}

/// The paper's Fig. 7: a deformable object of about 790 nodes with a constrained internal
/// boundary and 6 external forces (the `constrained_790` example and `fig7_organ.png`).
///
/// [`paper_organ_outline`] meshed with its own target edge (5.28 mm): 788 nodes, a kidney
/// shape about 0.14 m × 0.10 m in the plane y = 0. The vertices of its internal constraint
/// polyline ([`Self::polyline`]) are pinned; the outer boundary is free, so the organ hangs on
/// the polyline. The paper's linear springs, 1 g per vertex, k = 0.1 N/m, c = 0.001 N·s/m per
/// edge, dt = 1/60 s, no gravity. The forces ([`Self::forces`]) act on 6 disjoint groups of
/// free vertices ([`Self::groups`]).
///
/// ```
/// use rapier_touch::prelude::*;
/// use rapier_touch::scenes::Fig7Organ;
/// let organ = Fig7Organ::new();
/// let mut s = organ.surface(Integrator::EXACT);
/// for _ in 0..60 {
///     s.step();
/// }
/// assert!(s.max_displacement() > 0.0);
/// ```
///
/// [`paper_organ_outline`]: crate::surface::meshing::paper_organ_outline
#[derive(Clone, Debug)]
pub struct Fig7Organ {
    /// The planar mesh (788 nodes).
    pub planar: PlanarMesh,
    /// The pinned internal constraint polyline, in order.
    pub polyline: Vec<u32>,
    /// Each force's vertex group: the free vertex nearest to its site and its free edge
    /// neighbours.
    pub groups: Vec<Vec<u32>>,
}

impl Default for Fig7Organ {
    fn default() -> Self {
        Self::new()
    }
}

impl Fig7Organ {
    /// Time step (s).
    pub const DT: Real = 1.0 / 60.0;
    /// Mass of every vertex (kg).
    pub const MASS: Real = 0.001;
    /// Stiffness of every edge (N/m).
    pub const K: Real = 0.1;
    /// Damping of every edge (N·s/m).
    pub const C: Real = 0.001;

    /// Meshes the organ and finds the force groups. Panics if the mesh does not have exactly
    /// one internal constraint polyline or the groups overlap (neither happens with spade 2.15).
    pub fn new() -> Self {
        let planar = paper_organ();
        assert_eq!(planar.constrained.len(), 1, "one internal constraint");
        let polyline = planar.constrained[0].clone();
        let pinned: BTreeSet<u32> = polyline.iter().copied().collect();
        let mesh = &planar.mesh;
        let mut adjacent = vec![BTreeSet::new(); mesh.num_vertices()];
        for t in &mesh.triangles {
            for k in 0..3 {
                adjacent[t[k] as usize].insert(t[(k + 1) % 3]);
                adjacent[t[(k + 1) % 3] as usize].insert(t[k]);
            }
        }
        let groups: Vec<Vec<u32>> = Self::forces()
            .iter()
            .map(|([u, v], _)| {
                let site = Vector::new(*u, 0.0, *v);
                let centre = (0..mesh.num_vertices() as u32)
                    .filter(|i| !pinned.contains(i))
                    .min_by(|&a, &b| {
                        let da = (mesh.vertices[a as usize] - site).length();
                        let db = (mesh.vertices[b as usize] - site).length();
                        da.total_cmp(&db)
                    })
                    .expect("free vertices");
                std::iter::once(centre)
                    .chain(adjacent[centre as usize].iter().copied())
                    .filter(|i| !pinned.contains(i))
                    .collect()
            })
            .collect();
        let mut seen = BTreeSet::new();
        for g in &groups {
            assert!(
                g.iter().all(|i| seen.insert(*i)),
                "force groups are disjoint"
            );
        }
        Fig7Organ {
            planar,
            polyline,
            groups,
        }
    }

    /// The six force sites `(u, v)` and their profiles (each vertex of a group receives the
    /// profile's force):
    /// 1. (0.04, 0.03): step, 1 mN down (-y), from t = 0;
    /// 2. (-0.02, 0.03): ramp to 1 mN up (+y) over 2 s from t = 0;
    /// 3. (0.07, 0.0): step, 1 mN outward in the plane (+x), from t = 1 s to t = 6 s;
    /// 4. (0.0, -0.035): ramp to 1 mN in the plane (-z) over 3 s from t = 0.5 s;
    /// 5. (-0.035, -0.03): step, 1 mN along (-x, -y)/√2, from t = 2 s;
    /// 6. (0.055, -0.03): ramp to 1 mN along (0, -0.6, 0.8) over 2 s from t = 3 s.
    pub fn forces() -> [([Real; 2], ForceProfile); 6] {
        let mn = 0.001;
        let r = std::f32::consts::FRAC_1_SQRT_2;
        [
            (
                [0.04, 0.03],
                ForceProfile::Step {
                    force: Vector::new(0.0, -mn, 0.0),
                    start: 0.0,
                    end: None,
                },
            ),
            (
                [-0.02, 0.03],
                ForceProfile::Ramp {
                    force: Vector::new(0.0, mn, 0.0),
                    start: 0.0,
                    duration: 2.0,
                },
            ),
            (
                [0.07, 0.0],
                ForceProfile::Step {
                    force: Vector::new(mn, 0.0, 0.0),
                    start: 1.0,
                    end: Some(6.0),
                },
            ),
            (
                [0.0, -0.035],
                ForceProfile::Ramp {
                    force: Vector::new(0.0, 0.0, -mn),
                    start: 0.5,
                    duration: 3.0,
                },
            ),
            (
                [-0.035, -0.03],
                ForceProfile::Step {
                    force: Vector::new(-mn * r, -mn * r, 0.0),
                    start: 2.0,
                    end: None,
                },
            ),
            (
                [0.055, -0.03],
                ForceProfile::Ramp {
                    force: Vector::new(0.0, -0.6 * mn, 0.8 * mn),
                    start: 3.0,
                    duration: 2.0,
                },
            ),
        ]
    }

    /// The organ's surface with `integrator` and the six force schedules, at rest (the
    /// neighbour filter never falls back to the exact one: `neighbour_max_error` is infinite).
    pub fn surface(&self, integrator: Integrator) -> MassSpringSurface {
        let mesh = &self.planar.mesh;
        let mut s = MassSpringSurfaceBuilder::new(mesh.vertices.clone(), mesh.triangles.clone())
            .stiffness(Self::K)
            .damping(Self::C)
            .mass(MassDistribution::PerVertex(Self::MASS))
            .pinned(self.polyline.iter().copied())
            .dt(Self::DT)
            .integrator(integrator)
            .neighbour_max_error(Real::INFINITY)
            .build()
            .expect("valid organ mesh");
        for (g, (_, profile)) in self.groups.iter().zip(Self::forces()) {
            s.add_force_schedule(g.clone(), profile)
                .expect("valid force");
        }
        s
    }
}
