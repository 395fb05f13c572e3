//! Running a codel: staging its module's ids, calling it (here or on its task's thread),
//! judging its outcome (a fault takes the error path), and choosing the step the outcome
//! names (docs/engine.md, "Faults").

use alloc::sync::Arc;
use core::any::Any;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::Step;

use super::replies::Cause;
use super::schedule::count_first;
use super::{Engine, Stepped};
use crate::bind::{CodelTable, RunStep};
use crate::budgets::CodelTime;
use crate::codel::{call_guarded, Body, Ctx, DefaultCodels, Next};
use crate::error::{EngineError, StepAsError};
use crate::event::{Codel, CodelId, Event, Fault, FaultKind, Outcome};

/// How a codel run ended, before its step is chosen.
pub(super) enum CodelEnd {
    /// It yielded its `yield_k`-th declared yield and broke no rule.
    Yielded { yield_k: usize },
    /// It threw, or faulted: the error path, with this outcome.
    Failed(Outcome),
}

impl Engine {
    /// Runs codel `c` and commits the step its outcome names. With `forced`, the step
    /// must be the one in `self.forced`.
    pub(super) fn run_codel(&mut self, c: u32, forced: bool) -> Result<Stepped, StepAsError> {
        let ck = c as usize;
        let service = self.t.codels[ck].service as usize;
        self.stage_ids(ck);
        let starting = self.t.services[service]
            .activity
            .as_ref()
            .is_some_and(|a| self.gate.state().slots()[a.loc_slot as usize] == i64::from(a.ether));
        let t0 = self.time.clock.now_us();
        let default = matches!(self.runner.bodies[ck], Body::Default);
        let end = match &self.runner.bodies[ck] {
            Body::Default => self.default_end(ck, forced),
            _ => {
                let result = self.call_codel(ck, service, starting, t0);
                self.classify(ck, result)
            }
        };
        let simulated = if default {
            self.simulated_time(ck)
        } else {
            None
        };
        let took = simulated.unwrap_or_else(|| self.time.clock.now_us().saturating_sub(t0));
        self.commit_codel(c, end, t0, took, forced, true)
    }

    /// Stages the module's ids for codel `ck`: what it sees and writes, committed by
    /// its step.
    #[inline(always)]
    pub(super) fn stage_ids(&mut self, ck: usize) {
        self.runner.ids.clear();
        for f in &self.t.codels[ck].info.fields {
            self.runner
                .ids
                .push(self.gate.state().slots()[f.slot as usize]);
        }
        self.runner.written = 0;
        self.runner.fault = None;
    }

    /// Commits the step the end of codel `c`'s run (from `t0`, `took` µs) names, and
    /// accounts for its time: as its task's work (`of_task`), or as an async codel's
    /// own (checked against its WCET only).
    #[inline(always)]
    pub(super) fn commit_codel(
        &mut self,
        c: u32,
        end: CodelEnd,
        t0: u64,
        took: u64,
        forced: bool,
        of_task: bool,
    ) -> Result<Stepped, StepAsError> {
        let ck = c as usize;
        let period_us = self.t.codels[ck]
            .period_ticks
            .saturating_mul(self.time.tick_us);
        // the outcome of a run that failed; a normal one chose its run step
        let fail = self.t.codels[ck].map.fail;
        let error = match end {
            CodelEnd::Yielded { yield_k } => {
                if self.take_run_step(ck, yield_k, forced) {
                    None
                } else if forced {
                    return Err(StepAsError::Diverged);
                } else {
                    let fault = Fault {
                        codel: Arc::clone(&self.t.codels[ck].name),
                        kind: FaultKind::NotAllowed,
                    };
                    Some(Outcome::Fault(fault))
                }
            }
            CodelEnd::Failed(o) => Some(o),
        };
        if error.is_some() {
            if forced {
                let same = self
                    .gate
                    .enabled()
                    .steps_of(fail)
                    .find(|s| s.picks == &self.forced[..]);
                if same.is_none() {
                    return Err(StepAsError::Diverged);
                }
                self.chosen.set(self.gate.enabled(), same);
            } else {
                self.take_step_of(fail);
            }
            if self.chosen.picks(self.gate.enabled()).is_empty() {
                // run and fail share their guard, so this cannot happen; report it
                return Err(StepAsError::Engine(EngineError::Stopped(
                    self.internal_error(),
                )));
            }
        }
        if forced && self.chosen.picks(self.gate.enabled()) != &self.forced[..] {
            return Err(StepAsError::Diverged);
        }
        self.stats.codels += 1;
        self.check_budgets(ck, t0, took, of_task);
        if of_task && took > period_us {
            self.stats.overruns += 1;
            let i = &self.t.codels[ck].info;
            tracing::warn!(target: "bip_engine", module = i.module.as_str(),
                service = i.service.as_str(), codel = i.state.as_str(), took_us = took,
                period_us, "codel overran its task's period");
            let codel = Arc::clone(&self.t.codels[ck].name);
            self.emit(Event::Overrun {
                codel,
                took_us: took,
                period_us,
            });
        }
        let failed = error.is_some();
        // without an error, the codel's ids writes are part of the step: the module pick
        // set them
        if let Some(e) = &error {
            self.report_error(ck, e);
        }
        self.commit(Cause::Codel { error })?;
        Ok(Stepped::Codel {
            codel: CodelId(c),
            failed,
        })
    }

