//! Priorities as sparse bit masks: for each interaction, every interaction above it in the
//! closure of the priorities, when no `when` lies on a path up from it, as `(word, bits)`
//! pairs over a set of interactions (one bit each). Deciding whether such an interaction
//! is suppressed is then a few word tests instead of a walk up the priority graph. Built
//! once with the system, group by group from the highest down, each group's mask the union
//! of those of the groups right above it; the full step relation and [`crate::EnabledSet`]
//! both decide priorities with it.
//!
//! The masks hold the closure, which may grow with the square of the declared relation: a
//! group whose mask would take the masks past [`MAX_PAIRS`] (or their building past
//! [`MAX_WORK`]) gets none, and a group below a `when` gets only its *plain* mask (the
//! interactions above it through priorities without `when`). Those interactions are
//! *searched*: their suppression is decided per state by a walk up the graph
//! (`suppression`), which reads the masks it meets.

#[allow(unused_imports)]
use crate::prelude::*;

use alloc::collections::BTreeMap;
use alloc::sync::Arc;

use crate::eval::Expr;
use crate::model::{Atom, Component, Interaction, Priority};
use crate::priority_graph::PriorityGraph;

/// The most `(word, bits)` pairs the masks of one system may hold (16 MiB).
pub(crate) const MAX_PAIRS: usize = 1 << 20;
/// The most pairs building them may read.
const MAX_WORK: usize = 1 << 24;

#[derive(Clone, Debug, Default)]
pub(crate) struct PriorityMasks {
    /// `highs[a..b]` with `(a, b) = highs_of[i]`: the interactions above `i`, if it is not
    /// searched. Interactions with the same higher ones share their span (a GenoM layer's
    /// requests and tick: one span), so that a caller deciding many of them may decide each
    /// span once ([`PriorityMasks::span`]).
    highs_of: Arc<[(u32, u32)]>,
    highs: Arc<[(u32, u64)]>,
    /// Per group of the priority graph, its span in `highs`; `None` for a searched group.
    group_highs: Arc<[Option<(u32, u32)>]>,
    /// Per group, the span in `highs` of the interactions above it through priorities
    /// without `when`, if it fits (for a group that is not searched, its whole mask).
    group_plain: Arc<[Option<(u32, u32)>]>,
    /// The priorities with a `when`.
    pub(crate) with_when: Arc<[u32]>,
    /// Interactions whose suppression is searched per state.
    pub(crate) searched: Vec<u64>,
    /// Interactions that no priority names as higher, that are not searched and whose
    /// evaluation cannot fail: while suppressed they cannot change what any other
    /// interaction is allowed, nor be a range error.
    pub(crate) lazy: Vec<u64>,
    pub(crate) any_searched: bool,
}

pub(crate) fn bit(bits: &[u64], i: u32) -> bool {
    bits[i as usize / 64] >> (i % 64) & 1 == 1
}

pub(crate) fn set_bit(bits: &mut [u64], i: u32, on: bool) {
    let w = &mut bits[i as usize / 64];
    if on {
        *w |= 1 << (i % 64);
    } else {
        *w &= !(1 << (i % 64));
    }
}

/// The masks being built: every distinct set once, within the budgets.
struct Pool {
    pairs: Vec<(u32, u64)>,
    max_pairs: usize,
    /// Spans in `pairs` by length and hash of their content.
    index: BTreeMap<(usize, u64), Vec<(u32, u32)>>,
    work: usize,
    scratch: Vec<(u32, u64)>,
}

