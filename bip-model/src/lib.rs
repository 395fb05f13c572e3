//! `bip-model`: the bip model format and its one semantics.
//!
//! - [`load_file`] / [`load_str`] read a RON model (MODEL.md) with diagnostics that carry
//!   file, line and column;
//! - [`System`] is the compiled model: dense indices, compiled expressions, priorities
//!   closed transitively;
//! - [`System::enabled_steps`] and [`System::fire`] are the step relation, shared by the
//!   verifier, the simulator and the engine;
//! - [`StateLayout`] packs states into the fewest bits; [`Trace`] is the shared trace format.

mod compile;
mod deadlock;
pub mod diag;
pub mod eval;
pub mod expr;
pub mod genom;
mod load;
pub mod source;
mod state;
mod step;
pub mod syntax;
mod system;
pub mod trace;

pub use compile::{compile, Ty};
pub use deadlock::{Liveness, LivenessChecker};
pub use diag::{LoadError, ModelError};
pub use genom::{expand, GenomMap};
pub use load::{
    compile_def, expand_file, expand_str, load_file, load_str, parse_str, read_model_file,
    ron_options,
};
pub use state::{State, StateLayout};
pub use step::{Label, OwnedStep, Pick, Step, Steps};
pub use system::{
    Assign, Atom, Component, Connector, Family, Interaction, PortRef, PriorityRule, Property,
    PropertyKind, RangeError, RangeErrorKind, Role, Summary, System, Target, Transition, Var,
    VarType,
};
pub use trace::{Trace, TraceStep, TraceValue, Verdict};