    /// Counts and reports the error path codel `ck` takes: an exception, or a fault (one a
    /// replay takes as its trace says is no fault seen now).
    pub(super) fn report_error(&mut self, ck: usize, error: &Outcome) {
        match error {
            Outcome::Fault(f) if f.kind == FaultKind::Replayed => {}
            Outcome::Fault(f) => {
                self.stats.faults += 1;
                let i = &self.t.codels[ck].info;
                tracing::warn!(target: "bip_engine", module = i.module.as_str(),
                    service = i.service.as_str(), codel = i.state.as_str(),
                    fault = %f.kind, "codel fault: its error path is taken");
                self.emit(Event::Fault(f.clone()));
            }
            _ => self.stats.exceptions += 1,
        }
    }

    /// Calls a bound codel (here or on its task's thread).
    pub(super) fn call_codel(
        &mut self,
        ck: usize,
        service: usize,
        starting: bool,
        now_us: u64,
    ) -> Result<Next, String> {
        let tick = self.stats.ticks;
        let activity = self.t.services[service].activity.as_mut();
        // a codel at a request reads the request's arguments before it is accepted
        let (args_slot, output_slot) = match activity {
            _ if self.t.codels[ck].at_request => (
                Some(&mut self.runner.request_args),
                Some(&mut self.runner.request_output),
            ),
            Some(a) => {
                let slot = if starting {
                    &mut a.pending_args
                } else {
                    &mut a.current_args
                };
                (Some(slot), Some(&mut a.output))
            }
            None => (None, None),
        };
        #[cfg(feature = "std")]
        if let Body::Thread { worker, local } = self.runner.bodies[ck] {
            // the request's arguments and output move to the thread and back
            let (mut args_slot, mut output_slot) = (args_slot, output_slot);
            let Some(workers) = self.runner.workers.as_mut() else {
                return Err("no task threads".into());
            };
            let taken = args_slot.as_mut().and_then(|s| s.take());
            let output = output_slot.as_mut().and_then(|s| s.take());
            let job = crate::threads::Job {
                local,
                ids: core::mem::take(&mut self.runner.ids),
                written: 0,
                fault: None,
                ports: core::mem::take(&mut self.runner.ports),
                args: taken,
                output,
                now_us,
                tick,
                result: None,
            };
            let job = workers.run(worker, job);
            let Some(mut job) = job else {
                return Err("the task's thread is gone".into());
            };
            self.runner.ids = core::mem::take(&mut job.ids);
            self.runner.ports = core::mem::take(&mut job.ports);
            self.runner.written = job.written;
            self.runner.fault = job.fault.take();
            if let Some(s) = args_slot {
                *s = job.args.take();
            }
            if let Some(s) = output_slot {
                *s = job.output.take();
            }
            return job.result.unwrap_or_else(|| Err("no result".into()));
        }
        let args: Option<&(dyn Any + Send)> = args_slot.and_then(|s| s.as_deref());
        let output = output_slot;
        let mut ctx = Ctx {
            info: &self.t.codels[ck].info,
            ids: &mut self.runner.ids,
            written: &mut self.runner.written,
            fault: core::cell::Cell::from_mut(&mut self.runner.fault),
            ports: &mut self.runner.ports,
            args,
            output,
            now_us,
            tick,
        };
        match &mut self.runner.bodies[ck] {
            Body::Bound(f) => call_guarded(&mut ctx, f),
            &mut Body::Module { module, local } => match self.runner.modules.get_mut(module) {
                Some(m) => call_guarded(&mut ctx, |ctx: &mut Ctx<'_>| m(local, ctx)),
                None => Err("no such module object".into()),
            },
            _ => Err("not a bound codel".into()),
        }
    }

    /// (Inlined into the step: a call more costs the synchronous path; the async codels'
    /// out-of-line outcome calls it too.)
    #[inline(always)]
    pub(super) fn classify(&mut self, ck: usize, result: Result<Next, String>) -> CodelEnd {
        let c = &mut self.t.codels[ck];
        let next = match result {
            Err(msg) => return fault(&c.name, FaultKind::Panic(msg)),
            Ok(n) => n,
        };
        if let Some(f) = self.runner.fault.take() {
            return fault(&c.name, FaultKind::from(f));
        }
        match next {
            Next::Yield(y) => match c.yield_index(y) {
                Some(k) => ids_in_range(c, &self.runner.ids, self.runner.written, k),
                None => fault(&c.name, FaultKind::BadTransition(y)),
            },
            Next::Declared(k) => match usize::from(k).checked_sub(c.map.yields.len()) {
                None => ids_in_range(c, &self.runner.ids, self.runner.written, usize::from(k)),
                Some(_) => declared_exception(c, k),
            },
            Next::Throw(e) => match c.throws.iter().find(|x| &***x == e) {
                Some(x) => CodelEnd::Failed(Outcome::Exception(Arc::clone(x))),
                None => fault(&c.name, FaultKind::UndeclaredException(e)),
            },
        }
    }

    /// A default codel's outcome: what the forced step says, the first yield, or a
    /// random outcome.
    pub(super) fn default_end(&mut self, ck: usize, forced: bool) -> CodelEnd {
        let c = &self.t.codels[ck];
        if forced {
            if self.forced_is(c.map.fail) {
                return CodelEnd::Failed(Outcome::Fault(Fault {
                    codel: Arc::clone(&c.name),
                    kind: FaultKind::Replayed,
                }));
            }
            // the yield the activity pick takes, the ids values the module pick writes
            let mut yield_k = 0;
            for p in &self.forced {
                if let Some(y) = c
                    .map
                    .yields
                    .iter()
                    .position(|y| y.transitions.contains(&p.transition))
                {
                    if self.t.services[c.service as usize]
                        .activity
                        .as_ref()
                        .is_some_and(|a| a.component == p.component)
                    {
                        yield_k = y;
                    }
                }
                if p.component == c.module_component
                    && c.map.ids_transitions.contains(&p.transition)
                {
                    let mut rest = p.transition - c.map.ids_transitions.start;
                    for (j, f) in c.map.ids.iter().enumerate() {
                        let digit = rest / f.stride;
                        rest %= f.stride;
                        self.runner.ids[c.ids_field[j]] = f.lo + i64::from(digit);
                    }
                }
            }
            return CodelEnd::Yielded { yield_k };
        }
        match self.runner.defaults {
            DefaultCodels::FirstYield => CodelEnd::Yielded { yield_k: 0 },
            DefaultCodels::Random(_) => {
                let outcomes = c.map.yields.len() + c.throws.len();
                let k = self.runner.rng.below(outcomes);
                for (j, f) in c.map.ids.iter().enumerate() {
                    let span = (f.hi - f.lo + 1) as usize;
                    self.runner.ids[c.ids_field[j]] = f.lo + self.runner.rng.below(span) as i64;
                }
                if k < c.map.yields.len() {
                    CodelEnd::Yielded { yield_k: k }
                } else {
                    CodelEnd::Failed(Outcome::Exception(Arc::clone(
                        &c.throws[k - c.map.yields.len()],
                    )))
                }
            }
        }
    }

    /// Chooses a step of the codel's run interaction that takes
    /// yield `yield_k` and writes the staged ids, chosen by the policy if several (with
    /// `forced`, the forced step if it is one); false if there is none.
    #[inline(always)]
    pub(super) fn take_run_step(&mut self, ck: usize, yield_k: usize, forced: bool) -> bool {
        let c = &self.t.codels[ck];
        // steps from a table entry, and no ids to match: the step may be the one found last
        let pooled = if forced || !c.map.ids.is_empty() {
            None
        } else {
            self.gate.enabled().pooled_steps(c.map.run)
        };
        if let (Some((entry, width, _)), Some(m)) = (pooled, c.run_step) {
            if m.entry == entry && m.yield_k as usize == yield_k {
                self.chosen.set_pooled(c.map.run, m.step, width);
                return true;
            }
        }
        // the yield's transitions: the activity's, or a function's on its module
        let comp = match self.t.services[c.service as usize].activity.as_ref() {
            Some(activity) => activity.component,
            None => c.module_component,
        };
        let want_ids = if c.map.ids.is_empty() {
            None
        } else {
            let ids = &self.runner.ids;
            match c.map.ids_transition(|j| ids[c.ids_field[j]]) {
                Some(t) => Some(t),
                None => return false,
            }
        };
        let yields = &c.map.yields[yield_k].transitions;
        // one or two transitions: a plain loop, not `contains`'s wide search
        #[allow(clippy::manual_contains)]
        let takes_yield = |t: u32| yields.iter().any(|&y| y == t);
        let matches = |s: &Step<'_>| {
            s.picks
                .iter()
                .any(|p| p.component == comp && takes_yield(p.transition))
                && want_ids.is_none_or(|t| {
                    s.picks
                        .iter()
                        .any(|p| p.component == c.module_component && p.transition == t)
                })
        };
        let run = c.map.run;
        let mut remember = None;
        let step = if forced {
            self.gate
                .enabled()
                .steps_of(run)
                .find(|s| s.picks == &self.forced[..] && matches(s))
        } else {
            // as `choose_step`, keeping where the first match is among all the steps
            let all = self.gate.enabled().steps_of(run).enumerate();
            let (n, first) = count_first(all.filter(|(_, s)| matches(s)));
            match first {
                None => None,
                Some((k, first)) => match self.sched.chooser.choose(n) {
                    0 => {
                        if let (1, Some((entry, width, _))) = (n, pooled) {
                            remember = Some(RunStep {
                                entry,
                                yield_k: yield_k as u32,
                                step: entry + k as u32 * width,
                            });
                        }
                        Some(first)
                    }
                    k => self
                        .gate
                        .enabled()
                        .steps_of(run)
                        .filter(|s| matches(s))
                        .nth(k),
                },
            }
        };
        let found = step.is_some();
        self.chosen.set(self.gate.enabled(), step);
        if remember.is_some() {
            self.t.codels[ck].run_step = remember;
        }
        found
    }
}

