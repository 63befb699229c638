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
}

impl<K, E> Default for TouchDiff<K, E> {
    fn default() -> Self {
        Self {
            touching: HashSet::default(),
            events: Vec::new(),
            spare: HashSet::default(),
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
