//! Bounded response (`Response`, `Replies(within)`): bounded model checking and
//! k-induction on the product of the step relation with an observer, the counter of
//! `bip_model::ResponseWatch` (docs/symbolic.md, "Response properties").
//!
//! The observer is one integer per frame: 0 when no trigger waits, `c + 1` when the oldest
//! trigger not yet answered came `c` ticks ago, and `K + 2` ("late") once a tick passes the
//! bound `K`. A step updates it as `ResponseWatch::observe` does: a tick counts first (or
//! makes it late), then a response (on the step or in the state it leads to) clears it,
//! else a trigger starts it if none waits; a step both trigger and response clears it.
//! The product's bad states are the late ones, those where a trigger waits and no step is
//! enabled (the run stops unanswered), and those where the trigger or response cannot be
//! evaluated. Bounded model checking finds a shortest bad path, which counts only once
//! `System::shows_unanswered` confirms it on the run the step relation gives; k-induction,
//! strengthened with the invariants on every frame, proves that none is reachable.

use crate::properties::time_words;
use bip_model::{Happens, Label, ResponseSpec, ResponseWatch, Role, State, System, Trace, Verdict};
use z3::ast::{Bool, Int};
use z3::{Model, Solver};

use super::confirm::path_through;
use super::encode::{Enabling, Frame, StepFilter, StepVars};
use super::kinduction::{self, Unrolling};
use super::prover::{Placed, Prover};
use super::solver::Answer;
use super::term::{and, and2, eq_num, err_formula, ff, ite_int, not, num, or};

/// A shortest run that leaves a trigger unanswered is confirmed, with why it fails.
pub type Finding = kinduction::Finding<(Trace, String)>;

/// One frame of the product: the state's terms, what is enabled in it, its observer, and
/// the condition that evaluating the trigger or response failed on the way into it.
struct Observed {
    frame: Frame,
    en: Enabling,
    obs: Int,
    err_in: Bool,
}

struct Observer<'a> {
    spec: ResponseSpec<'a>,
    /// `K + 2`, the late value.
    late: i64,
}

