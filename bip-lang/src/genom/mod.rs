//! The GenoM layer (docs/model.md, "The GenoM layer"): GenoM3-style modules and constraints, expanded
//! into BIP core so that the verifier and the engine only ever see atoms, connectors and
//! priorities. docs/genom.md describes the expansion and its generated names.
//!
//! - `syntax`: the file format of modules and constraints;
//! - `check`: validation with positions (modules, codel automata and constraints, a file
//!   each);
//! - `machines`: a task's own state machine, made an activity of its module;
//! - `names`: the generated names;
//! - `rewrite`: the rewriting of GenoM names in users' expressions into generated ones;
//! - `tree`: the expressions the expansion generates, as syntax trees;
//! - `build`: the expansion itself, which builds guards, actions and conditions as trees
//!   holding the user's own subtrees with their positions in the file, so that the
//!   compiler reports an error in them where the user wrote it; a file per part (the
//!   clock and tick, modules, activities, services' connectors, the assembly with user
//!   connectors, priorities, properties);
//! - `timing`: the time budgets (CPUs, priorities, deadlines, WCETs), checked;
//! - `timed`: a timed layer's time unit, durations in units, cores and scheduling, checked;
//! - `recipe`: the engine's map of the layer by names, as the expansion writes it; once
//!   the expanded model is compiled it becomes a [`bip_model::GenomMap`].

mod build;
mod check;
mod events;
mod expansion;
mod machines;
mod names;
mod recipe;
mod rewrite;
pub mod syntax;
mod timed;
mod timing;
mod tree;

#[cfg(test)]
mod tests;

pub use build::Expansion;

pub use expansion::expand;
pub(crate) use expansion::expand_in;
