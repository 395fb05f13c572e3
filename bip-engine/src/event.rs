//! What the engine reports: replies to requests, faults, overruns, held codels.

use alloc::sync::Arc;
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

/// A callback for every event.
pub type EventFn = Box<dyn FnMut(&Event) + Send>;

/// Something the engine reports. Drain them with [`crate::Engine::events`], or receive
/// them as they happen with [`crate::EngineBuilder::on_event`].
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// About a request: accepted, refused, or its activity's outcome.
    Reply {
        ticket: Ticket,
        service: ServiceId,
        reply: Reply,
    },
    /// A codel's start or run is held by conditions that fail (the activity waits for
    /// them; it runs as soon as they hold). Reported once per change.
    Held {
        codel: CodelId,
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
        codel: CodelId,
        took_us: u64,
        period_us: u64,
    },
    /// A codel ran longer than its declared WCET (docs/model.md, "Time budgets"); its
    /// result was committed.
    WcetExceeded {
        codel: CodelId,
        took_us: u64,
        wcet_us: u64,
    },
    /// A codel of a task ended `elapsed_us` after the task's release, past its deadline
    /// (the period, unless the model gives one): the task's work of this period is late.
    /// Reported once per period.
    DeadlineMissed {
        codel: CodelId,
        elapsed_us: u64,
        deadline_us: u64,
    },
}

/// A reply to a request.
#[derive(Clone, Debug, PartialEq)]
pub enum Reply {
    /// The model took the request (an activity is now pending; a function has run).
    Accepted,
    /// The model does not allow the request now.
    Refused(Refusal),
    /// The activity ended (a function ends when it is accepted).
    Done(Outcome),
}

/// Why a request was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// These conditions of the service's `refusals` fail (`already requested or active`,
    /// `after ...`, a constraint on a function).
    Conditions(Reasons),
    /// Every listed condition holds, yet the request interaction is not enabled: the guard
    /// or a port of a connector of yours that extends it, or a priority, forbids it now.
    NotEnabled,
}

/// How an activity ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// It yielded `ether`: success.
    Ether,
    /// A codel threw one of its declared exceptions.
    Exception(Arc<str>),
    /// A request interrupted or replaced it, or a connector aborted it.
    Interrupted,
    /// A codel was faulty (the error path was taken).
    Fault(Fault),
}

/// A faulty codel run.
#[derive(Clone, Debug, PartialEq)]
pub struct Fault {
    pub codel: CodelId,
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
    /// It wrote an ids field its `writes` does not list (or the module has no such field).
    UndeclaredIdsWrite(String),
    /// It left an ids field out of its range.
    IdsOutOfRange { field: String, value: i64 },
    /// It wrote a port its `writes` does not list, or gave a port data of another type.
    PortWrite(String),
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
            FaultKind::UndeclaredIdsWrite(x) => {
                write!(f, "wrote ids field `{x}`, which its `writes` does not list")
            }
            FaultKind::IdsOutOfRange { field, value } => {
                write!(f, "left ids field `{field}` at {value}, outside its range")
            }
            FaultKind::PortWrite(p) => {
                write!(f, "wrote port `{p}` it may not write, or with another type")
            }
            FaultKind::Replayed => f.write_str("took its error path (replayed)"),
            FaultKind::NotAllowed => f.write_str("its outcome has no step in the model here"),
        }
    }
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Outcome::Ether => f.write_str("ether"),
            Outcome::Exception(e) => write!(f, "exception {e}"),
            Outcome::Interrupted => f.write_str("interrupted"),
            Outcome::Fault(x) => write!(f, "fault: {}", x.kind),
        }
    }
}
