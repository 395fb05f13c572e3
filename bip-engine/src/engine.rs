//! The engine: gates every step on the model, runs codels, serves requests, keeps time.
//!
//! One step of [`Engine::step`] (docs/engine.md, "Scheduling"):
//! 1. a tick that is due (by the clock) and enabled in the model is fired;
//! 2. otherwise one enabled progress step is taken, chosen by the [`Policy`]: a codel
//!    (run, then the step its outcome names is committed), or a step of a connector of
//!    yours or an internal transition;
//! 3. otherwise (the layer is quiescent) the oldest request is served: fired if its
//!    request interaction is enabled, refused with the failing conditions if not;
//! 4. otherwise the engine is idle until the next tick.
//!
//! Every step committed is a step [`bip_model::EnabledSet`] lists as enabled in the
//! current state, fired with [`System::fire`]: the engine's run is a path of the model.

use alloc::collections::VecDeque;
use alloc::sync::Arc;
use core::any::Any;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{
    CacheStats, CommitError, EnabledSet, Gate, Label, Pick, RangeError, State, Step, System, Trace,
    Verdict,
};

use crate::bind::{InterKind, PortKind, RunStep, Tables};
use crate::chosen::Chosen;
use crate::clock::Clock;
use crate::codel::{CodelFn, Ctx, CtxFault, Next};
use crate::error::{BuildError, EngineError, RequestError, StepAsError};
use crate::event::{
    CodelId, Event, Fault, FaultKind, Outcome, Reasons, Refusal, Reply, ServiceId, Ticket,
};
use crate::per_state::PerState;
use crate::policy::{Chooser, Policy, Rng};
use crate::ports::PortStore;
use crate::record::Recording;

/// What unbound codels do (for simulation and replay).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DefaultCodels {
    /// Yield the first declared yield, write nothing.
    FirstYield,
    /// Yield or throw one of the declared outcomes at random (seeded), and write random
    /// values in range into the ids the codel writes.
    Random(u64),
}

/// A callback for every event.
pub type EventFn = Box<dyn FnMut(&Event) + Send>;

/// Arguments of a request, for its activity's codels.
pub type Args = Box<dyn Any + Send>;

/// How a codel is run.
pub(crate) enum Body {
    Bound(CodelFn),
    Default,
    #[cfg(feature = "std")]
    Thread {
        worker: usize,
        local: usize,
    },
}

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

/// Counters since the engine started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Steps committed (ticks, codels, requests, others).
    pub steps: u64,
    pub ticks: u64,
    pub codels: u64,
    pub exceptions: u64,
    pub faults: u64,
    pub overruns: u64,
    pub requests_accepted: u64,
    pub requests_refused: u64,
    /// Events dropped because nobody drained the queue.
    pub events_dropped: u64,
}

/// How many states [`EngineBuilder::state_cache`] remembers by default: about 1.5 MiB
/// for a model the size of robots/rover.ron, at the 1.5 KiB per state measured there
/// (docs/engine.md, "The state cache").
pub const DEFAULT_STATE_CACHE: usize = 1024;

/// Builds an [`Engine`]: bind codels, choose a clock, a policy, recording.
pub struct EngineBuilder {
    system: System,
    bindings: Vec<((String, String, String), CodelFn)>,
    defaults: Option<DefaultCodels>,
    clock: Option<Box<dyn Clock>>,
    policy: Policy,
    tick_us: Option<u64>,
    record: Option<usize>,
    event_capacity: usize,
    on_event: Option<EventFn>,
    threads: bool,
    state_cache: usize,
}