impl Observer<'_> {
    /// What `happens` says of a frame alone, and when its evaluation fails.
    fn in_state(&self, p: &Prover<'_>, happens: &Happens, f: &Frame) -> (Bool, Bool) {
        match happens {
            Happens::State(e) => {
                let v = p.eval(e, f);
                (v.bool_term(), err_formula(&v.err))
            }
            Happens::Step(_) => (ff(), ff()),
        }
    }

    /// What `happens` says of the step `v` (numbering `labels`) from `f` to `g`, and when
    /// its evaluation fails (each part is evaluated only where the step relation's
    /// `System::happens_on` evaluates it: patterns in order up to the first that matches,
    /// and in each, `before` once the connector matches, `after` once `before` holds).
    fn on_step(
        &self,
        p: &Prover<'_>,
        happens: &Happens,
        labels: &[Label],
        v: &StepVars,
        f: &Frame,
        g: &Frame,
    ) -> (Bool, Bool) {
        let Happens::Step(patterns) = happens else {
            return (ff(), ff());
        };
        let sys = p.sys();
        let mut holds = Vec::new();
        let mut errs = Vec::new();
        for pat in patterns {
            let on = or(labels.iter().enumerate().filter_map(|(k, l)| {
                let matches = pat.connectors.is_empty()
                    || matches!(*l, Label::Interaction(i)
                        if pat.connectors.contains(&sys.interactions[i as usize].connector));
                matches.then(|| v.sel.is(k as i64))
            }));
            let (before, before_err) = match &pat.before {
                Some(e) => {
                    let x = p.eval(e, f);
                    (x.bool_term(), err_formula(&x.err))
                }
                None => (Bool::from_bool(true), ff()),
            };
            let (after, after_err) = match &pat.after {
                Some(e) => {
                    let x = p.eval(e, g);
                    (x.bool_term(), err_formula(&x.err))
                }
                None => (Bool::from_bool(true), ff()),
            };
            // evaluated only if no earlier pattern matched
            let reached = not(&or(holds.clone()));
            errs.push(and([reached.clone(), on.clone(), before_err]));
            errs.push(and([reached, on.clone(), before.clone(), after_err]));
            holds.push(and([on, before, after]));
        }
        (or(holds), or(errs))
    }

    /// The observer after the step `v` from `(f, o)` into `g`, and when evaluating the
    /// trigger or response on the step fails (their evaluation in `g` alone is `bad`'s).
    fn after_step(
        &self,
        p: &Prover<'_>,
        o: &Int,
        labels: &[Label],
        v: &StepVars,
        f: &Frame,
        g: &Frame,
    ) -> (Int, Bool) {
        let tick = or(labels
            .iter()
            .enumerate()
            .filter(|(_, l)| p.sys().role(**l) == Role::Time)
            .map(|(k, _)| v.sel.is(k as i64)));
        let waiting = o.ge(1);
        let (late, counted) = if p.sys().has_advance() {
            // a tick counts its advance, evaluated on the frame it leaves; it is late if
            // the count passes the bound
            let mut units = num(0);
            for (k, l) in labels.iter().enumerate() {
                let Label::Interaction(i) = *l else { continue };
                if p.sys().role(*l) != Role::Time {
                    continue;
                }
                let advance = match &p.sys().interactions[i as usize].advance {
                    Some(e) => p.eval(e, f).int_term(),
                    None => num(1),
                };
                units = ite_int(&v.sel.is(k as i64), &advance, &units);
            }
            let sum = o + &units;
            let late = and([waiting.clone(), tick.clone(), sum.ge(self.late)]);
            (late, ite_int(&and2(&waiting, &tick), &sum, o))
        } else {
            let at_bound = eq_num(o, self.late - 1);
            let late = and([waiting.clone(), tick.clone(), at_bound]);
            (late, ite_int(&and2(&waiting, &tick), &(o + 1i64), o))
        };
        let (rs, rs_err) = self.on_step(p, self.spec.response, labels, v, f, g);
        let (ra, _) = self.in_state(p, self.spec.response, g);
        let (ts, ts_err) = self.on_step(p, self.spec.trigger, labels, v, f, g);
        let (ta, _) = self.in_state(p, self.spec.trigger, g);
        let answered = or([rs, ra]);
        let triggered = and2(&eq_num(&counted, 0), &or([ts, ta]));
        let next = ite_int(
            &late,
            &num(self.late),
            &ite_int(&answered, &num(0), &ite_int(&triggered, &num(1), &counted)),
        );
        (next, or([rs_err, ts_err]))
    }

    /// The product frame is bad.
    fn bad(&self, p: &Prover<'_>, x: &Observed) -> Bool {
        let (_, t_err) = self.in_state(p, self.spec.trigger, &x.frame);
        let (_, r_err) = self.in_state(p, self.spec.response, &x.frame);
        let waiting = and2(&x.obs.ge(1), &x.obs.le(self.late - 1));
        or([
            eq_num(&x.obs, self.late),
            and2(&waiting, &stuck(p, &x.en)),
            t_err,
            r_err,
            x.err_in.clone(),
        ])
    }

    /// A fresh observer in its range, named after `prefix`.
    fn fresh(&self, solver: &z3::Solver, prefix: &str) -> Int {
        let o = Int::new_const(format!("{prefix}!obs"));
        solver.assert(o.ge(0));
        solver.assert(o.le(self.late));
        o
    }
}

/// No step at all is enabled in the frame, and its enabled steps can be computed (the
/// explicit method's state with no edge and no range error).
fn stuck(p: &Prover<'_>, en: &Enabling) -> Bool {
    let mut parts = vec![not(&en.guard_error)];
    parts.extend(en.allowed.iter().map(not));
    for (c, comp) in p.sys().components.iter().enumerate() {
        let internal = p.enc.by_port[comp.atom as usize].len() - 1;
        parts.push(not(&en.port_en[c][internal]));
    }
    and(parts)
}

/// Decides the bounded response property `name` within `max_depth` steps of bounded model
/// checking and k-induction up to `max_depth`.
pub fn bounded(p: &mut Prover<'_>, spec: ResponseSpec<'_>, name: &str) -> Finding {
    let sys = p.sys();
    let context = format!("property {name}");
    let Some(k_bound) = spec.within.and_then(|k| i64::try_from(k).ok()) else {
        return Finding::Unknown("the bound is too large for the symbolic observer".into());
    };
    let Some(late) = k_bound.checked_add(2) else {
        return Finding::Unknown("the bound is too large for the symbolic observer".into());
    };
    let obs = Observer { spec, late };
    let init = sys.initial_state();
    let start = match ResponseWatch::start(sys, spec, &init, &context) {
        Ok(w) => w.waiting.map_or(0, |_| 1),
        // the range error ends a trace of no step
        Err(_) => return confirm(sys, spec, name, &[init], &[]),
    };
    let mut product = Product {
        obs,
        start,
        all: StepFilter::all(sys),
        name,
        path_steps: Vec::new(),
    };
    kinduction::decide(p, &mut product, None)
}