impl Pool {
    /// The span of the union of `spans` and the interactions of `ranges`, or `None` past a
    /// budget.
    fn union(
        &mut self,
        spans: impl Iterator<Item = (u32, u32)> + Clone,
        ranges: impl Iterator<Item = core::ops::Range<u32>> + Clone,
    ) -> Option<(u32, u32)> {
        let words =
            |r: core::ops::Range<u32>| u64::from(r.end).div_ceil(64) - u64::from(r.start) / 64;
        let size: usize = spans.clone().map(|(a, b)| (b - a) as usize).sum::<usize>()
            + ranges.clone().map(|r| words(r) as usize).sum::<usize>();
        self.work += size;
        if self.work > MAX_WORK || self.pairs.len() + size > self.max_pairs {
            return None;
        }
        let u = &mut self.scratch;
        u.clear();
        for (a, b) in spans {
            u.extend_from_slice(&self.pairs[a as usize..b as usize]);
        }
        for r in ranges {
            let mut i = u64::from(r.start);
            while i < u64::from(r.end) {
                let w = i / 64;
                let end = u64::from(r.end).min((w + 1) * 64);
                let n = end - i;
                let bits = if n == 64 {
                    !0
                } else {
                    ((1u64 << n) - 1) << (i % 64)
                };
                u.push((w as u32, bits));
                i = end;
            }
        }
        u.sort_unstable_by_key(|&(w, _)| w);
        let mut k = 0;
        for j in 0..u.len() {
            if k > 0 && u[k - 1].0 == u[j].0 {
                u[k - 1].1 |= u[j].1;
            } else {
                u[k] = u[j];
                k += 1;
            }
        }
        u.truncate(k);
        let hash = u.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &(w, b)| {
            (h ^ u64::from(w) ^ b.rotate_left(17)).wrapping_mul(0x0100_0000_01b3)
        });
        let same = self.index.entry((u.len(), hash)).or_default();
        if let Some(&s) = same
            .iter()
            .find(|&&(a, b)| self.pairs[a as usize..b as usize] == u[..])
        {
            return Some(s);
        }
        let a = self.pairs.len() as u32;
        self.pairs.extend_from_slice(u);
        let s = (a, self.pairs.len() as u32);
        same.push(s);
        Some(s)
    }
}

impl PriorityMasks {
    // systems are compiled with `std` (loading needs it); a no-std build receives them
    /// The masks of the priorities of `graph` over `n_inter` interactions, with at most
    /// `max_pairs` pairs.
    pub(crate) fn new(
        graph: &PriorityGraph,
        priorities: &[Priority],
        n_inter: usize,
        max_pairs: usize,
        cannot_fail: impl Fn(u32) -> bool,
    ) -> PriorityMasks {
        let words = n_inter.div_ceil(64);
        let groups = graph.groups() as usize;
        let mut pool = Pool {
            pairs: Vec::new(),
            max_pairs,
            index: BTreeMap::new(),
            work: 0,
            scratch: Vec::new(),
        };
        let empty = pool.union(core::iter::empty(), core::iter::empty());
        // per group, its plain mask: the interactions above it through priorities without
        // `when` (`None`: past the budget, or not reached by the order: a cycle); and
        // whether it is searched (below a `when`, or its plain mask is not the whole answer)
        let mut plain: Vec<Option<(u32, u32)>> = vec![None; groups];
        let mut searched_group = vec![true; groups];
        // per priority without `when`, the union of its high side's groups and their plain
        // masks, once
        let mut above: Vec<Option<Option<(u32, u32)>>> = vec![None; priorities.len()];
        for &g in graph.order() {
            let mut parts: Vec<(u32, u32)> = Vec::new();
            let mut fits = true;
            let mut searched = false;
            for &p in graph.below(g) {
                let highs = graph.high_groups(p);
                searched |= highs.clone().any(|z| searched_group[z as usize]);
                if priorities[p as usize].when.is_some() {
                    searched = true;
                    continue;
                }
                let a = *above[p as usize].get_or_insert_with(|| {
                    let masks: Option<Vec<(u32, u32)>> =
                        highs.clone().map(|z| plain[z as usize]).collect();
                    pool.union(masks?.into_iter(), highs.map(|z| graph.interactions(z)))
                });
                match a {
                    Some(s) => parts.push(s),
                    None => fits = false,
                }
            }
            plain[g as usize] = match (fits, &parts[..]) {
                (false, _) => None,
                (true, []) => empty,
                (true, [one]) => Some(*one),
                (true, _) => pool.union(parts.iter().copied(), core::iter::empty()),
            };
            searched_group[g as usize] = searched || plain[g as usize].is_none();
        }
        let mask: Vec<Option<(u32, u32)>> = (0..groups)
            .map(|g| plain[g].filter(|_| !searched_group[g]))
            .collect();
        let mut highs_of = vec![(0u32, 0u32); n_inter];
        let mut searched = vec![0u64; words];
        let mut is_high = vec![0u64; words];
        for g in 0..groups as u32 {
            let below = !graph.below(g).is_empty();
            for i in graph.interactions(g) {
                match mask[g as usize] {
                    Some(s) => highs_of[i as usize] = s,
                    None if below => set_bit(&mut searched, i, true),
                    None => {}
                }
            }
        }
        let mut high_group = vec![false; groups];
        for p in 0..priorities.len() as u32 {
            for z in graph.high_groups(p) {
                high_group[z as usize] = true;
            }
        }
        for g in 0..groups as u32 {
            if high_group[g as usize] {
                for i in graph.interactions(g) {
                    set_bit(&mut is_high, i, true);
                }
            }
        }
        let mut lazy = vec![0u64; words];
        for i in 0..n_inter as u32 {
            // one whose evaluation may fail is evaluated in every state, as the step
            // relation evaluates it: its range error is the state's, suppressed or not
            set_bit(
                &mut lazy,
                i,
                !bit(&is_high, i) && !bit(&searched, i) && cannot_fail(i),
            );
        }
        PriorityMasks {
            highs_of: highs_of.into(),
            highs: pool.pairs.into(),
            group_highs: mask.into(),
            group_plain: plain.into(),
            with_when: (0..priorities.len() as u32)
                .filter(|&p| priorities[p as usize].when.is_some())
                .collect(),
            any_searched: searched.iter().any(|&w| w != 0),
            searched,
            lazy,
        }
    }

