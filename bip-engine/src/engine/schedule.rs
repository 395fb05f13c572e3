//! The step loop: a due tick, else a progress step chosen by the policy, else a request,
//! else idle (the module documentation of [`super`]).

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{EnabledSet, Label, Step};

use super::replies::Cause;
use super::{Candidate, Engine};
use crate::bind::{InterKind, Tables};
use crate::error::{EngineError, StepAsError};
use crate::event::CodelId;
use crate::event::Ticket;
use crate::policy::Chooser;

/// What one call of [`Engine::step`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stepped {
    /// A tick.
    Tick,
    /// A codel ran; `failed` if its error path was taken.
    Codel { codel: CodelId, failed: bool },
    /// A request was served (`accepted`) or refused.
    Request { ticket: Ticket, accepted: bool },
    /// Another step of the model (a connector of yours, an internal transition).
    Other,
    /// Nothing to do before `next_tick_us` (`None`: nothing will happen unless a request
    /// arrives, as no time step is enabled).
    Idle { next_tick_us: Option<u64> },
}

/// When [`Engine::run_until`] stops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Until {
    /// After this many steps (idle waits do not count).
    Steps(u64),
    /// When this many more ticks have passed.
    Ticks(u64),
    /// When the clock reaches this time.
    TimeUs(u64),
    /// When nothing is left to do before the next tick and no request waits.
    Quiescent,
}

impl Engine {
    /// Takes one step: a due tick, else a codel or another step of the model, else a
    /// waiting request; else nothing can happen before the next tick, and it returns
    /// [`Stepped::Idle`].
    ///
    /// Time: `step` never blocks. On a virtual clock (the default, [`crate::Clock::is_virtual`])
    /// an idle step also moves the clock to the next tick, so the next `step` fires it:
    /// calling `step` in a loop runs the model with time passing. On a real clock the
    /// time comes by itself: after `Idle { next_tick_us: Some(t) }` wait until `t`
    /// ([`Engine::wait_until`]) or call `step` again later. [`Engine::run_until`] steps
    /// and waits for you on either clock. `Idle { next_tick_us: None }`: nothing can
    /// happen until a request arrives (no time step is enabled).
    pub fn step(&mut self) -> Result<Stepped, EngineError> {
        let stepped = self.step_any()?;
        if let Stepped::Idle {
            next_tick_us: Some(t),
        } = stepped
        {
            if self.time.clock.is_virtual() && !self.returned_meanwhile(t) {
                self.time.clock.sleep_until(t);
            }
        }
        Ok(stepped)
    }

    /// One step, without moving a virtual clock when idle: in a timed model, first a
    /// codel whose time has come or a due time step (`timed.rs`).
    #[inline(always)]
    fn step_any(&mut self) -> Result<Stepped, EngineError> {
        if self.timed.is_some() {
            if let Some(stepped) = self.step_timed()? {
                return Ok(stepped);
            }
        }
        self.step_once()
    }

    /// One step, without moving a virtual clock when idle.
    fn step_once(&mut self) -> Result<Stepped, EngineError> {
        if let Some(e) = &self.stopped {
            return Err(EngineError::Stopped(e.clone()));
        }
        #[cfg(feature = "std")]
        self.drain_remote();
        // an async codel that has returned: its return, when the model allows it
        #[cfg(feature = "std")]
        if self.apart.live != 0 && self.return_apart()? {
            return Ok(Stepped::Other);
        }
        // 1. a due tick
        if self.time.clock.now_us() >= self.time.next_tick_us {
            if let Some(i) = self.enabled_time() {
                self.fire_time(i)?;
                return Ok(Stepped::Tick);
            }
        }
        // 2. progress
        self.collect_candidates();
        if !self.sched.candidates.is_empty() {
            let k = self.sched.chooser.choose(self.sched.candidates.len());
            return match self.sched.candidates[k] {
                Candidate::Codel(c) => self.run_codel(c, false).map_err(|e| match e {
                    StepAsError::Engine(e) => e,
                    // without a forced step a codel run never diverges or is refused
                    _ => EngineError::Stopped(self.internal_error()),
                }),
                #[cfg(feature = "std")]
                Candidate::Start(c) => self.start_apart(c, false).map_err(|e| match e {
                    StepAsError::Engine(e) => e,
                    _ => EngineError::Stopped(self.internal_error()),
                }),
                #[cfg(feature = "std")]
                Candidate::Outcome(c) => self.run_outcome(c, false).map_err(|e| match e {
                    StepAsError::Engine(e) => e,
                    _ => EngineError::Stopped(self.internal_error()),
                }),
                Candidate::TimedStart(c) => self.start_timed(c, false).map_err(|e| match e {
                    StepAsError::Engine(e) => e,
                    _ => EngineError::Stopped(self.internal_error()),
                }),
                #[cfg(not(feature = "std"))]
                // (without `std` no model with an async codel is built)
                Candidate::Start(c) | Candidate::Outcome(c) => {
                    let _ = c;
                    Err(EngineError::Stopped(self.internal_error()))
                }
                Candidate::Step(label, k) => {
                    self.choose_kth(label, k);
                    self.commit(self.progress_cause(label))?;
                    Ok(Stepped::Other)
                }
            };
        }
        // 3. quiescent: report what is held, serve a request
        if self.held.dirty {
            self.report_held()?;
            self.held.dirty = false;
        }
        if let Some((ticket, service, args)) = self.requests.inbox.pop_front() {
            return self.serve_request(ticket, service, args);
        }
        // 4. idle
        Ok(Stepped::Idle {
            next_tick_us: self.enabled_time().map(|_| self.time.next_tick_us),
        })
    }

