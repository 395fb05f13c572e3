//! The example controller of C codels: robots/genom3-rover.ron, whose modules are the
//! GenoM3 components of robots/genom3 (loco, loc, nav), run by bip-engine with their
//! codels written in C (codels/*.c), bound through the glue bip-codegen generates from
//! the `.gen` files (`build.rs`).
//!
//! ```text
//! cargo run --release -p bip-c-rover-controller
//! ```
//!
//! [`world`] is the simulated rover the codels drive (the hardware functions of
//! codels/sim.h); [`supervisor`] plays a script of requests, prints what happens and
//! checks the recording against the model; [`hooks`] lets a test choose the codels'
//! outcomes.

pub mod hooks;
pub mod supervisor;
pub mod world;

pub use supervisor::{run, Report};

/// The generated glue of each component, with the `#[repr(C)]` mirrors of its types.
pub mod loco_c {
    include!(concat!(env!("OUT_DIR"), "/loco_c.rs"));
}
pub mod loc_c {
    include!(concat!(env!("OUT_DIR"), "/loc_c.rs"));
}
pub mod nav_c {
    include!(concat!(env!("OUT_DIR"), "/nav_c.rs"));
}
