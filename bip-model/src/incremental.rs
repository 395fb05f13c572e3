//! The enabled steps of a state, kept up to date as the state moves.
//!
//! [`System::enabled_steps`] evaluates every interaction in every state. A runtime engine
//! takes one step at a time, and a step writes a few slots: only the interactions that
//! read those slots can change. [`EnabledSet`] caches, per interaction, its steps before
//! priorities, and after a step re-evaluates only the interactions that read a slot that
//! changed where the read matters (a participant's location; a variable that a guard of a
//! participant's transitions on its port reads, while the participant is where those
//! transitions start; a slot the connector's guard reads, while a required participant
//! is where it has transitions on its port and every required port had an enabled
//! transition when the interaction was last evaluated), as the full relation does: from
//! the interaction's step table where it has one, else with
//! [`System::compute_interaction_picks`]; priorities are applied by looking
//! up, for a lower interaction, whether one of its higher interactions has steps (a sparse
//! bit mask per lower interaction), or by the relation's own search for the interactions
//! the masks leave to it (those below a `when`). It is not a second notion of "enabled": it
//! yields exactly the steps of [`System::enabled_steps`], in the same order (a property
//! test checks it on random systems), only computed from a cache.
//!
//! A step with a fire plan ([`crate::FirePlans`]) is known before it is taken: where its
//! participants go and the constants it writes. [`EnabledSet::update_planned`] uses what
//! [`EnabledSet::plan_effects`] worked out from that once per plan ([`PlanEffects`]): the
//! steps of the interactions whose table key the plan fixes are stored without looking,
//! and the interactions a written slot marks where the watched component takes part are
//! listed per slot. The rest is read from the state as above.
//!
//! An interaction that is higher in no priority and that priorities suppress now cannot
//! change anything the set answers, so it is not evaluated until it is no longer
//! suppressed (it is "stale" meanwhile). In a GenoM layer that is the tick and the
//! requests while a codel is due: most of what a codel step would otherwise re-evaluate.

#[allow(unused_imports)]
use crate::prelude::*;

use alloc::sync::Arc;

use crate::enable_index::Read;
use crate::fire_plan::{FirePlans, PlanId};
use crate::found::Found;
use crate::model::RangeError;
use crate::plan_effects::{PlanEffects, SlotEffect};
use crate::priority_masks::{bit, set_bit, PriorityMasks};
use crate::state::State;
use crate::step_tables::LastKey;
use crate::steps::{Choices, Label, Pick, PrioritySearch, Step, Steps};
use crate::system::System;
use crate::watches::{location_bit, Dep, Mark, Watches, ANYWHERE};

/// The enabled steps of one state of one system (after priorities), maintained
/// incrementally with [`EnabledSet::update`].
///
/// After [`EnabledSet::new`] or [`EnabledSet::reset`] has sized its buffers, updates
/// allocate nothing unless an interaction has more steps than it ever had.
#[derive(Clone, Debug)]
pub struct EnabledSet {
    // ---- tables of the system (fixed) ----
    /// Per slot, the component it belongs to.
    slot_comp: Vec<u32>,
    /// Per component, whether its atom has internal transitions (none in a GenoM layer),
    /// and whether any has.
    has_internal: Vec<bool>,
    any_internal: bool,
    /// Per slot, the interactions whose steps (before priorities) depend on it: a
    /// participant's location, a variable that a guard of a participant's transitions on its
    /// port reads (while the participant is where those transitions start), a slot the
    /// connector's guard reads (while a required participant is where it has transitions
    /// on its port).
    watches: Watches,
    /// The system's priorities as sparse masks over `pre`.
    masks: PriorityMasks,

    // ---- the state's enabled steps ----
    /// Per interaction, what its last evaluation found (see [`Found`]); its picks are in
    /// `pool` (the system's step tables) or in `picks` (computed).
    found: Box<[Found]>,
    picks: Vec<Vec<Pick>>,
    pool: Arc<[Pick]>,
    /// Interactions with steps before priorities (one bit each).
    pre: Box<[u64]>,
    /// Lazy interactions not evaluated since they were suppressed: their `found`,
    /// `picks` and `pre` bit are out of date (and do not matter while they stay suppressed).
    stale: Box<[u64]>,
    /// Per searched interaction (see `priority_masks`): suppressed in this state.
    search_suppressed: Box<[u64]>,
    /// Per component, its enabled internal transitions.
    internal: Vec<Vec<Pick>>,

    // ---- scratch ----
    scratch: Choices,
    search: PrioritySearch,
    stamp: Vec<u32>,
    comp_stamp: Vec<u32>,
    epoch: u32,
    dirty: Vec<u32>,
    /// The last step table key computed, valid while the state stays the same (reset by
    /// each update and reset).
    last_key: LastKey,
    /// False after an update failed: the set must be [`EnabledSet::reset`].
    valid: bool,
}

