//! A GenoM3 component's C codels run on bip-engine (docs/codegen.md, "Running C
//! codels"): `build.rs` writes counter.gen's C headers and compiles codels/counter.c
//! against them; [`runtime`] is GenoM3's C context and the reading of a returned event;
//! [`counter`] binds the component's codels to an engine as one module object.

pub mod counter;
pub mod runtime;
