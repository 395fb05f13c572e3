//! Compositional deadlock freedom (D-Finder's rule, with data, priorities and time).
//!
//! The check is that no state satisfies the invariants (component invariants,
//! semiflows, learned traps) and the deadlock predicate. The solver proposes candidate
//! states; each one is examined with `bip-model`'s own step relation and deadlock
//! definition, then either ruled out (a trap that must be marked is empty in it; no state
//! satisfying the invariants leads to it in one step) or handed to an explicit search,
//! which confirms it as a real deadlock with a trace, or leaves it "possible".
//!
//! The deadlock predicate without `Time` connectors is "computing the enabled steps
//! succeeds and no progress step is enabled" (after priorities; without `Environment`
//! connectors either, "no step is enabled"). With `Time` connectors a deadlock is a state
//! where no progress step is enabled now nor after any sequence of time steps; the
//! predicate then looks `K` time steps ahead: the state has no progress step, and there is
//! a path of time steps, each to a state without progress, that either has `K` steps or
//! stops in a state where no time step is enabled. Every deadlock satisfies it whatever `K`
//! (all its time paths lack progress), so ruling it out proves deadlock freedom; `K` grows
//! when a candidate turns out to progress after more ticks. This look-ahead assumes time
//! steps never fail, so with `Time` connectors deadlock freedom is claimed only once the
//! range errors are proved absent.

use bip_model::eval::Expr;
use bip_model::{
    Liveness, LivenessChecker, Property, PropertyKind as ModelKind, Role, State, Steps, Trace,
};
use z3::ast::Bool;

use super::confirm;
use super::encode::{StepFilter, StepVars};
use super::prover::{Placed, Prover};
use super::solver::Answer;
use super::term::{and, err_formula, implies, not, or};
use crate::report::PropertyVerdict;

/// How far the time look-ahead may grow.
const MAX_LOOKAHEAD: usize = 64;
/// Candidates ruled out one by one (concrete states) before giving up.
const MAX_BLOCKED: usize = 256;
/// Candidates tried backwards (no predecessor satisfies the invariants) at most.
const MAX_BACKWARD: usize = 32;

pub enum Finding {
    /// Deadlock freedom is proved symbolically.
    Proved {
        candidates: usize,
    },
    /// A real deadlock, replayed with the step relation.
    Deadlock(Trace),
    /// An explicit exploration decided (a complete one, or one that found a failure).
    Explicit(PropertyVerdict, u64),
    /// A state satisfying every invariant and the deadlock predicate, not confirmed.
    Possible(State),
    Unknown(String),
}

