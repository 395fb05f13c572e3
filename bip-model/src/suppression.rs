//! Which interactions priorities suppress, for those the masks leave to a search: the
//! interactions below a `when`, and those whose closure did not fit the masks' budget.
//!
//! An enabled interaction is suppressed when a path of priorities whose `when`s hold leads
//! up from it to an enabled interaction (docs/model.md, "Priorities"). In most states no
//! priority with a `when` leads to an enabled interaction: none is evaluated, and the
//! paths without `when` decide alone, read from the groups' plain masks. Otherwise the
//! search walks the priority graph up from the state's enabled searched interactions, once
//! per state for all of them. First the groups they reach through priorities whose `when`s
//! hold,
//! evaluating each `when` met on the way once, and only if its priority leads to an enabled
//! interaction at all; a group that a path of priorities without `when` leads up from to
//! an enabled interaction is suppressed whatever the `when`s, and the walk does not start
//! or go on from it. Then, for each, whether such a path ends at an enabled interaction.
//! Groups with a mask end the walk: their mask answers for everything above them, and no
//! `when` lies there. So a priority's `when` is evaluated in a state exactly when its
//! priority leads to an enabled interaction and its low side is reached (the definition in
//! docs/model.md); which ones those are does not depend on the order of the walk, and the
//! verifier's encoding evaluates the same.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::eval::Env;
use crate::model::RangeError;
use crate::priority_masks::set_bit;
use crate::state::State;
use crate::steps::{Memo, PrioritySearch};
use crate::system::System;

/// A frame's priority has not been started.
const UNSTARTED: u32 = u32::MAX;

/// The priorities a path up may go through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Through {
    /// Any: the path may lead to an enabled interaction.
    Any = 0,
    /// Those without `when`, or whose `when` was found to hold: the path suppresses.
    Holding = 1,
    /// Those without `when`: the path suppresses whatever the `when`s.
    Plain = 2,
}

impl PrioritySearch {
    /// A new epoch for a new state, sized for `groups` groups and `priorities` priorities.
    fn begin(&mut self, groups: u32, priorities: usize) {
        let groups = groups as usize;
        if self.reached.len() != groups || self.when.len() != priorities {
            self.reached = vec![0; groups];
            self.leads = core::array::from_fn(|_| vec![(0, Memo::Open); groups]);
            self.when = vec![(0, false); priorities];
            self.epoch = 0;
        }
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.reached.fill(0);
            for l in &mut self.leads {
                l.fill((0, Memo::Open));
            }
            self.when.fill((0, false));
            self.epoch = 1;
        }
        self.stack.clear();
        self.frames.clear();
    }
}

impl System {
    /// For every interaction in `enabled` (those enabled in `state` before priorities)
    /// whose suppression the masks leave to a search, sets its bit in `out` if it is
    /// suppressed and clears it if not. A `when` that cannot be evaluated is a range error
    /// of the state.
    pub(crate) fn search_suppressed(
        &self,
        state: &State,
        enabled: &[u64],
        s: &mut PrioritySearch,
        out: &mut [u64],
    ) -> Result<(), RangeError> {
        let graph = &self.priority_graph;
        let masks = &self.priority_masks;
        s.begin(graph.groups(), self.priorities.len());
        let starts = || {
            enabled
                .iter()
                .zip(&masks.searched)
                .enumerate()
                .flat_map(|(w, (&e, &m))| Bits(e & m).map(move |b| (w * 64) as u32 + b))
        };
        // most states: no `when` can matter, so none is evaluated and only plain paths
        // suppress
        let mut any_live = false;
        for &p in masks.with_when.iter() {
            if self.live(p, enabled, s) {
                any_live = true;
                break;
            }
        }
        if !any_live {
            for i in starts() {
                let up = match graph.group_of(i) {
                    Some(g) => self.leads_up(g, Through::Plain, enabled, s),
                    None => false,
                };
                set_bit(out, i, up);
            }
            return Ok(());
        }
        for i in starts() {
            if let Some(g) = graph.group_of(i) {
                if s.reached[g as usize] != s.epoch {
                    s.reached[g as usize] = s.epoch;
                    if !self.leads_up(g, Through::Plain, enabled, s) {
                        s.stack.push(g);
                    }
                }
            }
        }
        while let Some(g) = s.stack.pop() {
            for &p in graph.below(g) {
                if !self.passes(state, p, enabled, s)? {
                    continue;
                }
                for z in graph.high_groups(p) {
                    // a masked group leads to no `when`
                    if masks.group_span(z).is_none() && s.reached[z as usize] != s.epoch {
                        s.reached[z as usize] = s.epoch;
                        if !self.leads_up(z, Through::Plain, enabled, s) {
                            s.stack.push(z);
                        }
                    }
                }
            }
        }
        for i in starts() {
            let up = match graph.group_of(i) {
                Some(g) => self.leads_up(g, Through::Holding, enabled, s),
                None => false,
            };
            set_bit(out, i, up);
        }
        Ok(())
    }

