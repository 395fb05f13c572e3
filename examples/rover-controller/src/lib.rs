//! An example controller: the engine embedded on `robots/rover.ron` through the bindings
//! bip-codegen generates from it (`build.rs`), with simulated hardware behind the codels
//! and a small supervisor script of typed requests.
//!
//! ```text
//! cargo run --release -p bip-rover-controller [-- --real-time]
//! ```
//!
//! Three parts: [`hardware`], the simulated world and the Rust types of the model's
//! ports; `codels`, one implementation of each module's generated `Codels` trait, whose
//! methods read and write through their typed contexts and return their own outcome
//! enums; [`supervisor`], the script, the run and its report. The script shows what the
//! model allows and what it does not: a request refused (its `after` is not met), starts
//! and codels held by the rover's constraints (each shown by its name, its line and as
//! written: `mast_still (line 140): Exclusive(…)`), activities that end in `ether`, in an
//! exception, interrupted and aborted by a rule of the model, and an overrun. At the end
//! the recorded run is checked with bip-model's step relation (it is a path of the model)
//! and against every invariant.

mod codels;
pub mod distributed;
pub mod hardware;
pub mod supervisor;

pub use supervisor::{run, Report};

/// The bindings of robots/rover.ron. The model's `Rust("Scan")`, `Rust("Dtm")` and
/// `Rust("Image")` port types are the hardware's.
pub mod rover {
    pub use crate::hardware::{Dtm, Image, Scan};
    include!(concat!(env!("OUT_DIR"), "/rover.rs"));
}
