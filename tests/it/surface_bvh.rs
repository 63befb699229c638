//! The contact search's BVH against brute force: a real surface stepping under gravity, pushed
//! about by teleports and re-pinned, at scales from 0.1 mm to 10 km; after every substep each
//! triangle whose bounds over the substep meet a query box, and each vertex inside it, must be
//! among the BVH's candidates, asked afresh or through a cache a drifting tool keeps.

use proptest::prelude::*;
use rapier_touch::geometry::{NearCache, SurfaceBvh, SurfaceSnapshot};
use rapier_touch::parry3d::bounding_volume::{Aabb, BoundingVolume};
use rapier_touch::prelude::*;
use rapier_touch::surface::meshing::{plate, plate_rim};
use rapier_touch::surface::Escaped;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]
    #[test]
    fn the_bvh_never_misses_what_a_scan_finds(
        scale_exp in -4.0f32..4.0,
        cells in 3u32..14,
        stiffness in 1.0f32..1000.0,
        slack_frac in 0.01f32..1.0,
        seed in any::<u64>(),
    ) {
        let size = 10f32.powf(scale_exp);
        let mesh = plate(size, size, cells, cells);
        let mut surface = MassSpringSurfaceBuilder::from_mesh(&mesh)
            .stiffness(stiffness)
            .damping(0.05 * stiffness)
            .pinned(plate_rim(cells, cells))
            .gravity(Vector::new(0.0, -9.81 * size, 0.0))
            .dt(1.0 / 240.0)
            .build()
            .unwrap();
        let edge = size / cells as f32;
        let slack = slack_frac * edge;
        let mut before = Vec::new();
        let mut now = Vec::new();
        surface.positions_into(&mut now);
        let mut bvh = SurfaceBvh::new(&now, surface.triangles(), slack);
        surface.watch_motion(slack);
        let mut rng = seed;
        let mut next = move || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 11) as f32 / (1u64 << 53) as f32
        };
        let n = now.len() as u32;
        let (mut moved, mut tris, mut verts) = (Vec::new(), Vec::new(), Vec::new());
        // A tool's box drifting over the plate, asked through a cache every substep.
        let mut cache = NearCache::default();
        let mut tool = Vector::new(next() * size, -0.1 * size, next() * size);
        let drift = Vector::new(next() - 0.5, 0.1 * (next() - 0.5), next() - 0.5) * (0.02 * size);
        let tool_half = Vector::splat(0.1 * size) * (0.2 + next());
        for _ in 0..60 {
            surface.positions_into(&mut before);
            surface.step();
            // Tools teleport a few vertices by up to two edges.
            for _ in 0..(next() * 4.0) as u32 {
                let v = (next() * n as f32) as u32 % n;
                let p = surface.position(v)
                    + Vector::new(next() - 0.5, next() - 0.5, next() - 0.5) * (4.0 * edge);
                surface.set_state(v, p, Vector::ZERO).unwrap();
            }
            // Now and then a pin comes or goes (pinned vertices jump home).
            if next() < 0.05 {
                let v = (next() * n as f32) as u32 % n;
                let pinned = surface.is_pinned(v);
                surface.set_pinned(v, !pinned).unwrap();
            }
            surface.positions_into(&mut now);
            match surface.take_escaped(&mut moved) {
                Escaped::Listed => bvh.update(&moved, &now, &before),
                Escaped::All => bvh.rebuild(&now, Some(&before)),
            }
            let snapshot = SurfaceSnapshot {
                before: &before,
                now: &now,
                triangles: surface.triangles(),
            };
            tool += drift;
            let query = Aabb::new(tool - tool_half, tool + tool_half);
            bvh.near_cached(&mut cache, &query, 0.2 * tool_half.x, &mut tris, &mut verts);
            for t in 0..surface.triangles().len() as u32 {
                let hits = snapshot.swept_bounds(t).unwrap().intersects(&query);
                prop_assert!(!hits || tris.binary_search(&t).is_ok(), "cached: triangle {t} missed");
            }
            // The coupling's filter of a tool's candidates (`triangles_meeting`, chunked and
            // fetched ahead) against bounds computed here: the same triangles in the same
            // order, an index out of range dropped.
            let mut asked = tris.clone();
            asked.insert(asked.len() / 2, u32::MAX);
            let mut kept = Vec::new();
            snapshot.triangles_meeting(&asked, &query, &mut kept);
            let expected: Vec<u32> = tris
                .iter()
                .copied()
                .filter(|&t| {
                    let idx = surface.triangles()[t as usize];
                    let (lo, hi) = idx
                        .iter()
                        .flat_map(|&v| [before[v as usize], now[v as usize]])
                        .fold((Vector::splat(f32::MAX), Vector::splat(f32::MIN)), |(l, h), p| {
                            (l.min(p), h.max(p))
                        });
                    lo.cmple(query.maxs).all() && hi.cmpge(query.mins).all()
                })
                .collect();
            prop_assert_eq!(kept, expected);
            for (v, p) in now.iter().enumerate() {
                let inside = query.contains_local_point(*p);
                prop_assert!(
                    !inside || verts.binary_search(&(v as u32)).is_ok(),
                    "cached: vertex {v} missed"
                );
            }
            for _ in 0..8 {
                let centre = Vector::new(next() * size, (next() - 0.7) * size, next() * size);
                let half = Vector::new(next(), next(), next()) * (0.3 * size);
                let query = Aabb::new(centre - half, centre + half);
                bvh.triangles_in(&query, &mut tris);
                for t in 0..surface.triangles().len() as u32 {
                    let hits = snapshot.swept_bounds(t).unwrap().intersects(&query);
                    prop_assert!(!hits || tris.binary_search(&t).is_ok(), "triangle {t} missed");
                }
                bvh.vertices_in(&query, &mut verts);
                verts.sort_unstable();
                for (v, p) in now.iter().enumerate() {
                    let inside = query.contains_local_point(*p);
                    prop_assert!(
                        !inside || verts.binary_search(&(v as u32)).is_ok(),
                        "vertex {v} missed"
                    );
                }
            }
        }
    }
}

