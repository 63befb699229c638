//! The soft-surface model's bad input: empty and degenerate meshes, NaN and out-of-range
//! values, bad point presses and force profiles are errors that change nothing; the neighbour
//! filter's fallback to the exact filter is logged once per surface.

use crate::surface::grid;
use rapier_touch::prelude::*;

#[test]
fn bad_input_is_an_error() {
    let (v, t) = grid(2, 2, 1.0);
    let b = || MassSpringSurfaceBuilder::new(v.clone(), t.clone());
    assert_eq!(
        MassSpringSurfaceBuilder::new(vec![], vec![])
            .build()
            .unwrap_err(),
        SurfaceError::EmptyMesh
    );
    assert!(matches!(
        b().mass(MassDistribution::PerVertex(0.0)).build(),
        Err(SurfaceError::NonPositiveMass(_))
    ));
    assert!(matches!(
        b().mass(MassDistribution::Total(-1.0)).build(),
        Err(SurfaceError::NonPositiveMass(_))
    ));
    assert!(matches!(
        b().stiffness(0.0).build(),
        Err(SurfaceError::InvalidSpring { .. })
    ));
    assert!(matches!(
        b().damping(-1.0).build(),
        Err(SurfaceError::InvalidSpring { .. })
    ));
    assert!(matches!(
        b().dt(0.0).build(),
        Err(SurfaceError::InvalidTimeStep(_))
    ));
    assert!(matches!(
        b().dt(f32::NAN).build(),
        Err(SurfaceError::InvalidTimeStep(_))
    ));
    assert!(matches!(
        b().pinned([99]).build(),
        Err(SurfaceError::VertexOutOfRange { .. })
    ));
    assert!(matches!(
        b().edge_stiffness(0, 8, 1.0).build(),
        Err(SurfaceError::NotAnEdge(0, 8))
    ));
    let mut nan = v.clone();
    nan[3].y = f32::NAN;
    assert_eq!(
        MassSpringSurfaceBuilder::new(nan, t.clone())
            .build()
            .unwrap_err(),
        SurfaceError::NonFiniteVertex(3)
    );
    assert!(matches!(
        MassSpringSurfaceBuilder::new(v.clone(), vec![[0, 0, 1], [0, 1, 2]]).build(),
        Err(SurfaceError::AllTrianglesDegenerate(2))
    ));
    assert!(matches!(
        MassSpringSurfaceBuilder::network(v.clone(), vec![[0, 1]])
            .mass(MassDistribution::AreaDensity(1.0))
            .build(),
        Err(SurfaceError::NonPositiveMass(_))
    ));
    // Degenerate triangles dropped and reported; an isolated vertex kept and free.
    let mut v2 = v.clone();
    v2.push(Vector::new(5.0, 5.0, 5.0));
    let mut t2 = t.clone();
    t2.push([0, 0, 3]);
    let mut s = MassSpringSurfaceBuilder::new(v2, t2)
        .gravity(Vector::new(0.0, -9.81, 0.0))
        .build()
        .unwrap();
    assert_eq!(s.dropped_triangles(), &[t.len() as u32]);
    assert_eq!(s.isolated_vertices(), &[9]);
    assert_eq!(
        s.set_force(0, Vector::new(f32::NAN, 0.0, 0.0)),
        Err(SurfaceError::NonFiniteForce)
    );
    assert!(s.set_force(100, Vector::X).is_err());
    assert!(s.set_dt(-1.0).is_err());
    for _ in 0..10 {
        s.step();
    }
    assert!(s.is_finite());
    assert!(s.position(9).y < 5.0, "the isolated vertex falls freely");
}

