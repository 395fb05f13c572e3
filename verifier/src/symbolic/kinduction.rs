//! Bounded model checking and k-induction side by side, on an unrolling of the step
//! relation: the plain one (`induction.rs`) or its product with a response observer
//! (`response.rs`).
//!
//! For k = 1, 2, … up to `--max-depth`:
//! - *base*: is a frame at depth k - 1 of the path from the initial state bad? The first
//!   yes is a shortest counterexample;
//! - *step*: can k good frames of a chain, each anywhere the invariants allow, be followed
//!   by a bad one? A no proves that no bad frame is reachable. A yes may teach an invariant
//!   that rules its first frame out (the step is asked again); one that repeats a state
//!   makes the chain's frames pairwise distinct (simple paths), which makes the method
//!   complete for finite systems given a large enough k. A step the solver cannot decide
//!   closes the induction; the base goes on.

use z3::ast::Bool;
use z3::{Model, Solver};

use super::encode::{Frame, StepVars};
use super::prover::{Placed, Prover};
use super::solver::Answer;
use super::term::not;

pub enum Finding<B> {
    /// No bad frame is reachable; `how` says which argument proved it.
    Holds {
        how: String,
    },
    /// A shortest path to a bad frame, confirmed by the step relation.
    Bad(B),
    Unknown(String),
}

/// What an unrolling makes of its frames; the driver, [`decide`], is the same for all.
pub trait Unrolling {
    /// A frame of the path or of the induction's chain.
    type Frame;
    /// What a model says of a frame of the chain, compared to see a state repeat.
    type Seen: PartialEq;
    /// What a model says of the path.
    type Path;
    /// A counterexample, confirmed.
    type Bad;
    /// The bounded model checking, as the progress line names it.
    const CHECKING: &'static str;
    /// What the k-induction is on, as its proof is noted (after `{k}-induction`).
    const ON: &'static str;

