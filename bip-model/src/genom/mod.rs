//! The GenoM layer (MODEL.md section 4): GenoM3-style modules and constraints, expanded
//! into BIP core so that the verifier and the engine only ever see atoms, connectors and
//! priorities. docs/genom.md describes the expansion and its generated names.
//!
//! - `syntax`: the file format of modules and constraints;
//! - `check`: validation with positions;
//! - `names`: the generated names and the rewriting of GenoM names in expressions;
//! - `build`: the expansion itself;
//! - `map`: the engine's map of the layer ([`GenomMap`]), kept in [`crate::System::genom`];
//!   `recipe`: the same by names, as the expansion writes it.
//!
//! Without the `std` feature only `map` is built: a compiled system keeps its map.

#[cfg(feature = "std")]
mod build;
#[cfg(feature = "std")]
mod check;
#[cfg(feature = "std")]
mod expansion;
pub mod map;
#[cfg(feature = "std")]
mod names;
#[cfg(feature = "std")]
mod origin;
#[cfg(feature = "std")]
mod recipe;
mod stuck;
#[cfg(feature = "std")]
pub mod syntax;

#[cfg(test)]
mod tests;

#[cfg(feature = "std")]
pub use build::Expansion;
pub use map::{
    AgeMap, CodelMap, Condition, GenomMap, IdsField, IdsWrite, ModuleMap, PortMap, Reason,
    ServiceKind, ServiceMap, TaskMap, YieldMap,
};
pub use stuck::Stuck;

#[cfg(feature = "std")]
pub(crate) use expansion::compile;
#[cfg(feature = "std")]
pub use expansion::expand;
