//! Which interactions a changed slot can give other steps, by where a component is.
//!
//! An interaction's steps read a slot only where it matters: a guard of a participant's
//! transitions matters while the participant is where those transitions start; the
//! connector's guard, while a required participant is where it has transitions on its
//! port. [`crate::EnabledSet`] describes each read as a [`Dep`] (the slot, the component
//! whose location is watched, the locations where the read matters). Filtering a slot's
//! dependencies by location one by one costs as much as the few re-evaluations they
//! spare, so [`Watches`] sorts them once: per slot, per watched location slot, per
//! location, the interactions to mark. A changed slot then reads one location per watched
//! component and marks exactly the interactions listed there.

#[allow(unused_imports)]
use crate::prelude::*;

/// An interaction whose steps read a slot, when the component whose location is slot
/// `watch` is at one of `locations` (elsewhere the interaction has no step that the slot
/// could change, and if that component moves, its location slot marks the interaction).
/// With `connector_only`, only the connector's guard reads the slot, and the read matters
/// only while the interaction's required ports all have an enabled transition (when that
/// changes, a location or a transition guard's read marks the interaction).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Dep {
    pub interaction: u32,
    pub watch: u32,
    pub locations: u64,
    pub connector_only: bool,
}

/// Every location.
pub(crate) const ANYWHERE: u64 = u64::MAX;

/// The bit of a location in [`Dep::locations`]; locations from 63 on share the last bit.
pub(crate) fn location_bit(loc: u32) -> u64 {
    1 << loc.min(63)
}

/// An interaction to re-evaluate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Mark {
    pub interaction: u32,
    pub connector_only: bool,
}

/// One watched location slot of a changed slot: `lists[lists + l]` are the marks while
/// it holds location `l` (`l` below `n`, the last list for every location from `n - 1`).
#[derive(Clone, Copy, Debug)]
struct Watch {
    slot: u32,
    lists: u32,
    n: u32,
}

/// The dependencies of every slot, sorted by watched slot and location.
#[derive(Clone, Debug, Default)]
pub(crate) struct Watches {
    /// Per slot, its watches: `watches[start[s]..start[s + 1]]`.
    start: Vec<u32>,
    watches: Vec<Watch>,
    /// Per watch and location, its marks: `marks[lists[k]..lists[k + 1]]`.
    lists: Vec<u32>,
    marks: Vec<Mark>,
}

impl Watches {
    /// From each slot's dependencies; `locations(slot)` is how many locations the component
    /// of a location slot has.
    pub(crate) fn new(per_slot: &[Vec<Dep>], locations: impl Fn(u32) -> u32) -> Watches {
        let mut w = Watches::default();
        let mut watched: Vec<u32> = Vec::new();
        for deps in per_slot {
            w.start.push(w.watches.len() as u32);
            watched.clear();
            for d in deps {
                if !watched.contains(&d.watch) {
                    watched.push(d.watch);
                }
            }
            for &slot in &watched {
                // locations from 63 on share the last bit, so they share the last list
                let n = locations(slot).clamp(1, 64);
                w.watches.push(Watch {
                    slot,
                    lists: w.lists.len() as u32,
                    n,
                });
                for l in 0..n {
                    w.lists.push(w.marks.len() as u32);
                    let first = w.marks.len();
                    for d in deps {
                        if d.watch != slot || d.locations & location_bit(l) == 0 {
                            continue;
                        }
                        let mark = Mark {
                            interaction: d.interaction,
                            connector_only: d.connector_only,
                        };
                        // a read by a participant's guard subsumes the connector's
                        let same = w.marks[first..]
                            .iter()
                            .position(|m| m.interaction == d.interaction);
                        match same {
                            Some(k) => w.marks[first + k].connector_only &= d.connector_only,
                            None => w.marks.push(mark),
                        }
                    }
                }
            }
        }
        w.start.push(w.watches.len() as u32);
        w.lists.push(w.marks.len() as u32);
        w
    }

    /// Calls `f` with every interaction to re-evaluate when slot `s` changed, in state
    /// `slots` (an interaction may come once per watched slot).
    #[inline(always)]
    pub(crate) fn for_each(&self, s: u32, slots: &[i64], mut f: impl FnMut(Mark)) {
        for k in self.watches_of(s) {
            self.for_watch(k, slots, &mut f);
        }
    }

    /// The watches of slot `s` (indices for [`Watches::watched_slot`],
    /// [`Watches::marks_at`], [`Watches::for_watch`]).
    #[inline(always)]
    pub(crate) fn watches_of(&self, s: u32) -> core::ops::Range<u32> {
        self.start[s as usize]..self.start[s as usize + 1]
    }

    /// The location slot watch `k` reads.
    pub(crate) fn watched_slot(&self, k: u32) -> u32 {
        self.watches[k as usize].slot
    }

    /// The marks of watch `k` while its location slot holds `location`.
    #[inline(always)]
    pub(crate) fn marks_at(&self, k: u32, location: i64) -> &[Mark] {
        let w = &self.watches[k as usize];
        // a location beyond the last list reads the last one, as its bit does
        let l = (location as u64).min(u64::from(w.n - 1)) as u32;
        let k = (w.lists + l) as usize;
        &self.marks[self.lists[k] as usize..self.lists[k + 1] as usize]
    }

    /// The marks of watch `k` at every location (with repeats).
    pub(crate) fn all_marks(&self, k: u32) -> &[Mark] {
        let w = &self.watches[k as usize];
        let (a, b) = (w.lists as usize, (w.lists + w.n) as usize);
        &self.marks[self.lists[a] as usize..self.lists[b] as usize]
    }

    /// Calls `f` with the marks of watch `k` in state `slots`.
    #[inline(always)]
    pub(crate) fn for_watch(&self, k: u32, slots: &[i64], f: &mut impl FnMut(Mark)) {
        let location = slots[self.watches[k as usize].slot as usize];
        for &m in self.marks_at(k, location) {
            f(m);
        }
    }
}