    /// Runs until `until`; waits (or, with a virtual clock, jumps) to the next tick when
    /// idle. Returns early if nothing can ever happen (no time step is enabled and no
    /// request waits).
    pub fn run_until(&mut self, until: Until) -> Result<(), EngineError> {
        let steps0 = self.stats.steps;
        let ticks0 = self.stats.ticks;
        loop {
            match until {
                Until::Steps(n) if self.stats.steps - steps0 >= n => return Ok(()),
                Until::Ticks(n) if self.stats.ticks - ticks0 >= n => return Ok(()),
                Until::TimeUs(t) if self.time.clock.now_us() >= t => return Ok(()),
                _ => {}
            }
            if let Stepped::Idle { next_tick_us } = self.step_any()? {
                if until == Until::Quiescent {
                    return Ok(());
                }
                let target = match (next_tick_us, until) {
                    (Some(n), Until::TimeUs(t)) => n.min(t),
                    (Some(n), _) => n,
                    (None, Until::TimeUs(t)) => t,
                    (None, _) if self.has_remote() => self.time.clock.now_us() + self.time.tick_us,
                    (None, _) => return Ok(()),
                };
                self.wait_until(target);
            }
        }
    }

    pub(super) fn has_remote(&self) -> bool {
        #[cfg(feature = "std")]
        {
            self.remote.is_some()
        }
        #[cfg(not(feature = "std"))]
        {
            false
        }
    }

    /// Waits until the clock reaches `t` (a virtual clock jumps there), taking in requests
    /// from handles meanwhile.
    #[inline]
    pub fn wait_until(&mut self, t: u64) {
        if self.returned_meanwhile(t) {
            return;
        }
        #[cfg(feature = "std")]
        if self.remote.is_some() {
            self.wait_remote(t);
            return;
        }
        self.time.clock.sleep_until(t);
    }

    /// Whether an async codel running apart returned while the engine waited for time
    /// `t` (then the clock stays: its return is the next step).
    #[inline(always)]
    fn returned_meanwhile(&mut self, t: u64) -> bool {
        #[cfg(feature = "std")]
        {
            self.apart.live != 0 && self.wait_apart(t)
        }
        #[cfg(not(feature = "std"))]
        {
            let _ = t;
            false
        }
    }

    /// The first enabled time interaction.
    #[inline]
    pub(super) fn enabled_time(&self) -> Option<u32> {
        // a model has one or two: asking each is cheaper than walking the enabled ones
        let enabled = self.gate.enabled();
        self.t.time.iter().copied().find(|&i| enabled.is_enabled(i))
    }

    pub(super) fn fire_time(&mut self, i: u32) -> Result<(), EngineError> {
        if self.timed.is_some() {
            return self.fire_timed_tick(i, false);
        }
        self.take_step_of(i);
        self.commit(Cause::Other)?;
        self.count_tick();
        Ok(())
    }

    #[inline(always)]
    pub(super) fn count_tick(&mut self) {
        self.stats.ticks += 1;
        // a period begins when its tick was due
        let due = self.time.next_tick_us;
        self.run_simulated_cpus(due);
        for task in &mut self.budgets.tasks {
            task.tick(due);
        }
        self.time.next_tick_us = self.time.next_tick_us.saturating_add(self.time.tick_us);
    }

