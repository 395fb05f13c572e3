//! Turning symbolic findings into real ones, with `bip-model`'s step relation only.
//!
//! A symbolic counterexample is reported as real only once it is a run of the model:
//! - a bounded model check's states become a trace by finding, between consecutive states,
//!   a step `System::enabled_steps` offers that `System::fire` takes to the next state
//!   (then `Trace::replay` checks it again);
//! - a candidate deadlock is confirmed by an explicit search: first a bounded breadth-first
//!   exploration (the explicit verifier with a state budget: shortest traces), then a
//!   greedy search that steers toward the candidate's locations and values, for models too
//!   large to explore (the deadlock of ten thousand philosophers is ten thousand steps
//!   deep).

use std::collections::HashSet;
use std::hash::{Hash, Hasher};

use bip_model::eval::Expr;
use bip_model::{
    Label, Liveness, LivenessChecker, OwnedStep, Property, State, Steps, System, Trace, TraceStep,
    Verdict as TraceVerdict,
};

use crate::explore;
use crate::options::Options;
use crate::report::PropertyVerdict;
use crate::watch::Watch;

/// The trace through `states` (the first is the initial state), each step found with the
/// step relation; an error names the first pair no step connects.
pub fn trace_through(
    sys: &System,
    states: &[State],
    verdict: TraceVerdict,
) -> Result<Trace, String> {
    let path = path_through(sys, states, &[])?;
    let trace = Trace::from_path(sys, verdict, &path);
    trace
        .replay(sys)
        .map_err(|e| format!("the trace does not replay: {e}"))?;
    Ok(trace)
}

/// The steps through `states` (the first is the initial state), each with the state it
/// leads to, found with the step relation; with `labels`, the `k`-th step has the `k`-th
/// label (which two steps of the same effect may not share: a tick and another step).
pub fn path_through(
    sys: &System,
    states: &[State],
    labels: &[Label],
) -> Result<Vec<(OwnedStep, State)>, String> {
    let mut steps = Steps::new();
    let mut path: Vec<(OwnedStep, State)> = Vec::with_capacity(states.len());
    if states.first() != Some(&sys.initial_state()) {
        return Err("the path does not start in the initial state".into());
    }
    for (k, pair) in states.windows(2).enumerate() {
        let (from, to) = (&pair[0], &pair[1]);
        sys.enabled_steps(from, &mut steps)
            .map_err(|e| format!("state {k} of the path has a range error: {e}"))?;
        let mut next = from.clone();
        let mut found = None;
        for s in steps.iter() {
            let labelled = labels.get(k).is_none_or(|l| *l == s.label);
            if labelled && sys.fire(from, s, &mut next).is_ok() && &next == to {
                found = Some(s.to_owned());
                break;
            }
        }
        let step =
            found.ok_or_else(|| format!("no step leads from state {k} of the path to the next"))?;
        path.push((step, to.clone()));
    }
    Ok(path)
}

/// What a bounded explicit exploration says about one property.
pub struct Bounded {
    pub verdict: PropertyVerdict,
    /// Every reachable state was explored.
    pub complete: bool,
    pub states: u64,
}

/// Explores at most `max_states` states (and `max_memory` bytes) for `property` alone,
/// within what remains of the run's limits (`run`, watched by `watch`).
pub fn bounded_explicit(
    sys: &System,
    property: &Property,
    max_states: u64,
    max_memory: u64,
    run: &Options,
    watch: &Watch,
) -> Option<Bounded> {
    let mut one = sys.clone();
    one.properties = vec![property.clone()];
    let options = Options {
        jobs: run.jobs,
        max_states: Some(max_states),
        max_memory: Some(watch.max_memory().map_or(max_memory, |m| m.min(max_memory))),
        timeout: run
            .timeout
            .map(|t| t.saturating_sub(watch.started().elapsed())),
        interrupt: run.interrupt.clone(),
        ..Options::default()
    };
    let report = explore::verify(&one, &options, &|_| {}).ok()?;
    let p = report.property(&property.name)?;
    Some(Bounded {
        verdict: p.verdict.clone(),
        complete: report.stats.complete && report.stopped.is_none(),
        states: report.stats.states,
    })
}

/// A deadlock (not excused by `terminal`) found by a greedy search from the initial state
/// that takes, at each state, the step bringing it closest to `target` (fewest slots
/// differing), never revisiting a state; at most `max_steps` steps.
pub fn greedy_deadlock(
    sys: &System,
    target: &State,
    terminal: Option<&Expr>,
    max_steps: u64,
    watch: &Watch,
) -> Option<Trace> {
    let mut state = sys.initial_state();
    let mut steps = Steps::new();
    let mut checker = LivenessChecker::default();
    let mut visited: HashSet<u64> = HashSet::new();
    visited.insert(fingerprint(&state));
    let mut trace_steps: Vec<TraceStep> = Vec::new();
    let mut next = state.clone();
    let slots = sys.slot_count();
    for _ in 0..max_steps {
        if watch.stopped().is_some() {
            return None;
        }
        sys.enabled_steps(&state, &mut steps).ok()?;
        if let Ok(Liveness::Deadlock) = sys.liveness(&state, &steps, &mut checker) {
            let excused = terminal.is_some_and(|t| sys.holds(t, &state, "").unwrap_or(false));
            if !excused {
                return Some(Trace::new(sys, TraceVerdict::Deadlock, trace_steps));
            }
        }
        // score every step: exactly (by firing) when the model is small, else by the
        // locations its participants move to
        let exact = steps.len().saturating_mul(slots) <= 1 << 20;
        let mut scored: Vec<(i64, usize)> = Vec::with_capacity(steps.len());
        for (k, s) in steps.iter().enumerate() {
            let score = if exact {
                if sys.fire(&state, s, &mut next).is_err() {
                    continue;
                }
                distance(&state, target) - distance(&next, target)
            } else {
                s.picks
                    .iter()
                    .map(|p| {
                        let atom = sys.atom_of(p.component);
                        let t = &atom.transitions[p.transition as usize];
                        let goal = sys.location(target, p.component);
                        i64::from(t.to == goal) - i64::from(t.from == goal)
                    })
                    .sum()
            };
            scored.push((score, k));
        }
        scored.sort_by_key(|&(score, k)| (-score, k));
        let mut moved = false;
        for &(_, k) in &scored {
            let s = steps.get(k);
            if sys.fire(&state, s, &mut next).is_err() {
                continue;
            }
            if !visited.insert(fingerprint(&next)) {
                continue;
            }
            trace_steps.push(TraceStep {
                step: sys.label_name(s.label),
                state: sys.diff(&state, &next),
            });
            std::mem::swap(&mut state, &mut next);
            moved = true;
            break;
        }
        if !moved {
            return None;
        }
    }
    None
}

fn distance(a: &State, b: &State) -> i64 {
    a.slots()
        .iter()
        .zip(b.slots())
        .filter(|(x, y)| x != y)
        .count() as i64
}

fn fingerprint(s: &State) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    s.hash(&mut h);
    h.finish()
}
