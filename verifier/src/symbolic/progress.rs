//! Time progress (`TimeProgress`) by a sufficient condition: every state satisfying the
//! invariants (component invariants, semiflows, learned traps) either has a step of a
//! `Time` connector enabled, or is a state from which a breadth-first search with the step
//! relation finds one (such states are excluded one by one). Then from every reachable
//! state a tick can fire, at once or after the steps found, and no state is timelocked.
//!
//! The condition is far from necessary: in a GenoM layer the tick waits while a codel can
//! run, so many states satisfy the invariants without a tick. A candidate the search
//! cannot clear leaves the property inconclusive, with the candidate; never "holds"
//! without the proof. A tick that fails when fired would break the argument, so the proof
//! is claimed only once range errors are proved absent.

use std::collections::{HashSet, VecDeque};

use bip_model::{Role, State, Steps, System};

use super::prover::Prover;
use super::solver::Answer;
use super::term::not;

/// Candidates cleared one by one before giving up.
const MAX_CLEARED: usize = 256;
/// States the search from one candidate may visit.
const SEARCH_STATES: usize = 10_000;

pub enum Finding {
    /// Every state satisfying the invariants has a tick, at once or after `cleared`
    /// candidates' searches.
    Proved {
        cleared: usize,
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
