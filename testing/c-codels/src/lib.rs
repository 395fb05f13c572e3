//! A GenoM3 component's C codels run on bip-engine (docs/codegen.md, "Running C codels on
//! the engine"): `build.rs` writes counter.gen's C headers and its Rust glue
//! (`bip_codegen::c::write_c_bindings`) and compiles codels/counter.c against the headers;
//! [`counter`] is the generated glue (the mirrors of its types, its codels' declarations,
//! `CODELS`, `bind`), on the runtime of `bip-genom-c`; [`camera_glue`] is camera.gen's,
//! whose data hold pointers; [`apart_glue`] is apart.gen's, with an async codel; [`hooks`] are the tests' handles on the C file.

pub mod hooks;

/// counter.gen's generated glue, with the `#[repr(C)]` mirrors of its types.
pub mod glue {
    include!(concat!(env!("OUT_DIR"), "/counter_c.rs"));
}

pub use glue::{counter, place};

/// camera.gen's generated glue: data of pointers (an image's unbounded sequence of bytes,
/// strings), owned by the module object's memory and the engine's copies.
pub mod camera_glue {
    include!(concat!(env!("OUT_DIR"), "/camera_c.rs"));
}

/// apart.gen's generated glue: its async codel runs apart from its module object.
pub mod apart_glue {
    include!(concat!(env!("OUT_DIR"), "/apart_c.rs"));
}

/// The mirrors of mirrors.gen's types: one of each kind, for the layout tests.
pub mod mirrors_types {
    include!(concat!(env!("OUT_DIR"), "/mirrors_types.rs"));
}
