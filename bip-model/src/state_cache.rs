//! The states a run went through, what was enabled in each, and which plan led where.
//!
//! A robot's functional layer runs in cycles: each task's codels run, the tick comes, they
//! run again. An engine keeps passing through the same few states, and a fire plan fired
//! from a state always leads to the same state, with the same enabled steps: both are
//! functions of the state ([`crate::System::fire_planned`], [`EnabledSet`]). A
//! [`StateCache`] remembers, for up to a given number of states, each state's slots and
//! what its [`EnabledSet`] knew of it (an [`Evaluation`]), and per state where each plan
//! fired from it led. The next time that plan is fired from that state, the step is
//! looked up instead of fired and re-evaluated. It is built as the run goes and bounded,
//! like the lazy DFA of the `regex` crate: once it is full it learns no more states, and
//! steps it does not know are computed as without it.
//!
//! An evaluation moves, it is not copied: the current state's evaluation is in the set,
//! and the cache's entry for that state holds a spare one. A known step exchanges the
//! set's evaluation with the spare (the entry has its own again) and then with the next
//! state's (which becomes the spare): no copy and no allocation. Before a step the cache
//! does not know, the set's evaluation is copied into its entry, and the set is updated
//! as usual; the state it reaches is then looked up by its slots, or remembered.
//!
//! Only an [`EnabledSet`] whose whole knowledge is its evaluation is remembered or
//! entered ([`EnabledSet::fits_evaluation`]): none of a system with internal transitions,
//! none with steps computed outside the step tables (they live outside the evaluation).
//!
//! Exact means: the same steps, enabled interactions and states as without the cache.
//! Which lazy interactions the set left unevaluated ("stale", suppressed by a priority)
//! depends on the path to a state, so [`EnabledSet::has_steps_before_priorities`] may
//! answer `None` where the set without the cache answers, or the other way round.

#[allow(unused_imports)]
use crate::prelude::*;

use hashbrown::HashTable;

use crate::fire_plan::PlanId;
use crate::incremental::{EnabledSet, Evaluation};
use crate::state::State;
use crate::system::System;

/// The most bytes the states a cache remembers may take, with their evaluations: a state
/// of a wide model is big (100,000 dining philosophers: 200,000 slots and 300,000
/// interactions, some 6 MiB a state), and a cache of a thousand of them would not fit in
/// memory; a state of the rover's size (1.5 KiB) is far from it.
pub const STATE_CACHE_BYTES: usize = 64 << 20;

/// What remembering one state of `system` costs: its slots, its hash and index entry, its
/// evaluation (per interaction what was found, and three bit sets).
fn state_bytes(system: &System) -> usize {
    let interactions = system.interactions.len();
    let found = interactions * core::mem::size_of::<crate::found::Found>();
    let bits = 3 * interactions.div_ceil(64) * 8;
    system.slot_count() * 8 + 8 + 5 + found + bits
}

/// The states a run went through and the plans between them (see the module
/// documentation). Use one cache with one [`EnabledSet`], as
/// [`StateCache::take_known`], [`StateCache::leave`] and [`StateCache::arrive`] say.
#[derive(Clone, Debug)]
pub struct StateCache {
    capacity: usize,
    /// Slots per state.
    width: usize,
    /// State `k`'s slots are `slots[k * width..(k + 1) * width]`.
    slots: Vec<i64>,
    /// State `k`'s evaluation, or the spare while the set describes state `k`.
    evaluations: Vec<Evaluation>,
    /// Per state, the plans fired from it: the state each led to, and where the slots
    /// that step changed are listed in `changed`.
    edges: Vec<Vec<Edge>>,
    changed: Vec<u32>,
    /// Where the slots the last known step changed are in `changed`.
    last_changed: (u32, u32),
    /// The states by their slots.
    index: HashTable<u32>,
    /// Per state, its hash; and the hash of the state the set describes.
    hashes: Vec<u64>,
    hash: u64,
    /// True while `hash` is not the set's state's (after a rest).
    hash_stale: bool,
    /// Steps looked for, and found, since the last check (see
    /// [`StateCache::rest_policy`]); steps left to rest.
    window_steps: u32,
    window_hits: u32,
    resting: u32,
    window: u32,
    rest: u32,
    /// Per slot, the last `epoch` it was counted in.
    seen: Vec<u32>,
    epoch: u32,
    /// The state the set describes, if the cache knows it.
    current: Option<u32>,
    /// The state and plan of a step [`StateCache::take_known`] did not know, until
    /// [`StateCache::arrive`] links it to where it led.
    leaving: Option<(u32, PlanId)>,
    /// The hits, misses and rests (`stats` counts the states and edges).
    stats: CacheStats,
}

