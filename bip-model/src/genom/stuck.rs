//! Why a GenoM layer is stuck: at a deadlock, the codels whose activity is ready to run
//! them (now, or once time passes) but that a constraint or an `after` holds back. The
//! verifier prints this under a deadlock trace, so that "deadlock after 1 step" comes with
//! the constraint to look at.

use crate::prelude::*;

use hashbrown::HashSet;

use super::map::{Condition, GenomMap};
use crate::model::{RangeError, Role};
use crate::state::State;
use crate::steps::Steps;
use crate::system::System;

/// A codel held back: its activity's own transition is enabled, the constraints are not.
#[derive(Clone, Debug)]
pub struct Stuck<'m> {
    pub module: &'m str,
    pub service: &'m str,
    /// The codel state, as bound by the engine.
    pub codel: &'m str,
    /// Time steps after the given state at which the codel is ready (0: now).
    pub after_ticks: u32,
    pub held_by: Vec<&'m Condition>,
}

/// Bound on the states explored by time steps alone from the given state.
const MAX_TIME_STATES: usize = 4096;

impl GenomMap {
    /// The codels held back by their conditions in `state` or in a state that time steps
    /// alone lead to from it (a GenoM activity usually waits for its task's next period
    /// before its codel is ready). Each codel is listed once, at its earliest readiness.
    pub fn stuck<'m>(
        &'m self,
        system: &System,
        state: &State,
    ) -> Result<Vec<Stuck<'m>>, RangeError> {
        self.search(system, state, false)
    }

    /// Every codel whose activity is ready to run it in `state` or once time steps alone
    /// have passed, at its earliest readiness, held back (`held_by` lists by what) or not
    /// (`held_by` is empty: it only waits for its task's period, or runs now).
    pub fn readiness<'m>(
        &'m self,
        system: &System,
        state: &State,
    ) -> Result<Vec<Stuck<'m>>, RangeError> {
        self.search(system, state, true)
    }

    fn search<'m>(
        &'m self,
        system: &System,
        state: &State,
        free_too: bool,
    ) -> Result<Vec<Stuck<'m>>, RangeError> {
        let mut out: Vec<Stuck<'m>> = Vec::new();
        let mut seen = HashSet::new();
        seen.insert(state.clone());
        // breadth-first over time steps, so that the first readiness found is the earliest
        let mut layer = vec![state.clone()];
        let mut steps = Steps::new();
        let mut next = state.clone();
        let mut ticks = 0;
        while !layer.is_empty() {
            let mut following = Vec::new();
            for s in &layer {
                self.collect_stuck(system, s, ticks, free_too, &mut out)?;
                system.enabled_steps(s, &mut steps)?;
                for step in steps.iter() {
                    if system.role(step.label) != Role::Time {
                        continue;
                    }
                    system.fire(s, step, &mut next)?;
                    if seen.len() < MAX_TIME_STATES && seen.insert(next.clone()) {
                        following.push(next.clone());
                    }
                }
            }
            layer = following;
            ticks += 1;
        }
        Ok(out)
    }

    fn collect_stuck<'m>(
        &'m self,
        system: &System,
        state: &State,
        ticks: u32,
        free_too: bool,
        out: &mut Vec<Stuck<'m>>,
    ) -> Result<(), RangeError> {
        for m in &self.modules {
            for svc in &m.services {
                let Some(activity) = svc.component else {
                    continue;
                };
                for codel in &svc.codels {
                    let listed = |s: &Stuck<'_>| {
                        s.module == m.name && s.service == svc.name && s.codel == codel.state
                    };
                    if out.iter().any(listed)
                        || !system.participant_ready(state, codel.gated(), activity)?
                    {
                        continue;
                    }
                    let held_by = codel.held_by(system, state)?;
                    if free_too || !held_by.is_empty() {
                        out.push(Stuck {
                            module: &m.name,
                            service: &svc.name,
                            codel: &codel.state,
                            after_ticks: ticks,
                            held_by,
                        });
                    }
                }
            }
        }
        Ok(())
    }
}

/// `ndd.GoTo codel start is ready after 1 tick`; the conditions are listed by the caller.
impl core::fmt::Display for Stuck<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{}.{} codel {} is ready",
            self.module, self.service, self.codel
        )?;
        match self.after_ticks {
            0 => Ok(()),
            1 => f.write_str(" after 1 tick"),
            n => write!(f, " after {n} ticks"),
        }
    }
}
