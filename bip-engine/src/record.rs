//! Recording: the steps the engine committed, compactly (labels and picks, no states), and
//! their rendering as a shared-format [`Trace`] by re-firing them from the initial state.

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{Label, OwnedStep, Pick, State, Step, System, Trace, Verdict};

#[derive(Clone, Debug, Default)]
pub(crate) struct Recording {
    steps: Vec<(Label, u32, u32)>,
    picks: Vec<Pick>,
}

impl Recording {
    pub fn with_capacity(steps: usize) -> Recording {
        Recording {
            steps: Vec::with_capacity(steps),
            picks: Vec::with_capacity(steps * 3),
        }
    }

    pub fn push(&mut self, step: Step<'_>) {
        let start = self.picks.len() as u32;
        self.picks.extend_from_slice(step.picks);
        self.steps
            .push((step.label, start, self.picks.len() as u32));
    }

    pub fn len(&self) -> usize {
        self.steps.len()
    }

    pub fn step(&self, k: usize) -> Step<'_> {
        let (label, s, e) = self.steps[k];
        Step {
            label,
            picks: &self.picks[s as usize..e as usize],
        }
    }

    /// The recorded run as a trace. Firing is deterministic, so re-firing the steps from
    /// the initial state gives back the states the engine went through.
    pub fn to_trace(&self, system: &System, verdict: Verdict) -> Trace {
        let mut path: Vec<(OwnedStep, State)> = Vec::with_capacity(self.len());
        let mut state = system.initial_state();
        let mut next = state.clone();
        for k in 0..self.len() {
            let step = self.step(k);
            if system.fire(&state, step, &mut next).is_err() {
                break; // the engine never commits a step that fails to fire
            }
            core::mem::swap(&mut state, &mut next);
            path.push((step.to_owned(), state.clone()));
        }
        Trace::from_path(system, verdict, &path)
    }
}
