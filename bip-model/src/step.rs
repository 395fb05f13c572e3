//! The step relation of docs/model.md ("Semantics: one step"): the enabled steps of a state and
//! the firing of a step. This is the one implementation the verifier, the simulator and the
//! engine share.
//!
//! Steps are collected into a reusable [`Steps`] buffer so that computing them allocates
//! nothing once the buffer has grown to the model's needs.

#[allow(unused_imports)]
use crate::prelude::*;

use crate::enable_index::{PortCell, Read, STAYS};
use crate::eval::{Env, EvalError};
use crate::fast_path::ActionCode;
use crate::model::{Assign, RangeError, RangeErrorKind};
use crate::priority_masks::bit;
use crate::state::State;
use crate::step_tables::LastKey;
use crate::steps::{Choices, Label, OwnedStep, Pick, Step, StepEntry, Steps};
use crate::system::System;

impl System {
    /// Every step enabled in `state` (after priorities), into `out`.
    ///
    /// A guard that cannot be evaluated (division by zero, an index out of its family)
    /// is a range error of the state.
    pub fn enabled_steps(&self, state: &State, out: &mut Steps) -> Result<(), RangeError> {
        out.clear();
        self.push_internal_steps(state, out)?;
        // one state: an interaction that reads what the one before read shares its key
        let mut last = LastKey::NONE;
        for i in 0..self.interactions.len() as u32 {
            self.push_steps_of(state, i, out, &mut last)?;
        }
        if !self.priorities.is_empty() {
            self.apply_priorities(state, out)?;
        }
        Ok(())
    }

    /// True if no step is enabled in `state`.
    pub fn is_deadlock(&self, state: &State, scratch: &mut Steps) -> Result<bool, RangeError> {
        self.enabled_steps(state, scratch)?;
        Ok(scratch.is_empty())
    }

    fn push_internal_steps(&self, state: &State, out: &mut Steps) -> Result<(), RangeError> {
        for c in 0..self.components.len() as u32 {
            self.push_internal_steps_of(state, c, out)?;
        }
        Ok(())
    }

    /// Pushes the enabled internal transitions of component `c` in `state`.
    pub(crate) fn push_internal_steps_of(
        &self,
        state: &State,
        c: u32,
        out: &mut Steps,
    ) -> Result<(), RangeError> {
        let start = out.picks.len();
        self.internal_picks(state, c, &mut out.picks)?;
        for k in start..out.picks.len() {
            out.entries.push(StepEntry {
                label: Label::Internal { component: c },
                picks_start: k as u32,
                picks_end: k as u32 + 1,
            });
        }
        Ok(())
    }

    /// Appends to `out` the enabled internal transitions of component `c` in `state`.
    pub(crate) fn internal_picks(
        &self,
        state: &State,
        c: u32,
        out: &mut Vec<Pick>,
    ) -> Result<(), RangeError> {
        let cell = &self.enable_index.internal[c as usize];
        let (start, end) = self.enable_index.transitions(cell, state.slots());
        for t in start..end {
            if self.cell_guard(state, cell, t)? {
                out.push(Pick {
                    component: cell.component,
                    transition: t,
                });
            }
        }
        Ok(())
    }

