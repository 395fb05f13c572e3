//! Safety properties: bounded model checking for counterexamples, k-induction for proofs.
//!
//! A goal names the bad states: those violating an invariant, those with a range error
//! (a guard that cannot be evaluated, or an enabled step whose firing fails), or those
//! satisfying a `Reachable` expression (whose absence makes the property fail).
//!
//! 1. *Invariants first*: if no state satisfying the invariants (component invariants,
//!    semiflows, learned traps) is bad, the goal holds. Candidates that an empty
//!    initially-marked trap excludes teach traps, as in the deadlock check.
//! 2. *Bounded model checking* from the initial state, depth by depth, finds the shortest
//!    bad path; its states are turned into a trace with the step relation and replayed.
//! 3. *k-induction*, strengthened with the invariants on every frame: if `k` consecutive
//!    good states satisfying the invariants are never followed by a bad one, and no bad
//!    state is within `k - 1` steps of the initial state, no bad state is reachable. Frames
//!    are made pairwise distinct (simple paths) when a step case repeats a state, which
//!    makes the method complete for finite systems given a large enough `k`.

use bip_model::eval::Expr;
use bip_model::{State, Steps, System, Trace, Verdict as TraceVerdict};
use z3::ast::Bool;

use super::confirm::trace_through;
use super::encode::{Enabling, Frame, StepFilter, StepVars};
use super::prover::Prover;
use super::solver::Answer;
use super::term::{and, err_formula, not, or};

/// What is bad.
#[derive(Clone, Copy)]
pub enum Goal<'a> {
    /// The invariant fails (or cannot be evaluated) in the state.
    Invariant(&'a Expr, &'a str),
    /// The expression holds (or cannot be evaluated) in the state.
    Reach(&'a Expr, &'a str),
    /// A range error happens in the state.
    RangeError,
}

pub enum Finding {
    /// No bad state is reachable; `how` says which argument proved it.
    Holds {
        how: String,
    },
    /// A shortest path to a bad state, replayed.
    Bad(Trace),
    Unknown(String),
}

impl Goal<'_> {
    fn bad(&self, p: &mut Prover<'_>, f: &Frame, en: &Enabling) -> Bool {
        match *self {
            Goal::Invariant(e, _) => {
                let v = p.eval(e, f);
                or([not(&v.bool_term()), err_formula(&v.err)])
            }
            Goal::Reach(e, _) => {
                let v = p.eval(e, f);
                or([v.bool_term(), err_formula(&v.err)])
            }
            Goal::RangeError => {
                let v = StepVars::fresh(p.sys(), &p.fresh_name("e"));
                p.enc.range_error(f, en, &v)
            }
        }
    }

    /// The goal as a hypothesis on a frame of the induction's step case (for range errors,
    /// the part that needs no choice of step: the enabled steps can be computed).
    fn good(&self, p: &mut Prover<'_>, f: &Frame, en: &Enabling) -> Bool {
        match *self {
            Goal::Invariant(e, _) => {
                let v = p.eval(e, f);
                and([v.bool_term(), not(&err_formula(&v.err))])
            }
            Goal::Reach(e, _) => {
                let v = p.eval(e, f);
                and([not(&v.bool_term()), not(&err_formula(&v.err))])
            }
            Goal::RangeError => not(&en.guard_error),
        }
    }

    /// The verdict of a trace ending in a bad state, read with the step relation; `None`
    /// if the state is not bad after all (the encoding would be wrong).
    fn trace_verdict(&self, sys: &System, last: &State) -> Option<TraceVerdict> {
        match *self {
            Goal::Invariant(e, name) => match sys.holds(e, last, &format!("property {name}")) {
                Ok(true) => None,
                Ok(false) => Some(TraceVerdict::Violation(name.to_string())),
                Err(err) => Some(TraceVerdict::RangeError(err.to_string())),
            },
            Goal::Reach(e, name) => match sys.holds(e, last, &format!("property {name}")) {
                Ok(true) => Some(TraceVerdict::Witness(name.to_string())),
                Ok(false) => None,
                Err(err) => Some(TraceVerdict::RangeError(err.to_string())),
            },
            Goal::RangeError => {
                let mut steps = Steps::new();
                if let Err(e) = sys.enabled_steps(last, &mut steps) {
                    return Some(TraceVerdict::RangeError(e.to_string()));
                }
                let mut next = last.clone();
                for s in steps.iter() {
                    if let Err(e) = sys.fire(last, s, &mut next) {
                        return Some(TraceVerdict::RangeError(e.to_string()));
                    }
                }
                None
            }
        }
    }
}