impl EngineBuilder {
    /// Binds codel `state` of service `service` of module `module`.
    pub fn codel(
        mut self,
        (module, service, state): (&str, &str, &str),
        f: impl FnMut(&mut Ctx<'_>) -> Next + Send + 'static,
    ) -> Self {
        self.bindings
            .push(((module.into(), service.into(), state.into()), Box::new(f)));
        self
    }

    /// Runs unbound codels with a default instead of refusing to build.
    pub fn default_codels(mut self, d: DefaultCodels) -> Self {
        self.defaults = Some(d);
        self
    }

    /// The clock (default: a [`crate::VirtualClock`]).
    pub fn clock(mut self, c: impl Clock + 'static) -> Self {
        self.clock = Some(Box::new(c));
        self
    }

    pub fn policy(mut self, p: Policy) -> Self {
        self.policy = p;
        self
    }

    /// The length of a tick (default: the model's `tick_ms`, else 1 ms).
    pub fn tick_us(mut self, us: u64) -> Self {
        self.tick_us = Some(us.max(1));
        self
    }

    /// Records the steps for [`Engine::record`], with room for `capacity` steps before
    /// the recording allocates.
    pub fn record(mut self, capacity: usize) -> Self {
        self.record = Some(capacity);
        self
    }

    /// How many events the engine keeps for [`Engine::events`] (default 1024; the oldest
    /// are dropped and counted in [`Stats::events_dropped`]).
    pub fn event_capacity(mut self, n: usize) -> Self {
        self.event_capacity = n;
        self
    }

    /// Calls `f` with every event as it happens (besides queueing it).
    pub fn on_event(mut self, f: impl FnMut(&Event) + Send + 'static) -> Self {
        self.on_event = Some(Box::new(f));
        self
    }

    /// Runs the codels of each task on a thread of their own (docs/engine.md, "Threads").
    pub fn threads(mut self, on: bool) -> Self {
        self.threads = on;
        self
    }

    /// Remembers up to `states` states of the model, with their enabled steps and the
    /// steps between them, so that a step taken before from the same state is looked up
    /// rather than computed (default [`DEFAULT_STATE_CACHE`]; 0: none). See
    /// docs/engine.md, "The state cache", and [`Engine::cache_stats`].
    pub fn state_cache(mut self, states: usize) -> Self {
        self.state_cache = states;
        self
    }

    pub fn build(self) -> Result<Engine, BuildError> {
        let system = self.system;
        let mut t = Tables::new(&system)?;
        if !self.bindings.is_empty() && system.genom.is_none() {
            return Err(BuildError::NoGenomLayer);
        }
        let mut bodies: Vec<Option<Body>> = t.codels.iter().map(|_| None).collect();
        for ((m, s, c), f) in self.bindings {
            let Some(k) = t.codel_index(&m, &s, &c) else {
                return Err(BuildError::UnknownCodel(m, s, c));
            };
            if bodies[k].is_some() {
                return Err(BuildError::BoundTwice(m, s, c));
            }
            bodies[k] = Some(Body::Bound(f));
        }
        let mut out = Vec::with_capacity(bodies.len());
        for (k, b) in bodies.into_iter().enumerate() {
            match (b, self.defaults) {
                (Some(b), _) => out.push(b),
                (None, Some(_)) => out.push(Body::Default),
                (None, None) => {
                    let i = &t.codels[k].info;
                    return Err(BuildError::Unbound(
                        i.module.clone(),
                        i.service.clone(),
                        i.state.clone(),
                    ));
                }
            }
        }
        let clock = match self.clock {
            Some(c) => c,
            None => default_clock()?,
        };
        let tick_us = self
            .tick_us
            .or(system.tick_ms.map(|ms| ms.saturating_mul(1000)))
            .unwrap_or(1000)
            .max(1);
        let gate = Gate::new(system, self.state_cache).map_err(BuildError::Range)?;
        let pool = gate.enabled().pool();
        let plan_moves = gate
            .plans()
            .steps()
            .map(|(i, at, width)| {
                t.step_moves_request(i, &pool[at as usize..(at + width) as usize])
            })
            .collect();
        let ports = PortStore::new(core::mem::take(&mut t.ports));
        let max_fields = t.codels.iter().map(|c| c.info.fields.len()).max();
        let activities = t.activities.len();
        #[cfg(feature = "std")]
        let workers = if self.threads {
            Some(crate::threads::Workers::spawn(&t, &mut out))
        } else {
            None
        };
        #[cfg(not(feature = "std"))]
        if self.threads {
            return Err(BuildError::NoThreads);
        }
        let now = clock.now_us();
        Ok(Engine {
            gate,
            bodies: out,
            t,
            ports,
            ids_buf: Vec::with_capacity(max_fields.unwrap_or(0)),
            written: 0,
            ctx_fault: None,
            inbox: VecDeque::with_capacity(16),
            events: VecDeque::with_capacity(self.event_capacity.min(4096)),
            event_capacity: self.event_capacity,
            on_event: self.on_event,
            clock,
            tick_us,
            next_tick_us: now + tick_us,
            chooser: Chooser::new(self.policy),
            defaults: self.defaults.unwrap_or(DefaultCodels::FirstYield),
            default_rng: Rng::new(match self.defaults {
                Some(DefaultCodels::Random(s)) => s,
                _ => 0,
            }),
            candidates: Vec::with_capacity(16),
            chosen: Chosen::with_capacity(16),
            plan_moves,
            known_candidates: PerState::new(),
            known_held: PerState::new(),
            held_now: Vec::with_capacity(activities),
            forced: Vec::with_capacity(16),
            recording: self.record.map(Recording::with_capacity),
            stats: Stats::default(),
            next_ticket: 0,
            quiescent_dirty: true,
            stopped: None,
            codel_stamp: Vec::new(),
            #[cfg(feature = "std")]
            workers,
            #[cfg(feature = "std")]
            remote: None,
        })
    }
}

#[cfg(target_has_atomic = "64")]
fn default_clock() -> Result<Box<dyn Clock>, BuildError> {
    Ok(Box::new(crate::clock::VirtualClock::new()))
}

#[cfg(not(target_has_atomic = "64"))]
fn default_clock() -> Result<Box<dyn Clock>, BuildError> {
    Err(BuildError::NoClock)
}

#[derive(Clone, Copy, Debug)]
enum Candidate {
    Codel(u32),
    /// The `k`-th enabled step with this label.
    Step(Label, u32),
}

/// Why a step is committed, for replies.
enum Cause {
    Request {
        service: u32,
        ticket: Option<Ticket>,
        args: Option<Box<dyn Any + Send>>,
    },
    Codel {
        /// The outcome of a failed codel (exception or fault).
        error: Option<Outcome>,
    },
    Other,
}

/// How a codel run ended, before the step is chosen.
enum Verdict2 {
    Normal { yield_k: usize },
    Error(Outcome),
}

/// The runtime engine (see the module documentation and docs/engine.md).
pub struct Engine {
    /// The model's state and its enabled steps: every step is committed through it.
    gate: Gate,
    t: Tables,
    bodies: Vec<Body>,
    pub(crate) ports: PortStore,
    ids_buf: Vec<i64>,
    written: u64,
    ctx_fault: Option<CtxFault>,
    inbox: VecDeque<(Ticket, u32, Option<Args>)>,
    events: VecDeque<Event>,
    event_capacity: usize,
    on_event: Option<EventFn>,
    clock: Box<dyn Clock>,
    tick_us: u64,
    next_tick_us: u64,
    chooser: Chooser,
    defaults: DefaultCodels,
    default_rng: Rng,
    candidates: Vec<Candidate>,
    /// The step being committed.
    chosen: Chosen,
    /// Per fire plan of the gate, whether its step moves a request
    /// (`Tables::step_moves_request`).
    plan_moves: Vec<bool>,
    /// The progress candidates of the states in the cache.
    known_candidates: PerState<Candidate>,
    /// The codel each activity has held, per state in the cache, and in this one.
    known_held: PerState<Option<(u32, Reasons)>>,
    held_now: Vec<Option<(u32, Reasons)>>,
    /// Scratch: the step [`Engine::step_as`] was asked to take.
    forced: Vec<Pick>,
    recording: Option<Recording>,
    stats: Stats,
    next_ticket: u64,
    /// Something moved since the held codels were last looked at.
    quiescent_dirty: bool,
    stopped: Option<RangeError>,
    /// Scratch for deduplicating codel candidates: per codel, the step count at which it
    /// was last collected (64 bits: the count does not come back to a stamp).
    codel_stamp: Vec<u64>,
    #[cfg(feature = "std")]
    workers: Option<crate::threads::Workers>,
    #[cfg(feature = "std")]
    pub(crate) remote: Option<crate::handle::Remote>,
}

impl Engine {
    /// Starts building an engine for `system`.
    pub fn builder(system: System) -> EngineBuilder {
        EngineBuilder {
            system,
            bindings: Vec::new(),
            defaults: None,
            clock: None,
            policy: Policy::default(),
            tick_us: None,
            record: None,
            event_capacity: 1024,
            on_event: None,
            threads: false,
            state_cache: DEFAULT_STATE_CACHE,
        }
    }