    /// True if priority `p` carries suppression in this state: it has no `when`, or its
    /// `when` holds and its high side leads to an enabled interaction (the `when` is
    /// evaluated only then, once per state).
    fn passes(
        &self,
        state: &State,
        p: u32,
        enabled: &[u64],
        s: &mut PrioritySearch,
    ) -> Result<bool, RangeError> {
        let prio = &self.priorities[p as usize];
        let Some(w) = &prio.when else {
            return Ok(true);
        };
        let (stamp, holds) = s.when[p as usize];
        if stamp == s.epoch {
            return Ok(holds);
        }
        let holds = self.live(p, enabled, s)
            && w.holds(&mut Env::new(state.slots(), 0))
                .map_err(|e| self.range_error(e, &format!("priority {}", prio.text)))?;
        s.when[p as usize] = (s.epoch, holds);
        Ok(holds)
    }

    /// True if priority `p`'s high side leads to an enabled interaction through any
    /// priorities.
    fn live(&self, p: u32, enabled: &[u64], s: &mut PrioritySearch) -> bool {
        self.priority_graph.high_groups(p).any(|z| {
            self.look(z, Through::Any, enabled, s)
                .unwrap_or_else(|| self.leads_up(z, Through::Any, enabled, s))
        })
    }

    /// What the masks say of whether a path of the kind `through` leads up from group `g`
    /// to an enabled interaction, if they know.
    #[inline]
    fn masked(&self, g: u32, through: Through, enabled: &[u64]) -> Option<bool> {
        let masks = &self.priority_masks;
        // a masked group has no `when` above it: every path up is plain
        let span = masks.group_span(g).or_else(|| {
            (through == Through::Plain)
                .then(|| masks.group_plain(g))
                .flatten()
        })?;
        Some(masks.span_blocked(span, enabled))
    }

    /// What is known without a walk of whether group `z` is or leads to an enabled
    /// interaction (through the priorities `through` says).
    #[inline]
    fn look(&self, z: u32, through: Through, enabled: &[u64], s: &PrioritySearch) -> Option<bool> {
        if crate::step::any_bit(enabled, self.priority_graph.interactions(z)) {
            return Some(true);
        }
        if let Some(yes) = self.masked(z, through, enabled) {
            return Some(yes);
        }
        let (stamp, memo) = s.leads[through as usize][z as usize];
        // (open in this epoch: on the walk's path, which a cycle would come back to)
        (stamp == s.epoch).then_some(memo == Memo::Yes)
    }

    /// True if a path of priorities (of the kind `through` says) leads up from group `g` to
    /// an enabled interaction. A walk with a memo per group, without recursion (chains may
    /// be long).
    fn leads_up(&self, g: u32, through: Through, enabled: &[u64], s: &mut PrioritySearch) -> bool {
        let graph = &self.priority_graph;
        let epoch = s.epoch;
        let memo = |s: &mut PrioritySearch, z: u32, m: Memo| {
            s.leads[through as usize][z as usize] = (epoch, m);
        };
        if let Some(yes) = self.masked(g, through, enabled) {
            return yes;
        }
        let known = s.leads[through as usize][g as usize];
        if known.0 == epoch {
            return known.1 == Memo::Yes;
        }
        memo(s, g, Memo::Open);
        s.frames.clear();
        s.frames.push((g, 0, UNSTARTED));
        while let Some(&(g, k, z)) = s.frames.last() {
            let below = graph.below(g);
            let Some(&p) = below.get(k as usize) else {
                memo(s, g, Memo::No);
                s.frames.pop();
                continue;
            };
            let highs = graph.high_groups(p);
            let when = self.priorities[p as usize].when.is_some();
            let skip = match through {
                Through::Any => false,
                Through::Holding => when && s.when[p as usize] != (epoch, true),
                Through::Plain => when,
            };
            let z = match (z, skip) {
                (UNSTARTED, true) => highs.end,
                (UNSTARTED, false) => highs.start,
                (z, _) => z,
            };
            let top = s.frames.len() - 1;
            if z >= highs.end {
                s.frames[top] = (g, k + 1, UNSTARTED);
                continue;
            }
            s.frames[top] = (g, k, z + 1);
            match self.look(z, through, enabled, s) {
                Some(true) => {
                    // every group on the path leads there
                    for f in 0..s.frames.len() {
                        let on = s.frames[f].0;
                        memo(s, on, Memo::Yes);
                    }
                    s.frames.clear();
                    return true;
                }
                Some(false) => {}
                None => {
                    memo(s, z, Memo::Open);
                    s.frames.push((z, 0, UNSTARTED));
                }
            }
        }
        false
    }
}

/// The set bits of a word, lowest first.
struct Bits(u64);

impl Iterator for Bits {
    type Item = u32;

    #[inline]
    fn next(&mut self) -> Option<u32> {
        (self.0 != 0).then(|| {
            let b = self.0.trailing_zeros();
            self.0 &= self.0 - 1;
            b
        })
    }
}