pub fn deadlock_free(p: &mut Prover<'_>, prop: &Property, range_errors_proved: bool) -> Finding {
    let sys = p.sys();
    let terminal: Option<&Expr> = match &prop.kind {
        ModelKind::DeadlockFree { terminal } => terminal.as_ref(),
        _ => None,
    };
    let has_time = sys.has_time();
    if has_time && !range_errors_proved {
        return Finding::Unknown(
            "with time steps, deadlock freedom is proved only once range errors are excluded, and they are not"
                .into(),
        );
    }
    let mut lookahead = usize::from(has_time);
    let mut blocked: Vec<State> = Vec::new();
    let mut backward_tries = 0;
    let mut candidates = 0;
    'rebuild: loop {
        let solver = p.solver();
        let mut frames: Vec<Placed> = vec![p.reachable_frame(&solver)];
        let en0 = p.enc.enabling(&frames[0].frame);
        solver.assert(p.enc.no_progress(&en0));
        if let Some(t) = terminal {
            let v = p.eval(t, &frames[0].frame);
            solver.assert(or([not(&v.bool_term()), err_formula(&v.err)]));
        }
        if has_time {
            let time = StepFilter::role(&p.enc, Role::Time);
            let mut en = en0;
            let mut reached = super::term::tt();
            let mut prev_go: Option<Bool> = None;
            for i in 0..lookahead {
                let go = Bool::new_const(p.fresh_name("go"));
                let next = p.reachable_frame(&solver);
                let en_next = p.enc.enabling(&next.frame);
                let v = StepVars::fresh(sys, &p.fresh_name("t"));
                let step = p
                    .enc
                    .transition(&frames[i].frame, &en, &v, &time, &next.frame);
                solver.assert(implies(
                    &go,
                    &and([reached.clone(), step, p.enc.no_progress(&en_next)]),
                ));
                let stops = and([reached.clone(), not(&go)]);
                solver.assert(implies(&stops, &not(&p.enc.some_allowed(&en, Role::Time))));
                if let Some(pg) = prev_go {
                    solver.assert(implies(&go, &pg));
                }
                reached = go.clone();
                prev_go = Some(go);
                frames.push(next);
                en = en_next;
            }
        }
        for b in &blocked {
            solver.assert(not(&p.enc.frame_is(&frames[0].frame, b)));
        }
        let mut steps = Steps::new();
        let mut checker = LivenessChecker::default();
        loop {
            p.step(format!(
                "{} candidate deadlock{} examined{}",
                candidates,
                if candidates == 1 { "" } else { "s" },
                if lookahead > 0 {
                    format!(", looking {lookahead} time steps ahead")
                } else {
                    String::new()
                }
            ));
            for f in &mut frames {
                p.give_traps(&solver, f);
            }
            match p.check(&solver, &[]) {
                Answer::Unsat => return Finding::Proved { candidates },
                Answer::Unknown(why) => return Finding::Unknown(why),
                Answer::Sat => {}
            }
            candidates += 1;
            let Some(state) = solver
                .get_model()
                .and_then(|m| p.enc.read_state(&m, &frames[0].frame))
            else {
                return Finding::Unknown("the solver gave no model for a candidate".into());
            };
            tracing::debug!(candidate = %p.describe(&state), "deadlock candidate");
            // the candidate, by the one deadlock definition
            if let Err(e) = sys.enabled_steps(&state, &mut steps) {
                return Finding::Unknown(format!(
                    "internal error: the encoding and the step relation disagree on a candidate ({e})"
                ));
            }
            let live = match sys.liveness(&state, &steps, &mut checker) {
                Ok(Liveness::Progress) => Some(0),
                Ok(Liveness::AfterTime { ticks }) => Some(ticks as usize),
                Ok(Liveness::Deadlock | Liveness::Unknown) | Err(_) => None,
            };
            let excused = terminal.is_some_and(|t| sys.holds(t, &state, "").unwrap_or(false));
            if let Some(ticks) = live {
                if !has_time || excused {
                    return Finding::Unknown(
                        "internal error: the encoding and the step relation disagree on a candidate deadlock"
                            .into(),
                    );
                }
                // time steps lead to progress beyond the look-ahead: look further
                if lookahead < MAX_LOOKAHEAD {
                    lookahead = (lookahead * 2).max(ticks + 1).min(MAX_LOOKAHEAD);
                    continue 'rebuild;
                }
                if !block(p, &solver, &frames[0], &mut blocked, state) {
                    return Finding::Unknown(
                        "too many candidates that progress only after many time steps".into(),
                    );
                }
                continue;
            }
            if excused {
                return Finding::Unknown(
                    "internal error: the encoding and the step relation disagree on the terminal condition"
                        .into(),
                );
            }
            // an initially marked trap empty in the candidate rules it (and its kind) out
            if p.learn_traps(&state) > 0 {
                continue;
            }
            // no state satisfying the invariants leads to it: unreachable
            if backward_tries < MAX_BACKWARD && state != sys.initial_state() {
                backward_tries += 1;
                match no_predecessor(p, &state) {
                    Some(true) => {
                        if !block(p, &solver, &frames[0], &mut blocked, state) {
                            return Finding::Unknown(
                                "too many candidates to rule out one by one".into(),
                            );
                        }
                        continue;
                    }
                    Some(false) => {}
                    None => {}
                }
            }
            // confirm by explicit search
            let opts = &p.options;
            if opts.symbolic.confirm_states > 0 {
                p.step("confirming a candidate deadlock by explicit search");
                if let Some(b) = confirm::bounded_explicit(
                    sys,
                    prop,
                    opts.symbolic.confirm_states,
                    opts.symbolic.confirm_memory,
                    opts,
                    &p.budget.watch,
                ) {
                    if b.verdict.fails() || (b.complete && b.verdict.holds()) {
                        return Finding::Explicit(b.verdict, b.states);
                    }
                }
            }
            if let Some(trace) = confirm::greedy_deadlock(
                sys,
                &state,
                terminal,
                p.options.symbolic.confirm_states,
                &p.budget.watch,
            ) {
                if trace.replay(sys).is_ok() {
                    return Finding::Deadlock(trace);
                }
            }
            if let Some(stop) = p.budget.watch.look() {
                return Finding::Unknown(stop.to_string());
            }
            return Finding::Possible(state);
        }
    }
}

/// Rules out one concrete state (it is known not to be a reachable deadlock).
fn block(
    p: &Prover<'_>,
    solver: &z3::Solver,
    f0: &Placed,
    blocked: &mut Vec<State>,
    s: State,
) -> bool {
    if blocked.len() >= MAX_BLOCKED {
        return false;
    }
    solver.assert(not(&p.enc.frame_is(&f0.frame, &s)));
    blocked.push(s);
    true
}

/// `Some(true)` if no state satisfying the invariants has a step to `state`.
fn no_predecessor(p: &mut Prover<'_>, state: &State) -> Option<bool> {
    let sys = p.sys();
    let solver = p.solver();
    let pre = p.reachable_frame(&solver);
    let en = p.enc.enabling(&pre.frame);
    let v = StepVars::fresh(sys, &p.fresh_name("b"));
    let target = p.enc.concrete_frame(state);
    solver.assert(
        p.enc
            .transition(&pre.frame, &en, &v, &StepFilter::all(sys), &target),
    );
    match p.check(&solver, &[]) {
        Answer::Unsat => Some(true),
        Answer::Sat => Some(false),
        Answer::Unknown(_) => None,
    }
}
