//! The GenoM layer of a compiled system: the engine's map of it ([`GenomMap`], kept in
//! [`crate::System::genom`]) and why a deadlock state is stuck ([`Stuck`]). The expansion
//! of modules and constraints into atoms and connectors is the front end's (`bip-lang`).

mod conditions;
pub mod map;
mod stuck;

pub use conditions::failing;
pub use map::{
    AgeMap, CodelMap, Condition, ConstraintRef, GenomMap, IdsField, IdsWrite, ModuleMap, PortMap,
    Reason, ServiceKind, ServiceMap, TaskMap, TimedCodelMap, TimedTaskMap, YieldMap,
};
pub use stuck::Stuck;