/// The step relation's product with the observer, unrolled.
struct Product<'a> {
    obs: Observer<'a>,
    /// The observer in the initial state.
    start: i64,
    all: StepFilter,
    /// The property's name.
    name: &'a str,
    /// The steps of the path so far, and the labels they number.
    path_steps: Vec<(StepVars, Vec<Label>)>,
}

impl Product<'_> {
    /// The frame after the step `v` from `prev` into `next`, its observer named after
    /// `name`, the step and the observer's update asserted in `solver`; and the labels `v`
    /// numbers.
    fn follow(
        &self,
        p: &Prover<'_>,
        solver: &Solver,
        prev: &Observed,
        v: &StepVars,
        next: Frame,
        name: &str,
    ) -> (Observed, Vec<Label>) {
        let (t, labels) = p
            .enc
            .transition_labelled(&prev.frame, &prev.en, v, &self.all, &next);
        solver.assert(&t);
        let (o_next, err_in) = self
            .obs
            .after_step(p, &prev.obs, &labels, v, &prev.frame, &next);
        let o = self.obs.fresh(solver, name);
        solver.assert(o.eq(&o_next));
        let x = Observed {
            en: p.enc.enabling(&next),
            frame: next,
            obs: o,
            err_in,
        };
        (x, labels)
    }
}

impl Unrolling for Product<'_> {
    type Frame = Observed;
    type Seen = Option<(State, Option<i64>, Option<bool>)>;
    type Path = (Vec<State>, Vec<Label>);
    type Bad = (Trace, String);
    const CHECKING: &'static str = "bounded model checking of the observer";
    const ON: &'static str = " on the product with the observer";

    fn initial(&mut self, p: &mut Prover<'_>) -> Observed {
        let first = p.enc.concrete_frame(&p.sys().initial_state());
        Observed {
            en: p.enc.enabling(&first),
            frame: first,
            obs: num(self.start),
            err_in: ff(),
        }
    }

    fn place(&mut self, p: &mut Prover<'_>, step: &Solver, placed: Placed) -> Observed {
        let name = p.fresh_name("o");
        Observed {
            en: p.enc.enabling(&placed.frame),
            frame: placed.frame,
            obs: self.obs.fresh(step, &name),
            err_in: ff(),
        }
    }

    fn follow_path(
        &mut self,
        p: &mut Prover<'_>,
        bmc: &Solver,
        last: &Observed,
        v: StepVars,
        next: Frame,
        name: &str,
    ) -> Observed {
        let (x, labels) = self.follow(p, bmc, last, &v, next, name);
        self.path_steps.push((v, labels));
        x
    }

    fn follow_chain(
        &mut self,
        p: &mut Prover<'_>,
        step: &Solver,
        last: &Observed,
        v: &StepVars,
        next: Placed,
    ) -> Observed {
        let name = p.fresh_name("o");
        self.follow(p, step, last, v, next.frame, &name).0
    }

    fn good(&mut self, p: &mut Prover<'_>, x: &Observed) -> Bool {
        not(&self.obs.bad(p, x))
    }

    fn bad(&mut self, p: &mut Prover<'_>, x: &Observed) -> Bool {
        self.obs.bad(p, x)
    }

    /// The same state with the same observer, reached by a step alike in failing to
    /// evaluate the property or not: a frame's badness must be a function of what `same`
    /// compares, or the chain's simple paths would miss a bad frame that repeats a good
    /// one's state (the step into it being what fails).
    fn same(&self, p: &Prover<'_>, a: &Observed, b: &Observed) -> Bool {
        and([
            p.enc.frames_equal(&a.frame, &b.frame),
            a.obs.eq(&b.obs),
            a.err_in.iff(&b.err_in),
        ])
    }

    fn read_path(
        &self,
        p: &Prover<'_>,
        m: &Model,
        path: &[Observed],
    ) -> Option<(Vec<State>, Vec<Label>)> {
        let states: Option<Vec<State>> =
            path.iter().map(|x| p.enc.read_state(m, &x.frame)).collect();
        let labels: Option<Vec<Label>> = self
            .path_steps
            .iter()
            .map(|(v, labels)| {
                (0..labels.len()).find_map(|k| {
                    m.eval(&v.sel.is(k as i64), true)?
                        .as_bool()?
                        .then_some(labels[k])
                })
            })
            .collect();
        Some((states?, labels?))
    }

    fn read_chain(&self, p: &Prover<'_>, m: &Model, chain: &[Observed]) -> Vec<Self::Seen> {
        chain
            .iter()
            .map(|x| {
                let s = p.enc.read_state(m, &x.frame)?;
                let o = m.eval(&x.obs, true).and_then(|o| o.as_i64());
                Some((s, o, m.eval(&x.err_in, true).and_then(|e| e.as_bool())))
            })
            .collect()
    }

    /// A bad frame at the path's end, preferring a step into it that fails to evaluate
    /// the property: that range error is met one state earlier, where the explicit method
    /// reports it, and so ends the shortest counterexample.
    fn counterexample(
        &mut self,
        p: &mut Prover<'_>,
        bmc: &Solver,
        path: &[Observed],
        read: (Vec<State>, Vec<Label>),
    ) -> Finding {
        let last = path.last().expect("a path has a first frame");
        bmc.push();
        bmc.assert(&last.err_in);
        let earlier = match p.check(bmc, &[]) {
            Answer::Sat => bmc.get_model().and_then(|m| self.read_path(p, &m, path)),
            _ => None,
        };
        bmc.pop(1);
        let (states, labels) = earlier.unwrap_or(read);
        confirm(p.sys(), self.obs.spec, self.name, &states, &labels)
    }
}