/// Bad point presses are errors and change nothing; a press on pinned vertices only, or on a
/// held vertex, is not held; a good one moves its point exactly by its depth.
#[test]
fn bad_point_presses_are_errors() {
    let (v, t) = grid(2, 2, 1.0);
    let mut s = MassSpringSurfaceBuilder::new(v, t)
        .pinned([0])
        .mass(MassDistribution::PerVertex(1.0))
        .build()
        .unwrap();
    let down = Vector::new(0.0, -1.0, 0.0);
    let before: Vec<Vector> = (0..s.num_vertices() as u32)
        .map(|i| s.position(i))
        .collect();
    type Press<'a> = (&'a [(u32, f32)], Vector, f32, f32);
    let bad: [Press<'_>; 8] = [
        (&[], down, 0.01, 0.0),
        (&[(1, 0.5), (2, 0.5), (3, 0.0), (4, 0.0)], down, 0.01, 0.0),
        (&[(1, -0.5), (2, 1.5)], down, 0.01, 0.0),
        (&[(1, 0.0), (2, 0.0)], down, 0.01, 0.0),
        (&[(1, f32::NAN), (2, 0.5)], down, 0.01, 0.0),
        (&[(1, 0.5), (2, 0.5)], Vector::ZERO, 0.01, 0.0),
        (&[(1, 0.5), (2, 0.5)], down, f32::INFINITY, 0.0),
        (&[(1, 0.5), (2, 0.5)], down, 0.01, f32::NAN),
    ];
    for (w, n, d, vel) in bad {
        assert_eq!(
            s.press_point(w, n, d, vel),
            Err(SurfaceError::InvalidPointHold),
            "{w:?} {n:?} {d} {vel}"
        );
    }
    assert!(matches!(
        s.press_point(&[(99, 1.0)], down, 0.01, 0.0),
        Err(SurfaceError::VertexOutOfRange { .. })
    ));
    // Friction that is not a number, negative, or kinetic above static.
    let coulomb = |v: Vector, s: f32, d: f32| Tangential::Coulomb {
        velocity: v,
        static_coefficient: s,
        dynamic_coefficient: d,
    };
    for tangential in [
        coulomb(Vector::X, 0.5, -0.1),
        coulomb(Vector::X, 0.2, 0.3),
        coulomb(Vector::X, f32::NAN, 0.3),
        coulomb(Vector::X, f32::INFINITY, 0.3),
        coulomb(Vector::new(f32::NAN, 0.0, 0.0), 0.5, 0.3),
        Tangential::Grasped(Vector::splat(f32::INFINITY)),
    ] {
        let press = PointPress {
            vertices: &[(1, 0.5), (2, 0.5)],
            normal: down,
            depth: 0.01,
            normal_velocity: 0.0,
            tangential,
            holder: None,
        };
        assert_eq!(
            s.press_points(&[press]),
            Err(SurfaceError::InvalidPointHold),
            "{tangential:?}"
        );
    }
    let after: Vec<Vector> = (0..s.num_vertices() as u32)
        .map(|i| s.position(i))
        .collect();
    assert_eq!(before, after);
    assert_eq!(s.num_point_holds(), 0);
    // Only a pinned vertex: nothing to move.
    assert_eq!(s.press_point(&[(0, 1.0)], down, 0.01, 0.0), Ok(None));
    // Beside a held vertex: the held vertex stays where its holder keeps it, and the free one
    // takes the whole press (the midpoint 1 cm down: vertex 5 by 2 cm).
    s.hold(4).unwrap();
    let (held0, free0) = (s.position(4), s.position(5));
    assert!(s
        .press_point(&[(4, 0.5), (5, 0.5)], down, 0.01, 0.0)
        .unwrap()
        .is_some());
    assert_eq!(s.position(4), held0);
    assert!((s.position(5) - free0 - down * 0.02).length() < 1e-6);
    // Mostly on the held vertex (less than a quarter of the weight free): its holder carries
    // it.
    assert_eq!(
        s.press_point(&[(4, 0.8), (6, 0.2)], down, 0.01, 0.0),
        Ok(None)
    );
    // Two free vertices: the midpoint moves 1 cm down, equal masses share it equally.
    let id = s
        .press_point(&[(1, 0.5), (2, 0.5)], down, 0.01, 0.0)
        .unwrap();
    assert!(id.is_some());
    let mid = (s.position(1) + s.position(2)) * 0.5;
    let mid0 = (before[1] + before[2]) * 0.5;
    assert!((mid - mid0 - down * 0.01).length() < 1e-6);
    assert!((s.position(1) - s.position(2) - (before[1] - before[2])).length() < 1e-6);
}

/// Messages the crate logs, kept by a logger installed once for the test binary.
fn logged() -> &'static std::sync::Mutex<Vec<String>> {
    struct Keep;
    static LINES: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    impl log::Log for Keep {
        fn enabled(&self, _: &log::Metadata) -> bool {
            true
        }
        fn log(&self, record: &log::Record) {
            if let Ok(mut lines) = LINES.lock() {
                lines.push(format!("{}: {}", record.level(), record.args()));
            }
        }
        fn flush(&self) {}
    }
    static KEEP: Keep = Keep;
    if log::set_logger(&KEEP).is_ok() {
        log::set_max_level(log::LevelFilter::Warn);
    }
    &LINES
}

/// The neighbour filter's fallback is a `log` warning, once per surface however often the
/// filter is rebuilt; a surface that does not fall back logs nothing.
#[test]
fn the_filter_fallback_is_logged_once_per_surface() {
    let lines = logged();
    // A 7 x 5 grid (48 vertices): a size no other test logs about.
    let (v, t) = grid(7, 5, 1.0);
    let mut s = MassSpringSurfaceBuilder::new(v.clone(), t.clone())
        .stiffness(1e4)
        .mass(MassDistribution::PerVertex(1e-3))
        .integrator(Integrator::NEIGHBOUR)
        .build()
        .unwrap();
    assert!(s.filter_fallback());
    s.set_dt(1.0 / 30.0).unwrap();
    s.set_spring(2e4, 1.0).unwrap();
    assert!(s.filter_fallback());
    let ours = |lines: &[String]| {
        lines
            .iter()
            .filter(|l| l.starts_with("WARN") && l.contains(" 48-vertex surface"))
            .count()
    };
    assert_eq!(
        ours(&lines.lock().unwrap()),
        1,
        "{:?}",
        lines.lock().unwrap()
    );
    // A second surface falling back logs once more; a soft one not at all.
    let other = MassSpringSurfaceBuilder::new(v.clone(), t.clone())
        .stiffness(1e4)
        .mass(MassDistribution::PerVertex(1e-3))
        .integrator(Integrator::NEIGHBOUR)
        .build()
        .unwrap();
    assert!(other.filter_fallback());
    let soft = MassSpringSurfaceBuilder::new(v, t)
        .stiffness(1.0)
        .damping(0.0)
        .dt(0.01)
        .integrator(Integrator::NEIGHBOUR)
        .build()
        .unwrap();
    assert!(!soft.filter_fallback());
    assert_eq!(ours(&lines.lock().unwrap()), 2);
}