impl EnabledSet {
    /// The enabled steps of `state`, evaluated in full.
    pub fn new(system: &System, state: &State) -> Result<EnabledSet, RangeError> {
        let n_inter = system.interactions.len();
        let n_comp = system.components.len();
        let words = n_inter.div_ceil(64);

        let n_slots = system.slot_count();
        let mut slot_comp = vec![0u32; n_slots];
        for (c, comp) in system.components.iter().enumerate() {
            let end = system
                .components
                .get(c + 1)
                .map_or(n_slots, |next| next.slot as usize);
            slot_comp[comp.slot as usize..end].fill(c as u32);
        }

        // slot -> interactions whose steps read it, each with where the read matters
        let mut per_slot: Vec<Vec<Dep>> = vec![Vec::new(); n_slots];
        // the locations of a participant from which it has transitions on its port
        let ready_at = |p: &crate::model::PortRef| {
            let atom = system.atom_of(p.component);
            let from = atom.transitions.iter().filter(|t| t.port == Some(p.port));
            from.fold(0u64, |m, t| m | location_bit(t.from))
        };
        for (i, inter) in system.interactions.iter().enumerate() {
            let i = i as u32;
            let mut add = |s: u32, watch: u32, locations: u64, connector_only: bool| {
                let list = &mut per_slot[s as usize];
                let same = |d: &&mut Dep| {
                    d.interaction == i && d.watch == watch && d.connector_only == connector_only
                };
                match list.iter_mut().find(same) {
                    Some(d) => d.locations |= locations,
                    None => list.push(Dep {
                        interaction: i,
                        watch,
                        locations,
                        connector_only,
                    }),
                }
            };
            // the connector's guard matters only where a required participant is ready:
            // watch the one ready in the fewest locations
            let required = inter
                .ports
                .iter()
                .enumerate()
                .filter(|(k, _)| inter.trigger.is_none_or(|tr| tr as usize == *k));
            let watched = required
                .map(|(_, p)| (ready_at(p), system.components[p.component as usize].slot))
                .min_by_key(|(m, _)| m.count_ones());
            let (connector_at, connector_watch) = watched.unwrap_or((ANYWHERE, 0));
            system.interaction_reads(i, &mut |s, read| match read {
                Read::Location { port } => {
                    let slot = system.components[inter.ports[port].component as usize].slot;
                    add(s, slot, ANYWHERE, false);
                }
                // a transition's guard matters only where the transition starts (an
                // atom's guards read only its own variables; anything else, anywhere)
                Read::Guard { port, from } => {
                    let p = inter.ports[port];
                    let own = slot_comp[s as usize] == p.component;
                    let at = if own { location_bit(from) } else { ANYWHERE };
                    let slot = system.components[p.component as usize].slot;
                    add(s, slot, at, false);
                }
                Read::Connector => add(s, connector_watch, connector_at, true),
            });
        }
        let watches = Watches::new(&per_slot, |slot| {
            (system.slot_ranges()[slot as usize].1 + 1).clamp(1, i64::from(u32::MAX)) as u32
        });

        let has_internal: Vec<bool> = system
            .components
            .iter()
            .map(|c| {
                let atom = &system.atoms[c.atom as usize];
                atom.transitions.iter().any(|t| t.port.is_none())
            })
            .collect();
        let any_internal = has_internal.iter().any(|&h| h);
        let mut set = EnabledSet {
            slot_comp,
            any_internal,
            has_internal,
            watches,
            masks: system.priority_masks.clone(),
            picks: vec![Vec::new(); n_inter],
            pool: system.enable_index.tables.pool(),
            found: vec![Found::default(); n_inter].into_boxed_slice(),
            pre: vec![0; words].into_boxed_slice(),
            stale: vec![0; words].into_boxed_slice(),
            search_suppressed: vec![0; words].into_boxed_slice(),
            internal: vec![Vec::new(); n_comp],
            scratch: Choices::default(),
            search: PrioritySearch::default(),
            stamp: vec![0; n_inter],
            comp_stamp: vec![0; n_comp],
            epoch: 0,
            dirty: Vec::with_capacity(n_inter),
            last_key: LastKey::NONE,
            valid: false,
        };
        set.reset(system, state)?;
        Ok(set)
    }