/// The run through `states` by steps of `labels`, reported only if the step relation
/// confirms it: it meets a range error in the trigger or response (the trace then ends
/// where `System::first_range_error` meets it, as the explicit method's does), or
/// `System::shows_unanswered` agrees that it leaves a trigger unanswered.
fn confirm(
    sys: &System,
    spec: ResponseSpec<'_>,
    name: &str,
    states: &[State],
    labels: &[Label],
) -> Finding {
    let path = match path_through(sys, states, labels) {
        Ok(path) => path,
        Err(e) => {
            return Finding::Unknown(format!(
                "internal error: a symbolic counterexample is not a run of the model ({e})"
            ))
        }
    };
    let context = format!("property {name}");
    if let Some((k, e)) = sys.first_range_error(spec, &path, &context) {
        let message = e.to_string();
        let trace = Trace::from_path(sys, Verdict::RangeError(message.clone()), &path[..k]);
        return replayed(sys, trace, format!("range error: {message}"));
    }
    match sys.shows_unanswered(spec, &path, None, &context) {
        Ok(true) => {}
        Ok(false) => {
            return Finding::Unknown(
                "internal error: the observer and the step relation disagree on a counterexample"
                    .into(),
            )
        }
        Err(e) => {
            return Finding::Unknown(format!(
                "internal error: a symbolic counterexample's last state has a range error ({e})"
            ))
        }
    }
    let trace = Trace::from_path(sys, Verdict::Violation(name.to_string()), &path);
    // worded as the explicit method words it
    let within = spec.within.unwrap_or(0);
    let n = path.len();
    let reason = if passes_bound(sys, spec, &path, name) {
        format!(
            "the response does not come within {}: the tick of step {n} passes the bound",
            time_words(sys, within)
        )
    } else {
        format!(
            "the response never comes: the run stops after {n} step{} with the trigger unanswered (bound {})",
            if n == 1 { "" } else { "s" },
            time_words(sys, within)
        )
    };
    replayed(sys, trace, reason)
}

/// The counterexample `trace`, failing for `reason`, once it replays.
fn replayed(sys: &System, trace: Trace, reason: String) -> Finding {
    if let Err(e) = trace.replay(sys) {
        return Finding::Unknown(format!(
            "internal error: a symbolic counterexample does not replay ({e})"
        ));
    }
    Finding::Bad((trace, reason))
}

/// The last step of `path` is a tick past the bound (rather than a stop with a trigger
/// waiting).
fn passes_bound(
    sys: &System,
    spec: ResponseSpec<'_>,
    path: &[(bip_model::OwnedStep, State)],
    name: &str,
) -> bool {
    let context = format!("property {name}");
    let mut before = sys.initial_state();
    let Ok(mut watch) = ResponseWatch::start(sys, spec, &before, &context) else {
        return false;
    };
    for (s, after) in path {
        if let Ok(true) = watch.observe(sys, spec, &before, s.as_step(), after, &context) {
            return true;
        }
        before = after.clone();
    }
    false
}