/// Force schedules with NaN or infinite times, a negative ramp duration or an end before the
/// start are errors, and nothing is scheduled.
#[test]
fn bad_force_profiles_are_errors() {
    let (v, t) = grid(2, 2, 1.0);
    let mut s = MassSpringSurfaceBuilder::new(v, t).build().unwrap();
    let f = Vector::Y;
    let ramp = |start: f32, duration: f32| ForceProfile::Ramp {
        force: f,
        start,
        duration,
    };
    let step = |start: f32, end: Option<f32>| ForceProfile::Step {
        force: f,
        start,
        end,
    };
    for p in [
        ramp(f32::NAN, 1.0),
        ramp(f32::INFINITY, 1.0),
        ramp(0.0, f32::NAN),
        ramp(0.0, f32::INFINITY),
        ramp(0.0, -1.0),
        step(f32::NAN, None),
        step(f32::NEG_INFINITY, None),
        step(0.0, Some(f32::NAN)),
        step(1.0, Some(0.5)),
    ] {
        assert_eq!(
            s.add_force_schedule(vec![1], p),
            Err(SurfaceError::InvalidForceProfile),
            "{p:?}"
        );
    }
    let nan_force = ForceProfile::Step {
        force: Vector::new(f32::NAN, 0.0, 0.0),
        start: 0.0,
        end: None,
    };
    assert_eq!(
        s.add_force_schedule(vec![1], nan_force),
        Err(SurfaceError::NonFiniteForce)
    );
    // Nothing was scheduled: the surface stays at rest.
    for _ in 0..10 {
        s.step();
    }
    assert_eq!(s.max_displacement(), 0.0);
    // A zero-length ramp is a step, and is accepted.
    assert!(s.add_force_schedule(vec![1], ramp(0.0, 0.0)).is_ok());
}

/// Rigid holders ([`MassSpringSurface::set_holders`]) that are not finite or have a negative
/// inverse mass or inertia are errors and leave the holders as they were; a press naming a
/// holder past the list, or with a non-finite pressing point, is an error and presses nothing.
#[test]
fn bad_rigid_holders_are_errors() {
    use rapier_touch::surface::RigidHolder;
    let (v, t) = grid(2, 2, 1.0);
    let mut s = MassSpringSurfaceBuilder::new(v, t)
        .pinned([0])
        .build()
        .unwrap();
    let good = RigidHolder::point_mass(0.1, Vector::ZERO, Vector::ZERO);
    s.set_holders(&[good]).unwrap();
    let nan = RigidHolder {
        velocity: Vector::new(f32::NAN, 0.0, 0.0),
        ..good
    };
    let negative = RigidHolder {
        inverse_mass: rapier_touch::rapier3d::math::Matrix::from_diagonal(Vector::new(
            -1.0, 1.0, 1.0,
        )),
        ..good
    };
    let far = RigidHolder {
        centre: Vector::splat(f32::INFINITY),
        ..good
    };
    for bad in [nan, negative, far] {
        assert_eq!(
            s.set_holders(&[good, bad]),
            Err(SurfaceError::InvalidHolder)
        );
    }
    // Still the one good holder: index 0 works, index 1 does not.
    let press = |holder| PointPress {
        vertices: &[(4, 1.0)],
        normal: Vector::new(0.0, -1.0, 0.0),
        depth: 0.01,
        normal_velocity: 0.0,
        tangential: Tangential::Free,
        holder,
    };
    assert_eq!(
        s.press_points(&[press(Some((1, Vector::ZERO)))]),
        Err(SurfaceError::InvalidPointHold)
    );
    assert_eq!(
        s.press_points(&[press(Some((0, Vector::splat(f32::NAN))))]),
        Err(SurfaceError::InvalidPointHold)
    );
    assert_eq!(s.num_point_holds(), 0);
    assert_eq!(
        s.press_points(&[press(Some((0, Vector::ZERO)))]),
        Ok(vec![Some(0)])
    );
    assert!(s.holder_impulse(0).is_some() && s.holder_impulse(1).is_none());
}
