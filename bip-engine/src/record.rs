//! Recording: the steps the engine committed, compactly (labels and picks, no states), and
//! their rendering as a shared-format [`Trace`] by re-firing them from the state they
//! started in. A recording keeps every step, or only the last ones (a window, so that a
//! run of any length records in constant memory): then it keeps two segments, the last
//! complete one and the one being filled, each with the state it starts from.

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{Label, Pick, State, Step, System, Trace, TraceStep, Verdict};

/// Steps in the order they were committed, from a start state.
#[derive(Clone, Debug, Default)]
struct Segment {
    /// The state before the first step (`None`: the initial state).
    start: Option<State>,
    steps: Vec<(Label, u32, u32)>,
    picks: Vec<Pick>,
}

impl Segment {
    fn with_capacity(steps: usize) -> Segment {
        Segment {
            start: None,
            steps: Vec::with_capacity(steps),
            picks: Vec::with_capacity(steps * 3),
        }
    }

    fn step(&self, k: usize) -> Step<'_> {
        let (label, s, e) = self.steps[k];
        Step {
            label,
            picks: &self.picks[s as usize..e as usize],
        }
    }

    fn clear_from(&mut self, state: &State) {
        self.steps.clear();
        self.picks.clear();
        match &mut self.start {
            Some(s) => s.copy_from(state),
            None => self.start = Some(state.clone()),
        }
    }
}

#[derive(Clone, Debug, Default)]
pub(crate) struct Recording {
    /// Steps forgotten before `older` (window mode) or taken away.
    skipped: u64,
    /// The last complete segment of a window (empty otherwise), then the current one.
    older: Segment,
    current: Segment,
    /// The length of a window's segment (`None`: keep every step).
    segment: Option<usize>,
}

/// The last steps of a run, from the state they start in.
#[derive(Clone, Debug, PartialEq)]
pub struct Window {
    /// Steps of the run before the window's first.
    pub skipped: u64,
    /// The state before the window's first step.
    pub start: State,
    /// The window's steps (each with what it changed), and the verdict.
    pub trace: Trace,
}

impl Recording {
    pub fn with_capacity(steps: usize) -> Recording {
        Recording {
            current: Segment::with_capacity(steps),
            ..Recording::default()
        }
    }

    /// A recording of the last `window` to `2 * window` steps.
    pub fn window(window: usize) -> Recording {
        let window = window.max(1);
        Recording {
            older: Segment::with_capacity(window),
            current: Segment::with_capacity(window),
            segment: Some(window),
            ..Recording::default()
        }
    }

    /// Records `step`, which led to `after`.
    pub fn push(&mut self, step: Step<'_>, after: &State) {
        let seg = &mut self.current;
        let start = seg.picks.len() as u32;
        seg.picks.extend_from_slice(step.picks);
        seg.steps.push((step.label, start, seg.picks.len() as u32));
        if self.segment.is_some_and(|n| seg.steps.len() >= n) {
            // the older segment is forgotten; its storage holds the next one
            self.skipped += self.older.steps.len() as u64;
            core::mem::swap(&mut self.older, &mut self.current);
            self.current.clear_from(after);
        }
    }

    pub fn len(&self) -> usize {
        self.older.steps.len() + self.current.steps.len()
    }

    /// The recorded steps, from the state they start in, as a trace: re-firing them gives
    /// back the states the engine went through (firing is deterministic).
    pub fn to_window(&self, system: &System, verdict: Verdict) -> Window {
        let first = if self.older.steps.is_empty() {
            &self.current
        } else {
            &self.older
        };
        let start = first
            .start
            .clone()
            .unwrap_or_else(|| system.initial_state());
        // two states at a time, whatever the window's length: a state of a wide model is
        // big, what a step changed is small
        let mut trace_steps = Vec::with_capacity(self.len());
        let mut state = start.clone();
        let mut next = state.clone();
        let steps = (0..self.older.steps.len())
            .map(|k| self.older.step(k))
            .chain((0..self.current.steps.len()).map(|k| self.current.step(k)));
        for step in steps {
            if system.fire(&state, step, &mut next).is_err() {
                break; // the engine never commits a step that fails to fire
            }
            trace_steps.push(TraceStep::between(system, step.label, &state, &next));
            core::mem::swap(&mut state, &mut next);
        }
        Window {
            skipped: self.skipped,
            trace: Trace::new(system, verdict, trace_steps),
            start,
        }
    }

    /// Takes the recorded steps away (as [`Recording::to_window`] renders them); the
    /// recording goes on from `now`.
    pub fn take(&mut self, system: &System, now: &State) -> Window {
        let window = self.to_window(system, Verdict::None);
        self.skipped += self.len() as u64;
        self.older.steps.clear();
        self.older.picks.clear();
        self.current.clear_from(now);
        window
    }
}
