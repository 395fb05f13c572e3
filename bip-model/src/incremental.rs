//! The enabled steps of a state, kept up to date as the state moves.
//!
//! [`System::enabled_steps`] evaluates every interaction in every state. A runtime engine
//! takes one step at a time, and a step moves a few components: only the interactions that
//! read those components can change. [`EnabledSet`] caches, per interaction, its steps
//! before priorities, and after a step re-evaluates only the interactions whose participants
//! or read components (`Interaction::reads`) moved, with the same function the full
//! relation uses ([`System::push_interaction_steps`]); priorities are applied with
//! per-rule counts of enabled higher interactions, or with [`System::is_suppressed`] itself
//! for interactions under a rule with a `when`. It is not a second notion of "enabled": it
//! yields exactly the steps of [`System::enabled_steps`], in the same order (a property
//! test checks it on random systems), only computed from a cache.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::state::State;
use crate::step::{Label, Pick, Step, Steps};
use crate::system::{RangeError, System};

/// The enabled steps of one state of one system (after priorities), maintained
/// incrementally with [`EnabledSet::update`].
///
/// After [`EnabledSet::new`] or [`EnabledSet::reset`] has sized its buffers, updates
/// allocate nothing unless an interaction has more steps than it ever had.
#[derive(Clone, Debug)]
pub struct EnabledSet {
    // ---- tables of the system (fixed) ----
    /// Per component, its slots: `slots[comp_slots[c]..comp_slots[c + 1]]`.
    comp_slots: Vec<u32>,
    /// Per component, the interactions that read it (as a participant, or in a guard or
    /// action): `deps[deps_start[c]..deps_start[c + 1]]`.
    deps_start: Vec<u32>,
    deps: Vec<u32>,
    /// Per interaction, the priority rules in which it is one of the higher interactions.
    by_high_start: Vec<u32>,
    by_high: Vec<u32>,
    /// Per rule without a `when`, the interactions it suppresses (`low`), as `start..end`;
    /// empty for a rule with a `when`. A copy of `System::priorities`' ranges packed in 8
    /// bytes a rule: [`EnabledSet::flip`] walks them on every change of an interaction.
    rule_low: Vec<(u32, u32)>,
    /// Interactions under some rule with a `when`: their suppression is decided by
    /// [`System::is_suppressed`] in each state.
    under_when: Vec<u64>,
    any_when: bool,

    // ---- the state's enabled steps ----
    /// Per interaction, the picks of its steps before priorities, `width` picks per step.
    picks: Vec<Vec<Pick>>,
    width: Vec<u32>,
    /// Interactions with steps before priorities (one bit each).
    pre: Vec<u64>,
    /// Per rule, how many of its higher interactions have steps.
    high_count: Vec<u32>,
    /// Per interaction, how many rules without `when` suppress it now.
    blockers: Vec<u32>,
    /// Per interaction under a `when` rule: suppressed in this state.
    when_suppressed: Vec<u64>,
    /// Per component, its enabled internal transitions.
    internal: Vec<Vec<Pick>>,

    // ---- scratch ----
    scratch: Steps,
    stamp: Vec<u32>,
    epoch: u32,
    dirty: Vec<u32>,
    /// False after an update failed: the set must be [`EnabledSet::reset`].
    valid: bool,
}

fn bit(bits: &[u64], i: u32) -> bool {
    bits[i as usize / 64] >> (i % 64) & 1 == 1
}

fn set_bit(bits: &mut [u64], i: u32, on: bool) {
    let w = &mut bits[i as usize / 64];
    if on {
        *w |= 1 << (i % 64);
    } else {
        *w &= !(1 << (i % 64));
    }
}

