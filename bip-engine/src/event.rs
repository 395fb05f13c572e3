//! What the engine reports: replies to requests, faults, overruns, held codels. Every
//! event carries the names of the codel or service it is about, so that it reads (its
//! `Display`) in the model's terms without asking the engine.

use alloc::sync::Arc;
use core::any::Any;
use core::fmt;

#[allow(unused_imports)]
use crate::prelude::*;

/// The number the engine gives a request; its replies carry it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Ticket(pub u64);

/// A codel of the model: an index into the engine's codels, in the GenoM map's order
/// (modules, services, codels as declared). [`crate::Inspect::codel_name`] names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CodelId(pub u32);

/// A service of the model, in the GenoM map's order. [`crate::Inspect::service_name`]
/// names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ServiceId(pub u32);

/// A set of conditions, one bit per condition of a list the context says: a service's
/// `refusals` or a codel's `holds` in the GenoM map (bip-model `genom::map`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Reasons(pub u64);

impl Reasons {
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The positions of the conditions in their list.
    pub fn iter(self) -> impl Iterator<Item = usize> {
        let mut bits = self.0;
        core::iter::from_fn(move || {
            if bits == 0 {
                return None;
            }
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            Some(k)
        })
    }
}

/// A codel of the model, as events name it: its id and its names.
#[derive(Debug, PartialEq, Eq, Hash)]
pub struct Codel {
    pub id: CodelId,
    pub module: String,
    pub service: String,
    /// Its codel state (`"start"`, `"track"`, ...).
    pub state: String,
    /// Its `holds` conditions as the model writes them, in order: [`Event::Held`]'s
    /// reasons index them.
    pub holds: Vec<String>,
}

/// A service of the model, as events name it: its id and its names.
#[derive(Debug, PartialEq, Eq, Hash)]
pub struct Service {
    pub id: ServiceId,
    pub module: String,
    pub name: String,
    /// Its `refusals` conditions as the model writes them, in order:
    /// [`Refusal::Conditions`] indexes them.
    pub refusals: Vec<String>,
}

impl fmt::Display for Codel {
    /// `module.Service.codel`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}.{}", self.module, self.service, self.state)
    }
}

impl fmt::Display for Service {
    /// `module.Service`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{}", self.module, self.name)
    }
}

/// Writes the conditions of `list` that `reasons` names, separated by `; `.
fn conditions(f: &mut fmt::Formatter<'_>, list: &[String], reasons: Reasons) -> fmt::Result {
    for (n, k) in reasons.iter().enumerate() {
        if n > 0 {
            f.write_str("; ")?;
        }
        match list.get(k) {
            Some(c) => f.write_str(c)?,
            None => write!(f, "condition {k}")?,
        }
    }
    Ok(())
}

fn ticks(n: u64) -> &'static str {
    if n == 1 {
        "tick"
    } else {
        "ticks"
    }
}

/// A callback for every event.
pub type EventFn = Box<dyn FnMut(&Event) + Send>;

/// Something the engine reports. Drain them with [`crate::Engine::events`], or receive
/// them as they happen with [`crate::EngineBuilder::on_event`]. An event names what it is
/// about ([`Codel`], [`Service`]), and its `Display` is one line in the model's terms:
/// `#2 rflex.TrackSpeed: refused: after rflex.Init`.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// About a request: accepted, refused, its activity started, or its outcome.
    Reply {
        ticket: Ticket,
        service: Arc<Service>,
        reply: Reply,
    },
    /// A codel's start or run is held by conditions that fail (the activity waits for
    /// them; it runs as soon as they hold). Reported once per change.
    Held {
        codel: Arc<Codel>,
        /// The request the activity serves, if the engine accepted it.
        ticket: Option<Ticket>,
        /// Bits into the codel's `holds`; empty if no listed condition fails (an extending
        /// connector's guard or port is what holds it).
        reasons: Reasons,
    },
    /// A codel was faulty; its activity took its error path (the codel's `_fail` step).
    Fault(Fault),
    /// A codel ran longer than its task's period; its result was committed.
    Overrun {
        codel: Arc<Codel>,
        took_us: u64,
        period_us: u64,
    },
    /// A codel ran longer than its declared WCET (docs/model.md, "Time budgets"); its
    /// result was committed.
    WcetExceeded {
        codel: Arc<Codel>,
        took_us: u64,
        wcet_us: u64,
    },
    /// A task's job was still active `elapsed_us` after its release, past its deadline
    /// (the period, unless the model gives one): in a timed model, a step made the task's
    /// deadline invariant false (reported once until it holds again); in an untimed one,
    /// a codel of the task ended past the deadline (once per period).
    DeadlineMissed {
        /// The task, `module.task`.
        task: Arc<str>,
        /// The codel of the task that ran last, if any.
        codel: Option<Arc<Codel>>,
        elapsed_us: u64,
        deadline_us: u64,
    },
    /// A bounded response property of the model (`Response ... within`,
    /// `Replies(within)`) was not answered in time: a tick passed its bound while its
    /// oldest trigger waited. Reported once per trigger; the engine goes on.
    ResponseLate {
        /// The property's name as reports show it (`Replies(ndd.GoTo, within: 20)` unless
        /// it has a `name`).
        property: Arc<str>,
        within: u64,
        /// The time units since the trigger at the tick that passed the bound: `within + 1`
        /// where each tick is one unit, more where a tick stands for several (`advance`).
        elapsed_ticks: u64,
        /// The request that the engine accepted in the step on which the trigger happened:
        /// for a `request(m.S)` trigger (and so `Replies`), the request that started the
        /// wait. `None` if the trigger happened on another step (a codel, a tick, a request
        /// sent by a connector of the model) or in the initial state.
        ticket: Option<Ticket>,
    },
}

