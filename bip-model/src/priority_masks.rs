//! Priorities as sparse bit masks: for each interaction, the interactions higher than it
//! under rules without a `when`, as `(word, bits)` pairs over a set of interactions (one
//! bit each). Deciding whether such an interaction is suppressed is then a few word
//! tests instead of a walk over its rules and their ranges. Built once with the system;
//! the full step relation and [`crate::EnabledSet`] both decide priorities with it.

#[allow(unused_imports)]
use crate::prelude::*;

use alloc::collections::BTreeMap;

use crate::model::PriorityRule;

#[derive(Clone, Debug, Default)]
pub(crate) struct PriorityMasks {
    /// `highs[a..b]` with `(a, b) = highs_of[i]`: the higher interactions of `i` under
    /// rules without a `when`. Interactions with the same higher ones share their span (a
    /// GenoM layer's requests and tick: one span), so that a caller deciding many of
    /// them may decide each span once ([`PriorityMasks::span`]).
    highs_of: Vec<(u32, u32)>,
    highs: Vec<(u32, u64)>,
    /// Interactions under some rule with a `when`: their suppression depends on the state.
    pub(crate) under_when: Vec<u64>,
    /// Interactions that no rule names as higher and no `when` decides: while suppressed
    /// they cannot change what any other interaction is allowed.
    pub(crate) lazy: Vec<u64>,
    pub(crate) any_when: bool,
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

impl PriorityMasks {
    // systems are compiled with `std` (loading needs it); a no-std build receives them
    pub(crate) fn new(
        priorities: &[PriorityRule],
        rules_by_low: &[Vec<u32>],
        n_inter: usize,
    ) -> PriorityMasks {
        let words = n_inter.div_ceil(64);
        let rule_has_when: Vec<bool> = priorities.iter().map(|r| !r.when.is_empty()).collect();
        let mut under_when = vec![0u64; words];
        for (i, rules) in rules_by_low.iter().enumerate() {
            if rules.iter().any(|&r| rule_has_when[r as usize]) {
                set_bit(&mut under_when, i as u32, true);
            }
        }
        let mut is_high = vec![0u64; words];
        let mut per_low: Vec<Vec<(u32, u64)>> = vec![Vec::new(); n_inter];
        for (rule, &when) in priorities.iter().zip(&rule_has_when) {
            for h in rule.high.clone() {
                set_bit(&mut is_high, h, true);
            }
            if when {
                continue;
            }
            for l in rule.low.clone() {
                let masks = &mut per_low[l as usize];
                for h in rule.high.clone() {
                    let (w, b) = (h / 64, 1u64 << (h % 64));
                    match masks.iter_mut().find(|(mw, _)| *mw == w) {
                        Some((_, m)) => *m |= b,
                        None => masks.push((w, b)),
                    }
                }
            }
        }
        let mut highs = Vec::new();
        let mut spans: BTreeMap<&[(u32, u64)], (u32, u32)> = BTreeMap::new();
        let highs_of = per_low
            .iter()
            .map(|l| {
                *spans.entry(&l[..]).or_insert_with(|| {
                    let a = highs.len() as u32;
                    highs.extend_from_slice(l);
                    (a, highs.len() as u32)
                })
            })
            .collect();
        let mut lazy = vec![0u64; words];
        for i in 0..n_inter as u32 {
            set_bit(&mut lazy, i, !bit(&is_high, i) && !bit(&under_when, i));
        }
        PriorityMasks {
            highs_of,
            highs,
            under_when,
            lazy,
            any_when: rule_has_when.iter().any(|&w| w),
        }
    }

    /// True if a higher interaction of `i` under a rule without `when` is in `enabled`.
    #[inline]
    pub(crate) fn blocked(&self, i: u32, enabled: &[u64]) -> bool {
        self.span_blocked(self.span(i), enabled)
    }

    /// Where the higher interactions of `i` are listed: two interactions with the same
    /// span have the same higher interactions.
    #[inline]
    pub(crate) fn span(&self, i: u32) -> (u32, u32) {
        self.highs_of[i as usize]
    }

    /// [`PriorityMasks::blocked`] for the interactions of span `(a, b)`.
    #[inline]
    pub(crate) fn span_blocked(&self, (a, b): (u32, u32), enabled: &[u64]) -> bool {
        self.highs[a as usize..b as usize]
            .iter()
            .any(|&(w, m)| enabled[w as usize] & m != 0)
    }
}
