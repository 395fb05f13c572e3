//! `bip-model`: the bip model format and its one semantics.
//!
//! - [`load_file`] / [`load_str`] read a RON model (MODEL.md) with diagnostics that carry
//!   file, line and column;
//! - [`System`] is the compiled model: dense indices, compiled expressions, priorities
//!   closed transitively;
//! - [`System::enabled_steps`] and [`System::fire`] are the step relation, shared by the
//!   verifier, the simulator and the engine; [`EnabledSet`] keeps a state's enabled steps
//!   up to date as the state moves, re-evaluating only what a step can have changed;
//! - [`StateLayout`] packs states into the fewest bits; [`Trace`] is the shared trace format.
//!
//! # Features
//! `std` (default) adds loading: RON parsing, diagnostics, files, the GenoM expansion and
//! trace files. Without it the crate is `no_std` with `alloc` and holds the semantic core
//! (the compiled system, expressions, states, the step relation, deadlock, traces, the
//! GenoM engine map), which is what `bip-engine` needs on a bare-metal node.

#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

/// What the standard prelude gives, for the modules that build without `std`.
mod prelude {
    #[allow(unused_imports)]
    pub(crate) use alloc::{
        borrow::ToOwned,
        boxed::Box,
        format,
        string::{String, ToString},
        vec,
        vec::Vec,
    };
}

#[cfg(feature = "std")]
mod compile;
mod deadlock;
#[cfg(feature = "std")]
pub mod diag;
pub mod eval;
#[cfg(feature = "std")]
pub mod expr;
mod fast_path;
mod fire_plan;
mod gate;
pub mod genom;
mod incremental;
#[cfg(feature = "std")]
mod load;
pub mod ops;
mod ordered_map;
mod plan_effects;
mod priority_masks;
mod radix;
mod rng;
#[cfg(feature = "std")]
pub mod source;
mod state;
mod state_cache;
mod step;
mod step_tables;
#[cfg(feature = "std")]
pub mod syntax;
mod system;
pub mod trace;
mod watches;

#[cfg(feature = "std")]
pub use compile::{compile, Ty};
pub use deadlock::{Liveness, LivenessChecker};
#[cfg(feature = "std")]
pub use diag::{LoadError, ModelError};
pub use fire_plan::{FirePlans, PlanId};
pub use gate::{CommitError, Committed, Gate, GateStep};
#[cfg(feature = "std")]
pub use genom::expand;
pub use genom::GenomMap;
pub use incremental::{Enabled, EnabledSet};
#[cfg(feature = "std")]
pub use load::{
    compile_def, expand_file, expand_str, load_file, load_str, parse_str, read_model_file,
    ron_options,
};
pub use ordered_map::OrderedMap;
pub use plan_effects::PlanEffects;
pub use rng::Rng;
pub use state::{State, StateLayout};
pub use state_cache::{CacheStats, StateCache};
pub use step::{Label, OwnedStep, Pick, Step, Steps};
pub use system::{
    Assign, Atom, Component, Connector, Family, Interaction, PortRef, PriorityRule, Property,
    PropertyKind, RangeError, RangeErrorKind, Role, Summary, System, Target, Transition, Var,
    VarType,
};
pub use trace::{Trace, TraceStep, TraceValue, Verdict};
