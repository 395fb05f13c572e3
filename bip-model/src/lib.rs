//! `bip-model`: a compiled bip model and its one semantics, `no_std` + `alloc`.
//!
//! - [`System`] is the compiled model: dense indices, compiled expressions, priorities
//!   closed transitively (as a graph, [`PriorityGraph`]); [`System::new`] builds one from
//!   [`SystemParts`] (the front end, `bip-lang`, reads and compiles model files into them);
//! - [`System::enabled_steps`] and [`System::fire`] are the step relation, shared by the
//!   verifier, the simulator and the engine; [`EnabledSet`] keeps a state's enabled steps
//!   up to date as the state moves, re-evaluating only what a step can have changed;
//! - [`StateLayout`] packs states into the fewest bits; [`Trace`] is the shared trace format.

#![no_std]

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

mod assemble;
mod budgets;
pub mod choices;
mod deadlock;
mod enable_index;
pub mod eval;
mod fast_path;
mod fire_plan;
mod found;
mod gate;
pub mod genom;
mod incremental;
mod model;
pub mod ops;
mod ordered_map;
mod plan_effects;
mod priority_graph;
mod priority_masks;
mod radix;
mod response;
mod rng;
mod state;
mod state_cache;
mod step;
mod step_tables;
mod steps;
mod suppression;
mod system;
mod timelock;
pub mod trace;
mod watches;

pub use assemble::SystemParts;
pub use budgets::{Budgets, ComponentTask};
pub use deadlock::{Liveness, LivenessChecker};
pub use fire_plan::{FirePlans, PlanId};
pub use gate::{CommitError, Committed, Gate, GateStep};
pub use genom::GenomMap;
pub use incremental::{Enabled, EnabledSet};
pub use model::{
    family_indices, Assign, Atom, Component, Connector, Family, Happens, Interaction, PortRef,
    Priority, Property, PropertyKind, RangeError, RangeErrorKind, Role, StepPattern, Target,
    Transition, Var, VarType,
};
pub use ordered_map::OrderedMap;
pub use plan_effects::PlanEffects;
pub use priority_graph::{PriorityGraph, MAX_INCIDENCES};
pub use response::{Happenings, ResponseSpec, ResponseWatch};
pub use rng::Rng;
pub use state::{State, StateLayout};
pub use state_cache::{CacheStats, StateCache, STATE_CACHE_BYTES};
pub use steps::{Label, OwnedStep, Pick, Step, Steps};
pub use system::{Summary, System};
pub use timelock::{TimeHeld, TIME_PROGRESS};
pub use trace::{Trace, TraceStep, TraceValue, Verdict};
