//! The example controller of C codels: rover.ron, whose modules are the GenoM3
//! components of robots/genom3 (loco, loc, nav) and odo (odo.gen, the odometry loc's in
//! port reads), run by bip-engine with their codels written in C (codels/*.c), bound
//! through the glue bip-codegen generates from the `.gen` files (`build.rs`).
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

/// The generated glue of the four components (`rover_c::loco::bind`, …), with the
/// `#[repr(C)]` mirrors of their types (`rover_c::rover::speed`), shared.
pub mod rover_c {
    include!(concat!(env!("OUT_DIR"), "/rover_c.rs"));
}