    /// The path's first frame, the initial state.
    fn initial(&mut self, p: &mut Prover<'_>) -> Self::Frame;
    /// The chain's first frame, at `placed` (anywhere the invariants allow).
    fn place(&mut self, p: &mut Prover<'_>, step: &Solver, placed: Placed) -> Self::Frame;
    /// The frame after the step `v` from `last` into `next`, named `name`, on the path:
    /// the step asserted in `bmc`.
    fn follow_path(
        &mut self,
        p: &mut Prover<'_>,
        bmc: &Solver,
        last: &Self::Frame,
        v: StepVars,
        next: Frame,
        name: &str,
    ) -> Self::Frame;
    /// The frame after the step `v` from `last` into `next`, in the chain: the step
    /// asserted in `step`.
    fn follow_chain(
        &mut self,
        p: &mut Prover<'_>,
        step: &Solver,
        last: &Self::Frame,
        v: &StepVars,
        next: Placed,
    ) -> Self::Frame;
    /// What the step case assumes of the frames before its last: not bad, or the part of
    /// that which needs no choice of a step.
    fn good(&mut self, p: &mut Prover<'_>, f: &Self::Frame) -> Bool;
    /// The frame is bad.
    fn bad(&mut self, p: &mut Prover<'_>, f: &Self::Frame) -> Bool;
    /// The two frames are the same.
    fn same(&self, p: &Prover<'_>, a: &Self::Frame, b: &Self::Frame) -> Bool;
    /// The path in a model; `None` if the model does not say.
    fn read_path(&self, p: &Prover<'_>, m: &Model, path: &[Self::Frame]) -> Option<Self::Path>;
    /// The chain in a model.
    fn read_chain(&self, p: &Prover<'_>, m: &Model, chain: &[Self::Frame]) -> Vec<Self::Seen>;
    /// Learns from a step case's model, read as `seen`, invariants that may rule it out;
    /// false if there are none (the default).
    fn learn(&mut self, _p: &mut Prover<'_>, _seen: &[Self::Seen]) -> bool {
        false
    }
    /// Asserts on the chain the invariants learned since it was last given them.
    fn give_learned(&mut self, _p: &mut Prover<'_>, _step: &Solver, _chain: &mut [Self::Frame]) {}
    /// The finding of a bad path read from a model (`bmc` as it was before the bad frame
    /// was asked for).
    fn counterexample(
        &mut self,
        p: &mut Prover<'_>,
        bmc: &Solver,
        path: &[Self::Frame],
        read: Self::Path,
    ) -> Finding<Self::Bad>;
}

/// Decides whether a bad frame of `u` is reachable, within `max_depth` steps of bounded
/// model checking and k-induction up to `max_depth`. `unknown` says why an earlier attempt
/// did not decide (it is added to an inconclusive answer's reason).
pub fn decide<U: Unrolling>(
    p: &mut Prover<'_>,
    u: &mut U,
    mut unknown: Option<String>,
) -> Finding<U::Bad> {
    let max = p.options.symbolic.max_depth as usize;
    let bmc = p.solver();
    let mut path = vec![u.initial(p)];
    let step = p.solver();
    let placed = p.reachable_frame(&step);
    let mut chain = vec![u.place(p, &step, placed)];
    let mut distinct = false;
    let mut induction_open = true;
    for k in 1..=max.max(1) {
        // base: no bad frame at depth k - 1
        let d = k - 1;
        p.step(format!(
            "{} at depth {d}{}",
            U::CHECKING,
            if induction_open {
                format!(", k-induction at k = {k}")
            } else {
                String::new()
            }
        ));
        let bad = u.bad(p, &path[d]);
        bmc.push();
        bmc.assert(&bad);
        let answer = p.check(&bmc, &[]);
        if answer == Answer::Sat {
            let read = bmc.get_model().and_then(|m| u.read_path(p, &m, &path));
            bmc.pop(1);
            let Some(read) = read else {
                return Finding::Unknown("the solver gave no model for a counterexample".into());
            };
            return u.counterexample(p, &bmc, &path, read);
        }
        bmc.pop(1);
        if let Answer::Unknown(why) = answer {
            return Finding::Unknown(format!("bounded model checking at depth {d}: {why}"));
        }
        // step: k good frames satisfying the invariants, then a bad one
        if induction_open {
            let good = u.good(p, &chain[k - 1]);
            step.assert(&good);
            let placed = p.reachable_frame(&step);
            let v = StepVars::fresh(p.sys(), &p.fresh_name("s"));
            let next = u.follow_chain(p, &step, &chain[k - 1], &v, placed);
            if distinct {
                for f in &chain {
                    step.assert(not(&u.same(p, f, &next)));
                }
            }
            chain.push(next);
            loop {
                u.give_learned(p, &step, &mut chain);
                let bad = u.bad(p, &chain[k]);
                step.push();
                step.assert(&bad);
                let answer = p.check(&step, &[]);
                let model = (answer == Answer::Sat).then(|| step.get_model()).flatten();
                step.pop(1);
                match answer {
                    Answer::Unsat => {
                        return Finding::Holds {
                            how: format!("{k}-induction{}", U::ON),
                        }
                    }
                    Answer::Unknown(why) => {
                        unknown = Some(format!("k-induction at k = {k}: {why}"));
                        induction_open = false;
                        break;
                    }
                    Answer::Sat => {}
                }
                let seen = model
                    .map(|m| u.read_chain(p, &m, &chain))
                    .unwrap_or_default();
                if u.learn(p, &seen) {
                    continue;
                }
                let repeats =
                    (0..seen.len()).any(|i| (i + 1..seen.len()).any(|j| seen[i] == seen[j]));
                if repeats && !distinct {
                    distinct = true;
                    for i in 0..chain.len() {
                        for j in i + 1..chain.len() {
                            step.assert(not(&u.same(p, &chain[i], &chain[j])));
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
        let v = StepVars::fresh(p.sys(), &p.fresh_name("p"));
        let next = u.follow_path(p, &bmc, &path[d], v, next, &name);
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
