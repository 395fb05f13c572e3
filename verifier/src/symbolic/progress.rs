//! Time progress (`TimeProgress`) by sufficient conditions on the states satisfying the
//! invariants (component invariants, semiflows, learned traps):
//!
//! 1. each has a step of a `Time` connector enabled, or is a state from which a
//!    breadth-first search with the step relation finds one (such states are excluded
//!    one by one); or else
//! 2. none has no step at all without a tick, and no path of `K` steps without a tick
//!    starts from one, each of its states satisfying the invariants and without a tick
//!    (`K` doubling up to [`MAX_PATH`]): every run from a reachable state then meets a
//!    tick within `K` steps. A GenoM layer, whose tick waits while a codel can run and
//!    whose codels cannot loop without a pause, passes this one.
//!
//! Then from every reachable state a tick can fire, and no state is timelocked; and no
//! run stays for ever on a cycle of states without a tick (a busy loop): under the first
//! condition every state has a tick enabled, or it is proved by the second (states
//! cleared one by one by a search are followed by the second condition, since they may
//! form such a cycle). A candidate neither condition clears leaves the property
//! inconclusive, with the candidate; never "holds" without the proof. A tick that fails when fired would break
//! the argument, so the proof is claimed only once range errors are proved absent.

use std::collections::{HashSet, VecDeque};

use bip_model::{Role, State, Steps, System};

use super::encode::{StepFilter, StepVars};
use super::prover::Prover;
use super::solver::Answer;
use super::term::{and, not};

/// Candidates cleared one by one before giving up.
const MAX_CLEARED: usize = 256;
/// States the search from one candidate may visit.
const SEARCH_STATES: usize = 10_000;
/// The longest path without a tick the second condition looks at.
const MAX_PATH: usize = 32;

pub enum Finding {
    /// Every state satisfying the invariants has a tick, at once or after `cleared`
    /// candidates' searches ([`time_progress`] answers this only with `cleared` 0).
    Proved {
        cleared: usize,
    },
    /// No path without a tick of `steps` steps, nor a state with no step and no tick.
    Bounded {
        steps: usize,
    },
    /// A state satisfying the invariants from which no tick was found.
    Candidate(State),
    Unknown(String),
}

pub fn time_progress(p: &mut Prover<'_>, range_errors_proved: bool) -> Finding {
    if !range_errors_proved {
        return Finding::Unknown(
            "time progress is proved only once range errors are excluded, and they are not".into(),
        );
    }
    match states_tick(p) {
        // states without a tick that each reach one may still form a cycle, a busy loop
        // on which a run stays for ever: only the bound on paths without a tick excludes it
        Finding::Proved { cleared } if cleared > 0 => paths_tick(p).unwrap_or_else(|| {
            Finding::Unknown(format!(
                "no state is a timelock ({cleared} states satisfying the invariants have no tick enabled but reach one), but a busy loop through such states is not excluded: no bound on the steps without a tick was found"
            ))
        }),
        Finding::Candidate(state) => paths_tick(p).unwrap_or(Finding::Candidate(state)),
        Finding::Unknown(why) if p.budget.watch.look().is_none() => {
            paths_tick(p).unwrap_or(Finding::Unknown(why))
        }
        f => f,
    }
}

