//! The rows of the filtered step's constraint solve ([`super::constrain`]): each held vertex
//! along its normal (or its three axes), each point hold along its normal and, while its
//! holder carries it, along two directions of its tangent plane.

use super::super::active_set::{give_back, repeated_rows, zeroed, Scratch};
use super::super::point_hold::PointHold;
use super::super::rigid_holder::HolderState;
use super::super::NOT_FREE;
use glamx::DVec3;

/// A constraint: direction, up to three (slot, weight) entries and how many are used, and
/// what it holds.
pub(super) type Con = (DVec3, [(usize, f64); 3], usize, Row);

/// An entry left out of a row because a hold fixes its vertex's velocity along it: row,
/// vertex, weight.
pub(super) type Known = (usize, u32, f64);

/// The solve's rows over the free slots `list` they load (sorted), with the normal row of
/// each point hold and its tangent rows.
pub(super) struct Rows {
    pub list: Vec<u32>,
    pub cons: Vec<Con>,
    pub normal_row: Vec<usize>,
    pub tangent_rows: Vec<Option<(usize, usize)>>,
    /// The entries left out of point holds' normal rows: held vertices whose velocity along
    /// the row is their holder's ([`held_along`]).
    pub known: Vec<Known>,
}

/// Whether a vertex's velocity along `d` after the filtered step is fixed by its hold (so a
/// point row can count it as known rather than solve for it): a full hold fixes every
/// direction, a sliding hold its normal, and `d` within about a degree of that normal
/// (`|d × n| ≤ 0.02`) is taken as along it.
///
/// A tool's edge across a surface edge next to a vertex the tool holds puts most of the
/// point's weight on that vertex: its row repeated the vertex's own within the solve's
/// tolerance and was left out, so the far vertex, which only the point holds down, sprang
/// back in every step and was pushed back after it: its free neighbours never came to rest
/// (a two-jaw tool on a 62.5 mm mesh, a point with 7.6 % of its weight on the far vertex: 0.24
/// mm up and down each substep, 0.07 N on each of five neighbours at rest).
pub(super) fn held_along(held: bool, normal: DVec3, d: DVec3) -> bool {
    held && (normal == DVec3::ZERO || normal.cross(d).length() <= 0.02)
}