    pub fn system(&self) -> &System {
        self.gate.system()
    }

    /// The current state of the model.
    pub fn state(&self) -> &State {
        self.gate.state()
    }

    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// What the state cache holds and how often it knew the step
    /// ([`EngineBuilder::state_cache`]).
    pub fn cache_stats(&self) -> CacheStats {
        self.gate.cache_stats()
    }

    /// The bytes the state cache and what the engine keeps per cached state hold.
    pub fn cache_bytes(&self) -> usize {
        self.gate.cache_bytes() + self.known_candidates.bytes() + self.known_held.bytes()
    }

    /// The clock's time (microseconds since the engine started).
    pub fn now_us(&self) -> u64 {
        self.clock.now_us()
    }

    /// The length of a tick.
    pub fn tick_us(&self) -> u64 {
        self.tick_us
    }

    /// The enabled steps of the current state.
    pub fn enabled(&self) -> &EnabledSet {
        &self.gate.enabled()
    }

    /// The value of an ids field (`None` if there is no such module or field).
    pub fn ids(&self, module: &str, field: &str) -> Option<i64> {
        let m = self.gate.system().genom.as_ref()?.module(module)?;
        let f = m.ids.iter().find(|f| f.name == field)?;
        Some(self.gate.state().slots()[f.slot as usize])
    }

    /// The data last written on a port, if any and of type `T`.
    pub fn port<T: Any>(&self, module: &str, port: &str) -> Option<&T> {
        self.ports.get(module, port)
    }

    /// `(module, service, state)` of a codel.
    pub fn codel_name(&self, c: CodelId) -> (&str, &str, &str) {
        let i = &self.t.codels[c.0 as usize].info;
        (&i.module, &i.service, &i.state)
    }

    /// `(module, service)` of a service.
    pub fn service_name(&self, s: ServiceId) -> (&str, &str) {
        let s = &self.t.services[s.0 as usize];
        (&s.module, &s.name)
    }

    pub fn codel_id(&self, module: &str, service: &str, state: &str) -> Option<CodelId> {
        self.t
            .codel_index(module, service, state)
            .map(|k| CodelId(k as u32))
    }

    pub fn service_count(&self) -> usize {
        self.t.services.len()
    }

    pub fn codel_count(&self) -> usize {
        self.t.codels.len()
    }

    #[cfg(feature = "std")]
    pub(crate) fn sleep_clock_until(&self, t: u64) {
        self.clock.sleep_until(t);
    }

    pub fn service_id(&self, module: &str, service: &str) -> Option<ServiceId> {
        self.t
            .service_index(module, service)
            .map(|k| ServiceId(k as u32))
    }

    /// The conditions of a service's refusals that `r` names, as the model writes them.
    pub fn refusal_texts(&self, s: ServiceId, r: Reasons) -> impl Iterator<Item = String> + '_ {
        let list = &self.t.services[s.0 as usize].refusals;
        r.iter()
            .filter_map(move |k| list.get(k))
            .map(|c| format!("{} ({})", c.reason, c.text))
    }