/// A reply to a request.
#[derive(Clone, Debug, PartialEq)]
pub enum Reply {
    /// The model took the request (an activity is now pending; a function has run).
    Accepted,
    /// The model does not allow the request now.
    Refused(Refusal),
    /// The activity left `ether`: its `start` codel ran.
    Started,
    /// The activity ended (a function ends when it is accepted).
    Done {
        outcome: Outcome,
        /// What its codels gave with [`crate::Ctx::set_output`], the last they gave.
        output: Option<Output>,
    },
}

impl Reply {
    /// The activity ended with `outcome` and no output.
    pub fn done(outcome: Outcome) -> Reply {
        Reply::Done {
            outcome,
            output: None,
        }
    }
}

/// A service's output: a value of any type, shared by the replies that carry it.
#[derive(Clone)]
pub struct Output(pub(crate) Arc<dyn Any + Send + Sync>);

impl Output {
    pub fn new<T: Any + Send + Sync>(value: T) -> Output {
        Output(Arc::new(value))
    }

    /// The output, if it is a `T`.
    pub fn get<T: Any>(&self) -> Option<&T> {
        self.0.downcast_ref()
    }
}

impl PartialEq for Output {
    /// The same output: the one a codel gave.
    fn eq(&self, other: &Output) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl fmt::Debug for Output {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Output(..)")
    }
}

/// Why a request was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum Refusal {
    /// These conditions of the service's `refusals` fail (`already requested or active`,
    /// `after ...`, a constraint on a function): [`Service::refusals`] says them.
    Conditions(Reasons),
    /// Every listed condition holds, yet the request interaction is not enabled: the guard
    /// or a port of a connector of yours that extends it, or a priority, forbids it now.
    NotEnabled,
    /// The service's `validate` codel refused it: the exception it threw, or a fault (a
    /// return it does not declare, a panic), which refuses it too (docs/genom.md, "Codels
    /// at the request").
    Validation(Outcome),
}

/// How an activity ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// It yielded `ether`: success.
    Ether,
    /// A codel threw one of its declared exceptions.
    Exception(Arc<str>),
    /// A request interrupted it: a request of a service that `interrupts` it, or a new
    /// request of the same service, which replaces it. `by` is that service (`None` when
    /// a connector of the model sent the request on its own).
    Interrupted { by: Option<Arc<Service>> },
    /// A connector of the model aborted it through its `abort` port: a rule of the model
    /// (a safety rule, a supervisor in the model), not a client.
    Aborted,
    /// A codel was faulty (the error path was taken).
    Fault(Fault),
}

/// A faulty codel run.
#[derive(Clone, Debug, PartialEq)]
pub struct Fault {
    pub codel: Arc<Codel>,
    pub kind: FaultKind,
}

#[derive(Clone, Debug, PartialEq)]
pub enum FaultKind {
    /// The codel panicked (with the `std` feature; without it a panic is the platform's).
    Panic(String),
    /// It returned a yield that is not among its `yields` (GenoM's bad transition).
    BadTransition(&'static str),
    /// It threw an exception that is not among its `throws`.
    UndeclaredException(&'static str),
    /// It returned [`crate::Next::Declared`] past its declared outcomes.
    UndeclaredOutcome(u16),
    /// It wrote an ids field its `writes` does not list (or the module has no such field).
    UndeclaredIdsWrite(String),
    /// It left an ids field out of its range.
    IdsOutOfRange { field: String, value: i64 },
    /// It wrote a port its `writes` does not list.
    PortWrite(String),
    /// It read a port (`module.port`) the model does not have.
    NoSuchPort(String),
    /// It wrote or read a port, or gave its service an output, with a value of another
    /// type than the model declares (or than the port holds): `what` it did, the type
    /// `expected` in words, the Rust type `given`.
    WrongType {
        what: String,
        expected: String,
        given: &'static str,
    },
    /// The codel was to run in its module's process, which did not run it within the
    /// run's deadline or refused it (the process is gone, hung or cut off): why.
    Remote(String),
    /// The error path taken because a replayed trace takes it (the trace does not say
    /// whether an exception or a fault led there).
    Replayed,
    /// The model has no step for this outcome here (cannot happen with a model from the
    /// GenoM expansion; reported rather than assumed).
    NotAllowed,
}

impl fmt::Display for FaultKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FaultKind::Panic(m) => write!(f, "panicked: {m}"),
            FaultKind::BadTransition(y) => write!(f, "returned `{y}`, which it does not yield"),
            FaultKind::UndeclaredException(e) => {
                write!(f, "threw `{e}`, which it does not declare")
            }
            FaultKind::UndeclaredOutcome(k) => {
                write!(
                    f,
                    "returned outcome {k}, past the yields and exceptions it declares"
                )
            }
            FaultKind::UndeclaredIdsWrite(x) => {
                write!(f, "wrote ids field `{x}`, which its `writes` does not list")
            }
            FaultKind::IdsOutOfRange { field, value } => {
                write!(f, "left ids field `{field}` at {value}, outside its range")
            }
            FaultKind::PortWrite(p) => {
                write!(f, "wrote port `{p}`, which its `writes` does not list")
            }
            FaultKind::NoSuchPort(p) => write!(f, "read port `{p}`, which the model does not have"),
            FaultKind::WrongType {
                what,
                expected,
                given,
            } => write!(f, "{what} with a `{given}`, where the model has {expected}"),
            FaultKind::Remote(why) => write!(f, "was not run by its module's process: {why}"),
            FaultKind::Replayed => f.write_str("took its error path (replayed)"),
            FaultKind::NotAllowed => f.write_str("its outcome has no step in the model here"),
        }
    }
}

