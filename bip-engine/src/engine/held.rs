//! Held codels: activities with work to do whose codel has no step, reported once per
//! change at quiescent points, with the conditions that hold them.

use alloc::sync::Arc;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::genom::Condition;

use super::Engine;
use crate::error::EngineError;
use crate::event::{CodelId, Event, Reasons};

impl Engine {
    /// At a quiescent point: activities with work that cannot run (a start held by
    /// `Exclusive`, a codel held by `Requires`...), reported once per change.
    pub(super) fn report_held(&mut self) -> Result<(), EngineError> {
        let n = self.t.activities.len();
        let Some(here) = self.gate.cached_state() else {
            for k in 0..n {
                let w = &self.t.activities[k];
                // most activities wait for their period at a quiescent point: nothing is
                // held, and nothing was reported held before
                if w.held.is_none() && w.rest.at_rest(self.gate.state().slots()) {
                    continue;
                }
                let held = self.held_codel(w.service as usize)?;
                if held != self.t.activities[k].held {
                    self.note_held(k, held);
                }
            }
            return Ok(());
        };
        // what is held is a function of the state: worked out once per cached state
        self.held.now.clear();
        match self.held.known.get(here) {
            Some(known) => self.held.now.extend_from_slice(known),
            None => {
                for k in 0..n {
                    let held = self.held_codel(self.t.activities[k].service as usize)?;
                    self.held.now.push(held);
                }
                self.held.known.set(here, &self.held.now);
            }
        }
        for k in 0..n {
            let held = self.held.now[k];
            if held != self.t.activities[k].held {
                self.note_held(k, held);
            }
        }
        Ok(())
    }

    /// Activity `k` holds `held` now, which is news: reported.
    #[inline(never)]
    pub(super) fn note_held(&mut self, k: usize, held: Option<(u32, Reasons)>) {
        self.t.activities[k].held = held;
        let Some((c, reasons)) = held else { return };
        let s = self.t.activities[k].service as usize;
        let Some(a) = &self.t.services[s].activity else {
            return;
        };
        let loc = self.gate.state().slots()[a.loc_slot as usize] as u32;
        let ticket = if loc == a.ether { a.pending } else { a.current };
        let i = &self.t.codels[c as usize].info;
        tracing::info!(target: "bip_engine", module = i.module.as_str(),
            service = i.service.as_str(), codel = i.state.as_str(), reasons = reasons.0,
            "codel held");
        let codel = Arc::clone(&self.t.codels[c as usize].name);
        self.emit(Event::Held {
            codel,
            ticket,
            reasons,
        });
    }

    /// The codels held now: activities with work to do (requested, or running and not
    /// waiting for their period) whose codel has no step, with the conditions that fail.
    pub(super) fn held(&self) -> Result<Vec<(CodelId, Reasons)>, EngineError> {
        let mut out = Vec::new();
        for s in 0..self.t.services.len() {
            if let Some((c, r)) = self.held_codel(s)? {
                out.push((CodelId(c), r));
            }
        }
        Ok(out)
    }

    /// Every activity with work outstanding (requested, or running): the codel it runs
    /// next, whether it waits for its task's period, and the conditions of that codel
    /// that fail now (what holds it once its period comes).
    pub(super) fn outstanding(&self) -> Result<Vec<(CodelId, bool, Reasons)>, EngineError> {
        let mut out = Vec::new();
        for svc in &self.t.services {
            let Some(a) = &svc.activity else { continue };
            let slots = self.gate.state().slots();
            let loc = slots[a.loc_slot as usize] as u32;
            if loc == a.ether && slots[a.req_slot as usize] == 0 {
                continue;
            }
            let Some(c) = a.codel_at.get(loc as usize).copied().flatten() else {
                continue;
            };
            let mask = self.failing(&self.t.codels[c as usize].map.holds)?;
            let paused = slots[a.paused_slot as usize] != 0;
            out.push((CodelId(c), paused, Reasons(mask)));
        }
        Ok(out)
    }

    pub(super) fn held_codel(&self, s: usize) -> Result<Option<(u32, Reasons)>, EngineError> {
        let Some(a) = &self.t.services[s].activity else {
            return Ok(None);
        };
        let slots = self.gate.state().slots();
        if a.rest().at_rest(slots) {
            return Ok(None);
        }
        let loc = slots[a.loc_slot as usize] as u32;
        let Some(c) = a.codel_at.get(loc as usize).copied().flatten() else {
            return Ok(None);
        };
        let cm = &self.t.codels[c as usize].map;
        // codels are higher than the tick in every GenoM layer, so the set evaluates them
        // always (`None`, never evaluated, cannot happen here)
        // (an async codel's start, or its return while it runs apart, is its progress)
        let can = |i: u32| self.gate.enabled().has_steps_before_priorities(i) != Some(false);
        if can(cm.run) || can(cm.fail) || cm.apart.is_some_and(|p| can(p.start) || can(p.returned))
        {
            return Ok(None); // it can run; it may only wait for its turn
        }
        let failing = self.failing(&cm.holds)?;
        // a timed codel also waits for its task's core and its locks, which hold nothing:
        // it is held only by its conditions, before it starts
        if cm.timed.is_some() && (failing == 0 || self.is_running(c)) {
            return Ok(None);
        }
        Ok(Some((c, Reasons(failing))))
    }

    /// The conditions of a request or a codel that fail now, as bits, evaluated as the
    /// step relation evaluates its guard (`bip_model::genom::failing`).
    pub(super) fn failing(&self, conds: &[Condition]) -> Result<u64, EngineError> {
        let mut mask = 0u64;
        bip_model::genom::failing(conds, self.gate.system(), self.gate.state(), |k| {
            mask |= 1 << k
        })
        .map_err(EngineError::Range)?;
        Ok(mask)
    }
}
