//! A timed model on the engine (docs/engine.md, "Codel times"; docs/genom.md, "Timed
//! models"): a codel's body runs at its start step, which takes its task's core, and
//! its finish (the yield it returned, or its failure) is committed once its task's `x`
//! has reached the time units the engine chose for the run. The model decides what may
//! happen when; the engine's only choice beside the model's is when a started codel
//! finishes, between its BCET and its WCET:
//! - a bound codel takes the time it took by the clock, in whole units rounded up (its
//!   finish comes after its return), within [BCET, WCET]: one still running at its WCET
//!   is reported ([`crate::Event::WcetExceeded`]) and finishes at WCET in the model;
//! - a default codel takes the time [`CodelTime`] says: its WCET, its BCET (`Zero`: as
//!   early as the model allows), or a duration drawn in [BCET, WCET] at its start.
//!
//! The tick is the model's time step: it stands for its `advance` units, and the engine
//! fires it when its clock has reached the model's time plus that many units (a virtual
//! clock is moved there when nothing else is left to do).

use alloc::sync::Arc;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::genom::TimedTaskMap;

use super::codels::CodelEnd;
use super::replies::Cause;
use super::{Engine, Stepped};
use crate::budgets::CodelTime;
use crate::codel::Body;
use crate::error::{EngineError, StepAsError};
use crate::event::{Codel, Event};

/// A timed model's time and running codels.
pub(super) struct Timed {
    /// The model's time unit.
    unit_us: u64,
    /// The model's time by the engine's clock: the clock's time at the start plus the
    /// units of the time steps committed since.
    pub(super) model_us: u64,
    /// Per task of `Tables::tasks`: its name, its atom (if it runs codels), its deadline,
    /// the codel it runs, the codel it ran last, whether its deadline invariant is false.
    tasks: Vec<TimedTask>,
}

struct TimedTask {
    name: Arc<str>,
    map: Option<TimedTaskMap>,
    deadline_us: u64,
    run: Option<Run>,
    last: Option<u32>,
    late: bool,
}

/// A codel started and not finished.
struct Run {
    codel: u32,
    /// The time units it takes: its finish comes once its task's `x` has reached them.
    units: u64,
    /// When it started by the clock, and how long it took (a default codel: its units).
    t0: u64,
    took: u64,
    /// A bound codel's end, with the ids values it staged and which it wrote; a default
    /// codel's end is drawn at its finish (or read from a replayed finish).
    end: Option<(CodelEnd, Vec<i64>, u64)>,
}

impl Timed {
    /// The timed part of an engine for a model whose GenoM map gives `unit_us`, starting
    /// at `now_us`; `tasks` as `Tables::timed_tasks`, with each task's deadline.
    pub(super) fn new(
        unit_us: u64,
        now_us: u64,
        tasks: impl Iterator<Item = (Arc<str>, Option<TimedTaskMap>, u64)>,
    ) -> Timed {
        Timed {
            unit_us: unit_us.max(1),
            model_us: now_us,
            tasks: tasks
                .map(|(name, map, deadline_us)| TimedTask {
                    name,
                    map,
                    deadline_us,
                    run: None,
                    last: None,
                    late: false,
                })
                .collect(),
        }
    }

    /// The deadline invariants to watch: (task, property).
    pub(super) fn deadlines(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.tasks
            .iter()
            .enumerate()
            .filter_map(|(k, t)| Some((k, t.map?.deadline? as usize)))
    }
}

impl Engine {
    /// What comes first in a timed model's step: a codel whose time has come finishes,
    /// else a time step that is due. Otherwise (`None`) the step goes on as an untimed
    /// model's, a zero-time step chosen by the policy (a dispatch, a codel's start, a
    /// job's end, a release, a step of yours) or a request, with the time step's time as
    /// the next tick's.
    #[inline(never)]
    pub(super) fn step_timed(&mut self) -> Result<Option<Stepped>, EngineError> {
        if let Some(e) = &self.stopped {
            return Err(EngineError::Stopped(e.clone()));
        }
        if let Some((codel, dropped)) = self.due_finish() {
            let finished = match dropped {
                false => self.finish_timed(codel, false),
                true => self.drop_timed(codel, false),
            };
            // without a forced step a finish never diverges or is refused
            return finished.map(Some).map_err(|e| match e {
                StepAsError::Engine(e) => e,
                _ => EngineError::Stopped(self.internal_error()),
            });
        }
        let next = self.next_timed_tick()?;
        self.time.next_tick_us = next.map_or(u64::MAX, |(_, at)| at);
        match next {
            Some((i, at)) if self.time.clock.now_us() >= at => {
                self.fire_timed_tick(i, false)?;
                Ok(Some(Stepped::Tick))
            }
            _ => Ok(None),
        }
    }

