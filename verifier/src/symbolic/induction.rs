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
use z3::{Model, Solver};

use super::confirm::trace_through;
use super::encode::{Enabling, Frame, StepFilter, StepVars};
use super::kinduction::{self, Unrolling};
use super::prover::{Placed, Prover};
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

/// A shortest path to a bad state is a trace, replayed.
pub type Finding = kinduction::Finding<Trace>;

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
    let mut safety = Safety {
        goal,
        all: StepFilter::all(sys),
    };
    kinduction::decide(p, &mut safety, unknown)
}

/// A frame of the path or of the chain, and what is enabled in it.
struct Plain {
    placed: Placed,
    en: Enabling,
}

/// The step relation unrolled for a goal.
struct Safety<'a> {
    goal: Goal<'a>,
    all: StepFilter,
}

impl Safety<'_> {
    fn plain(p: &Prover<'_>, placed: Placed) -> Plain {
        Plain {
            en: p.enc.enabling(&placed.frame),
            placed,
        }
    }
}

impl Unrolling for Safety<'_> {
    type Frame = Plain;
    type Seen = State;
    type Path = Vec<State>;
    type Bad = Trace;
    const CHECKING: &'static str = "bounded model checking";
    const ON: &'static str = "";

    fn initial(&mut self, p: &mut Prover<'_>) -> Plain {
        let frame = p.enc.concrete_frame(&p.sys().initial_state());
        Safety::plain(p, Placed::bare(frame))
    }

    fn place(&mut self, p: &mut Prover<'_>, _step: &Solver, placed: Placed) -> Plain {
        Safety::plain(p, placed)
    }

    fn follow_path(
        &mut self,
        p: &mut Prover<'_>,
        bmc: &Solver,
        last: &Plain,
        v: StepVars,
        next: Frame,
        _name: &str,
    ) -> Plain {
        bmc.assert(
            p.enc
                .transition(&last.placed.frame, &last.en, &v, &self.all, &next),
        );
        Safety::plain(p, Placed::bare(next))
    }

    fn follow_chain(
        &mut self,
        p: &mut Prover<'_>,
        step: &Solver,
        last: &Plain,
        v: &StepVars,
        next: Placed,
    ) -> Plain {
        step.assert(
            p.enc
                .transition(&last.placed.frame, &last.en, v, &self.all, &next.frame),
        );
        Safety::plain(p, next)
    }

    fn good(&mut self, p: &mut Prover<'_>, f: &Plain) -> Bool {
        self.goal.good(p, &f.placed.frame, &f.en)
    }

    fn bad(&mut self, p: &mut Prover<'_>, f: &Plain) -> Bool {
        self.goal.bad(p, &f.placed.frame, &f.en)
    }

    fn same(&self, p: &Prover<'_>, a: &Plain, b: &Plain) -> Bool {
        p.enc.frames_equal(&a.placed.frame, &b.placed.frame)
    }

    fn read_path(&self, p: &Prover<'_>, m: &Model, path: &[Plain]) -> Option<Vec<State>> {
        path.iter()
            .map(|f| p.enc.read_state(m, &f.placed.frame))
            .collect()
    }

    fn read_chain(&self, p: &Prover<'_>, m: &Model, chain: &[Plain]) -> Vec<State> {
        chain
            .iter()
            .filter_map(|f| p.enc.read_state(m, &f.placed.frame))
            .collect()
    }

    /// The first frame may be unreachable: a trap may say so.
    fn learn(&mut self, p: &mut Prover<'_>, seen: &[State]) -> bool {
        seen.first().is_some_and(|first| p.learn_traps(first) > 0)
    }

    fn give_learned(&mut self, p: &mut Prover<'_>, step: &Solver, chain: &mut [Plain]) {
        for f in chain {
            p.give_traps(step, &mut f.placed);
        }
    }

    fn counterexample(
        &mut self,
        p: &mut Prover<'_>,
        bmc: &Solver,
        path: &[Plain],
        states: Vec<State>,
    ) -> Finding {
        counterexample(p, self.goal, bmc, path, states)
    }
}

/// The trace to a bad state found at the end of `states`. For a `Reachable` goal, a
/// witness counts only if no range error of its expression is as near, and conversely
/// (the explicit method reports whichever its breadth-first order meets first).
fn counterexample(
    p: &mut Prover<'_>,
    goal: Goal<'_>,
    bmc: &Solver,
    path: &[Plain],
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
        let v = p.eval(e, &path[d].placed.frame);
        let other = match verdict {
            TraceVerdict::Witness(_) => err_formula(&v.err),
            _ => and([v.bool_term(), not(&err_formula(&v.err))]),
        };
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
