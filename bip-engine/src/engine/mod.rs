//! The engine: gates every step on the model, runs codels, serves requests, keeps time.
//!
//! One step of [`Engine::step`] (docs/engine.md, "Scheduling"):
//! 1. a tick that is due (by the clock) and enabled in the model is fired;
//! 2. otherwise one enabled progress step is taken, chosen by the [`crate::Policy`]: a
//!    codel (run, then the step its outcome names is committed), or a step of a connector
//!    of yours or an internal transition;
//! 3. otherwise (the layer is quiescent) the oldest request is served: fired if its
//!    request interaction is enabled, refused with the failing conditions if not;
//! 4. otherwise the engine is idle until the next tick.
//!
//! Every step committed goes through the engine's [`bip_model::Gate`], which commits only
//! steps it lists as enabled in the current state: the engine's run is a path of the
//! model.
//!
//! The engine is one struct whose methods live by concern in this module's files:
//! `builder.rs` (building), `schedule.rs` (the step loop and the policy's choices),
//! `requests.rs`, `codels.rs` (running a codel and judging its outcome), `commit.rs`,
//! `replies.rs` (following the activities to reply), `held.rs` (held codels),
//! `forced.rs` (taking a given step, for replay), `inspect.rs` (the inspection view),
//! `monitor.rs` (the bounded response properties, watched at run time) and `remote.rs`
//! (requests from other threads). They see each other only through
//! [`Engine`] and the types of this file.

use alloc::collections::VecDeque;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::{Gate, Label, Pick, RangeError, Trace, Verdict};

use crate::bind::Tables;
use crate::budgets::{CodelTime, CodelTimes, SimulatedCpus, TaskClock};
use crate::chosen::Chosen;
use crate::clock::Clock;
use crate::codel::{Args, Body, CtxFault, DefaultCodels};
use crate::event::{Event, EventFn, Reasons, Ticket};
use crate::per_state::PerState;
use crate::policy::{Chooser, Rng};
use crate::ports::PortStore;
use crate::record::{Recording, Window};

#[cfg(feature = "std")]
mod apart;
mod at_request;
mod builder;
mod codels;
mod commit;
mod forced;
mod held;
mod inspect;
mod monitor;
#[cfg(feature = "std")]
mod remote;
mod replies;
mod requests;
mod schedule;
mod timed;

pub use builder::{EngineBuilder, DEFAULT_STATE_CACHE};
pub use inspect::Inspect;
pub use schedule::{Stepped, Until};

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
    /// Codel runs longer than their WCET.
    pub wcet_exceeded: u64,
    /// Task periods whose work ended past the deadline.
    pub deadlines_missed: u64,
    pub requests_accepted: u64,
    pub requests_refused: u64,
    /// Events dropped because nobody drained the queue.
    pub events_dropped: u64,
    /// Bounded response properties whose bound a tick passed ([`Event::ResponseLate`]).
    pub responses_late: u64,
}

/// The runtime engine: it runs your codels and takes only the steps the model allows.
///
/// Build it with [`Engine::builder`] (bind every codel, or ask for default codels), send
/// requests with [`Engine::request`], and drive it with [`Engine::step`] (one step; on a
/// virtual clock an idle step moves time to the next tick) or [`Engine::run_until`] (steps,
/// and waits for the ticks). [`Engine::events`] gives the replies, held codels and faults,
/// each naming its service or codel; [`Engine::inspect`] is the read-only view;
/// [`Engine::record`] the run as a trace. docs/engine.md is the user's guide.
pub struct Engine {
    /// The model's state and its enabled steps: every step is committed through it.
    gate: Gate,
    /// The GenoM map's tables, and the activities' requests and holds as they go.
    t: Tables,
    /// Per fire plan of the gate, whether its step moves a request
    /// (`Tables::step_moves_request`).
    plan_moves: Vec<bool>,
    /// The step being committed.
    chosen: Chosen,
    /// Scratch: the step `Engine::step_as` was asked to take.
    forced: Vec<Pick>,
    runner: Runner,
    time: Time,
    sched: Schedule,
    held: HeldReports,
    requests: Inbox,
    events: EventQueue,
    recording: Option<Recording>,
    stats: Stats,
    /// The codels' run times, and each task's period as it goes.
    budgets: Budgets,
    /// The range error that stopped the engine.
    stopped: Option<RangeError>,
    /// The bounded response properties, watched step by step.
    monitor: monitor::Monitor,
    /// A timed model's time and running codels (`None` for an untimed one).
    timed: Option<Box<timed::Timed>>,
    #[cfg(feature = "std")]
    remote: Option<crate::handle::Remote>,
    /// The async codels' threads and runs.
    #[cfg(feature = "std")]
    apart: apart::Apart,
}