/// The first condition.
fn states_tick(p: &mut Prover<'_>) -> Finding {
    let sys = p.sys();
    let solver = p.solver();
    let mut frame = p.reachable_frame(&solver);
    let en = p.enc.enabling(&frame.frame);
    solver.assert(not(&p.enc.some_allowed(&en, Role::Time)));
    let mut cleared = 0;
    loop {
        p.step(format!(
            "{cleared} state{} without a tick cleared",
            if cleared == 1 { "" } else { "s" }
        ));
        p.give_traps(&solver, &mut frame);
        match p.check(&solver, &[]) {
            Answer::Unsat => return Finding::Proved { cleared },
            Answer::Unknown(why) => return Finding::Unknown(why),
            Answer::Sat => {}
        }
        let Some(state) = solver
            .get_model()
            .and_then(|m| p.enc.read_state(&m, &frame.frame))
        else {
            return Finding::Unknown("the solver gave no model for a candidate".into());
        };
        // an initially marked trap empty in the candidate rules it (and its kind) out
        if p.learn_traps(&state) > 0 {
            continue;
        }
        match tick_reachable(sys, &state, &p.budget.watch) {
            Some(true) if cleared < MAX_CLEARED => {
                solver.assert(not(&p.enc.frame_is(&frame.frame, &state)));
                cleared += 1;
            }
            Some(true) => {
                return Finding::Unknown(format!(
                    "more than {MAX_CLEARED} states satisfying the invariants have no tick enabled"
                ))
            }
            Some(false) => return Finding::Candidate(state),
            None => {
                let why = p
                    .budget
                    .watch
                    .look()
                    .map_or("the run stopped".into(), |s| s.to_string());
                return Finding::Unknown(why);
            }
        }
    }
}

/// The second condition: `Some(Bounded)` once proved, `Some(Unknown)` if the solver
/// could not answer or the run must stop, `None` if a path of [`MAX_PATH`] steps without
/// a tick (or a state with no step) satisfies the invariants.
fn paths_tick(p: &mut Prover<'_>) -> Option<Finding> {
    let sys = p.sys();
    let others = StepFilter {
        interactions: sys
            .interactions
            .iter()
            .map(|i| sys.connectors[i.connector as usize].role != Role::Time)
            .collect(),
        internal: true,
    };
    let mut k = 0;
    loop {
        p.step(format!("paths of {k} steps without a tick"));
        let solver = p.solver();
        let mut frames = vec![p.reachable_frame(&solver)];
        let mut en = p.enc.enabling(&frames[0].frame);
        solver.assert(not(&p.enc.some_allowed(&en, Role::Time)));
        if k == 0 {
            // no step at all: neither progress, nor environment, nor time
            solver.assert(and([
                p.enc.no_progress(&en),
                not(&p.enc.some_allowed(&en, Role::Environment)),
            ]));
        }
        for _ in 0..k {
            let next = p.reachable_frame(&solver);
            let v = StepVars::fresh(sys, &p.fresh_name("p"));
            let last = &frames[frames.len() - 1].frame;
            solver.assert(p.enc.transition(last, &en, &v, &others, &next.frame));
            en = p.enc.enabling(&next.frame);
            solver.assert(not(&p.enc.some_allowed(&en, Role::Time)));
            frames.push(next);
        }
        for f in &mut frames {
            p.give_traps(&solver, f);
        }
        match p.check(&solver, &[]) {
            Answer::Unsat if k > 0 => return Some(Finding::Bounded { steps: k }),
            Answer::Unsat => {}
            Answer::Unknown(why) => return Some(Finding::Unknown(why)),
            Answer::Sat if k == 0 => return None,
            Answer::Sat => {}
        }
        if k >= MAX_PATH {
            return None;
        }
        k = (k * 2).max(1);
    }
}

/// Whether some run from `state` fires a tick, by a breadth-first search of at most
/// [`SEARCH_STATES`] states: `Some(false)` if none was found (within the bound, or at
/// all), `None` if the run must stop.
fn tick_reachable(sys: &System, state: &State, watch: &crate::watch::Watch) -> Option<bool> {
    let mut seen: HashSet<State> = HashSet::from([state.clone()]);
    let mut queue = VecDeque::from([state.clone()]);
    let mut steps = Steps::new();
    let mut next = state.clone();
    while let Some(s) = queue.pop_front() {
        if watch.stopped().is_some() {
            return None;
        }
        if sys.enabled_steps(&s, &mut steps).is_err() {
            continue;
        }
        for step in steps.iter() {
            if sys.role(step.label) == Role::Time {
                return Some(true);
            }
            if sys.fire(&s, step, &mut next).is_ok()
                && seen.len() < SEARCH_STATES
                && seen.insert(next.clone())
            {
                queue.push_back(next.clone());
            }
        }
    }
    Some(false)
}