/// The rows of the held vertices (`held`, with `held_normal`: zero for a full hold) and the
/// point holds; `None` when they load no free vertex.
pub(super) fn rows(
    free: &[u32],
    free_index: &[u32],
    held: &[bool],
    held_normal: &[DVec3],
    points: &[PointHold],
) -> Option<Rows> {
    // The free slots involved, sorted (the neighbour filter's gather searches them).
    let mut list: Vec<u32> = free
        .iter()
        .enumerate()
        .filter(|(_, &v)| held[v as usize])
        .map(|(fi, _)| fi as u32)
        .collect();
    for p in points.iter() {
        for (v, _) in p.entries() {
            let fi = free_index[v as usize];
            if fi != NOT_FREE {
                list.push(fi);
            }
        }
    }
    list.sort_unstable();
    list.dedup();
    if list.is_empty() {
        return None;
    }
    let slot = |fi: u32| list.binary_search(&fi).ok();
    let mut cons: Vec<Con> = Vec::with_capacity(list.len());
    for (k, &fi) in list.iter().enumerate() {
        let v = free[fi as usize] as usize;
        if !held[v] {
            continue;
        }
        let entry = [(k, 1.0), (0, 0.0), (0, 0.0)];
        let n = held_normal[v];
        if n == DVec3::ZERO {
            cons.extend([DVec3::X, DVec3::Y, DVec3::Z].map(|d| (d, entry, 1, Row::Vertex)));
        } else {
            cons.push((n, entry, 1, Row::Vertex));
        }
    }
    let mut known = Vec::new();
    for (pi, p) in points.iter().enumerate() {
        let mut entry = [(0, 0.0); 3];
        let mut count = 0;
        // The normal row's entries on vertices that move with the solve, and those a hold
        // fixes along it.
        let mut normal_entry = [(0, 0.0); 3];
        let mut normal_count = 0;
        let mut fixed = [(0u32, 0.0); 3];
        let mut fixed_count = 0;
        for (v, w) in p.entries() {
            if let Some(k) = slot(free_index[v as usize]) {
                entry[count] = (k, w);
                count += 1;
                let vi = v as usize;
                if held_along(held[vi], held_normal[vi], p.normal) {
                    fixed[fixed_count] = (v, w);
                    fixed_count += 1;
                } else {
                    normal_entry[normal_count] = (k, w);
                    normal_count += 1;
                }
            }
        }
        if count > 0 {
            // (A point all on held vertices keeps its whole row: they carry it.)
            if normal_count > 0 && fixed_count > 0 {
                let c = cons.len();
                known.extend(fixed[..fixed_count].iter().map(|&(v, w)| (c, v, w)));
                cons.push((p.normal, normal_entry, normal_count, Row::Normal(pi)));
            } else {
                cons.push((p.normal, entry, count, Row::Normal(pi)));
            }
            if p.carried.is_some() {
                let (t1, t2) = p.normal.any_orthonormal_pair();
                cons.push((t1, entry, count, Row::Tangent(pi)));
                cons.push((t2, entry, count, Row::Tangent(pi)));
            }
        }
    }
    // The normal row of each point hold, and its tangent rows.
    let mut normal_row = vec![usize::MAX; points.len()];
    let mut tangent_rows: Vec<Option<(usize, usize)>> = vec![None; points.len()];
    for (c, con) in cons.iter().enumerate() {
        match con.3 {
            Row::Normal(pi) => normal_row[pi] = c,
            Row::Tangent(pi) if tangent_rows[pi].is_none() => tangent_rows[pi] = Some((c, c + 1)),
            _ => {}
        }
    }
    Some(Rows {
        list,
        cons,
        normal_row,
        tangent_rows,
        known,
    })
}

/// Each row's target, the velocity change along it that the solve's impulses must give
/// (`vel` before the step, `dv` the step's change as it stands, by free slot): none for a
/// vertex hold, a point's least velocity for its normal row (less what the held vertices
/// left out of it keep, [`held_along`]), its holder's velocity for a carried point's tangent
/// rows.
pub(super) fn targets(
    (list, cons, known): (&[u32], &[Con], &[Known]),
    points: &[PointHold],
    holders: &[HolderState],
    (free, held_normal): (&[u32], &[DVec3]),
    (vel, dv): (&[DVec3], &[DVec3]),
) -> Vec<f64> {
    // A normal row's velocity along `da` from the held vertices left out of it: what their
    // holds keep, along their normals.
    let known_along = |c: usize, da: DVec3| {
        known
            .iter()
            .filter(|(kc, _, _)| *kc == c)
            .map(|&(_, v, w)| {
                let (v, n) = (v as usize, held_normal[v as usize]);
                let along = if n == DVec3::ZERO {
                    vel[v]
                } else {
                    n * vel[v].dot(n)
                };
                w * da.dot(along)
            })
            .sum::<f64>()
    };
    cons.iter()
        .enumerate()
        .map(|(c, (da, ea, na, row))| {
            // The point's velocity along `da` after the step as it stands.
            let along = || {
                ea[..*na]
                    .iter()
                    .map(|&(k, w)| {
                        let fi = list[k] as usize;
                        w * da.dot(vel[free[fi] as usize] + dv[fi])
                    })
                    .sum::<f64>()
            };
            match *row {
                Row::Vertex => -ea[..*na]
                    .iter()
                    .map(|&(k, w)| w * da.dot(dv[list[k] as usize]))
                    .sum::<f64>(),
                Row::Normal(pi) => {
                    points[pi].normal_target(holders) - along() - known_along(c, *da)
                }
                Row::Tangent(pi) => {
                    points[pi]
                        .carried_target(holders)
                        .map_or(0.0, |target| da.dot(target))
                        - along()
                }
            }
        })
        .collect()
}

