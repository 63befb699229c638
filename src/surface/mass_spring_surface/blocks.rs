//! The independent blocks of a filtered step's constraint system: constraints whose vertices
//! the filter does not connect do not act on each other, and each group is solved on its own.

/// Splits constraints into independent groups. `h` vertex slots; `p_col` the filter on them
/// (`h × h`, column-major), or `None` when it connects every pair (the exact filter: one
/// group); `rows` each constraint's slots. Two constraints share a group when a chain of
/// nonzero filter entries, or of constraints sharing a slot, joins their slots: the system
/// `J P Jᵀ` is then block-diagonal over the groups, and an active-set solve of each block
/// gives the whole system's solution.
///
/// Returns the groups, each listing its constraints in increasing order, the groups in the
/// order of their first constraint.
pub(super) fn independent_blocks<I: IntoIterator<Item = usize>>(
    h: usize,
    p_col: Option<&[f64]>,
    rows: impl ExactSizeIterator<Item = I>,
) -> Vec<Vec<usize>> {
    let m = rows.len();
    let Some(p_col) = p_col else {
        return vec![(0..m).collect()];
    };
    let mut parent: Vec<usize> = (0..h).collect();
    for j in 0..h {
        let column = &p_col[j * h..j * h + h];
        for (i, &v) in column.iter().enumerate().skip(j + 1) {
            if v != 0.0 {
                union(&mut parent, i, j);
            }
        }
    }
    let mut first_slot = Vec::with_capacity(m);
    for slots in rows {
        let mut slots = slots.into_iter();
        let first = slots.next();
        if let Some(f) = first {
            slots.for_each(|s| union(&mut parent, f, s));
        }
        first_slot.push(first);
    }
    // Group index per root, in the order the constraints first reach it.
    let mut group_of_root = vec![usize::MAX; h];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut loose = Vec::new();
    for (c, slot) in first_slot.into_iter().enumerate() {
        let Some(slot) = slot else {
            // A constraint on no slot acts on nothing: a block of its own.
            loose.push(vec![c]);
            continue;
        };
        let root = find(&mut parent, slot);
        if group_of_root[root] == usize::MAX {
            group_of_root[root] = groups.len();
            groups.push(Vec::new());
        }
        groups[group_of_root[root]].push(c);
    }
    groups.extend(loose);
    groups
}

/// The root of `i`'s set (path halving).
fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Joins the sets of `a` and `b`.
fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb);
    }
}

#[cfg(test)]
mod tests {
    use super::independent_blocks;

    #[test]
    fn constraints_on_unconnected_slots_fall_in_separate_blocks() {
        // Four slots: 0-1 connected by the filter, 2 alone, 3 reached only by a constraint
        // on 2 and 3.
        let h = 4;
        let mut p = vec![0.0; h * h];
        for i in 0..h {
            p[i * h + i] = 1.0;
        }
        p[1] = 0.5;
        p[h] = 0.5;
        let rows: Vec<Vec<usize>> = vec![vec![0], vec![2], vec![1], vec![3], vec![2, 3], vec![]];
        let blocks = independent_blocks(h, Some(&p), rows.iter().map(|r| r.iter().copied()));
        assert_eq!(blocks, vec![vec![0, 2], vec![1, 3, 4], vec![5]]);
        let dense = independent_blocks(h, None, rows.iter().map(|r| r.iter().copied()));
        assert_eq!(dense, vec![(0..6).collect::<Vec<_>>()]);
    }
}