impl EnabledSet {
    /// The enabled steps of `state`, evaluated in full.
    pub fn new(system: &System, state: &State) -> Result<EnabledSet, RangeError> {
        let n_inter = system.interactions.len();
        let n_comp = system.components.len();
        let words = n_inter.div_ceil(64);

        let mut comp_slots: Vec<u32> = system.components.iter().map(|c| c.slot).collect();
        comp_slots.push(system.slot_count() as u32);

        // component -> interactions reading it (participants and reads), deduplicated
        let mut per_comp: Vec<Vec<u32>> = vec![Vec::new(); n_comp];
        for (i, inter) in system.interactions.iter().enumerate() {
            let i = i as u32;
            for c in inter
                .ports
                .iter()
                .map(|p| p.component)
                .chain(inter.reads.iter().copied())
            {
                let list = &mut per_comp[c as usize];
                if list.last() != Some(&i) && !list.contains(&i) {
                    list.push(i);
                }
            }
        }
        // rules with a `when`: the interactions under them are re-decided in every state,
        // so the components their `when`s read need no table
        let rule_has_when: Vec<bool> = system
            .priorities
            .iter()
            .map(|r| !r.when.is_empty())
            .collect();
        let mut under_when = vec![0u64; words];
        for (i, rules) in system.rules_by_low.iter().enumerate() {
            if rules.iter().any(|&r| rule_has_when[r as usize]) {
                set_bit(&mut under_when, i as u32, true);
            }
        }
        let any_when = rule_has_when.iter().any(|&w| w);
        let rule_low = system
            .priorities
            .iter()
            .zip(&rule_has_when)
            .map(|(r, &when)| {
                if when {
                    (0, 0)
                } else {
                    (r.low.start, r.low.end)
                }
            })
            .collect();
        let (deps_start, deps) = flatten(&per_comp);

        let mut per_high: Vec<Vec<u32>> = vec![Vec::new(); n_inter];
        for (r, rule) in system.priorities.iter().enumerate() {
            for h in rule.high.clone() {
                per_high[h as usize].push(r as u32);
            }
        }
        let (by_high_start, by_high) = flatten(&per_high);

        let mut set = EnabledSet {
            comp_slots,
            deps_start,
            deps,
            by_high_start,
            by_high,
            rule_low,
            under_when,
            any_when,
            picks: vec![Vec::new(); n_inter],
            width: vec![0; n_inter],
            pre: vec![0; words],
            high_count: vec![0; system.priorities.len()],
            blockers: vec![0; n_inter],
            when_suppressed: vec![0; words],
            internal: vec![Vec::new(); n_comp],
            scratch: Steps::new(),
            stamp: vec![0; n_inter],
            epoch: 0,
            dirty: Vec::with_capacity(n_inter),
            valid: false,
        };
        set.reset(system, state)?;
        Ok(set)
    }

    /// Re-evaluates everything for `state` (after an error, or to jump to another state).
    pub fn reset(&mut self, system: &System, state: &State) -> Result<(), RangeError> {
        self.valid = false;
        self.pre.fill(0);
        self.high_count.fill(0);
        self.blockers.fill(0);
        self.when_suppressed.fill(0);
        for p in &mut self.picks {
            p.clear();
        }
        self.width.fill(0);
        for c in 0..system.components.len() as u32 {
            self.eval_internal(system, state, c)?;
        }
        for i in 0..system.interactions.len() as u32 {
            self.eval_interaction(system, state, i)?;
        }
        self.decide_whens(system, state)?;
        self.valid = true;
        Ok(())
    }

