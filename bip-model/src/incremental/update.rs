//! Bringing an [`EnabledSet`] from one state to the next: the slots that changed mark the
//! interactions that read them, which are evaluated again, then priorities are settled.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::fire_plan::{FirePlans, PlanId};
use crate::found::Found;
use crate::model::RangeError;
use crate::plan_effects::{PlanEffects, SlotEffect};
use crate::priority_masks::{bit, set_bit};
use crate::state::State;
use crate::step_tables::LastKey;
use crate::system::System;
use crate::watches::Mark;

use super::EnabledSet;

impl EnabledSet {
    /// Brings the set from `before` (the state it describes) to `after`, the state a step
    /// led to, re-evaluating only the interactions that read a slot that differs (and the
    /// internal transitions of the components owning one).
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
        self.begin_update();
        let (a, b) = (before.slots(), after.slots());
        debug_assert!(a.len() == self.slot_comp.len() && b.len() == self.slot_comp.len());
        // a step writes few slots: skip unchanged ones four at a time (xor, no call)
        const W: usize = 4;
        let whole = a.len().min(b.len()) / W * W;
        for (k, (x, y)) in a.chunks_exact(W).zip(b.chunks_exact(W)).enumerate() {
            if (x[0] ^ y[0]) | (x[1] ^ y[1]) | (x[2] ^ y[2]) | (x[3] ^ y[3]) == 0 {
                continue;
            }
            for j in 0..W {
                if x[j] != y[j] {
                    self.slot_changed(system, after, (k * W + j) as u32)?;
                }
            }
        }
        for s in whole..a.len().min(b.len()) {
            if a[s] != b[s] {
                self.slot_changed(system, after, s as u32)?;
            }
        }
        self.finish_update(system, after)
    }

    /// [`EnabledSet::update`] when the caller knows which slots may differ between
    /// `before` and `after`: those in `written` ([`System::fire_in_place`] lists them);
    /// the others are not looked at.
    pub fn update_written(
        &mut self,
        system: &System,
        before: &State,
        after: &State,
        written: &[u32],
    ) -> Result<(), RangeError> {
        self.begin_update();
        let (a, b) = (before.slots(), after.slots());
        for &s in written {
            if a[s as usize] != b[s as usize] {
                self.slot_changed(system, after, s)?;
            }
        }
        self.finish_update(system, after)
    }

    /// [`EnabledSet::update`] after the step of plan `p` of `plans` was fired from
    /// `before` ([`System::fire_planned`]), with `effects` made by
    /// [`EnabledSet::plan_effects`] for those plans: what the plan makes known ahead of
    /// time is not read from the state again. The step must be enabled in `before`, the
    /// state the set describes.
    pub fn update_planned(
        &mut self,
        system: &System,
        effects: &PlanEffects,
        p: PlanId,
        before: &State,
        after: &State,
    ) -> Result<(), RangeError> {
        self.begin_update();
        let (a, b) = (before.slots(), after.slots());
        let (s0, s1, f0, f1) = effects.plans[p.index()];
        // what the step leads to in every case: stored now, and not marked again
        for &(i, f) in &effects.found[f0 as usize..f1 as usize] {
            #[cfg(debug_assertions)]
            {
                // the entry the state's key finds is the one the plan fixed
                let tables = &system.enable_index.tables;
                let mut fresh = LastKey::NONE;
                let e = tables.lookup_sharing(i, b, &mut fresh).map(Found::of);
                debug_assert_eq!(
                    e.map(|e| (e.start, e.len, e.width, e.ready)),
                    Some((f.start, f.len, f.width, f.ready)),
                    "interaction {i}"
                );
            }
            self.store(i, f);
            set_bit(&mut self.stale, i, false);
            self.stamp[i as usize] = self.epoch;
        }
        for &SlotEffect {
            slot,
            marks,
            dynamic,
        } in &effects.slots[s0 as usize..s1 as usize]
        {
            if a[slot as usize] == b[slot as usize] {
                continue;
            }
            if self.any_internal {
                self.internal_changed(system, after, slot)?;
            }
            let (found, stamp, dirty, epoch) =
                (&self.found, &mut self.stamp, &mut self.dirty, self.epoch);
            let mut mark = |m: Mark| mark(found, stamp, dirty, epoch, m);
            for &m in &effects.marks[marks.0 as usize..marks.1 as usize] {
                mark(m);
            }
            for &k in &effects.dynamic[dynamic.0 as usize..dynamic.1 as usize] {
                self.watches.for_watch(k, b, &mut mark);
            }
        }
        self.finish_update(system, after)
    }

    /// What firing each of `plans` (the plans of this set's system) does to the set, for
    /// [`EnabledSet::update_planned`] (see [`PlanEffects`]).
    pub fn plan_effects(&self, system: &System, plans: &FirePlans) -> PlanEffects {
        let tables = &system.enable_index.tables;
        let mut out = PlanEffects::default();
        let mut scratch = State::from_slots(vec![0; system.slot_count()]);
        let mut written: Vec<u32> = Vec::new();
        let mut reached: Vec<u32> = Vec::new();
        for p in plans.ids() {
            let after = system.plan_after(plans, p);
            let known = |slot: u32| after.get(&slot).copied().flatten();
            written.clear();
            written.extend_from_slice(plans.written(p));
            written.sort_unstable();
            written.dedup();
            // every interaction a change of a written slot may mark
            reached.clear();
            for &slot in &written {
                for k in self.watches.watches_of(slot) {
                    let marks = match known(self.watches.watched_slot(k)) {
                        Some(location) => self.watches.marks_at(k, location),
                        None => self.watches.all_marks(k),
                    };
                    reached.extend(marks.iter().map(|m| m.interaction));
                }
            }
            reached.sort_unstable();
            reached.dedup();
            // an interaction whose key is made of known values finds the same entry in
            // every state the step leads to (a value out of its range has no entry, and
            // an entry where the relation fails is not known: both are left to the state)
            let f0 = out.found.len() as u32;
            for &i in &reached {
                let Some(digits) = tables.key_digits(i) else {
                    continue;
                };
                let mut all_known = true;
                for d in digits {
                    match known(d.slot()) {
                        Some(v) => scratch.slots_mut()[d.slot() as usize] = v,
                        None => all_known = false,
                    }
                }
                if !all_known {
                    continue;
                }
                let mut fresh = LastKey::NONE;
                if let Some(e) = tables.lookup_sharing(i, scratch.slots(), &mut fresh) {
                    out.found.push((i, Found::of(e)));
                }
            }
            let is_known = |i: u32| out.found[f0 as usize..].iter().any(|&(j, _)| j == i);
            // the marks left to make, where they depend on whether the slot changes
            let s0 = out.slots.len() as u32;
            for &slot in &written {
                let (m0, d0) = (out.marks.len() as u32, out.dynamic.len() as u32);
                for k in self.watches.watches_of(slot) {
                    match known(self.watches.watched_slot(k)) {
                        Some(location) => {
                            let marks = self.watches.marks_at(k, location);
                            let left = marks.iter().filter(|m| !is_known(m.interaction));
                            out.marks.extend(left);
                        }
                        None => out.dynamic.push(k),
                    }
                }
                let (m1, d1) = (out.marks.len() as u32, out.dynamic.len() as u32);
                // a slot that marks nothing matters only for internal transitions
                if m0 < m1 || d0 < d1 || self.any_internal {
                    out.slots.push(SlotEffect {
                        slot,
                        marks: (m0, m1),
                        dynamic: (d0, d1),
                    });
                }
            }
            out.plans
                .push((s0, out.slots.len() as u32, f0, out.found.len() as u32));
        }
        out
    }

    fn begin_update(&mut self) {
        self.valid = false;
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.stamp.fill(0);
            self.comp_stamp.fill(0);
            self.epoch = 1;
        }
        self.dirty.clear();
        self.last_key = LastKey::NONE;
    }

    /// Re-evaluates the interactions [`EnabledSet::slot_changed`] marked.
    fn finish_update(&mut self, system: &System, after: &State) -> Result<(), RangeError> {
        for k in 0..self.dirty.len() {
            let i = self.dirty[k];
            if bit(&self.masks.lazy, i) {
                set_bit(&mut self.stale, i, true);
            } else {
                self.eval_interaction(system, after, i)?;
            }
        }
        self.settle(system, after)?;
        self.valid = true;
        Ok(())
    }

    /// Marks the interactions reading slot `s` dirty, and re-evaluates the internal
    /// transitions of its component (once per update).
    #[inline(always)]
    fn slot_changed(&mut self, system: &System, after: &State, s: u32) -> Result<(), RangeError> {
        if self.any_internal {
            self.internal_changed(system, after, s)?;
        }
        let (found, stamp, dirty, epoch) =
            (&self.found, &mut self.stamp, &mut self.dirty, self.epoch);
        self.watches
            .for_each(s, after.slots(), |m| mark(found, stamp, dirty, epoch, m));
        Ok(())
    }

    /// Re-evaluates the internal transitions of the component of slot `s`, once per update.
    #[inline(never)]
    fn internal_changed(
        &mut self,
        system: &System,
        after: &State,
        s: u32,
    ) -> Result<(), RangeError> {
        let c = self.slot_comp[s as usize];
        if self.has_internal[c as usize] && self.comp_stamp[c as usize] != self.epoch {
            self.comp_stamp[c as usize] = self.epoch;
            self.eval_internal(system, after, c)?;
        }
        Ok(())
    }

    /// With every interaction that some priority names as higher up to date: evaluates the
    /// stale interactions that are no longer suppressed, and decides the searched ones.
    #[inline(always)]
    pub(super) fn settle(&mut self, system: &System, state: &State) -> Result<(), RangeError> {
        // most updates leave nothing stale (a codel is due, or none is): a word test
        if self.stale.iter().any(|&w| w != 0) {
            self.settle_stale(system, state)?;
        }
        if self.masks.any_searched {
            self.decide_searched(system, state)?;
        }
        Ok(())
    }

    /// Evaluates the stale interactions that are no longer suppressed.
    #[inline(never)]
    fn settle_stale(&mut self, system: &System, state: &State) -> Result<(), RangeError> {
        // a stale interaction is higher in no priority, so evaluating one changes no other's
        // verdict: consecutive interactions with the same higher ones are decided once
        let mut last: Option<((u32, u32), bool)> = None;
        for w in 0..self.stale.len() {
            let mut bits = self.stale[w];
            while bits != 0 {
                let i = (w * 64) as u32 + bits.trailing_zeros();
                bits &= bits - 1;
                let span = self.masks.span(i);
                let blocked = match last {
                    Some((s, b)) if s == span => b,
                    _ => {
                        let b = self.masks.span_blocked(span, &self.pre);
                        last = Some((span, b));
                        b
                    }
                };
                if !blocked {
                    set_bit(&mut self.stale, i, false);
                    self.eval_interaction(system, state, i)?;
                }
            }
        }
        Ok(())
    }
}

/// Marks interaction `m` dirty unless it already is, or only its connector's guard reads
/// the slot and its required ports were not all ready ([`Found::ready`]).
#[inline(always)]
fn mark(found: &[Found], stamp: &mut [u32], dirty: &mut Vec<u32>, epoch: u32, m: Mark) {
    let i = m.interaction;
    if m.connector_only && !found[i as usize].ready {
        return;
    }
    if stamp[i as usize] != epoch {
        stamp[i as usize] = epoch;
        dirty.push(i);
    }
}