    /// Re-evaluates everything for `state` (after an error, or to jump to another state).
    pub fn reset(&mut self, system: &System, state: &State) -> Result<(), RangeError> {
        self.valid = false;
        self.last_key = LastKey::NONE;
        self.pre.fill(0);
        self.search_suppressed.fill(0);
        for p in &mut self.picks {
            p.clear();
        }
        self.found.fill(Found::default());
        for c in 0..system.components.len() as u32 {
            self.eval_internal(system, state, c)?;
        }
        // the lazy ones are left for `settle`, once the others are known
        self.stale.copy_from_slice(&self.masks.lazy);
        for i in 0..system.interactions.len() as u32 {
            if !bit(&self.masks.lazy, i) {
                self.eval_interaction(system, state, i)?;
            }
        }
        self.settle(system, state)?;
        self.valid = true;
        Ok(())
    }

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
    fn settle(&mut self, system: &System, state: &State) -> Result<(), RangeError> {
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

    /// True unless the last update or reset failed.
    pub fn is_valid(&self) -> bool {
        self.valid
    }

    /// True if everything the set knows of its state is in its [`Evaluation`]: no
    /// internal transitions, and every interaction with steps has them in the pool (the
    /// picks computed for the others are not part of an evaluation).
    pub(crate) fn fits_evaluation(&self) -> bool {
        self.valid && !self.any_internal && self.found.iter().all(|f| f.in_pool || f.width == 0)
    }

    /// Exchanges what the set knows of its state with `e`, an evaluation of the same
    /// system that [`EnabledSet::save_evaluation`] filled (the set then describes the
    /// state `e` was saved from, if [`EnabledSet::fits_evaluation`] held then).
    #[inline]
    pub(crate) fn exchange_evaluation(&mut self, e: &mut Evaluation) {
        core::mem::swap(&mut self.found, &mut e.found);
        core::mem::swap(&mut self.pre, &mut e.pre);
        core::mem::swap(&mut self.stale, &mut e.stale);
        core::mem::swap(&mut self.search_suppressed, &mut e.search_suppressed);
        // the key found last is of the state before
        self.last_key = LastKey::NONE;
    }

    /// Copies what the set knows of its state into `e` (reusing its buffers).
    pub(crate) fn save_evaluation(&self, e: &mut Evaluation) {
        fn copy<T: Copy>(to: &mut Box<[T]>, from: &[T]) {
            if to.len() == from.len() {
                to.copy_from_slice(from);
            } else {
                *to = from.into();
            }
        }
        copy(&mut e.found, &self.found);
        copy(&mut e.pre, &self.pre);
        copy(&mut e.stale, &self.stale);
        copy(&mut e.search_suppressed, &self.search_suppressed);
    }

    fn eval_internal(&mut self, system: &System, state: &State, c: u32) -> Result<(), RangeError> {
        let out = &mut self.internal[c as usize];
        out.clear();
        system.internal_picks(state, c, out)
    }

    /// The steps of interaction `i` computed from the state, into `picks` (out of line:
    /// most interactions have step tables).
    #[inline(never)]
    fn compute_interaction(
        &mut self,
        system: &System,
        state: &State,
        i: u32,
    ) -> Result<Found, RangeError> {
        let picks = &mut self.picks[i as usize];
        picks.clear();
        let (width, ready) =
            system.compute_interaction_picks(state, i, &mut self.scratch, picks)?;
        Ok(Found {
            width: width as u32,
            ready,
            ..Found::default()
        })
    }

    #[inline(always)]
    fn eval_interaction(
        &mut self,
        system: &System,
        state: &State,
        i: u32,
    ) -> Result<(), RangeError> {
        let tables = &system.enable_index.tables;
        let found = match tables.lookup_sharing(i, state.slots(), &mut self.last_key) {
            Some(e) => Found::of(e),
            None => self.compute_interaction(system, state, i)?,
        };
        self.store(i, found);
        Ok(())
    }

    #[inline(always)]
    fn store(&mut self, i: u32, found: Found) {
        set_bit(&mut self.pre, i, found.width > 0);
        self.found[i as usize] = found;
    }

    /// True if an interaction above `i` in the masks has steps.
    #[inline]
    fn blocked(&self, i: u32) -> bool {
        self.masks.blocked(i, &self.pre)
    }

    /// Decides suppression of the enabled searched interactions.
    #[inline(never)]
    fn decide_searched(&mut self, system: &System, state: &State) -> Result<(), RangeError> {
        system.search_suppressed(
            state,
            &self.pre,
            &mut self.search,
            &mut self.search_suppressed,
        )
    }

    /// True if interaction `i` has steps before priorities are applied; `None` if the
    /// set did not evaluate it because it is suppressed and higher in no priority.
    pub fn has_steps_before_priorities(&self, i: u32) -> Option<bool> {
        (!bit(&self.stale, i)).then(|| bit(&self.pre, i))
    }

    /// True if interaction `i` has enabled steps (after priorities).
    #[inline(always)]
    pub fn is_enabled(&self, i: u32) -> bool {
        bit(&self.pre, i) && !self.is_suppressed(i)
    }

    #[inline]
    fn is_suppressed(&self, i: u32) -> bool {
        if bit(&self.masks.searched, i) {
            bit(&self.search_suppressed, i)
        } else {
            self.blocked(i)
        }
    }

    /// The interactions with enabled steps (after priorities), in index order.
    pub fn interactions(&self) -> Enabled<'_> {
        self.enabled_among(None)
    }