/// Most of a surface moving past the slack at once (a plate waving and drifting away, every
/// vertex further than the slack each substep): the BVH refits every leaf in place instead of
/// walking each one's path, and still misses nothing a scan finds, asked afresh and through a
/// drifting tool's cache, including far from where the tree was built.
#[test]
fn the_bvh_refit_in_place_after_a_wholesale_move_misses_nothing() {
    let (size, cells) = (2.0f32, 24u32);
    let mesh = plate(size, size, cells, cells);
    let edge = size / cells as f32;
    let slack = 0.1 * edge;
    let home = mesh.vertices.clone();
    let wave = |t: f32| -> Vec<Vector> {
        home.iter()
            .map(|p| {
                let y = 0.3 * size * (3.0 * p.x / size + 2.0 * p.z / size + t).sin();
                *p + Vector::new(0.4 * t * size, y, 0.0)
            })
            .collect()
    };
    let mut now = home.clone();
    let mut bvh = SurfaceBvh::new(&now, &mesh.triangles, slack);
    let all: Vec<u32> = (0..now.len() as u32).collect();
    let mut cache = NearCache::default();
    let (mut tris, mut verts) = (Vec::new(), Vec::new());
    for step in 1..=30 {
        let before = std::mem::replace(&mut now, wave(step as f32 * 0.1));
        // Every vertex moved more than the slack.
        assert!(now
            .iter()
            .zip(&before)
            .all(|(a, b)| (*a - *b).length() > slack));
        bvh.update(&all, &now, &before);
        let snapshot = SurfaceSnapshot {
            before: &before,
            now: &now,
            triangles: &mesh.triangles,
        };
        let centre = now[(step * 37) % now.len()];
        for (k, half) in [0.05f32, 0.2, 0.6].into_iter().enumerate() {
            let query = Aabb::new(
                centre - Vector::splat(half * size),
                centre + Vector::splat(half * size),
            );
            if k == 0 {
                bvh.near_cached(&mut cache, &query, 0.2 * half * size, &mut tris, &mut verts);
            } else {
                bvh.triangles_in(&query, &mut tris);
                bvh.vertices_in(&query, &mut verts);
                verts.sort_unstable();
            }
            let mut found = 0;
            for t in 0..mesh.triangles.len() as u32 {
                if snapshot.swept_bounds(t).unwrap().intersects(&query) {
                    found += 1;
                    assert!(
                        tris.binary_search(&t).is_ok(),
                        "step {step}: triangle {t} missed"
                    );
                }
            }
            assert!(found > 0, "step {step}: the query meets the surface");
            for (v, p) in now.iter().enumerate() {
                if query.contains_local_point(*p) {
                    assert!(
                        verts.binary_search(&(v as u32)).is_ok(),
                        "step {step}: vertex {v} missed"
                    );
                }
            }
        }
    }
}