    /// Brings the set from `before` (the state it describes) to `after`, the state a step
    /// led to, re-evaluating only what reads a component whose slots differ.
    ///
    /// On a range error (a guard that cannot be evaluated in `after`), the set is left
    /// unusable until [`EnabledSet::reset`]; so is any state of a system other than the
    /// one it was built for.
    pub fn update(
        &mut self,
        system: &System,
        before: &State,
        after: &State,
    ) -> Result<(), RangeError> {
        self.valid = false;
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.stamp.fill(0);
            self.epoch = 1;
        }
        self.dirty.clear();
        let (a, b) = (before.slots(), after.slots());
        for c in 0..self.comp_slots.len() - 1 {
            let (lo, hi) = (self.comp_slots[c] as usize, self.comp_slots[c + 1] as usize);
            if a[lo..hi] == b[lo..hi] {
                continue;
            }
            self.eval_internal(system, after, c as u32)?;
            let (s, e) = (self.deps_start[c] as usize, self.deps_start[c + 1] as usize);
            for k in s..e {
                let i = self.deps[k];
                if self.stamp[i as usize] != self.epoch {
                    self.stamp[i as usize] = self.epoch;
                    self.dirty.push(i);
                }
            }
        }
        for k in 0..self.dirty.len() {
            let i = self.dirty[k];
            self.eval_interaction(system, after, i)?;
        }
        self.decide_whens(system, after)?;
        self.valid = true;
        Ok(())
    }

    /// True unless the last update or reset failed.
    pub fn is_valid(&self) -> bool {
        self.valid
    }

    fn eval_internal(&mut self, system: &System, state: &State, c: u32) -> Result<(), RangeError> {
        let out = &mut self.internal[c as usize];
        out.clear();
        self.scratch.clear();
        system.push_internal_steps_of(state, c, &mut self.scratch)?;
        out.extend_from_slice(&self.scratch.picks);
        Ok(())
    }

    fn eval_interaction(
        &mut self,
        system: &System,
        state: &State,
        i: u32,
    ) -> Result<(), RangeError> {
        self.scratch.clear();
        system.push_interaction_steps(state, i, &mut self.scratch)?;
        let steps = self.scratch.len();
        let picks = &mut self.picks[i as usize];
        picks.clear();
        picks.extend_from_slice(&self.scratch.picks);
        self.width[i as usize] = picks.len().checked_div(steps).unwrap_or(0) as u32;
        let now = steps > 0;
        if now != bit(&self.pre, i) {
            set_bit(&mut self.pre, i, now);
            self.flip(i, now);
        }
        Ok(())
    }

    /// Interaction `i` gained (`on`) or lost its steps: count it in the rules where it is
    /// higher, and update what those rules suppress.
    fn flip(&mut self, i: u32, on: bool) {
        let (s, e) = (
            self.by_high_start[i as usize] as usize,
            self.by_high_start[i as usize + 1] as usize,
        );
        for &r in &self.by_high[s..e] {
            let r = r as usize;
            let before = self.high_count[r];
            let after = if on { before + 1 } else { before - 1 };
            self.high_count[r] = after;
            if (before == 0) != (after == 0) {
                let (lo, hi) = self.rule_low[r];
                for b in &mut self.blockers[lo as usize..hi as usize] {
                    *b = if on { *b + 1 } else { *b - 1 };
                }
            }
        }
    }

    /// Decides suppression of the enabled interactions under a rule with a `when`.
    fn decide_whens(&mut self, system: &System, state: &State) -> Result<(), RangeError> {
        if !self.any_when {
            return Ok(());
        }
        for w in 0..self.pre.len() {
            let mut bits = self.pre[w] & self.under_when[w];
            while bits != 0 {
                let i = (w * 64) as u32 + bits.trailing_zeros();
                bits &= bits - 1;
                let s = system.is_suppressed(state, i, &self.pre)?;
                set_bit(&mut self.when_suppressed, i, s);
            }
        }
        Ok(())
    }

    /// True if interaction `i` has steps before priorities are applied.
    pub fn has_steps_before_priorities(&self, i: u32) -> bool {
        bit(&self.pre, i)
    }

    /// True if interaction `i` has enabled steps (after priorities).
    #[inline]
    pub fn is_enabled(&self, i: u32) -> bool {
        bit(&self.pre, i) && !self.is_suppressed(i)
    }

    #[inline]
    fn is_suppressed(&self, i: u32) -> bool {
        if bit(&self.under_when, i) {
            bit(&self.when_suppressed, i)
        } else {
            self.blockers[i as usize] > 0
        }
    }

    /// The interactions with enabled steps (after priorities), in index order.
    pub fn interactions(&self) -> impl Iterator<Item = u32> + '_ {
        self.pre.iter().enumerate().flat_map(move |(w, &word)| {
            let mut bits = word;
            core::iter::from_fn(move || {
                while bits != 0 {
                    let i = (w * 64) as u32 + bits.trailing_zeros();
                    bits &= bits - 1;
                    if !self.is_suppressed(i) {
                        return Some(i);
                    }
                }
                None
            })
        })
    }

    /// The steps of interaction `i` (none if it is not enabled after priorities).
    pub fn steps_of(&self, i: u32) -> impl Iterator<Item = Step<'_>> + '_ {
        let enabled = self.is_enabled(i);
        let w = self.width[i as usize].max(1) as usize;
        let picks: &[Pick] = if enabled {
            &self.picks[i as usize]
        } else {
            &[]
        };
        picks.chunks(w).map(move |p| Step {
            label: Label::Interaction(i),
            picks: p,
        })
    }

    /// The enabled internal transitions, by component then transition.
    pub fn internal_steps(&self) -> impl Iterator<Item = Step<'_>> + '_ {
        self.internal.iter().enumerate().flat_map(|(c, picks)| {
            picks.chunks(1).map(move |p| Step {
                label: Label::Internal {
                    component: c as u32,
                },
                picks: p,
            })
        })
    }

    /// Every enabled step, in the order of [`System::enabled_steps`].
    pub fn steps(&self) -> impl Iterator<Item = Step<'_>> + '_ {
        self.internal_steps()
            .chain(self.interactions().flat_map(move |i| self.steps_of(i)))
    }

    /// Writes the enabled steps into `out`, as [`System::enabled_steps`] would.
    pub fn copy_to(&self, out: &mut Steps) {
        out.clear();
        for s in self.steps() {
            out.push(s.label, s.picks.iter().copied());
        }
    }

    /// True if no step is enabled.
    pub fn is_empty(&self) -> bool {
        self.internal.iter().all(Vec::is_empty) && self.interactions().next().is_none()
    }
}

/// Lists of lists as one array and start offsets (one more than lists).
fn flatten(lists: &[Vec<u32>]) -> (Vec<u32>, Vec<u32>) {
    let mut start = Vec::with_capacity(lists.len() + 1);
    let mut flat = Vec::new();
    for l in lists {
        start.push(flat.len() as u32);
        flat.extend_from_slice(l);
    }
    start.push(flat.len() as u32);
    (start, flat)
}