    /// True if an interaction above `i` (not searched) is in `enabled`.
    #[inline]
    pub(crate) fn blocked(&self, i: u32, enabled: &[u64]) -> bool {
        self.span_blocked(self.span(i), enabled)
    }

    /// Where the interactions above `i` are listed: two interactions with the same span
    /// have the same higher interactions.
    #[inline]
    pub(crate) fn span(&self, i: u32) -> (u32, u32) {
        self.highs_of[i as usize]
    }

    /// The span of the interactions above the interactions of group `g`, unless they are
    /// searched.
    #[inline]
    pub(crate) fn group_span(&self, g: u32) -> Option<(u32, u32)> {
        self.group_highs[g as usize]
    }

    /// The span of the interactions above the interactions of group `g` through
    /// priorities without `when`, if it fits.
    #[inline]
    pub(crate) fn group_plain(&self, g: u32) -> Option<(u32, u32)> {
        self.group_plain[g as usize]
    }

    /// [`PriorityMasks::blocked`] for the interactions of span `(a, b)`.
    #[inline]
    pub(crate) fn span_blocked(&self, (a, b): (u32, u32), enabled: &[u64]) -> bool {
        self.highs[a as usize..b as usize]
            .iter()
            .any(|&(w, m)| enabled[w as usize] & m != 0)
    }
}

/// True if evaluating interaction `i` in a state (its guard, and the guards of its ports'
/// transitions) can never be a range error.
pub(crate) fn evaluation_cannot_fail(
    atoms: &[Atom],
    components: &[Component],
    interactions: &[Interaction],
    i: u32,
) -> bool {
    let interaction = &interactions[i as usize];
    interaction.guard.as_ref().is_none_or(Expr::cannot_fail)
        && interaction.ports.iter().all(|p| {
            let atom = &atoms[components[p.component as usize].atom as usize];
            atom.transitions
                .iter()
                .filter(|t| t.port == Some(p.port))
                .all(|t| t.guard.as_ref().is_none_or(Expr::cannot_fail))
        })
}