impl Engine {
    /// Records codel `ck`'s run of `took` µs from `t0`, and reports a run past its WCET
    /// and a period's work past its task's deadline (the reports are cold, out of line).
    #[inline(always)]
    pub(super) fn check_budgets(&mut self, ck: usize, t0: u64, took: u64, of_task: bool) {
        let times = &mut self.budgets.times[ck];
        times.record(took);
        let (wcet, task) = (self.t.codels[ck].map.wcet_us, self.t.codels[ck].task);
        if let Some(wcet_us) = wcet.filter(|&w| took > w) {
            times.over_wcet += 1;
            self.report_over_wcet(ck, took, wcet_us);
        }
        let Some(k) = task.map(|k| k as usize).filter(|_| of_task) else {
            return;
        };
        if let Some(cpus) = &mut self.budgets.cpus {
            // the simulated CPUs judge the deadline when the work ends there
            let released_us = self.budgets.tasks[k].released_us;
            cpus.work(k, ck as u32, released_us, took);
            return;
        }
        let task = self.budgets.tasks.get_mut(k);
        if let Some((elapsed_us, deadline_us)) =
            task.and_then(|t| Some((t.ended(t0.saturating_add(took))?, t.deadline_us)))
        {
            self.report_deadline_missed(ck, elapsed_us, deadline_us);
        }
    }