    /// The enabled time step and the clock's time at which it is due: the model's time
    /// plus the units it stands for.
    #[inline(never)]
    pub(super) fn next_timed_tick(&mut self) -> Result<Option<(u32, u64)>, EngineError> {
        let Some(i) = self.enabled_time() else {
            return Ok(None);
        };
        let units = self.advance_of(i)?;
        let Some(timed) = &self.timed else {
            return Ok(None);
        };
        let at = timed
            .model_us
            .saturating_add(units.saturating_mul(timed.unit_us));
        Ok(Some((i, at)))
    }

    /// The units the enabled time step `i` stands for in the current state.
    fn advance_of(&mut self, i: u32) -> Result<u64, EngineError> {
        let Some(step) = self.gate.enabled().steps_of(i).next() else {
            return Ok(1);
        };
        match self.gate.system().time_advance(self.gate.state(), step) {
            Ok(units) => Ok(units),
            Err(e) => {
                self.stopped = Some(e.clone());
                Err(EngineError::Range(e))
            }
        }
    }

    /// Commits the time step of interaction `i` (chosen, or forced) and moves the
    /// model's time by the units it stands for.
    #[inline(never)]
    pub(super) fn fire_timed_tick(&mut self, i: u32, forced: bool) -> Result<(), EngineError> {
        let units = self.advance_of(i)?;
        if !forced {
            self.take_step_of(i);
        }
        self.commit(Cause::Other)?;
        self.stats.ticks += 1;
        if let Some(timed) = &mut self.timed {
            timed.model_us = timed
                .model_us
                .saturating_add(units.saturating_mul(timed.unit_us));
        }
        Ok(())
    }

    /// A running codel whose time has come and whose finish the model enables: (codel,
    /// whether its outcome is dropped).
    fn due_finish(&self) -> Option<(u32, bool)> {
        let timed = self.timed.as_ref()?;
        let slots = self.gate.state().slots();
        let enabled = self.gate.enabled();
        for task in &timed.tasks {
            let (Some(run), Some(map)) = (&task.run, task.map) else {
                continue;
            };
            let x = slots[map.elapsed_slot as usize];
            if x < i64::try_from(run.units).unwrap_or(i64::MAX) {
                continue;
            }
            let c = &self.t.codels[run.codel as usize].map;
            if enabled.is_enabled(c.run) || enabled.is_enabled(c.fail) {
                return Some((run.codel, false));
            }
            let dropped = c.timed.and_then(|t| t.dropped);
            if dropped.is_some_and(|d| enabled.is_enabled(d)) {
                return Some((run.codel, true));
            }
        }
        None
    }

    /// Commits codel `c`'s start (the step chosen, or forced), then runs its body: a
    /// bound codel now, for the time its clock measures; a default codel's outcome is
    /// drawn at its finish, its time now.
    #[inline(never)]
    pub(super) fn start_timed(&mut self, c: u32, forced: bool) -> Result<Stepped, StepAsError> {
        let ck = c as usize;
        if !forced {
            let Some(tc) = self.t.codels[ck].map.timed else {
                return Err(EngineError::Stopped(self.internal_error()).into());
            };
            self.take_step_of(tc.start);
        }
        self.commit(Cause::Other)?;
        let (bcet, wcet) = self.bounds_units(ck);
        let t0 = self.time.clock.now_us();
        let run = match self.runner.bodies[ck] {
            Body::Default => {
                let units = match self.budgets.codel_time {
                    CodelTime::Zero => bcet,
                    CodelTime::Wcet => wcet,
                    CodelTime::Random(_) => {
                        bcet + self.budgets.rng.next_u64() % (wcet - bcet).saturating_add(1)
                    }
                };
                let took = units.saturating_mul(self.unit_us());
                Run {
                    codel: c,
                    units,
                    t0,
                    took,
                    end: None,
                }
            }
            _ => {
                let service = self.t.codels[ck].service as usize;
                let starting = self.t.services[service].activity.as_ref().is_some_and(|a| {
                    self.gate.state().slots()[a.loc_slot as usize] == i64::from(a.ether)
                });
                self.stage_ids(ck);
                let result = self.call_codel(ck, service, starting, t0);
                let end = self.classify(ck, result);
                let took = self.time.clock.now_us().saturating_sub(t0);
                let units = took.div_ceil(self.unit_us()).clamp(bcet, wcet);
                let ids = self.runner.ids.clone();
                Run {
                    codel: c,
                    units,
                    t0,
                    took,
                    end: Some((end, ids, self.runner.written)),
                }
            }
        };
        if let Some(task) = self.timed_task(ck) {
            task.last = Some(c);
            task.run = Some(run);
        }
        Ok(Stepped::Other)
    }