/// Decides a goal within `max_depth` steps of bounded model checking and k-induction up
/// to `max_depth`.
pub fn prove(p: &mut Prover<'_>, goal: Goal<'_>) -> Finding {
    let sys = p.sys();
    // 1. the invariants alone
    p.step("implied by the invariants?");
    let mut unknown: Option<String> = None;
    {
        let solver = p.solver();
        let mut f = p.reachable_frame(&solver);
        let en = p.enc.enabling(&f.frame);
        let bad = goal.bad(p, &f.frame, &en);
        solver.assert(&bad);
        loop {
            match p.check(&solver, &[]) {
                Answer::Unsat => {
                    return Finding::Holds {
                        how: "implied by the component and interaction invariants".into(),
                    }
                }
                Answer::Unknown(why) => {
                    unknown = Some(why);
                    break;
                }
                Answer::Sat => {}
            }
            let Some(s) = solver
                .get_model()
                .and_then(|m| p.enc.read_state(&m, &f.frame))
            else {
                break;
            };
            if p.learn_traps(&s) == 0 {
                break;
            }
            p.give_traps(&solver, &mut f);
        }
    }
    // 2. and 3. bounded model checking and k-induction, side by side
    let max = p.options.symbolic.max_depth as usize;
    let all = StepFilter::all(sys);
    let bmc = p.solver();
    let mut path: Vec<Frame> = vec![p.enc.concrete_frame(&sys.initial_state())];
    let mut path_en: Vec<Enabling> = vec![p.enc.enabling(&path[0])];
    let step = p.solver();
    let mut frames = vec![p.reachable_frame(&step)];
    let mut frames_en = vec![p.enc.enabling(&frames[0].frame)];
    let mut distinct = false;
    let mut induction_open = true;
    for k in 1..=max.max(1) {
        // base: no bad state at depth k - 1
        let d = k - 1;
        p.step(format!(
            "bounded model checking at depth {d}{}",
            if induction_open {
                format!(", k-induction at k = {k}")
            } else {
                String::new()
            }
        ));
        let bad = goal.bad(p, &path[d], &path_en[d]);
        bmc.push();
        bmc.assert(&bad);
        let answer = p.check(&bmc, &[]);
        if answer == Answer::Sat {
            let states: Option<Vec<State>> = bmc
                .get_model()
                .and_then(|m| path.iter().map(|f| p.enc.read_state(&m, f)).collect());
            bmc.pop(1);
            let Some(states) = states else {
                return Finding::Unknown("the solver gave no model for a counterexample".into());
            };
            return counterexample(p, goal, &bmc, &path, &path_en, states);
        }
        bmc.pop(1);
        if let Answer::Unknown(why) = answer {
            return Finding::Unknown(format!("bounded model checking at depth {d}: {why}"));
        }
        // step: k good frames satisfying the invariants, then a bad one
        if induction_open {
            let good = goal.good(p, &frames[k - 1].frame, &frames_en[k - 1]);
            step.assert(&good);
            let next = p.reachable_frame(&step);
            let v = StepVars::fresh(sys, &p.fresh_name("s"));
            step.assert(p.enc.transition(
                &frames[k - 1].frame,
                &frames_en[k - 1],
                &v,
                &all,
                &next.frame,
            ));
            let en_next = p.enc.enabling(&next.frame);
            if distinct {
                for f in &frames {
                    step.assert(not(&p.enc.frames_equal(&f.frame, &next.frame)));
                }
            }
            frames.push(next);
            frames_en.push(en_next);
            loop {
                for f in &mut frames {
                    p.give_traps(&step, f);
                }
                let bad = goal.bad(p, &frames[k].frame, &frames_en[k]);
                step.push();
                step.assert(&bad);
                let answer = p.check(&step, &[]);
                let model = (answer == Answer::Sat).then(|| step.get_model()).flatten();
                step.pop(1);
                match answer {
                    Answer::Unsat => {
                        return Finding::Holds {
                            how: format!("{k}-induction"),
                        }
                    }
                    Answer::Unknown(why) => {
                        unknown = Some(format!("k-induction at k = {k}: {why}"));
                        induction_open = false;
                        break;
                    }
                    Answer::Sat => {}
                }
                let states: Vec<State> = model
                    .map(|m| {
                        frames
                            .iter()
                            .filter_map(|f| p.enc.read_state(&m, &f.frame))
                            .collect()
                    })
                    .unwrap_or_default();
                // the first frame may be unreachable: a trap may say so
                if let Some(first) = states.first() {
                    if p.learn_traps(first) > 0 {
                        continue;
                    }
                }
                let repeats = (0..states.len())
                    .any(|i| (i + 1..states.len()).any(|j| states[i] == states[j]));
                if repeats && !distinct {
                    distinct = true;
                    for i in 0..frames.len() {
                        for j in i + 1..frames.len() {
                            step.assert(not(&p
                                .enc
                                .frames_equal(&frames[i].frame, &frames[j].frame)));
                        }
                    }
                    continue;
                }
                break;
            }
        }
        // extend the bounded path by one step
        let name = p.fresh_name("i");
        let (next, domain) = p.enc.fresh_frame(&name);
        for c in domain {
            bmc.assert(&c);
        }
        let v = StepVars::fresh(sys, &p.fresh_name("p"));
        bmc.assert(p.enc.transition(&path[d], &path_en[d], &v, &all, &next));
        path_en.push(p.enc.enabling(&next));
        path.push(next);
        if let Some(stop) = p.budget.watch.look() {
            return Finding::Unknown(stop.to_string());
        }
    }
    let mut why = format!(
        "neither proved (k-induction up to k = {max}) nor refuted (no counterexample within {} steps)",
        max.max(1) - 1
    );
    if let Some(u) = unknown {
        why.push_str(&format!("; {u}"));
    }
    Finding::Unknown(why)
}

