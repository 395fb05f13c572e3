//! What a deadlock is, for every tool (docs/model.md, "Deadlocks, time and the environment").
//!
//! Without connectors of role `Time` or `Environment` a deadlock is a state
//! with no enabled step. With them, time passing and requests arriving are not progress: a
//! state is a deadlock when no progress step is enabled in it, nor in any state that time
//! steps alone lead to. (A clock can always tick and a client can always send; without
//! this, no model with a clock could ever deadlock.)

#[allow(unused_imports)]
use crate::prelude::*;

use hashbrown::HashSet;

use crate::model::{RangeError, Role};
use crate::state::State;
use crate::steps::Steps;
use crate::system::System;

/// The answer for one state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Liveness {
    /// A progress step is enabled now.
    Progress,
    /// No progress step now, but one becomes enabled after `ticks` time steps.
    AfterTime { ticks: u32 },
    /// A deadlock: no progress step now or after any sequence of time steps.
    Deadlock,
    /// The states reachable by time steps alone exceed the checker's bound.
    Unknown,
}

/// Reusable scratch for [`System::liveness`], with a memory of states whose answer is
/// known: in a model with a clock most candidate states share their time futures, so the
/// memory keeps the check cheap across a whole exploration.
#[derive(Debug)]
pub struct LivenessChecker {
    steps: Steps,
    /// The states of the current time search, each with its parent's index.
    nodes: Vec<(State, u32)>,
    seen: HashSet<State>,
    live: HashSet<State>,
    dead: HashSet<State>,
    /// Bound on the states explored by time steps from one state.
    pub max_time_states: usize,
    /// Bound on the remembered states (the memory is cleared when full).
    pub max_memo: usize,
}

impl Default for LivenessChecker {
    fn default() -> Self {
        LivenessChecker {
            steps: Steps::new(),
            nodes: Vec::new(),
            seen: HashSet::new(),
            live: HashSet::new(),
            dead: HashSet::new(),
            max_time_states: 100_000,
            max_memo: 1_000_000,
        }
    }
}

impl System {
    /// True if some step in `steps` is progress (neither time nor environment).
    pub fn has_progress(&self, steps: &Steps) -> bool {
        steps.iter().any(|s| self.role(s.label) == Role::Progress)
    }

    /// Decides whether `state` is a deadlock. `steps` must hold the enabled steps of
    /// `state` (the caller has usually just computed them).
    pub fn liveness(
        &self,
        state: &State,
        steps: &Steps,
        checker: &mut LivenessChecker,
    ) -> Result<Liveness, RangeError> {
        if self.has_progress(steps) {
            return Ok(Liveness::Progress);
        }
        if !steps.iter().any(|s| self.role(s.label) == Role::Time) {
            return Ok(Liveness::Deadlock);
        }
        if checker.live.contains(state) {
            return Ok(Liveness::AfterTime { ticks: 0 });
        }
        if checker.dead.contains(state) {
            return Ok(Liveness::Deadlock);
        }
        // breadth-first over time steps only; `nodes` in order is the queue
        checker.nodes.clear();
        checker.seen.clear();
        checker.seen.insert(state.clone());
        checker.nodes.push((state.clone(), u32::MAX));
        let mut next = state.clone();
        let mut head = 0;
        while head < checker.nodes.len() {
            let s = checker.nodes[head].0.clone();
            if head > 0 {
                self.enabled_steps(&s, &mut checker.steps)?;
                if self.has_progress(&checker.steps) || checker.live.contains(&s) {
                    let ticks = remember_path(checker, head);
                    return Ok(Liveness::AfterTime { ticks });
                }
            } else {
                checker.steps.clone_from(steps);
            }
            for k in 0..checker.steps.len() {
                let step = checker.steps.get(k);
                if self.role(step.label) != Role::Time {
                    continue;
                }
                self.fire(&s, step, &mut next)?;
                if !checker.seen.contains(&next) {
                    if checker.seen.len() >= checker.max_time_states {
                        return Ok(Liveness::Unknown);
                    }
                    checker.seen.insert(next.clone());
                    checker.nodes.push((next.clone(), head as u32));
                }
            }
            head += 1;
        }
        // nothing reachable by time makes progress, so every state seen is a deadlock too
        if checker.dead.len() + checker.nodes.len() > checker.max_memo {
            checker.dead.clear();
        }
        checker.dead.extend(checker.nodes.drain(..).map(|(s, _)| s));
        Ok(Liveness::Deadlock)
    }
}

/// Remembers the states on the time path to node `found` as live; returns its length.
fn remember_path(checker: &mut LivenessChecker, found: usize) -> u32 {
    if checker.live.len() + 64 > checker.max_memo {
        checker.live.clear();
    }
    let mut ticks = 0;
    let mut i = found;
    while i != u32::MAX as usize {
        let (s, parent) = &checker.nodes[i];
        checker.live.insert(s.clone());
        i = *parent as usize;
        ticks += 1;
    }
    ticks - 1
}
