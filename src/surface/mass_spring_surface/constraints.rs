//! What holds a surface from outside during a filtered step: vertex holds (a tool holding a
//! vertex, fully or along a normal) and point holds (a tool's vertex or edge pressing a point
//! inside a triangle or on an edge, which loads the vertices around it by barycentric
//! weights). Both are solved together through the filter's columns, so the rest of the
//! surface responds to them as to moving pins.

use super::active_set::{give_back, solve_pushing, zeroed};
use super::blocks::independent_blocks;
use super::point_hold::{ActiveMemory, PointHold, Remembered};
use super::rigid_holder::{give_impulses, merge_blocks, motion, HolderRow, HolderState};
use crate::surface::filter::{Filter, FilterKind};
use friction::{unit, Grip, HolderCuts, SlidingPoint, FRICTION_PASSES, HOLDER_FRICTION_PASSES};
use glamx::DVec3;
use rows::{book_impulses, rows, surface_independent, targets, Con, Row, Rows};

mod friction;
mod rows;

/// The holders' impulses in the filtered step. Each constraint is a direction `d` applied to a
/// weighted set of vertices: a sliding vertex hold (its normal, weight 1), a full vertex hold
/// (the three axes), a point hold (its normal, its barycentric weights). With `J` the
/// constraints' rows and `P = S⁻¹ = W M⁻¹` the filter as applied to impulses (exact or
/// neighbour), it finds the impulses `λ` with `J (Δv + P Jᵀ λ) = 0` — a small dense system
/// `J P Jᵀ λ = -J Δv`, the capacitance matrix of the held set — and adds `P Jᵀ λ` to `Δv`. The
/// rest of the surface then responds to the holds as to pins moving where the holders put them,
/// and a point hold whose impulse would pull is let go (contact only pushes),
/// at any `s`, without refactoring the filter: `P`'s columns for the held vertices are the
/// filter's own rows (neighbour) or one cached solve each (exact). A point its holder carries
/// (static friction) has two more rows, bilateral, along its tangent plane: they hold its
/// tangential velocity at the holder's while its normal row pushes, and go with it when it is
/// let go. A point on a rigid holder is held at the holder's velocity after the step: the
/// holder's compliance joins `A` between its rows ([`super::rigid_holder`]), and each holder
/// takes its rows' impulses.
#[allow(clippy::too_many_arguments)]
pub(super) fn constrain(
    filter: &mut Filter,
    holders: &mut [HolderState],
    free: &[u32],
    free_index: &[u32],
    (held, held_normal, hold_impulse): (&[bool], &[DVec3], &mut [DVec3]),
    points: &mut [PointHold],
    vel: &[DVec3],
    dv: &mut [DVec3],
    memory: &mut ActiveMemory,
) -> DVec3 {
    let Some(Rows {
        list,
        cons,
        normal_row,
        tangent_rows,
        known,
    }) = rows(free, free_index, held, held_normal, points)
    else {
        return DVec3::ZERO;
    };
    let h = list.len();
    // The rows on rigid holders, and the holder's compliance between two rows.
    // (Empty without holders: the kinematic tools' solve pays nothing for them.)
    let holder_rows: Vec<Option<HolderRow>> = if holders.is_empty() {
        Vec::new()
    } else {
        cons.iter()
            .map(|(d, _, _, row)| match *row {
                Row::Normal(pi) | Row::Tangent(pi) => {
                    let (k, arm) = points[pi].holder?;
                    holders.get(k).map(|s| HolderRow::new(k, s, *d, arm))
                }
                Row::Vertex => None,
            })
            .collect()
    };
    let any_holder = holder_rows.iter().any(Option::is_some);
    let coupling = |a: usize, b: usize| match (holder_rows.get(a), holder_rows.get(b)) {
        (Some(Some(x)), Some(Some(y))) => x.coupling(y),
        _ => 0.0,
    };
    // What the holders' motion under some impulses takes off row `c`.
    let holder_along = |c: usize, m: &[(DVec3, DVec3)]| {
        if m.is_empty() {
            return 0.0;
        }
        holder_rows
            .get(c)
            .copied()
            .flatten()
            .map_or(0.0, |r| r.along(m))
    };
    // P restricted to the involved vertices (h × h), one column read each.
    let mut p_hh = zeroed(&mut memory.scratch.block, h, h);
    filter.gather_block(&list, p_hh.as_mut_slice());
    let m = cons.len();
    // P's column k (column-major storage): P[(j, k)] = p_col[k * h + j] = P[(k, j)].
    let p_col = p_hh.as_slice();
    // Entry (a, b) of A = J P Jᵀ.
    let a_entry = |(da, ea, na, _): &Con, (db, eb, nb, _): &Con| {
        let mut s = 0.0;
        for &(ka, wa) in &ea[..*na] {
            let column = &p_col[ka * h..ka * h + h];
            for &(kb, wb) in &eb[..*nb] {
                s += wa * wb * column[kb];
            }
        }
        da.dot(*db) * s
    };
    // Vertex holds: no change of the held velocity. Point holds: at least their least
    // velocity.
    let rhs = targets(
        (&list, &cons, &known),
        points,
        holders,
        (free, held_normal),
        (vel, dv),
    );
    // A point hold on a held vertex, or two on the same points, repeat a constraint: a tiny
    // diagonal term keeps the system definite (the least-norm impulses).
    let scale = cons.iter().map(|c| a_entry(c, c)).fold(0.0, f64::max);
    // Point holds only push (one that would pull is let go) and a point left out must not pass
    // its holder; vertex holds are bilateral.
    let tol = 1e-9 * (1.0 + rhs.iter().fold(0.0, |a: f64, r| a.max(r.abs())));
    let keys: Vec<Option<[u32; 3]>> = cons
        .iter()
        .map(|c| match c.3 {
            Row::Normal(pi) => Some(points[pi].key()),
            Row::Vertex | Row::Tangent(_) => None,
        })
        .collect();
    let starts_in: Vec<bool> = (0..m)
        .map(|c| keys[c].is_none_or(|k| memory.starts_in(k, rhs[c])))
        .collect();
    // The neighbour filter reaches a few rings of vertices: tools pressing apart give
    // independent blocks of A, each solved on its own (six cubes on the 784-node plate: six
    // solves of about 18 rows instead of one of about 110). The exact filter connects every
    // pair: one block.
    let local = matches!(filter.kind(), FilterKind::Neighbour { .. });
    let blocks = independent_blocks(
        h,
        local.then_some(p_col),
        cons.iter()
            .map(|(_, e, n, _)| e[..*n].iter().map(|&(k, _)| k)),
    );
    // A holder's compliance joins the blocks its rows are in.
    let blocks = if any_holder {
        merge_blocks(blocks, &holder_rows)
    } else {
        blocks
    };
    let mut lambda = vec![0.0; m];
    let mut active = vec![false; m];
    // Each point with friction starts as it ended the last step (stuck, or sliding the same
    // way with the same load), a new one stuck if it asks for a push.
    let mut grip: Vec<Grip> = (0..points.len())
        .map(|pi| {
            let Some((t1, t2)) = tangent_rows[pi] else {
                return Grip::Off;
            };
            let Some((_, mu_d)) = points[pi].cone else {
                return Grip::Stuck;
            };
            match memory.friction.get(&points[pi].key()) {
                Some(&Remembered::Sliding { direction, load }) => {
                    match unit((direction.dot(cons[t1].0), direction.dot(cons[t2].0))) {
                        Some(direction) => Grip::Sliding {
                            direction,
                            impulse: mu_d * load,
                        },
                        None => Grip::Stuck,
                    }
                }
                Some(Remembered::Stuck) => Grip::Stuck,
                None if starts_in[normal_row[pi]] => Grip::Stuck,
                None => Grip::Off,
            }
        })
        .collect();
    // The velocity change impulses `(row, λ)` give the slots, and its part along row `c`.
    let slot_velocities = |impulses: &mut dyn Iterator<Item = (usize, f64)>| {
        let mut at_slots = vec![DVec3::ZERO; h];
        for (c, l) in impulses {
            let (d, e, n, _) = &cons[c];
            for &(k, w) in &e[..*n] {
                at_slots[k] += *d * (w * l);
            }
        }
        let mut out = vec![DVec3::ZERO; h];
        for (k, i) in at_slots.iter().enumerate() {
            if *i != DVec3::ZERO {
                for (o, p) in out.iter_mut().zip(&p_col[k * h..k * h + h]) {
                    *o += *i * *p;
                }
            }
        }
        out
    };
    let along = |c: usize, v: &[DVec3]| {
        if v.is_empty() {
            return 0.0;
        }
        let (d, e, n, _) = &cons[c];
        e[..*n].iter().map(|&(k, w)| w * d.dot(v[k])).sum::<f64>()
    };
    // Where each row sits in a pass's rows (and in the last pass's).
    let (mut at, mut last_at) = (vec![usize::MAX; m], vec![usize::MAX; m]);
    let mut factor = std::mem::take(&mut memory.scratch.factor);
    // Row `c`'s group (the rows loading the same weighted vertices), and where each group's
    // P-weighted column starts in `q` (filled as the passes need them).
    // (A normal row with held vertices left out loads fewer than its tangent rows: a group of
    // its own.)
    let mut reduced = vec![false; m];
    for &(c, _, _) in &known {
        reduced[c] = true;
    }
    let group = |c: usize| match cons[c].3 {
        Row::Normal(pi) if reduced[c] => points.len() + h + pi,
        Row::Normal(pi) | Row::Tangent(pi) => pi,
        Row::Vertex => points.len() + cons[c].1[0].0,
    };
    let mut q_at = vec![usize::MAX; 2 * points.len() + h];
    let mut q: Vec<f64> = Vec::new();
    // Whether each row pushed at the end of its block's last pass: the next pass starts from
    // there (on the six cubes with friction, 2.4 active-set passes a solve instead of 2.9,
    // 430 -> 392 µs a step).
    let mut in_last: Vec<Option<bool>> = vec![None; m];
    for block in &blocks {
        // The points with friction in the block.
        let frictional: Vec<usize> = block
            .iter()
            .filter_map(|&c| match cons[c].3 {
                Row::Normal(pi) if tangent_rows[pi].is_some() => Some(pi),
                _ => None,
            })
            .collect();
        let mut last: Option<(Vec<usize>, nalgebra::DMatrix<f64>)> = None;
        // Each pass solves the block's rows less the tangent rows of the points not stuck; a
        // sliding point's tangent impulse is fixed at kinetic friction of its normal impulse.
        // Then each point takes Coulomb's law on the impulses: one let go loses its friction,
        // a stuck one whose carrying impulse passes the static limit slides, a sliding one
        // that the fixed impulse would drive past its holder sticks; again until none
        // changes.
        let passes = if any_holder {
            HOLDER_FRICTION_PASSES
        } else {
            FRICTION_PASSES
        };
        // Set when the passes end with rigid holders' stuck points carried past their static
        // limit with a cut that would unbalance their holder: one more solve without
        // friction on those points (below).
        let mut fallback = false;
        for pass in 0..=passes {
            let mut rows: Vec<usize> = block
                .iter()
                .copied()
                .filter(|&c| match cons[c].3 {
                    Row::Tangent(pi) => matches!(grip[pi], Grip::Stuck),
                    _ => true,
                })
                .collect();
            // With a rigid holder, rows that repeat others on the surface are left out before
            // the holder's compliance joins them: a holder's rows at different points of it
            // load the same vertices, and the holder's turning would tell them apart, so the
            // solve answered their small disagreement by turning the holder with opposite
            // impulses (a box set down on a plate's vertex took 157 N on its 4.9 N weight and
            // was thrown 5 m high, spinning at 29 rad/s).
            if any_holder && rows.len() > 1 {
                rows = surface_independent(
                    &rows,
                    &cons,
                    &a_entry,
                    |c| {
                        (
                            matches!(cons[c].3, Row::Normal(pi) if !points[pi].grasped()),
                            rhs[c],
                        )
                    },
                    &mut memory.scratch,
                );
            }
            // The sliding points: tangent rows, unit direction and impulse.
            let sliding: Vec<SlidingPoint> = frictional
                .iter()
                .filter_map(|&pi| match (grip[pi], tangent_rows[pi]) {
                    (Grip::Sliding { direction, impulse }, Some(t)) => {
                        Some((t, direction, impulse))
                    }
                    _ => None,
                })
                .collect();
            let fixed: Vec<(usize, f64)> = sliding
                .iter()
                .flat_map(|&((t1, t2), d, l)| [(t1, d.0 * l), (t2, d.1 * l)])
                .collect();
            let mb = rows.len();
            // A is symmetric (P is): its lower triangle is computed down the columns
            // (contiguous) and mirrored; entries between rows of the last pass are copied from
            // its matrix.
            let mut a_mat = zeroed(&mut memory.scratch.system, mb, mb);
            if let Some((prev_rows, _)) = &last {
                last_at.iter_mut().for_each(|p| *p = usize::MAX);
                for (i, &c) in prev_rows.iter().enumerate() {
                    last_at[c] = i;
                }
            }
            // Each row group's P-weighted column, `q = P Σ w eₖ` over its entries (a group's
            // rows load the same weighted vertices: a point's normal and tangent rows, a
            // vertex's axes): an entry is then `(dₐ · d_b) Σ w_b q_a[k_b]`, three reads of `q`
            // in place of nine of `P` (one column read per entry for the whole group). A group's
            // column costs `h` per vertex it loads, so only a block of more than `h / 3` rows
            // gains: the exact filter's one block (six cubes at 60 Hz: 146 rows on 119
            // vertices), not the neighbour filter's blocks of a few rows each (one ball at
            // 1 kHz: its haptic step went from 39 to 54 µs with `q` for every block).
            let by_group = 3 * mb > h;
            for &c in rows.iter().filter(|_| by_group) {
                let g = group(c);
                if q_at[g] == usize::MAX {
                    q_at[g] = q.len();
                    q.resize(q.len() + h, 0.0);
                    let (_, e, n, _) = &cons[c];
                    for &(k, w) in &e[..*n] {
                        for (o, p) in q[q_at[g]..].iter_mut().zip(&p_col[k * h..k * h + h]) {
                            *o += w * p;
                        }
                    }
                }
            }
            for (i, &ca) in rows.iter().enumerate() {
                let qa = if by_group {
                    &q[q_at[group(ca)]..q_at[group(ca)] + h]
                } else {
                    &[]
                };
                let da = cons[ca].0;
                let column = &mut a_mat.as_mut_slice()[i * mb..i * mb + mb];
                for (j, &cb) in rows.iter().enumerate().skip(i) {
                    column[j] = match &last {
                        Some((_, prev))
                            if last_at[ca] != usize::MAX && last_at[cb] != usize::MAX =>
                        {
                            prev[(last_at[ca], last_at[cb])]
                        }
                        _ => {
                            let (db, eb, nb, _) = &cons[cb];
                            let entry = if by_group {
                                let s: f64 = eb[..*nb].iter().map(|&(k, w)| w * qa[k]).sum();
                                da.dot(*db) * s
                            } else {
                                a_entry(&cons[ca], &cons[cb])
                            };
                            let held = if any_holder { coupling(ca, cb) } else { 0.0 };
                            entry + held + if i == j { 1e-12 * scale } else { 0.0 }
                        }
                    };
                }
            }
            // The upper triangle, from the lower.
            for i in 0..mb {
                for j in i + 1..mb {
                    a_mat[(i, j)] = a_mat[(j, i)];
                }
            }
            // The sliding points' fixed impulses act on the other rows (through the velocity
            // change they give the block's vertices; nothing to compute without them).
            let from_fixed = if fixed.is_empty() {
                Vec::new()
            } else {
                slot_velocities(&mut fixed.iter().copied())
            };
            let fixed_motion = if any_holder && !fixed.is_empty() {
                motion(&holder_rows, holders.len(), fixed.iter().copied())
            } else {
                Vec::new()
            };
            let b = nalgebra::DVector::from_fn(mb, |i, _| {
                rhs[rows[i]] - along(rows[i], &from_fixed) - holder_along(rows[i], &fixed_motion)
            });
            // With a holder, a row repeats the others only where the surface's part of `A`
            // says so (`solve_pushing`).
            let reference: Vec<f64> = if any_holder {
                rows.iter()
                    .map(|&c| a_entry(&cons[c], &cons[c]) + 1e-12 * scale)
                    .collect()
            } else {
                Vec::new()
            };
            let solved = solve_pushing(
                &a_mat,
                &b,
                (
                    |i| matches!(cons[rows[i]].3, Row::Normal(pi) if !points[pi].grasped()),
                    |i| in_last[rows[i]].unwrap_or(starts_in[rows[i]]),
                ),
                &reference,
                tol,
                &mut factor,
                // Repeated rows relaxed, except with a rigid holder's rows (`solve_pushing`).
                !any_holder,
            );
            if let Some((_, prev)) = last.take() {
                give_back(&mut memory.scratch.system, prev);
            }
            // A block whose solve fails (not finite) gives no impulses; the others stand.
            let Some((x, act)) = solved else {
                give_back(&mut memory.scratch.system, a_mat);
                break;
            };
            for (i, &c) in rows.iter().enumerate() {
                at[c] = i;
                in_last[c] = Some(act[i]);
            }
            let value = |c: usize| (at[c] != usize::MAX).then(|| (x[at[c]], act[at[c]]));
            // What row `c` still lacks of its target after the pass (only for sliding points).
            let any_sliding = frictional
                .iter()
                .any(|&pi| matches!(grip[pi], Grip::Sliding { .. }));
            let all_impulses = || {
                fixed
                    .iter()
                    .copied()
                    .chain(rows.iter().copied().zip(x.iter().copied()))
            };
            let after = if any_sliding {
                slot_velocities(&mut all_impulses())
            } else {
                Vec::new()
            };
            let after_motion = if any_sliding && any_holder {
                motion(&holder_rows, holders.len(), all_impulses())
            } else {
                Vec::new()
            };
            let residual = |c: usize| rhs[c] - along(c, &after) - holder_along(c, &after_motion);
            let mut changed = false;
            let mut cuts = HolderCuts::new(holders.len());
            for &pi in frictional.iter().filter(|_| !fallback) {
                let (Some((t1, t2)), Some((mu_s, mu_d))) = (tangent_rows[pi], points[pi].cone)
                else {
                    continue;
                };
                // The normal impulse the holder gives over the step: the press's own (given
                // before the step) and the step's; no friction on a point the step does not
                // push.
                let load = match value(normal_row[pi]) {
                    Some((l, true)) if l > 0.0 => l + points[pi].impulse.max(0.0),
                    _ => 0.0,
                };
                let carrying = (
                    value(t1).map_or(0.0, |v| v.0),
                    value(t2).map_or(0.0, |v| v.0),
                );
                if let (Grip::Stuck, Some(holder)) = (grip[pi], points[pi].holder) {
                    let directions = (cons[t1].0, cons[t2].0);
                    cuts.add(pi, holder, (directions, carrying), mu_s * load, load);
                }
                let next = grip[pi].next(
                    load,
                    carrying,
                    || (residual(t1), residual(t2)),
                    (mu_s, mu_d),
                );
                changed |= grip[pi].changed_to(next);
                grip[pi] = next;
            }
            // After the last pass, stuck points whose cut to their limit would unbalance their
            // rigid holder are solved once more without friction ([`HolderCuts`]).
            let done = fallback || !changed || pass + 1 == passes;
            let cut_off = if done && !fallback {
                cuts.unbalancing()
            } else {
                Vec::new()
            };
            if !cut_off.is_empty() && pass < passes {
                fallback = true;
                for &pi in &cut_off {
                    grip[pi] = Grip::Off;
                }
                for &c in &rows {
                    at[c] = usize::MAX;
                }
                last = Some((rows, a_mat));
                continue;
            }
            if done {
                for (i, &c) in rows.iter().enumerate() {
                    lambda[c] = x[i];
                    active[c] = act[i];
                }
                // Kinetic friction never drives a point past its holder: where the fixed
                // impulse of a sliding point overshoots (its holder's velocity is behind it
                // along the impulse), it is cut by what its own compliance says overshot
                // (after the last pass's loads, or the last step's, kinetic friction could
                // otherwise push a point the wrong way for a step: energy from nothing).
                for &((t1, t2), d, l) in &sliding {
                    let over = residual(t1) * d.0 + residual(t2) * d.1;
                    let compliance = a_entry(&cons[t1], &cons[t1]) + coupling(t1, t1);
                    let l = if over < 0.0 && compliance > 0.0 {
                        (l + over / compliance).max(0.0)
                    } else {
                        l
                    };
                    lambda[t1] = d.0 * l;
                    lambda[t2] = d.1 * l;
                }
                // A rigid holder's point held stuck in this last pass whose carrying impulse
                // passes the static limit is held at that limit: past the last pass no solve
                // checks it, and a rigid holder's points are new at every substep (a dynamic
                // ball rolling over the surface: its points change with it), so each was held
                // with whatever impulse it took (a ball that should slip at μ = 0.05 on a 30°
                // slope spun up three times too fast and rolled). A kinematic tool's point
                // keeps its impulse for the substep and slides from the next one's first
                // pass (cut here without a third solve, a tilted U's corner dragged at μ 0.3
                // lost most of its pull; a third pass costs the six cubes 15 %).
                for &pi in frictional.iter().filter(|&&pi| points[pi].holder.is_some()) {
                    let (Some((t1, t2)), Some((mu_s, _))) = (tangent_rows[pi], points[pi].cone)
                    else {
                        continue;
                    };
                    // (One of the two tangent rows may have been left out as a near repeat of
                    // another row: the other still carries an impulse, held at the limit too.
                    // Skipped, a ball slipping at 1.9 m/s over a vertex whose press carried no
                    // load took 0.22 N·s across the slope from its kept row in one substep.)
                    if at[t1] == usize::MAX && at[t2] == usize::MAX {
                        continue;
                    }
                    // All the normal impulse its holder gave: the press's own and the step's.
                    let step = match (at[normal_row[pi]] != usize::MAX)
                        .then(|| (x[at[normal_row[pi]]], act[at[normal_row[pi]]]))
                    {
                        Some((l, true)) if l > 0.0 => l,
                        _ => 0.0,
                    };
                    let load = step + points[pi].impulse.max(0.0);
                    let t = lambda[t1].hypot(lambda[t2]);
                    if t > mu_s * load && t > 0.0 {
                        let scale = mu_s * load / t;
                        lambda[t1] *= scale;
                        lambda[t2] *= scale;
                    }
                }
                for &c in &rows {
                    at[c] = usize::MAX;
                }
                give_back(&mut memory.scratch.system, a_mat);
                break;
            }
            for &c in &rows {
                at[c] = usize::MAX;
            }
            last = Some((rows, a_mat));
        }
        if let Some((_, prev)) = last.take() {
            give_back(&mut memory.scratch.system, prev);
        }
    }
    memory.friction.clear();
    for (pi, g) in grip.iter().enumerate() {
        let (Some((t1, t2)), Some(_)) = (tangent_rows[pi], points[pi].cone) else {
            continue;
        };
        let remembered = match *g {
            Grip::Off => continue,
            Grip::Stuck => Remembered::Stuck,
            Grip::Sliding { direction, .. } => Remembered::Sliding {
                direction: cons[t1].0 * direction.0 + cons[t2].0 * direction.1,
                load: lambda[normal_row[pi]].max(0.0) + points[pi].impulse.max(0.0),
            },
        };
        memory.friction.insert(points[pi].key(), remembered);
    }
    memory.scratch.factor = factor;
    give_back(&mut memory.scratch.block, p_hh);
    memory.seen.clear();
    memory.pushing.clear();
    for (c, key) in keys.iter().enumerate() {
        if let Some(k) = key {
            memory.seen.insert(*k);
            if active[c] && lambda[c] > 0.0 {
                memory.pushing.insert(*k);
            }
        }
    }
    let impulse = book_impulses(
        (&list, &cons, &lambda),
        (free, held, held_normal),
        points,
        hold_impulse,
    );
    filter.add_impulses(&list, &impulse, dv);
    give_impulses(&holder_rows, &lambda, holders);
    impulse.iter().sum()
}