/// What a row of the filtered step's constraint solve holds.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(super) enum Row {
    /// A held vertex, along one direction (bilateral).
    Vertex,
    /// Point hold `i`'s normal (push-only, bilateral for a grasped point).
    Normal(usize),
    /// One direction of point hold `i`'s tangent plane, while it is carried (bilateral).
    Tangent(usize),
}

/// `rows` less those that nearly repeat others on the surface alone (`a_entry`: the entries of
/// `J P Jᵀ`), taken in the order a solve takes them (`priority`: bilateral first, then by
/// decreasing target: `priority` gives whether a row is push-only, and its target), keeping
/// their order.
pub(super) fn surface_independent(
    rows: &[usize],
    cons: &[Con],
    a_entry: &impl Fn(&Con, &Con) -> f64,
    priority: impl Fn(usize) -> (bool, f64),
    scratch: &mut Scratch,
) -> Vec<usize> {
    let m = rows.len();
    let mut s = zeroed(&mut scratch.system, m, m);
    let scale = rows
        .iter()
        .map(|&c| a_entry(&cons[c], &cons[c]))
        .fold(0.0, f64::max);
    for (i, &ca) in rows.iter().enumerate() {
        for (j, &cb) in rows.iter().enumerate().skip(i) {
            let e = a_entry(&cons[ca], &cons[cb]) + if i == j { 1e-12 * scale } else { 0.0 };
            s[(i, j)] = e;
            s[(j, i)] = e;
        }
    }
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&p, &q| {
        let (pp, qq) = (priority(rows[p]), priority(rows[q]));
        pp.0.cmp(&qq.0).then(qq.1.total_cmp(&pp.1)).then(p.cmp(&q))
    });
    let left_out = repeated_rows(&s, &order, &mut scratch.factor);
    give_back(&mut scratch.system, s);
    rows.iter()
        .enumerate()
        .filter(|(i, _)| !left_out.contains(i))
        .map(|(_, &c)| c)
        .collect()
}

/// What the solved impulses `lambda` (one per row of `cons`, over the slots of `list`) give:
/// the impulse on each slot, returned, and the books of each row's owner, its point hold's
/// impulses and momentum or its held vertex's hold impulse (`hold_impulse`, by vertex).
pub(super) fn book_impulses(
    (list, cons, lambda): (&[u32], &[Con], &[f64]),
    (free, held, held_normal): (&[u32], &[bool], &[DVec3]),
    points: &mut [PointHold],
    hold_impulse: &mut [DVec3],
) -> Vec<DVec3> {
    let mut impulse = vec![DVec3::ZERO; list.len()];
    // The surface vertex of slot `k`.
    let vertex = |k: usize| list.get(k).and_then(|&fi| free.get(fi as usize)).copied();
    for (c, (d, e, n, row)) in cons.iter().enumerate() {
        let mut weight = 0.0;
        // What the row gave vertices a sliding hold holds, across that hold's normal
        // ([`PointHold::held_across`]).
        let mut across = DVec3::ZERO;
        for &(k, w) in &e[..*n] {
            let given = *d * (w * lambda[c]);
            impulse[k] += given;
            weight += w;
            if let Some(v) = vertex(k).filter(|&v| held.get(v as usize) == Some(&true)) {
                let m = held_normal.get(v as usize).copied().unwrap_or(DVec3::ZERO);
                if m != DVec3::ZERO {
                    across += given - m * m.dot(given);
                }
            }
        }
        match *row {
            Row::Normal(pi) => {
                points[pi].impulse += lambda[c];
                points[pi].momentum += *d * (weight * lambda[c]);
                points[pi].held_across += across;
            }
            Row::Tangent(pi) => {
                points[pi].tangent_impulse += *d * lambda[c];
                points[pi].momentum += *d * (weight * lambda[c]);
                points[pi].held_across += across;
            }
            Row::Vertex => {
                // The vertex hold's impulse (`MassSpringSurface::hold_impulse`).
                if let Some(slot) = vertex(e[0].0).and_then(|v| hold_impulse.get_mut(v as usize)) {
                    *slot += *d * lambda[c];
                }
            }
        }
    }
    impulse
}