    pub(super) fn collect_candidates(&mut self) {
        self.sched.candidates.clear();
        // a state met before: its candidates are known
        let here = self.gate.cached_state();
        if let Some(known) = here.and_then(|s| self.sched.known_candidates.get(s)) {
            self.sched.candidates.extend_from_slice(known);
            return;
        }
        if self.sched.codel_stamp.len() != self.t.codels.len() {
            self.sched.codel_stamp = vec![u64::MAX; self.t.codels.len()];
        }
        collect_progress(
            self.gate.enabled(),
            &self.t,
            &mut self.sched.codel_stamp,
            self.stats.steps,
            &mut self.sched.candidates,
        );
        if let Some(s) = here {
            // (a state with internal transitions is not in the cache)
            self.sched.known_candidates.set(s, &self.sched.candidates);
        }
        if !self.t.has_internal {
            return;
        }
        let mut last = None;
        let mut k = 0;
        for s in self.gate.enabled().internal_steps() {
            if last != Some(s.label) {
                last = Some(s.label);
                k = 0;
            }
            self.sched.candidates.push(Candidate::Step(s.label, k));
            k += 1;
        }
    }

    /// Chooses the `k`-th enabled step with `label`.
    pub(super) fn choose_kth(&mut self, label: Label, k: u32) {
        let step = match label {
            Label::Interaction(i) => self.gate.enabled().steps_of(i).nth(k as usize),
            Label::Internal { .. } => self
                .gate
                .enabled()
                .internal_steps()
                .filter(|s| s.label == label)
                .nth(k as usize),
        };
        self.chosen.set(self.gate.enabled(), step);
    }

    /// Chooses one of the enabled steps of interaction `i` by the policy (none if it has
    /// none).
    pub(super) fn take_step_of(&mut self, i: u32) {
        // one step from the pool (a tick): nothing to walk, and nothing to choose (a
        // chooser asked to choose among one answers 0 and draws nothing, so seeded runs
        // do not change)
        if let Some((at, width, 1)) = self.gate.enabled().pooled_steps(i) {
            self.chosen.set_pooled(i, at, width);
            return;
        }
        let step = choose_step(&mut self.sched.chooser, || self.gate.enabled().steps_of(i));
        self.chosen.set(self.gate.enabled(), step);
    }
}

/// How many items `items` yields, and the first: the choice whenever there is one, found
/// in the same pass.
#[inline(always)]
pub(super) fn count_first<T>(items: impl Iterator<Item = T>) -> (usize, Option<T>) {
    let mut n = 0;
    let mut first = None;
    for x in items {
        first = first.or(Some(x));
        n += 1;
    }
    (n, first)
}

/// One of the steps `steps` yields, chosen by `chooser` among them all (`None` if there
/// are none). One pass counts them and keeps the first, the choice whenever there is only
/// one; the chooser sees the count either way, so seeded runs do not change.
fn choose_step<'a, I: Iterator<Item = Step<'a>>>(
    chooser: &mut Chooser,
    steps: impl Fn() -> I,
) -> Option<Step<'a>> {
    let (n, first) = count_first(steps());
    let first = first?;
    match chooser.choose(n) {
        0 => Some(first),
        k => steps().nth(k),
    }
}

/// Appends to `out` the progress candidates among the enabled interactions of
/// `t.progress_mask`, in index order: each codel once, where its first enabled interaction
/// (run or error path) is (`stamp`: the step count `epoch` when it was last collected),
/// and each step of a progress connector. A function of its own: the compiler then knows
/// that a push onto `out` changes nothing of the set it walks, and does not load the
/// set's tables again after each push.
fn collect_progress(
    enabled: &EnabledSet,
    t: &Tables,
    stamp: &mut [u64],
    epoch: u64,
    out: &mut Vec<Candidate>,
) {
    for i in enabled.interactions_in(&t.progress_mask) {
        match t.kind[i as usize] {
            InterKind::Codel { codel, .. } => {
                if stamp[codel as usize] != epoch {
                    stamp[codel as usize] = epoch;
                    // (candidates are kept per state: this is not looked at each step)
                    out.push(if t.codels[codel as usize].map.apart.is_some() {
                        Candidate::Outcome(codel)
                    } else {
                        Candidate::Codel(codel)
                    });
                }
            }
            InterKind::Start { codel } => out.push(Candidate::Start(codel)),
            InterKind::TimedStart { codel } => out.push(Candidate::TimedStart(codel)),
            InterKind::Progress => {
                let n = enabled.steps_of(i).count() as u32;
                for k in 0..n {
                    out.push(Candidate::Step(Label::Interaction(i), k));
                }
            }
            InterKind::Return { .. }
            | InterKind::Dropped { .. }
            | InterKind::Request { .. }
            | InterKind::AtRequestFail { .. }
            | InterKind::Time
            | InterKind::Environment => {}
        }
    }
}
