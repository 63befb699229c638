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
}

impl<K, E> Default for TouchDiff<K, E> {
    fn default() -> Self {
        Self {
            touching: HashSet::default(),
            events: Vec::new(),
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
        self.touching = now;
    }

    /// The events since the last drain, oldest first.
    pub fn drain(&mut self) -> std::vec::Drain<'_, E> {
        self.events.drain(..)
    }
}
