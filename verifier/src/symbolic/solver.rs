//! Solver calls with a budget.
//!
//! libz3 4.8.12 can deadlock when its own `timeout` fires (see ARCHITECTURE.md, "The z3
//! crate"), so a call's wall-clock limit is a watchdog thread that interrupts the context,
//! and `rlimit` (z3's deterministic resource counter) bounds the work of a call where a
//! reproducible budget is wanted (tests). An interrupted or exhausted call answers
//! "unknown", which the verifier reports as inconclusive.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use z3::ast::Bool;
use z3::{Params, SatResult, Solver};

/// Limits on solver work.
#[derive(Clone, Debug, Default)]
pub struct Budget {
    /// Wall-clock limit of one call.
    pub per_call: Option<Duration>,
    /// Wall-clock end of the whole run.
    pub deadline: Option<Instant>,
    /// z3's resource limit per call (deterministic).
    pub rlimit: Option<u32>,
}

/// A solver's answer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Answer {
    Sat,
    Unsat,
    /// Why the solver gave up (time, resources, or a theory it cannot decide).
    Unknown(String),
}

impl Budget {
    /// The time left for one call, if limited; `Some(ZERO)` once the run's deadline passed.
    fn time_left(&self) -> Option<Duration> {
        let until_deadline = self
            .deadline
            .map(|d| d.saturating_duration_since(Instant::now()));
        match (self.per_call, until_deadline) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    pub fn expired(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
    }

    /// A new solver with this budget's resource limit.
    pub fn solver(&self) -> Solver {
        let s = Solver::new();
        if let Some(r) = self.rlimit {
            let mut p = Params::new();
            p.set_u32("rlimit", r);
            s.set_params(&p);
        }
        s
    }
}

/// Counts solver calls, for the statistics.
#[derive(Clone, Debug, Default)]
pub struct Calls {
    pub count: u64,
    pub time: Duration,
}

/// `solver.check_assumptions(assumptions)` within the budget.
pub fn check(solver: &Solver, assumptions: &[Bool], budget: &Budget, calls: &mut Calls) -> Answer {
    let started = Instant::now();
    calls.count += 1;
    let answer = match budget.time_left() {
        Some(left) if left.is_zero() => {
            return Answer::Unknown("the time limit was reached".into())
        }
        Some(left) => {
            let (done, wait) = mpsc::channel::<()>();
            let ctx = solver.get_context().clone();
            std::thread::scope(|scope| {
                let handle = ctx.handle();
                scope.spawn(move || {
                    if let Err(mpsc::RecvTimeoutError::Timeout) = wait.recv_timeout(left) {
                        handle.interrupt();
                    }
                });
                let r = solver.check_assumptions(assumptions);
                let _ = done.send(());
                r
            })
        }
        None => solver.check_assumptions(assumptions),
    };
    calls.time += started.elapsed();
    tracing::debug!(
        seconds = started.elapsed().as_secs_f64(),
        answer = ?answer,
        assertions = solver.get_assertions().len(),
        "solver call"
    );
    match answer {
        SatResult::Sat => Answer::Sat,
        SatResult::Unsat => Answer::Unsat,
        SatResult::Unknown => Answer::Unknown(
            solver
                .get_reason_unknown()
                .filter(|r| !r.is_empty())
                .map(|r| match r.as_str() {
                    "interrupted" | "canceled" => "the solver's time limit was reached".to_string(),
                    "max. resource limit exceeded" => {
                        "the solver's resource limit was reached".to_string()
                    }
                    _ => format!("the solver gave up ({r})"),
                })
                .unwrap_or_else(|| "the solver gave up".into()),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use z3::ast::Int;

    #[test]
    fn answers_and_budgets() {
        let budget = Budget {
            per_call: Some(Duration::from_secs(30)),
            ..Budget::default()
        };
        let mut calls = Calls::default();
        let s = budget.solver();
        let x = Int::new_const("x");
        s.assert(x.gt(2));
        assert_eq!(check(&s, &[], &budget, &mut calls), Answer::Sat);
        assert_eq!(check(&s, &[x.lt(1)], &budget, &mut calls), Answer::Unsat);
        assert_eq!(calls.count, 2);
        // a hard nonlinear problem within a tiny resource budget gives up, deterministically
        let tight = Budget {
            rlimit: Some(2000),
            ..Budget::default()
        };
        let s = tight.solver();
        let (a, b, c) = (
            Int::new_const("a"),
            Int::new_const("b"),
            Int::new_const("c"),
        );
        s.assert(a.gt(1));
        s.assert(b.gt(1));
        s.assert(c.gt(1));
        s.assert((&a * &a * &a + &b * &b * &b).eq(&c * &c * &c));
        let Answer::Unknown(why) = check(&s, &[], &tight, &mut calls) else {
            panic!("a tiny rlimit must give up")
        };
        assert!(why.contains("resource"), "{why}");
        // and a deadline in the past gives up at once
        let past = Budget {
            deadline: Some(Instant::now()),
            ..Budget::default()
        };
        assert!(matches!(
            check(&s, &[], &past, &mut calls),
            Answer::Unknown(_)
        ));
    }
}
