//! Solver calls with a budget.
//!
//! libz3 4.8.12 can deadlock when its own `timeout` fires (see ARCHITECTURE.md, "The z3
//! crate"), so a call's wall-clock limit is kept by the run's watchdog (`watch.rs`), which
//! interrupts the context when the call overruns it or when the run must stop (its time or
//! memory limit, Ctrl-C); `rlimit` (z3's deterministic resource counter) bounds the work of
//! a call where a reproducible budget is wanted (tests). An interrupted or exhausted call
//! answers "unknown" with the reason, which the verifier reports as inconclusive.

use std::sync::Arc;
use std::time::{Duration, Instant};

use z3::ast::Bool;
use z3::{Params, SatResult, Solver};

use crate::report::Stop;
use crate::watch::Watch;

/// Limits on solver work.
#[derive(Clone)]
pub struct Budget {
    /// Wall-clock limit of one call.
    pub per_call: Option<Duration>,
    /// The run's limits; its watchdog interrupts the solver.
    pub watch: Arc<Watch>,
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
    /// A new solver with this budget's resource limit, which leaves Ctrl-C alone: by
    /// default z3 takes SIGINT over during a call (and swallows it, the call answering
    /// "canceled"), where the command's own handler must see it.
    pub fn solver(&self) -> Solver {
        let s = Solver::new();
        let mut p = Params::new();
        p.set_bool("ctrl_c", false);
        if let Some(r) = self.rlimit {
            p.set_u32("rlimit", r);
        }
        s.set_params(&p);
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
    if let Some(stop) = budget.watch.look() {
        return Answer::Unknown(stop.to_string());
    }
    let started = Instant::now();
    calls.count += 1;
    budget.watch.call_started(budget.per_call);
    let answer = solver.check_assumptions(assumptions);
    let call_timed_out = budget.watch.call_ended();
    calls.time += started.elapsed();
    tracing::debug!(
        seconds = started.elapsed().as_secs_f64(),
        answer = ?answer,
        "solver call"
    );
    match answer {
        SatResult::Sat => Answer::Sat,
        SatResult::Unsat => Answer::Unsat,
        SatResult::Unknown => {
            // the run's own stop first: an interrupt for Ctrl-C or the time limit of the
            // run is not the solver's doing
            if let Some(stop) = budget.watch.look() {
                return Answer::Unknown(stop.to_string());
            }
            let reason = solver.get_reason_unknown().unwrap_or_default();
            Answer::Unknown(match reason.as_str() {
                _ if call_timed_out => "the solver's time limit was reached".to_string(),
                "max. resource limit exceeded" => {
                    "the solver's resource limit was reached".to_string()
                }
                r if r.contains("memory") => {
                    // z3 was given what the run's memory limit left: the run is at its limit
                    if let Some(limit) = budget.watch.max_memory() {
                        budget.watch.raise(Stop::MaxMemory { limit });
                    }
                    "z3 ran out of the memory the memory limit leaves it".to_string()
                }
                "" => "the solver gave up".to_string(),
                r => format!("the solver gave up ({r})"),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::options::Options;
    use z3::ast::Int;

    fn limited(options: &Options, per_call: Option<Duration>, rlimit: Option<u32>) -> Budget {
        Budget {
            per_call,
            watch: Arc::new(Watch::new(options, None)),
            rlimit,
        }
    }

    #[test]
    fn answers_and_budgets() {
        let budget = limited(&Options::default(), Some(Duration::from_secs(30)), None);
        let mut calls = Calls::default();
        let s = budget.solver();
        let x = Int::new_const("x");
        s.assert(x.gt(2));
        assert_eq!(check(&s, &[], &budget, &mut calls), Answer::Sat);
        assert_eq!(check(&s, &[x.lt(1)], &budget, &mut calls), Answer::Unsat);
        assert_eq!(calls.count, 2);
        // a hard nonlinear problem within a tiny resource budget gives up, deterministically
        let tight = limited(&Options::default(), None, Some(2000));
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
        // a run past its time limit, or interrupted, gives up at once and says why
        let past = limited(
            &Options {
                timeout: Some(Duration::ZERO),
                ..Options::default()
            },
            None,
            None,
        );
        let Answer::Unknown(why) = check(&s, &[], &past, &mut calls) else {
            panic!("a run past its time limit makes no call")
        };
        assert!(why.contains("time limit ("), "{why}");
        let flag = Arc::new(std::sync::atomic::AtomicBool::new(true));
        let interrupted = limited(
            &Options {
                interrupt: Some(flag),
                ..Options::default()
            },
            None,
            None,
        );
        let Answer::Unknown(why) = check(&s, &[], &interrupted, &mut calls) else {
            panic!("an interrupted run makes no call")
        };
        assert_eq!(why, "the run was interrupted");
    }

    /// A call that overruns its own time limit is interrupted by the watchdog and says so;
    /// one interrupted for Ctrl-C says that instead.
    #[test]
    fn the_watchdog_interrupts_a_call() {
        let hard = |s: &Solver| {
            let (a, b, c) = (
                Int::new_const("a"),
                Int::new_const("b"),
                Int::new_const("c"),
            );
            s.assert(a.gt(1));
            s.assert(b.gt(1));
            s.assert(c.gt(1));
            s.assert((&a * &a * &a * &a + &b * &b * &b * &b).eq(&c * &c * &c * &c));
        };
        let mut calls = Calls::default();
        let b = limited(&Options::default(), Some(Duration::from_millis(200)), None);
        let ctx = z3::Context::thread_local();
        let handle = ctx.handle();
        let answer = b.watch.around(
            || handle.interrupt(),
            || {
                let s = b.solver();
                hard(&s);
                check(&s, &[], &b, &mut calls)
            },
        );
        assert_eq!(
            answer,
            Answer::Unknown("the solver's time limit was reached".into())
        );
    }
}