/// How the codels run, and what a run leaves behind for its step.
struct Runner {
    bodies: Vec<Body>,
    /// The module objects that `Body::Module` codels call.
    modules: Vec<crate::codel::ModuleFn>,
    /// The ports' data, which codels read and write.
    ports: PortStore,
    /// The module's ids fields a codel sees, staged: written into the state only by its
    /// step.
    ids: Vec<i64>,
    /// The ids fields the codel wrote (bit per field) and what it did wrong.
    written: u64,
    fault: Option<CtxFault>,
    defaults: DefaultCodels,
    rng: Rng,
    #[cfg(feature = "std")]
    workers: Option<crate::threads::Workers>,
    /// The arguments of the request being served and the output its function's codel
    /// gives, while its codels at the request run (`at_request`).
    request_args: Option<Box<dyn core::any::Any + Send>>,
    request_output: Option<crate::event::Output>,
}

struct Time {
    clock: Box<dyn Clock>,
    tick_us: u64,
    next_tick_us: u64,
}

/// Time budgets as the engine lives them (`budgets.rs`).
struct Budgets {
    /// Per codel.
    times: Vec<CodelTimes>,
    /// Per task of [`Tables::tasks`].
    tasks: Vec<TaskClock>,
    /// How long default codels take; with a simulated time, the CPUs that run it (and
    /// judge the deadlines instead of the task clocks) and the draws of random times.
    codel_time: CodelTime,
    cpus: Option<SimulatedCpus>,
    rng: Rng,
}

/// The choice among the progress steps.
struct Schedule {
    chooser: Chooser,
    candidates: Vec<Candidate>,
    /// The progress candidates of the states in the gate's cache.
    known_candidates: PerState<Candidate>,
    /// Scratch for deduplicating codel candidates: per codel, the step count at which it
    /// was last collected (64 bits: the count does not come back to a stamp).
    codel_stamp: Vec<u64>,
}

/// What is held, as last reported.
struct HeldReports {
    /// The codel each activity has held, per state in the gate's cache, and in this one.
    known: PerState<Option<(u32, Reasons)>>,
    now: Vec<Option<(u32, Reasons)>>,
    /// Something moved since the held codels were last looked at.
    dirty: bool,
}

struct Inbox {
    inbox: VecDeque<(Ticket, u32, Option<Args>)>,
    next_ticket: u64,
}

struct EventQueue {
    queue: VecDeque<Event>,
    capacity: usize,
    on_event: Option<EventFn>,
}

/// A progress step the policy may choose.
#[derive(Clone, Copy, Debug)]
enum Candidate {
    Codel(u32),
    /// An async codel's start, and its outcome.
    Start(u32),
    Outcome(u32),
    /// A timed codel's start.
    TimedStart(u32),
    /// The `k`-th enabled step with this label.
    Step(Label, u32),
}

impl Engine {
    /// Drains the events reported since the last call.
    pub fn events(&mut self) -> impl Iterator<Item = Event> + '_ {
        self.events.queue.drain(..)
    }

    /// The steps committed so far, as a trace in the shared format (empty unless the
    /// builder asked to record).
    pub fn record(&self) -> Trace {
        self.record_window().trace
    }

    /// The steps recorded so far, from the state before the first of them: all of them
    /// (from the initial state), or with [`EngineBuilder::record_window`] the last ones.
    pub fn record_window(&self) -> Window {
        match &self.recording {
            Some(r) => r.to_window(self.gate.system(), Verdict::None),
            None => Recording::default().to_window(self.gate.system(), Verdict::None),
        }
    }

    /// Takes the steps recorded so far away (as [`Engine::record_window`] gives them); the
    /// recording goes on from the current state. Streams a recording of any length.
    pub fn take_record(&mut self) -> Window {
        match &mut self.recording {
            Some(r) => r.take(self.gate.system(), self.gate.state()),
            None => Recording::default().to_window(self.gate.system(), Verdict::None),
        }
    }

    pub(super) fn emit(&mut self, e: Event) {
        if let Some(f) = &mut self.events.on_event {
            f(&e);
        }
        #[cfg(feature = "std")]
        if let Some(r) = &mut self.remote {
            r.deliver(&e);
        }
        if self.events.capacity == 0 {
            self.stats.events_dropped += 1;
            return;
        }
        if self.events.queue.len() >= self.events.capacity {
            self.events.queue.pop_front();
            self.stats.events_dropped += 1;
        }
        self.events.queue.push_back(e);
    }

    pub(super) fn internal_error(&self) -> RangeError {
        RangeError {
            context: "the engine (please report)".into(),
            kind: bip_model::RangeErrorKind::Overflow,
        }
    }
}