    /// The interactions with enabled steps (after priorities) among those whose bit is set
    /// in `mask` (bit `i % 64` of word `i / 64` for interaction `i`), in index order.
    /// Cheaper than filtering [`EnabledSet::interactions`]: priorities are looked at only
    /// for the interactions in the mask.
    pub fn interactions_in<'a>(&'a self, mask: &'a [u64]) -> Enabled<'a> {
        self.enabled_among(Some(mask))
    }

    fn enabled_among<'a>(&'a self, mask: Option<&'a [u64]>) -> Enabled<'a> {
        Enabled {
            set: self,
            mask,
            word: 0,
            bits: 0,
        }
    }

    /// The steps of interaction `i` (none if it is not enabled after priorities).
    pub fn steps_of(&self, i: u32) -> impl Iterator<Item = Step<'_>> + '_ {
        let enabled = self.is_enabled(i);
        let f = self.found[i as usize];
        let w = f.width.max(1) as usize;
        let picks: &[Pick] = if !enabled {
            &[]
        } else if f.in_pool {
            &self.pool[f.start as usize..(f.start + f.len) as usize]
        } else {
            &self.picks[i as usize]
        };
        picks.chunks(w).map(move |p| Step {
            label: Label::Interaction(i),
            picks: p,
        })
    }

    /// Where the steps of interaction `i` are in [`EnabledSet::pool`] (the start, the
    /// number of picks per step, and the number of steps), if it is enabled and they come
    /// from its step table. The pool never changes, so two states in which `i`'s steps
    /// start at the same place have the same steps: a caller may remember what it found
    /// among them.
    #[inline]
    pub fn pooled_steps(&self, i: u32) -> Option<(u32, u32, u32)> {
        let f = self.found[i as usize];
        // enabled means it has steps (`pre` is set exactly when `width > 0`)
        (f.in_pool && self.is_enabled(i)).then(|| (f.start, f.width, f.len / f.width))
    }

    /// Where the picks of a step that [`EnabledSet::steps_of`] gave start in
    /// [`EnabledSet::pool`], if they are in it (the step came from a step table); `None`
    /// for picks anywhere else. It compares addresses only and reads nothing.
    #[inline]
    pub fn pool_position(&self, picks: &[Pick]) -> Option<u32> {
        let size = core::mem::size_of::<Pick>();
        let base = self.pool.as_ptr() as usize;
        let at = picks.as_ptr() as usize;
        (at >= base && at < base + self.pool.len() * size).then(|| ((at - base) / size) as u32)
    }

    /// The picks of every step table entry (see [`EnabledSet::pooled_steps`]).
    pub fn pool(&self) -> &[Pick] {
        &self.pool
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

/// What an [`EnabledSet`] knows of the state it describes, apart from its tables: per
/// interaction what its last evaluation found, and the bits of those with steps, of the
/// stale ones and of the searched ones suppressed. [`crate::StateCache`] keeps one per
/// state it knows.
#[derive(Clone, Debug, Default)]
pub(crate) struct Evaluation {
    found: Box<[Found]>,
    pre: Box<[u64]>,
    stale: Box<[u64]>,
    search_suppressed: Box<[u64]>,
}

impl Evaluation {
    /// The bytes its buffers hold.
    pub(crate) fn bytes(&self) -> usize {
        self.found.len() * core::mem::size_of::<Found>()
            + (self.pre.len() + self.stale.len() + self.search_suppressed.len()) * 8
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

/// The interactions with enabled steps (after priorities), in index order, optionally
/// among those of a mask: [`EnabledSet::interactions`], [`EnabledSet::interactions_in`].
#[derive(Clone, Debug)]
pub struct Enabled<'a> {
    set: &'a EnabledSet,
    mask: Option<&'a [u64]>,
    /// The next word of `pre` to load.
    word: usize,
    /// The candidates of word `word - 1` not yet looked at.
    bits: u64,
}

impl Iterator for Enabled<'_> {
    type Item = u32;

    #[inline]
    fn next(&mut self) -> Option<u32> {
        loop {
            while self.bits != 0 {
                let i = ((self.word - 1) * 64) as u32 + self.bits.trailing_zeros();
                self.bits &= self.bits - 1;
                if !self.set.is_suppressed(i) {
                    return Some(i);
                }
            }
            let pre = self.set.pre.get(self.word)?;
            self.bits = match self.mask {
                None => *pre,
                Some(m) => pre & m.get(self.word).copied().unwrap_or(0),
            };
            self.word += 1;
        }
    }
}