    /// Commits the finish of codel `c`: the end its body returned at its start (a default
    /// codel's drawn now, or the forced step's).
    #[inline(never)]
    pub(super) fn finish_timed(&mut self, c: u32, forced: bool) -> Result<Stepped, StepAsError> {
        let ck = c as usize;
        let run = self.take_run(ck);
        self.stage_ids(ck);
        let now = self.time.clock.now_us();
        let (end, t0, took) = match run {
            Some(Run {
                end: Some((end, ids, written)),
                t0,
                took,
                ..
            }) => {
                self.runner.ids = ids;
                self.runner.written = written;
                (end, t0, took)
            }
            Some(Run { t0, took, .. }) => (self.default_end(ck, forced), t0, took),
            // a replayed trace that begins after the start
            None => (self.default_end(ck, forced), now, 0),
        };
        self.commit_codel(c, end, t0, took, forced, false)
    }

    /// Commits the finish of codel `c` whose activity left it while it ran: it frees the
    /// core, its outcome dropped; its run is counted.
    #[inline(never)]
    pub(super) fn drop_timed(&mut self, c: u32, forced: bool) -> Result<Stepped, StepAsError> {
        let ck = c as usize;
        if !forced {
            let Some(d) = self.t.codels[ck].map.timed.and_then(|t| t.dropped) else {
                return Err(EngineError::Stopped(self.internal_error()).into());
            };
            self.take_step_of(d);
        }
        let run = self.take_run(ck);
        self.commit(Cause::Other)?;
        if let Some(run) = run {
            self.stats.codels += 1;
            self.check_budgets(ck, run.t0, run.took, false);
        }
        Ok(Stepped::Other)
    }

    /// Whether codel `c` has started and not finished.
    #[inline(never)]
    pub(super) fn is_running(&self, c: u32) -> bool {
        let task = self.t.codels[c as usize].task;
        let run = task.and_then(|k| self.timed.as_ref()?.tasks.get(k as usize)?.run.as_ref());
        run.is_some_and(|r| r.codel == c)
    }

    /// The run of codel `ck`, taken from its task.
    fn take_run(&mut self, ck: usize) -> Option<Run> {
        let c = ck as u32;
        let task = self.timed_task(ck)?;
        match &task.run {
            Some(r) if r.codel == c => task.run.take(),
            _ => None,
        }
    }

    fn timed_task(&mut self, ck: usize) -> Option<&mut TimedTask> {
        let k = self.t.codels[ck].task? as usize;
        self.timed.as_mut()?.tasks.get_mut(k)
    }

    fn unit_us(&self) -> u64 {
        self.timed.as_ref().map_or(1, |t| t.unit_us)
    }

    /// Codel `ck`'s BCET and WCET in the model's units (a codel without a WCET takes no
    /// time).
    fn bounds_units(&self, ck: usize) -> (u64, u64) {
        let unit = self.unit_us();
        let map = &self.t.codels[ck].map;
        let wcet = map.wcet_us.unwrap_or(0) / unit;
        let bcet = (map.bcet_us.unwrap_or(0) / unit).min(wcet);
        (bcet, wcet)
    }

    /// Reports each task whose deadline invariant the step just committed made false
    /// (once, until it holds again). A range error in the invariant stops the engine.
    #[cold]
    #[inline(never)]
    pub(super) fn watch_deadlines(&mut self) -> Result<(), EngineError> {
        let Some(timed) = &self.timed else {
            return Ok(());
        };
        let deadlines: Vec<(usize, usize)> = timed.deadlines().collect();
        for (k, property) in deadlines {
            let system = self.gate.system();
            let p = &system.properties[property];
            let bip_model::PropertyKind::Invariant(expr) = &p.kind else {
                continue;
            };
            let context = format!("property {}", p.name);
            let holds = match system.holds(expr, self.gate.state(), &context) {
                Ok(h) => h,
                Err(e) => {
                    self.stopped = Some(e.clone());
                    return Err(EngineError::Range(e));
                }
            };
            let Some(timed) = &mut self.timed else {
                return Ok(());
            };
            let unit_us = timed.unit_us;
            let task = &mut timed.tasks[k];
            let newly = !holds && !task.late;
            task.late = !holds;
            if newly {
                let (name, deadline_us, last) =
                    (Arc::clone(&task.name), task.deadline_us, task.last);
                let codel = last.map(|c| Arc::clone(&self.t.codels[c as usize].name));
                // the model's time steps stop at the first unit past a deadline
                self.report_task_late(name, codel, deadline_us + unit_us, deadline_us);
            }
        }
        Ok(())
    }

    #[cold]
    fn report_task_late(
        &mut self,
        task: Arc<str>,
        codel: Option<Arc<Codel>>,
        elapsed_us: u64,
        deadline_us: u64,
    ) {
        self.stats.deadlines_missed += 1;
        tracing::warn!(target: "bip_engine", task = &*task, elapsed_us, deadline_us,
            "task's job is past its deadline");
        self.emit(Event::DeadlineMissed {
            task,
            codel,
            elapsed_us,
            deadline_us,
        });
    }
}