    /// The simulated time of a default run of codel `ck`, if codels have one.
    fn simulated_time(&mut self, ck: usize) -> Option<u64> {
        let wcet = self.t.codels[ck].map.wcet_us.unwrap_or(0);
        match self.budgets.codel_time {
            CodelTime::Zero => None,
            CodelTime::Wcet => Some(wcet),
            CodelTime::Random(_) => Some(self.budgets.rng.next_u64() % wcet.saturating_add(1)),
        }
    }

    /// Runs the simulated CPUs until `now_us`, reporting the deadlines missed there.
    pub(super) fn run_simulated_cpus(&mut self, now_us: u64) {
        let Some(mut cpus) = self.budgets.cpus.take() else {
            return;
        };
        cpus.run_until(now_us, |m| {
            self.report_deadline_missed(m.codel as usize, m.elapsed_us, m.deadline_us)
        });
        self.budgets.cpus = Some(cpus);
    }

    #[cold]
    #[inline(never)]
    fn report_over_wcet(&mut self, ck: usize, took_us: u64, wcet_us: u64) {
        self.stats.wcet_exceeded += 1;
        let i = &self.t.codels[ck].info;
        tracing::warn!(target: "bip_engine", module = i.module.as_str(),
            service = i.service.as_str(), codel = i.state.as_str(), took_us, wcet_us,
            "codel ran past its WCET");
        let codel = Arc::clone(&self.t.codels[ck].name);
        self.emit(Event::WcetExceeded {
            codel,
            took_us,
            wcet_us,
        });
    }