    /// True if `component` takes part in interaction `i` and one of its transitions on its
    /// port there is enabled in `state` (location and the atom's own guard; the
    /// interaction's guard and the other participants aside). Used to explain deadlocks.
    pub fn participant_ready(
        &self,
        state: &State,
        i: u32,
        component: u32,
    ) -> Result<bool, RangeError> {
        let Some(port) = self.interactions[i as usize]
            .ports
            .iter()
            .find(|p| p.component == component)
        else {
            return Ok(false);
        };
        let atom = self.atom_of(component);
        let loc = self.location(state, component);
        for t in atom.transitions_from(loc, Some(port.port)) {
            if self.transition_guard(state, component, t)? {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// The guard of transition `t` of the component of `cell`, in flat form if it has one.
    #[inline(always)]
    fn cell_guard(&self, state: &State, cell: &PortCell, t: u32) -> Result<bool, RangeError> {
        let idx = &self.enable_index;
        let code = idx.guards[(cell.code + t) as usize];
        match idx.flat.decide(code, state.slots(), cell.vars) {
            Some(ok) => Ok(ok),
            None => self.transition_guard(state, cell.component, t),
        }
    }

    #[inline(never)]
    fn transition_guard(&self, state: &State, c: u32, t: u32) -> Result<bool, RangeError> {
        let comp = &self.components[c as usize];
        let atom = &self.atoms[comp.atom as usize];
        match &atom.transitions[t as usize].guard {
            None => Ok(true),
            Some(g) => g
                .holds(&mut Env::new(state.slots(), comp.slot + 1))
                .map_err(|e| {
                    self.range_error(e, &format!("guard of {}", self.describe_transition(c, t)))
                }),
        }
    }

    /// Pushes the steps of interaction `i` in `state` (before priorities): one per
    /// combination of enabled transitions of its participants.
    pub fn push_interaction_steps(
        &self,
        state: &State,
        i: u32,
        out: &mut Steps,
    ) -> Result<(), RangeError> {
        let mut fresh = LastKey::NONE;
        self.push_steps_of(state, i, out, &mut fresh)
    }

    /// [`System::push_interaction_steps`] from the step tables where `i` has an entry (the
    /// key shared with the interaction looked up before, `last`, in the same state).
    #[inline]
    fn push_steps_of(
        &self,
        state: &State,
        i: u32,
        out: &mut Steps,
        last: &mut LastKey,
    ) -> Result<(), RangeError> {
        let start = out.picks.len();
        let tables = &self.enable_index.tables;
        let width = match tables.lookup_sharing(i, state.slots(), last) {
            Some(e) => {
                out.picks.extend_from_slice(tables.picks(e));
                e.width()
            }
            None => {
                let picks = &mut out.picks;
                self.compute_interaction_picks(state, i, &mut out.choices, picks)?
                    .0
            }
        };
        if width == 0 {
            return Ok(());
        }
        for first in (start..out.picks.len()).step_by(width) {
            out.entries.push(StepEntry {
                label: Label::Interaction(i),
                picks_start: first as u32,
                picks_end: (first + width) as u32,
            });
        }
        Ok(())
    }

    /// Every slot the steps of interaction `i` (before priorities) depend on, as
    /// [`System::compute_interaction_picks`] reads them, with why ([`Read`]): its
    /// participants' locations, the slots the guards of their transitions on its ports
    /// read, and those its connector's guard reads (a slot may come more than once). The
    /// step tables are made over these slots, and `EnabledSet` re-evaluates the interaction
    /// when one of them changes.
    pub(crate) fn interaction_reads(&self, i: u32, f: &mut impl FnMut(u32, Read)) {
        let inter = &self.interactions[i as usize];
        for (k, p) in inter.ports.iter().enumerate() {
            let comp = &self.components[p.component as usize];
            f(comp.slot, Read::Location { port: k });
            for t in &self.atoms[comp.atom as usize].transitions {
                if let (Some(port), Some(g)) = (t.port, &t.guard) {
                    if port == p.port {
                        let read = Read::Guard {
                            port: k,
                            from: t.from,
                        };
                        g.for_each_slot(comp.slot + 1, &mut |s| f(s, read));
                    }
                }
            }
        }
        if let Some(g) = &inter.guard {
            g.for_each_slot(0, &mut |s| f(s, Read::Connector));
        }
    }

    /// Appends to `out` the picks of the steps of interaction `i` in `state` (before
    /// priorities), one step after the other, computed from the state without the tables.
    /// Returns how many picks a step has (0: no step; every step of an interaction in a
    /// state has the same participants, the required ports and the broadcast receivers
    /// that can join), and whether every required port has an enabled transition (if not,
    /// no value of what only the connector's guard reads can give the interaction a step).
    #[inline]
    pub(crate) fn compute_interaction_picks(
        &self,
        state: &State,
        i: u32,
        scratch: &mut Choices,
        out: &mut Vec<Pick>,
    ) -> Result<(usize, bool), RangeError> {
        let slots = state.slots();
        let idx = &self.enable_index;
        let (first, last) = idx.inter_ports[i as usize];
        let ports = &idx.ports[first as usize..last as usize];
        // one required port (a GenoM layer's codels and requests): each enabled
        // transition is a step of one pick, in transition order
        if let [cell] = ports {
            if !cell.optional {
                let first = out.len();
                if self.push_enabled(state, cell, out)? == 0 {
                    return Ok((0, false));
                }
                if !self.connector_holds(state, i)? {
                    out.truncate(first);
                    return Ok((0, true));
                }
                return Ok((1, true));
            }
        }
        // most interactions are disabled in most states: reject them on the locations alone
        for cell in ports {
            if !cell.optional {
                let (start, end) = idx.transitions(cell, slots);
                if start == end {
                    return Ok((0, false));
                }
            }
        }
        let Choices {
            choices,
            bounds,
            cursor,
        } = scratch;
        // the enabled transitions of each joining port go straight to `out`: in the
        // common case (one per port) they are the one step
        let first = out.len();
        bounds.clear();
        let mut several = false;
        for cell in ports {
            let start = out.len();
            let len = self.push_enabled(state, cell, out)?;
            if len == 0 {
                if !cell.optional {
                    out.truncate(first);
                    return Ok((0, false)); // a required port is not enabled
                }
                continue; // a broadcast receiver that does not join
            }
            several |= len > 1;
            bounds.push(((start - first) as u32, len as u32));
        }
        if !self.connector_holds(state, i)? {
            out.truncate(first);
            return Ok((0, true));
        }
        let width = bounds.len();
        if !several {
            return Ok((width, true));
        }
        // every combination of one enabled transition per joining port, in port order
        choices.clear();
        choices.extend_from_slice(&out[first..]);
        out.truncate(first);
        cursor.clear();
        cursor.resize(width, 0);
        loop {
            for (k, &(s, _)) in bounds.iter().enumerate() {
                out.push(choices[(s + cursor[k]) as usize]);
            }
            // advance the odometer, last port fastest
            let mut k = width;
            loop {
                if k == 0 {
                    return Ok((width, true));
                }
                k -= 1;
                cursor[k] += 1;
                if cursor[k] < bounds[k].1 {
                    break;
                }
                cursor[k] = 0;
            }
        }
    }

    /// Pushes a pick for each enabled transition of the port of `cell`; how many.
    #[inline(always)]
    fn push_enabled(
        &self,
        state: &State,
        cell: &PortCell,
        out: &mut Vec<Pick>,
    ) -> Result<usize, RangeError> {
        let (from, to) = self.enable_index.transitions(cell, state.slots());
        let start = out.len();
        for t in from..to {
            if self.cell_guard(state, cell, t)? {
                out.push(Pick {
                    component: cell.component,
                    transition: t,
                });
            }
        }
        Ok(out.len() - start)
    }

    /// The guard of interaction `i`'s connector, in flat form if it has one.
    #[inline(always)]
    fn connector_holds(&self, state: &State, i: u32) -> Result<bool, RangeError> {
        let idx = &self.enable_index;
        match idx
            .flat
            .decide(idx.inter_guards[i as usize], state.slots(), 0)
        {
            Some(ok) => Ok(ok),
            None => self.connector_guard(state, i),
        }
    }

    #[inline(never)]
    fn connector_guard(&self, state: &State, i: u32) -> Result<bool, RangeError> {
        let inter = &self.interactions[i as usize];
        match &inter.guard {
            Some(g) => g
                .holds(&mut Env::new(state.slots(), 0))
                .map_err(|e| self.range_error(e, &format!("guard of {}", inter.name))),
            None => Ok(true),
        }
    }

    /// Removes the steps of interactions suppressed by priorities.
    fn apply_priorities(&self, state: &State, out: &mut Steps) -> Result<(), RangeError> {
        let words = self.interactions.len().div_ceil(64);
        out.enabled.clear();
        out.enabled.resize(words, 0);
        for e in &out.entries {
            if let Label::Interaction(i) = e.label {
                out.enabled[i as usize / 64] |= 1 << (i % 64);
            }
        }
        out.suppressed.clear();
        out.suppressed.resize(words, 0);
        let masks = &self.priority_masks;
        let mut any = false;
        // the interactions the masks leave to a search are decided together
        if masks.any_searched
            && (out.enabled.iter().zip(&masks.searched)).any(|(&e, &s)| e & s != 0)
        {
            let Steps {
                enabled,
                suppressed,
                search,
                ..
            } = out;
            self.search_suppressed(state, enabled, search, suppressed)?;
            any = suppressed.iter().any(|&w| w != 0);
        }
        let mut last = None;
        for e in &out.entries {
            let Label::Interaction(i) = e.label else {
                continue;
            };
            // steps of one interaction are adjacent: decide once per interaction
            if last == Some(i) {
                continue;
            }
            last = Some(i);
            if !bit(&masks.searched, i) && masks.blocked(i, &out.enabled) {
                out.suppressed[i as usize / 64] |= 1 << (i % 64);
                any = true;
            }
        }
        if any {
            let suppressed = &out.suppressed;
            out.entries.retain(|e| match e.label {
                Label::Interaction(i) => suppressed[i as usize / 64] >> (i % 64) & 1 == 0,
                Label::Internal { .. } => true,
            });
        }
        Ok(())
    }

    /// Fires `step` from `from`, writing the successor into `to` (which is overwritten; it
    /// must have the system's number of slots). The connector action runs first, then each
    /// participant's transition action in port order; then the participants move.
    ///
    /// On a range error, `to` holds a partial result and must not be used as a state.
    pub fn fire(&self, from: &State, step: Step<'_>, to: &mut State) -> Result<(), RangeError> {
        to.copy_from(from);
        self.fire_with(step, to, &mut ())
    }

    /// Fires `step` on `state` in place, as [`System::fire`] would from it, and appends to
    /// `written` every slot the step writes (a slot may appear more than once, and may
    /// keep its value). For a caller that keeps a copy of the state: the two differ only
    /// in `written`, so the copy is brought along (and an [`crate::EnabledSet`] updated,
    /// [`crate::EnabledSet::update_written`]) without looking at the other slots.
    ///
    /// On a range error, `state` holds a partial result: the slots in `written` may have
    /// changed.
    pub fn fire_in_place(
        &self,
        step: Step<'_>,
        state: &mut State,
        written: &mut Vec<u32>,
    ) -> Result<(), RangeError> {
        self.fire_with(step, state, written)
    }

    #[inline]
    fn fire_with<W: Written>(
        &self,
        step: Step<'_>,
        to: &mut State,
        written: &mut W,
    ) -> Result<(), RangeError> {
        self.fire_ops(step, |op| match op {
            FireOp::Action { code, base, who } => self.run_who(code, base, who, to, written),
            FireOp::Move { slot, to: dest } => {
                to.slots_mut()[slot as usize] = i64::from(dest);
                written.wrote(slot);
                Ok(())
            }
        })
    }

    /// What firing `step` does, in order: the connector's action, each participant's
    /// transition action in pick order (which is port order), then the participants'
    /// moves. [`System::fire`]
    /// runs them as they come; [`crate::FirePlans`] compiles them once per step.
    #[inline(always)]
    pub(crate) fn fire_ops(
        &self,
        step: Step<'_>,
        mut f: impl FnMut(FireOp) -> Result<(), RangeError>,
    ) -> Result<(), RangeError> {
        let idx = &self.enable_index;
        if let Label::Interaction(i) = step.label {
            let code = idx.inter_actions[i as usize];
            // an `advance` is evaluated (and checked) with the action, even an empty one
            if !code.is_empty() || self.interactions[i as usize].advance.is_some() {
                let who = ActionOf::Interaction(i);
                f(FireOp::Action { code, base: 0, who })?;
            }
        }
        for &p in step.picks {
            let (code_base, slot) = idx.comp_code[p.component as usize];
            let code = idx.actions[(code_base + p.transition) as usize];
            if !code.is_empty() {
                let who = ActionOf::Transition(p);
                f(FireOp::Action {
                    code,
                    base: slot + 1,
                    who,
                })?;
            }
        }
        for p in step.picks {
            let (code_base, slot) = idx.comp_code[p.component as usize];
            let dest = idx.moves[(code_base + p.transition) as usize];
            if dest != STAYS {
                f(FireOp::Move { slot, to: dest })?;
            }
        }
        Ok(())
    }

    /// Runs the action `code` of `who` (its variables from slot `base` on).
    #[inline(always)]
    pub(crate) fn run_who<W: Written>(
        &self,
        code: ActionCode,
        base: u32,
        who: ActionOf,
        state: &mut State,
        written: &mut W,
    ) -> Result<(), RangeError> {
        let tree = || match who {
            ActionOf::Interaction(i) => &self.interactions[i as usize].action[..],
            ActionOf::Transition(p) => {
                &self.atom_of(p.component).transitions[p.transition as usize].action[..]
            }
        };
        // the connector's action runs first, so `state` is still the one the step leaves
        let advance = match who {
            ActionOf::Interaction(i) => self.advance_of(i, state)?,
            ActionOf::Transition(_) => 1,
        };
        self.run_action(code, tree, base, advance, state, written)
            .map_err(|e| {
                let context = match who {
                    ActionOf::Interaction(i) => {
                        format!("action of {}", self.interactions[i as usize].name)
                    }
                    ActionOf::Transition(p) => format!(
                        "action of {}",
                        self.describe_transition(p.component, p.transition)
                    ),
                };
                self.name_error(e, &context)
            })
    }

    /// Runs assignments left to right on `state`, each seeing the ones before it (in flat
    /// form where an assignment has one; `tree` gives the assignments where it has not).
    fn run_action<'a, W: Written>(
        &'a self,
        code: ActionCode,
        tree: impl Fn() -> &'a [Assign],
        base: u32,
        advance: u64,
        state: &mut State,
        written: &mut W,
    ) -> Result<(), ActionError> {
        let flat = &self.enable_index.flat;
        if let Some(values) = flat.action_values(code, state.slots(), base) {
            // the whole action's values, in range: computed when the system was compiled
            for (a, &v) in flat.assigns(code).iter().zip(values) {
                let slot = a.slot(base);
                state.slots_mut()[slot as usize] = v;
                written.wrote(slot);
            }
            return Ok(());
        }
        for (k, a) in flat.assigns(code).iter().enumerate() {
            let (slot, v) = match a.eval(&self.enable_index.flat, state.slots(), base) {
                Some(r) => r.map_err(ActionError::Eval)?,
                None => {
                    let mut env = Env::new(state.slots(), base);
                    env.advance = advance as i64;
                    let v = tree()[k].value.eval(&mut env).map_err(ActionError::Eval)?;
                    (a.slot(base), v)
                }
            };
            let (lo, hi) = self.slot_ranges[slot as usize];
            if v < lo || v > hi {
                return Err(ActionError::OutOfRange { slot, value: v });
            }
            state.slots_mut()[slot as usize] = v;
            written.wrote(slot);
        }
        Ok(())
    }

    fn name_error(&self, e: ActionError, context: &str) -> RangeError {
        match e {
            ActionError::Eval(e) => self.range_error(e, context),
            ActionError::OutOfRange { slot, value } => {
                let (lo, hi) = self.slot_ranges[slot as usize];
                RangeError {
                    context: context.to_string(),
                    kind: RangeErrorKind::OutOfRange {
                        var: self.slot_name(slot),
                        value,
                        lo,
                        hi,
                    },
                }
            }
        }
    }

    /// The successors of `state` with the steps that lead to them, for tests, tools and
    /// small explorations (the verifier uses `enabled_steps` and `fire` directly).
    pub fn successors(&self, state: &State) -> Result<Vec<(OwnedStep, State)>, RangeError> {
        let mut steps = Steps::new();
        self.enabled_steps(state, &mut steps)?;
        let mut out = Vec::with_capacity(steps.len());
        for s in steps.iter() {
            let mut next = state.clone();
            self.fire(state, s, &mut next)?;
            out.push((s.to_owned(), next));
        }
        Ok(out)
    }

    /// The name a trace gives a step: the interaction's name, or `comp.internal`.
    pub fn label_name(&self, label: Label) -> String {
        match label {
            Label::Internal { component } => {
                format!("{}.internal", self.components[component as usize].name)
            }
            Label::Interaction(i) => self.interactions[i as usize].name.clone(),
        }
    }
}

/// One thing firing a step does ([`System::fire_ops`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum FireOp {
    /// Run an action, whose variables start at slot `base`.
    Action {
        code: ActionCode,
        base: u32,
        who: ActionOf,
    },
    /// Move a participant: its location slot takes location `to`.
    Move { slot: u32, to: u32 },
}

/// Whose action: a connector's, or a participant's transition's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ActionOf {
    Interaction(u32),
    Transition(Pick),
}