/// The trace to a bad state found at the end of `states`. For a `Reachable` goal, a
/// witness counts only if no range error of its expression is as near, and conversely
/// (the explicit method reports whichever its breadth-first order meets first).
fn counterexample(
    p: &mut Prover<'_>,
    goal: Goal<'_>,
    bmc: &z3::Solver,
    path: &[Frame],
    path_en: &[Enabling],
    states: Vec<State>,
) -> Finding {
    let sys = p.sys();
    let Some(last) = states.last() else {
        return Finding::Unknown("empty counterexample".into());
    };
    let Some(verdict) = goal.trace_verdict(sys, last) else {
        return Finding::Unknown(
            "internal error: the encoding and the step relation disagree on a counterexample"
                .into(),
        );
    };
    if let Goal::Reach(e, _) = goal {
        let d = path.len() - 1;
        let v = p.eval(e, &path[d]);
        let other = match verdict {
            TraceVerdict::Witness(_) => err_formula(&v.err),
            _ => and([v.bool_term(), not(&err_formula(&v.err))]),
        };
        let _ = &path_en[d];
        bmc.push();
        bmc.assert(&other);
        let answer = p.check(bmc, &[]);
        bmc.pop(1);
        if answer != Answer::Unsat {
            return Finding::Unknown(format!(
                "at depth {d}, some states satisfy the expression and others cannot evaluate it"
            ));
        }
    }
    match trace_through(sys, &states, verdict) {
        Ok(t) => Finding::Bad(t),
        Err(e) => Finding::Unknown(format!(
            "internal error: a symbolic counterexample is not a run of the model ({e})"
        )),
    }
}
