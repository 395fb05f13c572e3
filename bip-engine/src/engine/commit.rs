//! Committing the chosen step through the gate, and what follows a commit: replies,
//! recording, the tracing event.

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{CommitError, Label, Step};

use super::replies::Cause;
use super::Engine;
use crate::bind::InterKind;
use crate::error::EngineError;

impl Engine {
    /// Commits the chosen step through the gate, then replies and records.
    pub(super) fn commit(&mut self, cause: Cause) -> Result<(), EngineError> {
        let label = self.chosen.label();
        let (committed, unevaluated) = match self.gate.commit(self.chosen.step()) {
            Ok(c) => (c, None),
            Err(CommitError::Fire(e)) => {
                self.stopped = Some(e.clone());
                return Err(EngineError::Range(e));
            }
            // the step was taken: it is replied to and recorded, then the engine stops
            Err(CommitError::Evaluate { error, committed }) => (committed, Some(error)),
        };
        let moves = match (label, committed.plan) {
            (Label::Interaction(_), Some(p)) => self.plan_moves[p.index()],
            (Label::Interaction(i), None) => self
                .t
                .step_moves_request(i, self.chosen.picks(self.gate.enabled())),
            (Label::Internal { .. }, _) => false,
        };
        #[cfg(debug_assertions)]
        if let (Label::Interaction(i), Some(_)) = (label, committed.plan) {
            let picks = self.chosen.picks(self.gate.enabled());
            debug_assert_eq!(moves, self.t.step_moves_request(i, picks));
        }
        let ticket = match &cause {
            Cause::Request { ticket, .. } if !self.monitor.is_empty() => *ticket,
            _ => None,
        };
        if moves {
            self.track(cause);
        }
        if let Some(r) = &mut self.recording {
            r.push(
                Step {
                    label,
                    picks: self.chosen.picks(self.gate.enabled()),
                },
                self.gate.state(),
            );
        }
        if tracing::enabled!(target: "bip_engine", tracing::Level::DEBUG) {
            self.trace_step(label);
        }
        self.stats.steps += 1;
        self.held.dirty = true;
        if let Some(e) = unevaluated {
            self.stopped = Some(e.clone());
            return Err(EngineError::Range(e));
        }
        if !self.monitor.is_empty() {
            self.monitor_step(label, ticket)?;
        }
        Ok(())
    }

    pub(super) fn trace_step(&self, label: Label) {
        let name = match label {
            Label::Interaction(i) => self.gate.system().interactions[i as usize].name.as_str(),
            Label::Internal { .. } => "internal",
        };
        let time_us = self.time.clock.now_us();
        if let Label::Interaction(i) = label {
            if let InterKind::Codel { codel, fail } = self.t.kind[i as usize] {
                let c = &self.t.codels[codel as usize];
                let yielded = if fail {
                    "fail"
                } else {
                    self.chosen
                        .picks(self.gate.enabled())
                        .iter()
                        .find_map(|p| {
                            c.map.yield_of(p.transition).filter(|_| {
                                self.t.services[c.service as usize]
                                    .activity
                                    .as_ref()
                                    .is_some_and(|a| a.component == p.component)
                            })
                        })
                        .map_or("?", |y| y.target.as_str())
                };
                tracing::debug!(target: "bip_engine", time_us, step = name,
                    module = c.info.module.as_str(), service = c.info.service.as_str(),
                    codel = c.info.state.as_str(), r#yield = yielded, "codel");
                return;
            }
        }
        tracing::debug!(target: "bip_engine", time_us, step = name, "step");
    }
}