impl fmt::Display for Fault {
    /// `codel rflex.TrackSpeed.track panicked: ...`
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "codel {} {}", self.codel, self.kind)
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Outcome::Ether => f.write_str("ether"),
            Outcome::Exception(e) => write!(f, "exception {e}"),
            Outcome::Interrupted { by: Some(s) } => write!(f, "interrupted by a request of {s}"),
            Outcome::Interrupted { by: None } => f.write_str("interrupted by a request"),
            Outcome::Aborted => f.write_str("aborted by a rule of the model"),
            Outcome::Fault(x) => write!(f, "fault: {x}"),
        }
    }
}

impl fmt::Display for Refusal {
    /// Without the service's names: how many conditions fail. [`Event`]'s `Display`
    /// says them.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::Conditions(r) => {
                write!(f, "refused: {} of its conditions fail", r.iter().count())
            }
            Refusal::NotEnabled => f.write_str(
                "refused: its conditions hold, but a connector or a priority of the model forbids it now",
            ),
            Refusal::Validation(o) => write!(f, "refused by its validate codel: {o}"),
        }
    }
}

impl fmt::Display for Reply {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Reply::Accepted => f.write_str("accepted"),
            Reply::Refused(r) => r.fmt(f),
            Reply::Started => f.write_str("started"),
            Reply::Done {
                outcome,
                output: None,
            } => write!(f, "done: {outcome}"),
            Reply::Done {
                outcome,
                output: Some(_),
            } => write!(f, "done: {outcome}, with an output"),
        }
    }
}

impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Event::Reply {
                ticket,
                service,
                reply: Reply::Refused(Refusal::Conditions(r)),
            } => {
                write!(f, "#{} {service}: refused: ", ticket.0)?;
                conditions(f, &service.refusals, *r)
            }
            Event::Reply {
                ticket,
                service,
                reply,
            } => write!(f, "#{} {service}: {reply}", ticket.0),
            Event::Held { codel, reasons, .. } if reasons.is_empty() => write!(
                f,
                "{codel} held: a connector or a priority of the model forbids it now"
            ),
            Event::Held { codel, reasons, .. } => {
                write!(f, "{codel} held: ")?;
                conditions(f, &codel.holds, *reasons)
            }
            Event::Fault(x) => write!(f, "fault: {x}; its error path is taken"),
            Event::Overrun {
                codel,
                took_us,
                period_us,
            } => write!(
                f,
                "overrun: {codel} took {took_us} µs, its task's period is {period_us} µs"
            ),
            Event::WcetExceeded {
                codel,
                took_us,
                wcet_us,
            } => write!(
                f,
                "over budget: {codel} took {took_us} µs, its WCET is {wcet_us} µs"
            ),
            Event::DeadlineMissed {
                task,
                codel,
                elapsed_us,
                deadline_us,
            } => {
                write!(f, "deadline missed: task {task}")?;
                if let Some(codel) = codel {
                    write!(f, " (its codel {codel} ran last)")?;
                }
                write!(
                    f,
                    ": its job was active {elapsed_us} µs after its release, past {deadline_us} µs"
                )
            }
            Event::ResponseLate {
                property,
                within,
                elapsed_ticks,
                ticket,
            } => {
                write!(
                    f,
                    "response late: {property}: no response {elapsed_ticks} {} after its trigger, past its bound of {within}",
                    ticks(*elapsed_ticks)
                )?;
                match ticket {
                    Some(t) => write!(f, " (request #{})", t.0),
                    None => Ok(()),
                }
            }
        }
    }
}