enum ActionError {
    Eval(EvalError),
    OutOfRange { slot: u32, value: i64 },
}

/// True if a bit of `range` is set in `bits`.
pub(crate) fn any_bit(bits: &[u64], range: core::ops::Range<u32>) -> bool {
    let (mut i, end) = (range.start, range.end);
    while i < end {
        let word = bits[i as usize / 64];
        if i % 64 == 0 && end - i >= 64 {
            if word != 0 {
                return true;
            }
            i += 64;
            continue;
        }
        if word >> (i % 64) & 1 == 1 {
            return true;
        }
        i += 1;
    }
    false
}

/// Where [`System::fire_with`] notes the slots it writes: nowhere (the verifier compares
/// whole states) or in a list (the engine's incremental update).
pub(crate) trait Written {
    fn wrote(&mut self, slot: u32);
}

impl Written for () {
    #[inline(always)]
    fn wrote(&mut self, _: u32) {}
}

impl Written for Vec<u32> {
    #[inline(always)]
    fn wrote(&mut self, slot: u32) {
        self.push(slot);
    }
}

#[cfg(test)]
mod tests {
    use super::any_bit;
    use crate::prelude::*;

    #[test]
    fn any_bit_scans_ranges_across_words() {
        let mut bits = vec![0u64; 3];
        bits[1] |= 1 << 5; // bit 69
        assert!(any_bit(&bits, 0..192));
        assert!(any_bit(&bits, 69..70));
        assert!(!any_bit(&bits, 0..69));
        assert!(!any_bit(&bits, 70..192));
        assert!(any_bit(&bits, 64..128));
    }
}
