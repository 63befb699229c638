//! The rows of the filtered step's constraint solve ([`super::constrain`]): each held vertex
//! along its normal (or its three axes), each point hold along its normal and, while its
//! holder carries it, along two directions of its tangent plane.

use super::super::active_set::{give_back, repeated_rows, zeroed, Scratch};
use super::super::point_hold::PointHold;
use super::super::NOT_FREE;
use glamx::DVec3;

/// A constraint: direction, up to three (slot, weight) entries and how many are used, and
/// what it holds.
pub(super) type Con = (DVec3, [(usize, f64); 3], usize, Row);

/// The solve's rows over the free slots `list` they load (sorted), with the normal row of
/// each point hold and its tangent rows.
pub(super) struct Rows {
    pub list: Vec<u32>,
    pub cons: Vec<Con>,
    pub normal_row: Vec<usize>,
    pub tangent_rows: Vec<Option<(usize, usize)>>,
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
    for (pi, p) in points.iter().enumerate() {
        let mut entry = [(0, 0.0); 3];
        let mut count = 0;
        for (v, w) in p.entries() {
            if let Some(k) = slot(free_index[v as usize]) {
                entry[count] = (k, w);
                count += 1;
            }
        }
        if count > 0 {
            cons.push((p.normal, entry, count, Row::Normal(pi)));
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
    })
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