    /// The conditions of a codel's holds that `r` names.
    pub fn hold_texts(&self, c: CodelId, r: Reasons) -> impl Iterator<Item = String> + '_ {
        let list = &self.t.codels[c.0 as usize].map.holds;
        r.iter()
            .filter_map(move |k| list.get(k))
            .map(|c| format!("{} ({})", c.reason, c.text))
    }

    /// Drains the events reported since the last call.
    pub fn events(&mut self) -> impl Iterator<Item = Event> + '_ {
        self.events.drain(..)
    }

    /// The steps committed so far, as a trace in the shared format (empty unless the
    /// builder asked to record).
    pub fn record(&self) -> Trace {
        match &self.recording {
            Some(r) => r.to_trace(self.gate.system(), Verdict::None),
            None => Trace {
                system: self.gate.system().name.clone(),
                verdict: Verdict::None,
                steps: Vec::new(),
            },
        }
    }

    /// Number of steps recorded.
    pub fn recorded_steps(&self) -> usize {
        self.recording.as_ref().map_or(0, Recording::len)
    }

    // ---------------------------------------------------------------------------------
    // Requests

    /// Queues a request for `module.service` with arguments its codels can read
    /// ([`Ctx::args`]). The engine serves it at its next quiescent point: the reply
    /// ([`Event::Reply`]) says whether the model accepted it, and later how the activity
    /// ended.
    pub fn request<A: Any + Send>(
        &mut self,
        module: &str,
        service: &str,
        args: A,
    ) -> Result<Ticket, RequestError> {
        let s = self.request_target(module, service)?;
        let ticket = self.new_ticket();
        self.inbox.push_back((ticket, s, Some(Box::new(args))));
        Ok(ticket)
    }

    pub(crate) fn request_target(&self, module: &str, service: &str) -> Result<u32, RequestError> {
        let Some(s) = self.t.service_index(module, service) else {
            return Err(RequestError::UnknownService(module.into(), service.into()));
        };
        if self.t.services[s].owned {
            return Err(RequestError::OwnedByModel(module.into(), service.into()));
        }
        Ok(s as u32)
    }

    pub(crate) fn new_ticket(&mut self) -> Ticket {
        self.next_ticket += 1;
        Ticket(self.next_ticket)
    }

    #[cfg(feature = "std")]
    pub(crate) fn enqueue(&mut self, ticket: Ticket, service: u32, args: Box<dyn Any + Send>) {
        self.inbox.push_back((ticket, service, Some(args)));
    }

    /// Requests waiting to be served.
    pub fn waiting_requests(&self) -> usize {
        self.inbox.len()
    }

    // ---------------------------------------------------------------------------------
    // Running

    /// Takes one step (see the module documentation).
    pub fn step(&mut self) -> Result<Stepped, EngineError> {
        if let Some(e) = &self.stopped {
            return Err(EngineError::Stopped(e.clone()));
        }
        #[cfg(feature = "std")]
        self.drain_remote();
        // 1. a due tick
        if self.clock.now_us() >= self.next_tick_us {
            if let Some(i) = self.enabled_time() {
                self.fire_time(i)?;
                return Ok(Stepped::Tick);
            }
        }
        // 2. progress
        self.collect_candidates();
        if !self.candidates.is_empty() {
            let k = self.chooser.choose(self.candidates.len());
            return match self.candidates[k] {
                Candidate::Codel(c) => self.run_codel(c, false).map_err(|e| match e {
                    StepAsError::Engine(e) => e,
                    // without a forced step a codel run never diverges or is refused
                    _ => EngineError::Stopped(self.internal_error()),
                }),
                Candidate::Step(label, k) => {
                    self.choose_kth(label, k);
                    self.commit(Cause::Other)?;
                    Ok(Stepped::Other)
                }
            };
        }
        // 3. quiescent: report what is held, serve a request
        if self.quiescent_dirty {
            self.report_held()?;
            self.quiescent_dirty = false;
        }
        if let Some((ticket, service, args)) = self.inbox.pop_front() {
            return self.serve_request(ticket, service, args);
        }
        // 4. idle
        Ok(Stepped::Idle {
            next_tick_us: self.enabled_time().map(|_| self.next_tick_us),
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
                Until::TimeUs(t) if self.clock.now_us() >= t => return Ok(()),
                _ => {}
            }
            if let Stepped::Idle { next_tick_us } = self.step()? {
                if until == Until::Quiescent {
                    return Ok(());
                }
                let target = match (next_tick_us, until) {
                    (Some(n), Until::TimeUs(t)) => n.min(t),
                    (Some(n), _) => n,
                    (None, Until::TimeUs(t)) => t,
                    (None, _) if self.has_remote() => self.clock.now_us() + self.tick_us,
                    (None, _) => return Ok(()),
                };
                self.wait_until(target);
            }
        }
    }

    fn has_remote(&self) -> bool {
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
    pub fn wait_until(&mut self, t: u64) {
        #[cfg(feature = "std")]
        if self.remote.is_some() {
            self.wait_remote(t);
            return;
        }
        self.clock.sleep_until(t);
    }

    /// Takes exactly `step`, if the model allows it now: a codel step runs the codel,
    /// whose outcome must lead to this very step (a default codel does what the step
    /// says); a request step is a request from the engine; a time step is a tick. For
    /// replaying a trace through the engine.
    pub fn step_as(&mut self, step: Step<'_>) -> Result<Stepped, StepAsError> {
        if let Some(e) = &self.stopped {
            return Err(EngineError::Stopped(e.clone()).into());
        }
        let allowed = match step.label {
            Label::Interaction(i) => self
                .gate
                .enabled()
                .steps_of(i)
                .any(|s| s.picks == step.picks),
            Label::Internal { .. } => self.gate.enabled().internal_steps().any(|s| s == step),
        };
        if !allowed {
            return Err(StepAsError::NotAllowed);
        }
        self.forced.clear();
        self.forced.extend_from_slice(step.picks);
        let kind = match step.label {
            Label::Interaction(i) => self.t.kind[i as usize],
            Label::Internal { .. } => InterKind::Progress,
        };
        self.chosen.set_copied(step);
        match kind {
            InterKind::Codel { codel, .. } => self.run_codel(codel, true),
            InterKind::Request { service } => {
                let ticket = self.new_ticket();
                self.accept_request(ticket, service, None)?;
                Ok(Stepped::Request {
                    ticket,
                    accepted: true,
                })
            }
            InterKind::Time => {
                self.commit(Cause::Other)?;
                self.count_tick();
                Ok(Stepped::Tick)
            }
            InterKind::Progress | InterKind::Environment => {
                self.commit(Cause::Other)?;
                Ok(Stepped::Other)
            }
        }
    }

    fn internal_error(&self) -> RangeError {
        RangeError {
            context: "the engine (please report)".into(),
            kind: bip_model::RangeErrorKind::Overflow,
        }
    }

    /// The first enabled time interaction.
    fn enabled_time(&self) -> Option<u32> {
        // a model has one or two: asking each is cheaper than walking the enabled ones
        self.t
            .time
            .iter()
            .copied()
            .find(|&i| self.gate.enabled().is_enabled(i))
    }

    fn fire_time(&mut self, i: u32) -> Result<(), EngineError> {
        self.take_step_of(i);
        self.commit(Cause::Other)?;
        self.count_tick();
        Ok(())
    }

    fn count_tick(&mut self) {
        self.stats.ticks += 1;
        self.next_tick_us = self.next_tick_us.saturating_add(self.tick_us);
    }

    fn collect_candidates(&mut self) {
        self.candidates.clear();
        // a state met before: its candidates are known
        let here = self.gate.cached_state();
        if let Some(known) = here.and_then(|s| self.known_candidates.get(s)) {
            self.candidates.extend_from_slice(known);
            return;
        }
        if self.codel_stamp.len() != self.t.codels.len() {
            self.codel_stamp = vec![u64::MAX; self.t.codels.len()];
        }
        collect_progress(
            &self.gate.enabled(),
            &self.t,
            &mut self.codel_stamp,
            self.stats.steps,
            &mut self.candidates,
        );
        if let Some(s) = here {
            // (a state with internal transitions is not in the cache)
            self.known_candidates.set(s, &self.candidates);
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
            self.candidates.push(Candidate::Step(s.label, k));
            k += 1;
        }
    }

    /// Chooses the `k`-th enabled step with `label`.
    fn choose_kth(&mut self, label: Label, k: u32) {
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
    fn take_step_of(&mut self, i: u32) {
        // one step from the pool (a tick): nothing to walk, and nothing to choose (a
        // chooser asked to choose among one answers 0 and draws nothing, so seeded runs
        // do not change)
        if let Some((at, width, 1)) = self.gate.enabled().pooled_steps(i) {
            self.chosen.set_pooled(i, at, width);
            return;
        }
        let step = choose_step(&mut self.chooser, || self.gate.enabled().steps_of(i));
        self.chosen.set(self.gate.enabled(), step);
    }

    // ---------------------------------------------------------------------------------
    // Requests

    fn serve_request(
        &mut self,
        ticket: Ticket,
        service: u32,
        args: Option<Box<dyn Any + Send>>,
    ) -> Result<Stepped, EngineError> {
        let i = self.t.services[service as usize].request;
        if self.gate.enabled().is_enabled(i) {
            self.take_step_of(i);
            self.accept_request(ticket, service, args)?;
            return Ok(Stepped::Request {
                ticket,
                accepted: true,
            });
        }
        let mut mask = 0u64;
        for (k, c) in self.t.services[service as usize]
            .refusals
            .iter()
            .enumerate()
        {
            if !c
                .holds(self.gate.system(), self.gate.state())
                .map_err(EngineError::Range)?
            {
                mask |= 1 << k;
            }
        }
        let refusal = if mask == 0 {
            Refusal::NotEnabled
        } else {
            Refusal::Conditions(Reasons(mask))
        };
        self.stats.requests_refused += 1;
        let s = &self.t.services[service as usize];
        tracing::info!(target: "bip_engine", ticket = ticket.0, module = s.module.as_str(),
            service = s.name.as_str(), "request refused");
        self.emit(Event::Reply {
            ticket,
            service: ServiceId(service),
            reply: Reply::Refused(refusal),
        });
        Ok(Stepped::Request {
            ticket,
            accepted: false,
        })
    }

    /// Commits the chosen request step and replies.
    fn accept_request(
        &mut self,
        ticket: Ticket,
        service: u32,
        args: Option<Box<dyn Any + Send>>,
    ) -> Result<(), EngineError> {
        self.stats.requests_accepted += 1;
        self.emit(Event::Reply {
            ticket,
            service: ServiceId(service),
            reply: Reply::Accepted,
        });
        self.commit(Cause::Request {
            service,
            ticket: Some(ticket),
            args,
        })?;
        if self.t.services[service as usize].activity.is_none() {
            // a function or attribute runs at once
            self.emit(Event::Reply {
                ticket,
                service: ServiceId(service),
                reply: Reply::Done(Outcome::Ether),
            });
        }
        Ok(())
    }

    /// At a quiescent point: activities with work that cannot run (a start held by
    /// `Exclusive`, a codel held by `Requires`...), reported once per change.
    fn report_held(&mut self) -> Result<(), EngineError> {
        let n = self.t.activities.len();
        let Some(here) = self.gate.cached_state() else {
            for k in 0..n {
                let w = &self.t.activities[k];
                // most activities wait for their period at a quiescent point: nothing is
                // held, and nothing was reported held before
                if w.held.is_none() && w.rest.at_rest(self.gate.state().slots()) {
                    continue;
                }
                let held = self.held_codel(w.service as usize)?;
                if held != self.t.activities[k].held {
                    self.note_held(k, held);
                }
            }
            return Ok(());
        };
        // what is held is a function of the state: worked out once per cached state
        self.held_now.clear();
        match self.known_held.get(here) {
            Some(known) => self.held_now.extend_from_slice(known),
            None => {
                for k in 0..n {
                    let held = self.held_codel(self.t.activities[k].service as usize)?;
                    self.held_now.push(held);
                }
                self.known_held.set(here, &self.held_now);
            }
        }
        for k in 0..n {
            let held = self.held_now[k];
            if held != self.t.activities[k].held {
                self.note_held(k, held);
            }
        }
        Ok(())
    }

    /// Activity `k` holds `held` now, which is news: reported.
    #[inline(never)]
    fn note_held(&mut self, k: usize, held: Option<(u32, Reasons)>) {
        self.t.activities[k].held = held;
        let Some((c, reasons)) = held else { return };
        let s = self.t.activities[k].service as usize;
        let Some(a) = &self.t.services[s].activity else {
            return;
        };
        let loc = self.gate.state().slots()[a.loc_slot as usize] as u32;
        let ticket = if loc == a.ether { a.pending } else { a.current };
        let i = &self.t.codels[c as usize].info;
        tracing::info!(target: "bip_engine", module = i.module.as_str(),
            service = i.service.as_str(), codel = i.state.as_str(), reasons = reasons.0,
            "codel held");
        self.emit(Event::Held {
            codel: CodelId(c),
            ticket,
            reasons,
        });
    }

    /// The codels held now: activities with work to do (requested, or running and not
    /// waiting for their period) whose codel has no step, with the conditions that fail.
    pub fn held(&self) -> Result<Vec<(CodelId, Reasons)>, EngineError> {
        let mut out = Vec::new();
        for s in 0..self.t.services.len() {
            if let Some((c, r)) = self.held_codel(s)? {
                out.push((CodelId(c), r));
            }
        }
        Ok(out)
    }

    /// Every activity with work outstanding (requested, or running): the codel it runs
    /// next, whether it waits for its task's period, and the conditions of that codel
    /// that fail now (what holds it once its period comes).
    pub fn outstanding(&self) -> Result<Vec<(CodelId, bool, Reasons)>, EngineError> {
        let mut out = Vec::new();
        for svc in &self.t.services {
            let Some(a) = &svc.activity else { continue };
            let slots = self.gate.state().slots();
            let loc = slots[a.loc_slot as usize] as u32;
            if loc == a.ether && slots[a.req_slot as usize] == 0 {
                continue;
            }
            let Some(c) = a.codel_at.get(loc as usize).copied().flatten() else {
                continue;
            };
            let mut mask = 0u64;
            for (k, h) in self.t.codels[c as usize].map.holds.iter().enumerate() {
                if !h
                    .holds(self.gate.system(), self.gate.state())
                    .map_err(EngineError::Range)?
                {
                    mask |= 1 << k;
                }
            }
            let paused = slots[a.paused_slot as usize] != 0;
            out.push((CodelId(c), paused, Reasons(mask)));
        }
        Ok(out)
    }

    fn held_codel(&self, s: usize) -> Result<Option<(u32, Reasons)>, EngineError> {
        let Some(a) = &self.t.services[s].activity else {
            return Ok(None);
        };
        let slots = self.gate.state().slots();
        if a.rest().at_rest(slots) {
            return Ok(None);
        }
        let loc = slots[a.loc_slot as usize] as u32;
        let Some(c) = a.codel_at.get(loc as usize).copied().flatten() else {
            return Ok(None);
        };
        let cm = &self.t.codels[c as usize].map;
        // codels are higher than the tick in every GenoM layer, so the set evaluates them
        // always (`None`, never evaluated, cannot happen here)
        if self.gate.enabled().has_steps_before_priorities(cm.run) != Some(false)
            || self.gate.enabled().has_steps_before_priorities(cm.fail) != Some(false)
        {
            return Ok(None); // it can run; it may only wait for its turn
        }
        let mut mask = 0u64;
        for (k, h) in cm.holds.iter().enumerate() {
            if !h
                .holds(self.gate.system(), self.gate.state())
                .map_err(EngineError::Range)?
            {
                mask |= 1 << k;
            }
        }
        Ok(Some((c, Reasons(mask))))
    }

    // ---------------------------------------------------------------------------------
    // Codels

    /// Runs codel `c` and commits the step its outcome names. With `forced`, the step
    /// must be the one in `self.forced`.
    fn run_codel(&mut self, c: u32, forced: bool) -> Result<Stepped, StepAsError> {
        let ck = c as usize;
        let service = self.t.codels[ck].service as usize;
        // stage the module's ids
        self.ids_buf.clear();
        for f in &self.t.codels[ck].info.fields {
            self.ids_buf
                .push(self.gate.state().slots()[f.slot as usize]);
        }
        self.written = 0;
        self.ctx_fault = None;
        let starting = self.t.services[service]
            .activity
            .as_ref()
            .is_some_and(|a| self.gate.state().slots()[a.loc_slot as usize] == i64::from(a.ether));
        let t0 = self.clock.now_us();
        let verdict = match &self.bodies[ck] {
            Body::Default => self.default_verdict(ck, forced),
            _ => {
                let result = self.call_codel(ck, service, starting, t0);
                self.classify(ck, result)
            }
        };
        let took = self.clock.now_us().saturating_sub(t0);
        let period_us = self.t.codels[ck].period_ticks.saturating_mul(self.tick_us);
        // the outcome of a run that failed; a normal one chose its run step
        let fail = self.t.codels[ck].map.fail;
        let error = match verdict {
            Verdict2::Normal { yield_k } => {
                if self.take_run_step(ck, yield_k, forced) {
                    None
                } else if forced {
                    return Err(StepAsError::Diverged);
                } else {
                    let fault = Fault {
                        codel: CodelId(c),
                        kind: FaultKind::NotAllowed,
                    };
                    Some(Outcome::Fault(fault))
                }
            }
            Verdict2::Error(o) => Some(o),
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
        if took > period_us {
            self.stats.overruns += 1;
            let i = &self.t.codels[ck].info;
            tracing::warn!(target: "bip_engine", module = i.module.as_str(),
                service = i.service.as_str(), codel = i.state.as_str(), took_us = took,
                period_us, "codel overran its task's period");
            self.emit(Event::Overrun {
                codel: CodelId(c),
                took_us: took,
                period_us,
            });
        }
        let failed = error.is_some();
        match &error {
            // a replayed error path is what the trace says, not a fault seen now
            Some(Outcome::Fault(f)) if f.kind == FaultKind::Replayed => {}
            Some(Outcome::Fault(f)) => {
                self.stats.faults += 1;
                let i = &self.t.codels[ck].info;
                tracing::warn!(target: "bip_engine", module = i.module.as_str(),
                    service = i.service.as_str(), codel = i.state.as_str(),
                    fault = %f.kind, "codel fault: its error path is taken");
                self.emit(Event::Fault(f.clone()));
            }
            Some(_) => self.stats.exceptions += 1,
            // the codel's ids writes are part of the step: the module pick set them
            None => {}
        }
        self.commit(Cause::Codel { error })?;
        Ok(Stepped::Codel {
            codel: CodelId(c),
            failed,
        })
    }

    /// Calls a bound codel (here or on its task's thread).
    fn call_codel(
        &mut self,
        ck: usize,
        service: usize,
        starting: bool,
        now_us: u64,
    ) -> Result<Next, String> {
        let tick = self.stats.ticks;
        let activity = self.t.services[service].activity.as_mut();
        #[cfg(feature = "std")]
        if let Body::Thread { worker, local } = self.bodies[ck] {
            let mut args_slot = activity.map(|a| {
                if starting {
                    &mut a.pending_args
                } else {
                    &mut a.current_args
                }
            });
            let Some(workers) = self.workers.as_mut() else {
                return Err("no task threads".into());
            };
            let taken = args_slot.as_mut().and_then(|s| s.take());
            let job = crate::threads::Job {
                local,
                ids: core::mem::take(&mut self.ids_buf),
                written: 0,
                fault: None,
                ports: core::mem::take(&mut self.ports),
                args: taken,
                now_us,
                tick,
                result: None,
            };
            let job = workers.run(worker, job);
            let Some(mut job) = job else {
                return Err("the task's thread is gone".into());
            };
            self.ids_buf = core::mem::take(&mut job.ids);
            self.ports = core::mem::take(&mut job.ports);
            self.written = job.written;
            self.ctx_fault = job.fault.take();
            if let Some(s) = args_slot {
                *s = job.args.take();
            }
            return job.result.unwrap_or_else(|| Err("no result".into()));
        }
        let args: Option<&(dyn Any + Send)> = activity.and_then(|a| {
            if starting {
                a.pending_args.as_deref()
            } else {
                a.current_args.as_deref()
            }
        });
        let Body::Bound(f) = &mut self.bodies[ck] else {
            return Err("not a bound codel".into());
        };
        let mut ctx = Ctx {
            info: &self.t.codels[ck].info,
            ids: &mut self.ids_buf,
            written: &mut self.written,
            fault: &mut self.ctx_fault,
            ports: &mut self.ports,
            args,
            now_us,
            tick,
        };
        call_guarded(f, &mut ctx)
    }

    fn classify(&mut self, ck: usize, result: Result<Next, String>) -> Verdict2 {
        let c = &mut self.t.codels[ck];
        let fault = |kind| {
            Verdict2::Error(Outcome::Fault(Fault {
                codel: CodelId(ck as u32),
                kind,
            }))
        };
        let next = match result {
            Err(msg) => return fault(FaultKind::Panic(msg)),
            Ok(n) => n,
        };
        if let Some(f) = self.ctx_fault.take() {
            return fault(match f {
                CtxFault::IdsWrite(x) => FaultKind::UndeclaredIdsWrite(x),
                CtxFault::PortWrite(p) => FaultKind::PortWrite(p),
            });
        }
        match next {
            Next::Yield(y) => match c.yield_index(y) {
                None => fault(FaultKind::BadTransition(y)),
                Some(k) => {
                    for (j, f) in c.info.fields.iter().enumerate() {
                        let v = self.ids_buf[j];
                        if self.written >> j & 1 == 1 && (v < f.lo || v > f.hi) {
                            return fault(FaultKind::IdsOutOfRange {
                                field: f.name.clone(),
                                value: v,
                            });
                        }
                    }
                    Verdict2::Normal { yield_k: k }
                }
            },
            Next::Throw(e) => match c.throws.iter().find(|x| &***x == e) {
                Some(x) => Verdict2::Error(Outcome::Exception(Arc::clone(x))),
                None => fault(FaultKind::UndeclaredException(e)),
            },
        }
    }

    /// A default codel's outcome: what the forced step says, the first yield, or a
    /// random outcome.
    fn default_verdict(&mut self, ck: usize, forced: bool) -> Verdict2 {
        let c = &self.t.codels[ck];
        if forced {
            if self.forced_is(c.map.fail) {
                return Verdict2::Error(Outcome::Fault(Fault {
                    codel: CodelId(ck as u32),
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
                        self.ids_buf[c.ids_field[j]] = f.lo + i64::from(digit);
                    }
                }
            }
            return Verdict2::Normal { yield_k };
        }
        match self.defaults {
            DefaultCodels::FirstYield => Verdict2::Normal { yield_k: 0 },
            DefaultCodels::Random(_) => {
                let outcomes = c.map.yields.len() + c.throws.len();
                let k = self.default_rng.below(outcomes);
                for (j, f) in c.map.ids.iter().enumerate() {
                    let span = (f.hi - f.lo + 1) as usize;
                    self.ids_buf[c.ids_field[j]] = f.lo + self.default_rng.below(span) as i64;
                }
                if k < c.map.yields.len() {
                    Verdict2::Normal { yield_k: k }
                } else {
                    Verdict2::Error(Outcome::Exception(Arc::clone(
                        &c.throws[k - c.map.yields.len()],
                    )))
                }
            }
        }
    }

    fn forced_is(&self, interaction: u32) -> bool {
        // the forced step is a step of `interaction` if it is enabled among its steps
        self.gate
            .enabled()
            .steps_of(interaction)
            .any(|s| s.picks == &self.forced[..])
    }

    /// Chooses a step of the codel's run interaction that takes
    /// yield `yield_k` and writes the staged ids, chosen by the policy if several (with
    /// `forced`, the forced step if it is one); false if there is none.
    fn take_run_step(&mut self, ck: usize, yield_k: usize, forced: bool) -> bool {
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
        let Some(activity) = self.t.services[c.service as usize].activity.as_ref() else {
            return false;
        };
        let comp = activity.component;
        let want_ids = if c.map.ids.is_empty() {
            None
        } else {
            let ids = &self.ids_buf;
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
                Some((k, first)) => match self.chooser.choose(n) {
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

    // ---------------------------------------------------------------------------------
    // Committing

    /// Commits the chosen step through the gate, then replies and records.
    fn commit(&mut self, cause: Cause) -> Result<(), EngineError> {
        let label = self.chosen.label();
        let (committed, unevaluated) = match self.gate.commit(self.chosen.step()) {
            Ok(c) => (c, None),
            Err(CommitError::Fire(e)) => {
                self.stopped = Some(e.clone());
                return Err(EngineError::Range(e));
            }
            // the step was taken: it is replied to and recorded, then the engine stops
            Err(CommitError::Evaluate { error, committed }) => (committed, Some(error)),
        };
        let moves = match (label, committed.plan) {
            (Label::Interaction(_), Some(p)) => self.plan_moves[p.index()],
            (Label::Interaction(i), None) => self
                .t
                .step_moves_request(i, self.chosen.picks(self.gate.enabled())),
            (Label::Internal { .. }, _) => false,
        };
        #[cfg(debug_assertions)]
        if let (Label::Interaction(i), Some(_)) = (label, committed.plan) {
            let picks = self.chosen.picks(self.gate.enabled());
            debug_assert_eq!(moves, self.t.step_moves_request(i, picks));
        }
        if moves {
            self.track(cause);
        }
        if let Some(r) = &mut self.recording {
            r.push(Step {
                label,
                picks: self.chosen.picks(self.gate.enabled()),
            });
        }
        if tracing::enabled!(target: "bip_engine", tracing::Level::DEBUG) {
            self.trace_step(label);
        }
        self.stats.steps += 1;
        self.quiescent_dirty = true;
        if let Some(e) = unevaluated {
            self.stopped = Some(e.clone());
            return Err(EngineError::Range(e));
        }
        Ok(())
    }

    fn trace_step(&self, label: Label) {
        let name = match label {
            Label::Interaction(i) => self.gate.system().interactions[i as usize].name.as_str(),
            Label::Internal { .. } => "internal",
        };
        let time_us = self.clock.now_us();
        if let Label::Interaction(i) = label {
            if let InterKind::Codel { codel, fail } = self.t.kind[i as usize] {
                let c = &self.t.codels[codel as usize];
                let yielded = if fail {
                    "fail"
                } else {
                    self.chosen
                        .picks(&self.gate.enabled())
                        .iter()
                        .find_map(|p| {
                            c.map.yield_of(p.transition).filter(|_| {
                                self.t.services[c.service as usize]
                                    .activity
                                    .as_ref()
                                    .is_some_and(|a| a.component == p.component)
                            })
                        })
                        .map_or("?", |y| y.target.as_str())
                };
                tracing::debug!(target: "bip_engine", time_us, step = name,
                    module = c.info.module.as_str(), service = c.info.service.as_str(),
                    codel = c.info.state.as_str(), r#yield = yielded, "codel");
                return;
            }
        }
        tracing::debug!(target: "bip_engine", time_us, step = name, "step");
    }

    /// Follows the activities' life cycles through the step's picks to reply to the
    /// requests they serve (docs/genom.md, section 2, the activity atom).
    fn track(&mut self, cause: Cause) {
        let (mut req_ticket, mut req_args, req_service, mut error) = match cause {
            Cause::Request {
                service,
                ticket,
                args,
            } => (ticket, args, Some(service), None),
            Cause::Codel { error, .. } => (None, None, None, error),
            Cause::Other => (None, None, None, None),
        };
        for k in 0..self.chosen.picks(self.gate.enabled()).len() {
            let p = self.chosen.picks(self.gate.enabled())[k];
            // a tick, a codel that neither starts nor ends its activity, another component
            if !self.t.moves_request(p) {
                continue;
            }
            let Some(svc) = self.t.activity_of[p.component as usize] else {
                continue;
            };
            let tr = &self.gate.system().atom_of(p.component).transitions[p.transition as usize];
            let Some(port) = tr.port else { continue };
            let Some(a) = self.t.services[svc as usize].activity.as_mut() else {
                continue;
            };
            let kind = match a.port_kind.get(port as usize).copied().flatten() {
                Some(PortKind::Tick) | None => continue,
                Some(kind) => kind,
            };
            let from_ether = tr.from == a.ether;
            let to_ether = tr.to == a.ether;
            // the step is committed: what held before it is in the state before
            let slots = self.gate.previous().slots();
            let req_before = slots[a.req_slot as usize] != 0;
            let stopping_before = a.stopping_slot.is_some_and(|sl| slots[sl as usize] != 0);
            let mut replies: [Option<(Ticket, Outcome)>; 3] = [None, None, None];
            let mut n = 0;
            let mut reply = |t: Option<Ticket>, o: Outcome| {
                if let Some(t) = t {
                    replies[n] = Some((t, o));
                    n += 1;
                }
            };
            match kind {
                PortKind::Request => {
                    let (ticket, args) = if req_service == Some(svc) {
                        (req_ticket.take(), req_args.take())
                    } else {
                        (None, None)
                    };
                    if !from_ether && !stopping_before {
                        reply(a.current.take(), Outcome::Interrupted);
                        a.current_args = None;
                    }
                    if req_before {
                        reply(a.pending.take(), Outcome::Interrupted);
                    }
                    a.pending = ticket;
                    a.pending_args = args;
                }
                PortKind::Interrupt | PortKind::Abort => {
                    if !from_ether && !stopping_before {
                        reply(a.current.take(), Outcome::Interrupted);
                        a.current_args = None;
                    }
                    if req_before {
                        reply(a.pending.take(), Outcome::Interrupted);
                        a.pending_args = None;
                    }
                }
                PortKind::Run(_) => {
                    if from_ether {
                        a.current = a.pending.take();
                        a.current_args = a.pending_args.take();
                    }
                    if to_ether {
                        reply(a.current.take(), Outcome::Ether);
                        a.current_args = None;
                    }
                }
                PortKind::Fail(_) => {
                    if from_ether {
                        a.current = a.pending.take();
                        a.current_args = a.pending_args.take();
                    }
                    let o = error.take().unwrap_or(Outcome::Fault(Fault {
                        codel: CodelId(u32::MAX),
                        kind: FaultKind::Replayed,
                    }));
                    reply(a.current.take(), o);
                    a.current_args = None;
                }
                PortKind::Tick => {}
            }
            // taken in place: moving the array out would copy all three outcomes
            for r in &mut replies[..n] {
                if let Some((ticket, o)) = r.take() {
                    self.emit(Event::Reply {
                        ticket,
                        service: ServiceId(svc),
                        reply: Reply::Done(o),
                    });
                }
            }
        }
    }

    pub(crate) fn emit(&mut self, e: Event) {
        if let Some(f) = &mut self.on_event {
            f(&e);
        }
        #[cfg(feature = "std")]
        if let Some(r) = &mut self.remote {
            r.deliver(&e);
        }
        if self.event_capacity == 0 {
            self.stats.events_dropped += 1;
            return;
        }
        if self.events.len() >= self.event_capacity {
            self.events.pop_front();
            self.stats.events_dropped += 1;
        }
        self.events.push_back(e);
    }
}

/// How many items `items` yields, and the first: the choice whenever there is one, found
/// in the same pass.
#[inline(always)]
fn count_first<T>(items: impl Iterator<Item = T>) -> (usize, Option<T>) {
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
                    out.push(Candidate::Codel(codel));
                }
            }
            InterKind::Progress => {
                let n = enabled.steps_of(i).count() as u32;
                for k in 0..n {
                    out.push(Candidate::Step(Label::Interaction(i), k));
                }
            }
            InterKind::Request { .. } | InterKind::Time | InterKind::Environment => {}
        }
    }
}

#[cfg(feature = "std")]
pub(crate) fn call_guarded(f: &mut CodelFn, ctx: &mut Ctx<'_>) -> Result<Next, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(ctx))).map_err(|e| {
        if let Some(s) = e.downcast_ref::<&str>() {
            (*s).to_string()
        } else if let Some(s) = e.downcast_ref::<String>() {
            s.clone()
        } else {
            "a panic".to_string()
        }
    })
}

/// Without `std` a panic cannot be caught: it is the platform's panic handler's.
#[cfg(not(feature = "std"))]
pub(crate) fn call_guarded(f: &mut CodelFn, ctx: &mut Ctx<'_>) -> Result<Next, String> {
    Ok(f(ctx))
}