#[derive(Clone, Copy, Debug)]
struct Edge {
    plan: PlanId,
    to: u32,
    changed: (u32, u32),
}

/// What a [`StateCache`] holds and how often it knew the step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheStats {
    /// The states it knows.
    pub states: usize,
    /// The plans it knows, over all states.
    pub edges: usize,
    /// Steps it took from memory.
    pub hits: u64,
    /// Steps it did not know (computed), resting or not.
    pub misses: u64,
    /// How often it gave up for a while ([`StateCache::rest_policy`]).
    pub rests: u64,
}

impl StateCache {
    /// A cache of `system`'s states that remembers at most `capacity` of them, and no
    /// more than fit in [`STATE_CACHE_BYTES`] (0: none; it then only counts the steps as
    /// misses).
    pub fn new(system: &System, capacity: usize) -> StateCache {
        StateCache {
            capacity: capacity.min(STATE_CACHE_BYTES / state_bytes(system)),
            width: system.slot_count(),
            slots: Vec::new(),
            evaluations: Vec::new(),
            edges: Vec::new(),
            changed: Vec::new(),
            last_changed: (0, 0),
            index: HashTable::new(),
            hashes: Vec::new(),
            hash: 0,
            hash_stale: false,
            window_steps: 0,
            window_hits: 0,
            resting: 0,
            window: 4096,
            rest: 1 << 16,
            seen: vec![0; system.slot_count()],
            epoch: 0,
            current: None,
            leaving: None,
            stats: CacheStats::default(),
        }
    }

    /// The index of the state the set describes, if the cache knows it (indices count
    /// from 0 in the order the states were met, and a known state is never forgotten: a
    /// caller may keep what it works out from a state by its index).
    #[inline]
    pub fn current(&self) -> Option<usize> {
        self.current.map(|c| c as usize)
    }

    /// The most states it remembers.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// What it holds, and its hits and misses so far.
    pub fn stats(&self) -> CacheStats {
        CacheStats {
            states: self.hashes.len(),
            edges: self.edges.iter().map(Vec::len).sum(),
            ..self.stats
        }
    }

    /// The bytes it holds (its buffers' capacities).
    pub fn bytes(&self) -> usize {
        let edge = core::mem::size_of::<Edge>();
        let edges: usize = self.edges.iter().map(|e| e.capacity() * edge + 24).sum();
        let evaluations: usize = self.evaluations.iter().map(Evaluation::bytes).sum();
        let lists = (self.slots.capacity() + self.hashes.capacity() + self.changed.capacity()) * 8;
        lists + evaluations + edges + self.index.capacity() * 5
    }

