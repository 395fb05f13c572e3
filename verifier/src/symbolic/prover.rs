//! What every symbolic proof shares: the encoding, the invariants proved so far (component
//! invariants, semiflows, learned traps), the solver budget and the statistics.

use std::collections::HashSet;
use std::sync::Arc;
use std::time::Instant;

use bip_model::{State, System};
use z3::ast::Bool;
use z3::Solver;

use super::encode::{Encoding, Frame};
use super::invariants::{self, ComponentInvariants};
use super::net::Net;
use super::semiflows::{self, Semiflow};
use super::solver::{self, Answer, Budget, Calls};
use super::term::{or, Sym};
use super::traps;
use crate::options::Options;
use crate::progress::Progress;
use crate::report::Stop;
use crate::watch::Watch;

/// Traps learned from one candidate at most.
const TRAPS_PER_CANDIDATE: usize = 4096;

pub struct Prover<'s> {
    pub enc: Encoding<'s>,
    pub ci: ComponentInvariants,
    pub net: Net,
    pub semiflows: Vec<Semiflow>,
    /// Learned traps (sorted places), in the order learned.
    pub traps: Vec<Vec<u32>>,
    trap_set: HashSet<Vec<u32>>,
    pub budget: Budget,
    pub calls: Calls,
    pub options: Options,
    /// Frames created so far (their names must differ).
    frames: u64,
    progress: &'s (dyn Fn(&Progress) + Sync),
    /// The property being decided, for progress reports.
    property: String,
}

/// A frame in a solver: its terms, and how many learned traps it has been given.
pub struct Placed {
    pub frame: Frame,
    traps_given: usize,
}

impl Placed {
    /// A frame given no trap: one on a path from the initial state, reachable anyway.
    pub fn bare(frame: Frame) -> Placed {
        Placed {
            frame,
            traps_given: 0,
        }
    }
}

impl<'s> Prover<'s> {
    pub fn new(
        sys: &'s System,
        options: Options,
        watch: Arc<Watch>,
        progress: &'s (dyn Fn(&Progress) + Sync),
    ) -> Result<Prover<'s>, Stop> {
        let started = Instant::now();
        progress(&Progress::Proving {
            property: String::new(),
            step: "computing the component and interaction invariants".into(),
            solver_calls: 0,
            elapsed: watch.started().elapsed(),
        });
        let stop = || watch.stopped().is_some();
        let mut enc = Encoding::new(sys);
        enc.watch = Some(watch.clone());
        let ci = invariants::compute(&enc, &stop);
        let net = Net::new(&enc, &ci, &stop);
        let semiflows = semiflows::compute(&net, &stop);
        if let Some(why) = watch.look() {
            return Err(why.clone());
        }
        tracing::info!(
            components = sys.components.len(),
            approximate = ci.approximate,
            places = net.places(),
            groups = net.groups.len(),
            semiflows = semiflows.len(),
            seconds = started.elapsed().as_secs_f64(),
            "invariants computed"
        );
        let budget = Budget {
            per_call: options.symbolic.solver_timeout,
            watch,
            rlimit: options.symbolic.rlimit,
        };
        Ok(Prover {
            enc,
            ci,
            net,
            semiflows,
            traps: Vec::new(),
            trap_set: HashSet::new(),
            budget,
            calls: Calls::default(),
            options,
            frames: 0,
            progress,
            property: String::new(),
        })
    }

    /// Starts deciding `property` (for progress reports).
    pub fn start(&mut self, property: &str) {
        self.property = property.to_string();
    }

    /// Reports the step the proof of the current property is at.
    pub fn step(&self, step: impl Into<String>) {
        (self.progress)(&Progress::Proving {
            property: self.property.clone(),
            step: step.into(),
            solver_calls: self.calls.count,
            elapsed: self.budget.watch.started().elapsed(),
        });
    }

    pub fn sys(&self) -> &'s System {
        self.enc.sys
    }

    pub fn solver(&self) -> Solver {
        self.budget.solver()
    }

    pub fn check(&mut self, solver: &Solver, assumptions: &[Bool]) -> Answer {
        solver::check(solver, assumptions, &self.budget, &mut self.calls)
    }

    /// A fresh frame constrained to its domain and to every invariant known, asserted in
    /// `solver`.
    pub fn reachable_frame(&mut self, solver: &Solver) -> Placed {
        let (frame, domain) = self.fresh(solver);
        let mut placed = Placed {
            frame,
            traps_given: 0,
        };
        for d in domain {
            self.enc.poll();
            solver.assert(&d);
        }
        for c in self.ci.constraints(&self.enc, &placed.frame) {
            self.enc.poll();
            solver.assert(&c);
        }
        for s in &self.semiflows {
            self.enc.poll();
            solver.assert(s.constraint(&self.enc, &self.net, &placed.frame));
        }
        self.give_traps(solver, &mut placed);
        placed
    }

    fn fresh(&mut self, _solver: &Solver) -> (Frame, Vec<Bool>) {
        self.frames += 1;
        self.enc.fresh_frame(&format!("f{}", self.frames))
    }

    /// A fresh name prefix (for step variables).
    pub fn fresh_name(&mut self, what: &str) -> String {
        self.frames += 1;
        format!("{what}{}", self.frames)
    }

    /// Asserts the traps learned since the frame was placed.
    pub fn give_traps(&self, solver: &Solver, placed: &mut Placed) {
        for t in &self.traps[placed.traps_given..] {
            solver.assert(self.trap_constraint(t, &placed.frame));
        }
        placed.traps_given = self.traps.len();
    }

    pub fn trap_constraint(&self, trap: &[u32], f: &Frame) -> Bool {
        or(trap.iter().map(|&p| self.net.at(&self.enc, f, p)))
    }

    /// Learns the initially marked traps that are empty in `state`; returns how many are
    /// new. Zero means no trap excludes the state.
    pub fn learn_traps(&mut self, state: &State) -> usize {
        let Some(marked) = self.net.marking(&self.enc, state) else {
            return 0;
        };
        let mut new = 0;
        for t in traps::empty_traps(&self.net, &marked, TRAPS_PER_CANDIDATE) {
            if self.trap_set.insert(t.clone()) {
                self.traps.push(t);
                new += 1;
            }
        }
        new
    }

    /// Evaluates a global expression on a frame.
    pub fn eval(&self, e: &bip_model::eval::Expr, f: &Frame) -> Sym {
        self.enc.eval(e, f)
    }

    /// A readable description of a state: the locations of the components, and the
    /// variables that differ from the initial state; long states are cut.
    pub fn describe(&self, state: &State) -> String {
        let sys = self.sys();
        let init = sys.initial_state();
        let mut parts = Vec::new();
        for slot in 0..sys.slot_count() as u32 {
            let c = sys.component_of_slot(slot);
            let is_loc = sys.components[c as usize].slot == slot;
            if is_loc || state.slots()[slot as usize] != init.slots()[slot as usize] {
                parts.push(format!(
                    "{} = {}",
                    sys.slot_name(slot),
                    sys.trace_value(state, slot)
                ));
            }
        }
        const SHOWN: usize = 24;
        if parts.len() > SHOWN {
            let more = parts.len() - SHOWN;
            parts.truncate(SHOWN);
            parts.push(format!("… ({more} more)"));
        }
        parts.join(", ")
    }
}
