//! `bip-genom-c`: what a GenoM3 component's C codels need at run time on bip-engine, for
//! the glue `bip-codegen` generates from the component's `.gen` file (docs/codegen.md,
//! "C codels"). [`context`] is the `genom_context` a codel takes last (its `raise` and
//! `raised`, and the call the engine is making, which the port handles reach through it);
//! [`events`] reads the `genom_event` a codel returns as the engine's [`bip_engine::Next`];
//! [`owned`] holds the data of pointers (unbounded sequences and strings) that engine-owned
//! memory keeps, [`long_double`] C's `long double`, [`multiple`] a multiple port's
//! instances by name.
//! A controller depends on this crate and on bip-engine; its build script calls
//! `bip_codegen::c::write_c_bindings`.

pub mod context;
pub mod events;
pub mod long_double;
pub mod multiple;
pub mod owned;

pub use context::{Context, ContextIface, GenomEvent, Raised};

/// The engine the generated glue binds to, named through this crate
/// (`bip_genom_c::bip_engine::EngineBuilder`): the glue then needs this crate alone, and
/// names the very bip-engine this crate was built with.
pub use bip_engine;
pub use events::Events;
pub use long_double::LongDouble;
pub use multiple::Instances;
pub use owned::{GenomString, Sequence};