    /// If firing plan `p` from the state `set` describes is known: moves `next` (the
    /// set's state on entry) and `set` to the state it leads to, and returns true
    /// ([`StateCache::last_changed`] lists the slots that changed). Otherwise returns
    /// false, and the caller fires the plan and updates the set itself, then calls
    /// [`StateCache::arrive`] (or, if firing or updating failed, [`StateCache::leave`]
    /// before anything else: `arrive` would link the plan to the wrong state).
    #[inline]
    pub fn take_known(&mut self, p: PlanId, set: &mut EnabledSet, next: &mut State) -> bool {
        if self.resting > 0 {
            self.resting -= 1;
            self.stats.misses += 1;
            // (`enter` may have found the state meanwhile)
            self.leave(set);
            return false;
        }
        self.window_steps = self.window_steps.wrapping_add(1);
        let Some(c) = self.current else {
            self.stats.misses += 1;
            self.leaving = None;
            return false;
        };
        let c = c as usize;
        let Some(&edge) = self.edges[c].iter().find(|e| e.plan == p) else {
            // keep the state's evaluation: the set is about to be updated in place
            set.save_evaluation(&mut self.evaluations[c]);
            self.current = None;
            self.leaving = Some((c as u32, p));
            self.stats.misses += 1;
            return false;
        };
        let n = edge.to as usize;
        let after = &self.slots[n * self.width..(n + 1) * self.width];
        self.last_changed = edge.changed;
        let changed = &self.changed[edge.changed.0 as usize..edge.changed.1 as usize];
        let out = next.slots_mut();
        for &s in changed {
            out[s as usize] = after[s as usize];
        }
        // the set gives state c's evaluation back for the spare, then takes state n's
        set.exchange_evaluation(&mut self.evaluations[c]);
        set.exchange_evaluation(&mut self.evaluations[n]);
        self.current = Some(n as u32);
        self.hash = self.hashes[n];
        self.stats.hits += 1;
        self.window_hits = self.window_hits.wrapping_add(1);
        true
    }

    /// The slots the last step [`StateCache::take_known`] took changed (those
    /// [`crate::System::fire_planned`] would write, less those it leaves as they were).
    #[inline]
    pub fn last_changed(&self) -> &[u32] {
        &self.changed[self.last_changed.0 as usize..self.last_changed.1 as usize]
    }

    /// Before `set` changes other than by [`StateCache::take_known`] (a step without a
    /// plan, a reset): the state it describes keeps its evaluation, and the cache no
    /// longer knows where the set is.
    pub fn leave(&mut self, set: &EnabledSet) {
        self.leaving = None;
        if let Some(c) = self.current.take() {
            set.save_evaluation(&mut self.evaluations[c as usize]);
        }
    }

    /// `set` describes `state`, and the cache knew nothing of where the set was (at the
    /// start, after [`StateCache::leave`] and a reset): the cache finds the state among
    /// those it knows, or remembers it if there is room.
    pub fn enter(&mut self, set: &EnabledSet, state: &State) {
        self.leaving = None;
        let slots = state.slots();
        self.hash = state_hash(slots);
        self.hash_stale = false;
        self.settle(set, slots);
    }

    /// `set` now describes `after`, which a step from `before` (the state it described)
    /// led to, writing no slot but those in `written` (after a step
    /// [`StateCache::take_known`] did not know, or one after [`StateCache::leave`]): the
    /// cache finds the state among those it knows, or remembers it if there is room; and
    /// links the step that led here, if `take_known` saw it.
    #[inline]
    pub fn arrive(&mut self, set: &EnabledSet, before: &State, after: &State, written: &[u32]) {
        if self.capacity != 0 {
            self.arrive_at(set, before.slots(), after.slots(), written);
        }
    }

