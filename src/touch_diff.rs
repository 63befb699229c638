//! Touch started / touch ended from two consecutive sets of touching pairs: the one piece of
//! bookkeeping behind the rigid pairs' events ([`crate::hooks::PairTouchEvent`]) and the soft
//! surfaces' ([`crate::coupling::ToolTouchEvent`]).

use parry3d::utils::hashset::HashSet;
use std::hash::Hash;

/// The pairs touching at the end of the last step, and the events not drained yet.
#[derive(Clone, Debug)]
pub(crate) struct TouchDiff<K, E> {
    touching: HashSet<K>,
    events: Vec<E>,
    /// The set before last, emptied, for the caller to fill next ([`TouchDiff::take_spare`]).
    spare: HashSet<K>,
    /// The list `touching` was built from by [`TouchDiff::update_listed`], in the caller's
    /// order; `None` after a [`TouchDiff::update`].
    listed: Option<Vec<K>>,
    /// The list before last, emptied ([`TouchDiff::take_spare_list`]).
    spare_list: Vec<K>,
}

impl<K, E> Default for TouchDiff<K, E> {
    fn default() -> Self {
        Self {
            touching: HashSet::default(),
            events: Vec::new(),
            spare: HashSet::default(),
            listed: None,
            spare_list: Vec::new(),
        }
    }
}

impl<K: Copy + Eq + Hash, E> TouchDiff<K, E> {
    /// Compares the pairs touching now with those of the last step and records the changes:
    /// the stopped ones first, then the started ones, each sorted by `order` (deterministic).
    pub fn update<O: Ord>(
        &mut self,
        now: HashSet<K>,
        order: impl Fn(&K) -> O,
        stopped: impl Fn(K) -> E,
        started: impl Fn(K) -> E,
    ) {
        let mut gone: Vec<K> = self.touching.difference(&now).copied().collect();
        let mut new: Vec<K> = now.difference(&self.touching).copied().collect();
        gone.sort_unstable_by_key(&order);
        new.sort_unstable_by_key(&order);
        self.events.extend(gone.into_iter().map(stopped));
        self.events.extend(new.into_iter().map(started));
        self.spare = std::mem::replace(&mut self.touching, now);
        self.spare.clear();
        if let Some(list) = self.listed.take() {
            self.spare_list = list;
        }
    }

    /// [`TouchDiff::update`] from a list of the pairs touching now (duplicates allowed) in an
    /// order the caller keeps from step to step. A list equal to the last one changes nothing
    /// and builds no set: the rigid pairs of a sleeping pile come from rapier's contact graph
    /// in the same order every step, and hashing them into a set and comparing it with the
    /// last step's was two thirds of recording a sleeping pyramid's touches. Any other list
    /// goes through the sets (a list merely reordered gives no event).
    pub fn update_listed<O: Ord>(
        &mut self,
        now: Vec<K>,
        order: impl Fn(&K) -> O,
        stopped: impl Fn(K) -> E,
        started: impl Fn(K) -> E,
    ) {
        if self.listed.as_ref() == Some(&now) {
            self.spare_list = now;
            return;
        }
        let mut set = self.take_spare();
        set.extend(now.iter().copied());
        self.update(set, order, stopped, started);
        self.listed = Some(now);
    }

    /// An empty list with the capacity of an earlier one, to fill and hand to
    /// [`TouchDiff::update_listed`].
    pub fn take_spare_list(&mut self) -> Vec<K> {
        let mut list = std::mem::take(&mut self.spare_list);
        list.clear();
        list
    }

    /// An empty set with the capacity of an earlier one, to fill with the pairs touching now
    /// and hand to [`TouchDiff::update`] (a set of every touching pair built anew each step
    /// grows and rehashes every time).
    pub fn take_spare(&mut self) -> HashSet<K> {
        std::mem::take(&mut self.spare)
    }

    /// The events since the last drain, oldest first.
    pub fn drain(&mut self) -> std::vec::Drain<'_, E> {
        self.events.drain(..)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type Diff = TouchDiff<u32, (bool, u32)>;

    fn listed(diff: &mut Diff, now: &[u32]) -> Vec<(bool, u32)> {
        let mut list = diff.take_spare_list();
        list.extend_from_slice(now);
        diff.update_listed(list, |k| *k, |k| (false, k), |k| (true, k));
        diff.drain().collect()
    }

    #[test]
    fn a_listed_update_reports_what_a_set_comparison_does() {
        let mut diff = Diff::default();
        assert_eq!(listed(&mut diff, &[3, 1]), [(true, 1), (true, 3)]);
        assert!(listed(&mut diff, &[3, 1]).is_empty(), "the same list");
        assert!(
            listed(&mut diff, &[1, 3, 3]).is_empty(),
            "reordered, repeated"
        );
        assert_eq!(listed(&mut diff, &[1, 4]), [(false, 3), (true, 4)]);
        // A set update in between: the next list is compared with that set, not the old list.
        let mut set = diff.take_spare();
        set.insert(7);
        diff.update(set, |k| *k, |k| (false, k), |k| (true, k));
        assert_eq!(
            diff.drain().collect::<Vec<_>>(),
            [(false, 1), (false, 4), (true, 7)]
        );
        assert_eq!(
            listed(&mut diff, &[1, 4]),
            [(false, 7), (true, 1), (true, 4)]
        );
        assert_eq!(listed(&mut diff, &[]), [(false, 1), (false, 4)]);
        assert!(listed(&mut diff, &[]).is_empty());
    }
}
