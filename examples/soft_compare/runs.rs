//! One run of each engine over a configuration: the crate's surface set, rapier's soft body.

use super::*;

/// The crate: the surface attached to a fixed body, the tools pressing it, `SurfaceSet::step`.
pub(crate) fn run_touch(p: &Plate, cfg: Config) -> Row {
    let mut world = empty_world(cfg.dt);
    let ground = world.insert_body(RigidBodyBuilder::fixed());
    let mut set = SurfaceSet::new();
    let options = AttachOptions {
        substeps: 1,
        collider: true,
    };
    let h = set
        .insert(
            p.surface(cfg.dt, Integrator::EXACT),
            ground,
            &mut world,
            options,
        )
        .expect("attached");
    let sites = tool_sites(cfg.tools);
    let tools = insert_tools(&mut world, &sites, 0.0, cfg.friction);
    for t in &tools {
        set.add_tool(*t, &mut world).unwrap();
        let friction = Friction::new(cfg.friction, cfg.friction).expect("valid friction");
        set.set_tool_friction(*t, friction).unwrap();
    }
    let mut track = Tracker::new(cfg);
    let mut forces = Vec::with_capacity(tools.len());
    for k in 0..cfg.steps {
        let t = (k + 1) as Real * cfg.dt;
        drive_tools(&mut world, &tools, &sites, t, 0.0);
        let t0 = Instant::now();
        set.step(&mut world);
        track.times.push(t0.elapsed().as_secs_f64());
        let s = &set.get(h).expect("surface").surface;
        track.displacement(if s.is_finite() {
            s.max_displacement()
        } else {
            Real::NAN
        });
        forces.clear();
        forces.extend(
            tools
                .iter()
                .map(|t| set.tool_reaction(*t).map_or(Vector::ZERO, |r| r.force)),
        );
        track.forces(t, &forces);
    }
    track.row("touch", p.nodes())
}

/// rapier: a soft body on the same vertices, triangles and edges, the same tools, `world.step`.
pub(crate) fn run_rapier(p: &Plate, edges: &[[u32; 2]], cfg: Config) -> Row {
    let mut world = empty_world(cfg.dt);
    let (f, zeta) = rapier_softness(p.vertex_mass());
    let builder = SoftBodyBuilder::new(p.mesh.vertices.clone())
        .edges(edges.to_vec())
        .surface(p.mesh.triangles.clone())
        .pinned_particles(p.rim.iter().copied())
        .mass(TOTAL_MASS)
        .material(SoftBodyMaterial {
            edge_softness: SpringCoefficients::new(f, zeta),
            ..Default::default()
        })
        .particle_radius(SKIN);
    let handle = world.insert_soft_body(builder);
    let sites = tool_sites(cfg.tools);
    let tools = insert_tools(&mut world, &sites, SKIN, cfg.friction);
    let mut track = Tracker::new(cfg);
    let mut forces = Vec::with_capacity(tools.len());
    for k in 0..cfg.steps {
        let t = (k + 1) as Real * cfg.dt;
        drive_tools(&mut world, &tools, &sites, t, SKIN);
        let t0 = Instant::now();
        world.step();
        track.times.push(t0.elapsed().as_secs_f64());
        let d = world.soft_bodies[handle]
            .particle_positions()
            .zip(&p.mesh.vertices)
            .map(|(x, home)| (x - *home).length())
            .fold(
                0.0,
                |a: Real, d| if d.is_finite() { a.max(d) } else { Real::NAN },
            );
        track.displacement(d);
        // The impulses rapier wrote back into each tool's contact pairs over the step, over dt
        // (a manifold's normal points from collider1 to collider2).
        forces.clear();
        forces.extend(tools.iter().map(|tool| {
            world
                .contact_pairs_with(*tool)
                .map(|pair| {
                    let sign = if pair.collider1 == *tool { -1.0 } else { 1.0 };
                    pair.total_impulse() * (sign / cfg.dt)
                })
                .sum::<Vector>()
        }));
        track.forces(t, &forces);
    }
    track.row("rapier", p.nodes())
}