    fn arrive_at(&mut self, set: &EnabledSet, a: &[i64], b: &[i64], written: &[u32]) {
        if self.resting > 0 {
            // the hash is not kept up to date meanwhile
            self.leaving = None;
            self.hash_stale = true;
            return;
        }
        if self.hash_stale {
            self.hash_stale = false;
            self.hash = state_hash(b);
            self.settle(set, b);
            return;
        }
        // a slot may be listed twice (a plan's actions write it twice): count it once
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.seen.fill(0);
            self.epoch = 1;
        }
        for &s in written {
            let s = s as usize;
            let (x, y) = (a[s], b[s]);
            if x != y && self.seen[s] != self.epoch {
                self.seen[s] = self.epoch;
                self.hash = self
                    .hash
                    .wrapping_sub(slot_hash(s, x))
                    .wrapping_add(slot_hash(s, y));
            }
        }
        debug_assert_eq!(
            self.hash,
            state_hash(b),
            "`written` lists every slot written"
        );
        self.settle(set, b);
    }

    /// The set describes `slots`, whose hash is `self.hash`: find or remember the state.
    fn settle(&mut self, set: &EnabledSet, slots: &[i64]) {
        let leaving = self.leaving.take();
        debug_assert!(self.current.is_none(), "leave the state first");
        if self.capacity == 0 || slots.len() != self.width {
            return;
        }
        let (width, known, hash) = (self.width, &self.slots, self.hash);
        let found = self
            .index
            .find(hash, |&k| {
                &known[k as usize * width..(k as usize + 1) * width] == slots
            })
            .copied();
        let n = match found {
            // its entry's evaluation is the spare from now on: the set has the same, if
            // the set's evaluation holds all it knows (a set that computed steps outside
            // the tables, and kept them while blocked, is not entered: found by review)
            Some(n) if set.fits_evaluation() => n,
            Some(_) => return,
            None if self.hashes.len() < self.capacity && set.fits_evaluation() => {
                let n = self.hashes.len() as u32;
                self.slots.extend_from_slice(slots);
                self.hashes.push(hash);
                self.evaluations.push(Evaluation::default());
                self.edges.push(Vec::new());
                let hashes = &self.hashes;
                self.index.insert_unique(hash, n, |&k| hashes[k as usize]);
                // still learning: the count of what it knows starts again
                (self.window_steps, self.window_hits) = (0, 0);
                n
            }
            None => {
                self.consider_rest();
                return;
            }
        };
        self.current = Some(n);
        if let Some((c, plan)) = leaving {
            let (c, w) = (c as usize, self.width);
            let a = self.changed.len() as u32;
            for s in 0..w {
                if self.slots[c * w + s] != self.slots[n as usize * w + s] {
                    self.changed.push(s as u32);
                }
            }
            let changed = (a, self.changed.len() as u32);
            self.edges[c].push(Edge {
                plan,
                to: n,
                changed,
            });
        }
    }

    /// After a step to a state it does not know and cannot learn: if it knew fewer than
    /// one step in four over the last window of steps, it rests.
    fn consider_rest(&mut self) {
        if self.window_steps < self.window {
            return;
        }
        if u64::from(self.window_hits) * 4 < u64::from(self.window_steps) && self.rest > 0 {
            self.resting = self.rest;
            self.hash_stale = true;
            self.stats.rests += 1;
        }
        (self.window_steps, self.window_hits) = (0, 0);
    }

    /// How it gives up when it seldom knows the step (a run that keeps meeting new
    /// states once it is full): every `window` steps after it stopped learning, if it
    /// knew fewer than one in four, it neither looks steps up nor finds states (both cost
    /// a little on every step it does not know) for the next `rest` steps (0: never
    /// rests), then tries again. Default: windows of 4,096 steps, rests of 65,536.
    pub fn rest_policy(&mut self, window: u32, rest: u32) {
        self.window = window.max(1);
        self.rest = rest;
    }
}

/// A state's hash: the sum of its slots' parts.
fn state_hash(slots: &[i64]) -> u64 {
    let parts = slots.iter().enumerate().map(|(s, &v)| slot_hash(s, v));
    parts.fold(0, u64::wrapping_add)
}

/// A slot's part of a state's hash: the hash is the sum over the slots, so that a step
/// updates it from the slots it changed (as Zobrist hashing does). The mix is
/// splitmix64's finaliser.
#[inline]
fn slot_hash(slot: usize, value: i64) -> u64 {
    let mut z = (slot as u64)
        .wrapping_mul(0x9e37_79b9_7f4a_7c15)
        .wrapping_add(value as u64);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}