    #[cold]
    #[inline(never)]
    fn report_deadline_missed(&mut self, ck: usize, elapsed_us: u64, deadline_us: u64) {
        self.stats.deadlines_missed += 1;
        let i = &self.t.codels[ck].info;
        tracing::warn!(target: "bip_engine", module = i.module.as_str(),
            service = i.service.as_str(), codel = i.state.as_str(), elapsed_us, deadline_us,
            "task's period work ended past its deadline");
        let codel = Arc::clone(&self.t.codels[ck].name);
        let service = &self.t.services[self.t.codels[ck].service as usize];
        let task = format!(
            "{}.{}",
            service.module,
            service.task.as_deref().unwrap_or("?")
        );
        self.emit(Event::DeadlineMissed {
            task: task.into(),
            codel: Some(codel),
            elapsed_us,
            deadline_us,
        });
    }
}

/// The end of a faulty run of `codel`.
/// The exception `Next::Declared(k)` names, or a fault if `k` is past them.
#[cold]
fn declared_exception(c: &CodelTable, k: u16) -> CodelEnd {
    match c.throws.get(usize::from(k) - c.map.yields.len()) {
        Some(x) => CodelEnd::Failed(Outcome::Exception(Arc::clone(x))),
        None => fault(&c.name, FaultKind::UndeclaredOutcome(k)),
    }
}

/// Yield `yield_k`, unless the codel left an ids field it wrote out of its range.
fn ids_in_range(c: &CodelTable, ids: &[i64], written: u64, yield_k: usize) -> CodelEnd {
    for (j, f) in c.info.fields.iter().enumerate() {
        let v = ids[j];
        if written >> j & 1 == 1 && (v < f.lo || v > f.hi) {
            let field = f.name.clone();
            return fault(&c.name, FaultKind::IdsOutOfRange { field, value: v });
        }
    }
    CodelEnd::Yielded { yield_k }
}

#[cold]
fn fault(codel: &Arc<Codel>, kind: FaultKind) -> CodelEnd {
    CodelEnd::Failed(Outcome::Fault(Fault {
        codel: Arc::clone(codel),
        kind,
    }))
}
