//! Errors of building and running an engine.

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::RangeError;

/// The engine cannot be built as asked.
#[derive(Clone, PartialEq, Eq, thiserror::Error)]
pub enum BuildError {
    #[error("codel ({0}, {1}, {2}) is not bound; bind it, or ask for default codels")]
    Unbound(String, String, String),
    #[error("the model has no codel ({0}, {1}, {2})")]
    UnknownCodel(String, String, String),
    #[error("the model has no module `{0}` with codels")]
    UnknownModule(String),
    #[error("the model has no module `{0}`")]
    NoSuchModule(String),
    #[error("module `{module}` was bound for another model: {difference}; regenerate its bindings from this model")]
    OtherModel { module: String, difference: String },
    #[error("codel {1} of module `{0}` was bound apart, but `{0}` is bound to no module object with such a codel")]
    UnknownApart(String, usize),
    #[error("codel ({0}, {1}, {2}) is bound twice")]
    BoundTwice(String, String, String),
    #[error("the model has no GenoM layer, so it has no codel to bind")]
    NoGenomLayer,
    #[error("{0} has more than 64 {1}; the engine reports them in a 64-bit set")]
    TooMany(String, &'static str),
    #[error("threads for tasks need the `std` feature")]
    NoThreads,
    #[error("codel ({0}, {1}, {2}) is async: the engine runs an async codel on a thread of its own, which needs bip-engine's `std` feature; enable it, or make the codel synchronous")]
    Async(String, String, String),
    #[error("codel ({0}, {1}, {2}) runs at a request (a function's codel or a `validate` codel) that a component of the model sends: the engine cannot run it before the model's step; let the environment send the request, or leave the codel out")]
    AtRequest(String, String, String),
}

/// The engine cannot go on: the model computed a value outside a range (which `bip
/// verify` reports as a `RangeErrors` violation), or it stopped after such an error.
#[derive(Clone, PartialEq, Eq, thiserror::Error)]
pub enum EngineError {
    #[error("range error: {0}")]
    Range(RangeError),
    #[error("the engine stopped after a range error: {0}")]
    Stopped(RangeError),
}

/// A request the engine cannot even queue (the model's refusals come as replies).
#[derive(Clone, PartialEq, Eq, thiserror::Error)]
pub enum RequestError {
    #[error("the model has no service {0}.{1}")]
    UnknownService(String, String),
    #[error("requests for {0}.{1} come from a component of the model, not from outside")]
    OwnedByModel(String, String),
    #[error(
        "{0}.{1} is the machine of task {1}: it starts with the component, nothing requests it"
    )]
    TaskMachine(String, String),
    #[error("{service} is a function or attribute: no codel reads arguments, yet a `{given}` was given (send `()`)")]
    NoArguments {
        service: String,
        given: &'static str,
    },
    #[error("{service} takes arguments of type {declared} (a Rust `{rust}`), not a `{given}`")]
    WrongArguments {
        service: String,
        declared: String,
        rust: String,
        given: &'static str,
    },
    #[error("{service} takes arguments of type {declared}; {value} is outside it")]
    ArgumentsOutOfRange {
        service: String,
        declared: String,
        value: i64,
    },
}

/// An error's `Debug` is its message: `?` out of `main` prints the `Debug` of what it
/// returns, and a user reads the error in the model's terms there too.
macro_rules! debug_is_display {
    ($($error:ty),*) => {$(
        impl core::fmt::Debug for $error {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                core::fmt::Display::fmt(self, f)
            }
        }
    )*};
}

debug_is_display!(BuildError, EngineError, RequestError);

/// `Engine::step_as` (replay, simulation) could not take the step.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub(crate) enum StepAsError {
    #[error("the model does not allow this step now")]
    NotAllowed,
    #[error("the codel's outcome leads to another step than the one asked")]
    Diverged,
    /// The step was taken, and the state it leads to has a range error, which stopped the
    /// engine.
    #[error("range error after the step: {0}")]
    TakenThenStopped(RangeError),
    #[error(transparent)]
    Engine(#[from] EngineError),
}
