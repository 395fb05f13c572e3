//! A GenoM3 component's C codels run on bip-engine (docs/codegen.md, "Running C
//! codels"): `build.rs` writes counter.gen's C headers and compiles codels/counter.c
//! against them; [`runtime`] is GenoM3's C context and the reading of a returned event;
//! [`counter`] binds the component's codels to an engine as one module object, with the
//! ids in memory of their C layout ([`counter_types`], generated).

pub mod counter;
pub mod runtime;

/// The `#[repr(C)]` mirrors of counter.gen's C types (bip-codegen's `rust_mirrors`).
pub mod counter_types {
    include!(concat!(env!("OUT_DIR"), "/counter_types.rs"));
}

/// The mirrors of mirrors.gen's types: one of each kind, for the layout tests.
pub mod mirrors_types {
    include!(concat!(env!("OUT_DIR"), "/mirrors_types.rs"));
}
