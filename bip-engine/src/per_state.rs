//! What the engine works out from a model state alone, kept per state of its
//! [`bip_model::StateCache`].
//!
//! The progress candidates of a state and the codels held in it are functions of the
//! state and its enabled steps. While the cache knows the state the engine is in
//! ([`bip_model::StateCache::current`]), they are worked out once and looked up on every
//! later visit. The cache never forgets a state, so an index stays valid for good.

#[allow(unused_imports)]
use crate::prelude::*;

/// A list of `T` per state index, each known or not yet.
#[derive(Clone, Debug)]
pub(crate) struct PerState<T> {
    /// Per state, where its list is in `items` (`UNKNOWN`: not worked out yet).
    spans: Vec<(u32, u32)>,
    items: Vec<T>,
}

const UNKNOWN: (u32, u32) = (u32::MAX, u32::MAX);

impl<T: Copy> PerState<T> {
    pub fn new() -> PerState<T> {
        PerState {
            spans: Vec::new(),
            items: Vec::new(),
        }
    }

    /// The list of state `s`, if it was kept.
    #[inline]
    pub fn get(&self, s: usize) -> Option<&[T]> {
        match self.spans.get(s) {
            Some(&(a, b)) if (a, b) != UNKNOWN => Some(&self.items[a as usize..b as usize]),
            _ => None,
        }
    }

    /// The bytes it holds.
    pub fn bytes(&self) -> usize {
        self.spans.capacity() * 8 + self.items.capacity() * core::mem::size_of::<T>()
    }

    /// Keeps `list` for state `s` (once: a state's list never changes).
    pub fn set(&mut self, s: usize, list: &[T]) {
        if self.spans.len() <= s {
            self.spans.resize(s + 1, UNKNOWN);
        }
        debug_assert_eq!(self.spans[s], UNKNOWN, "a state's list is kept once");
        let a = self.items.len() as u32;
        self.items.extend_from_slice(list);
        self.spans[s] = (a, self.items.len() as u32);
    }
}
