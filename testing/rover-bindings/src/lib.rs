//! The bindings bip-codegen generates for robots/rover.ron, compiled under the workspace's
//! lints (`clippy -D warnings`): that they compile, warning-free, is the test, and
//! `tests/rover.rs` runs the rover through them. [`typed`] holds the bindings of
//! `models/typed.ron`, the model types the rover has no use for (ids of a range and a
//! `Bool`, an `Int` port, an `Int` output, a record with an `Int` field), under the same
//! test. [`apart`] holds those of `models/apart.ron`, a module with an async codel.
//!
//! The model names three Rust types, `Rust("Scan")`, `Rust("Dtm")` and `Rust("Image")`:
//! a Rust type is resolved where the bindings are included, so they are defined here.

pub use bip_engine;

/// A laser scan (port `sick.scan`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scan {
    pub ranges: Vec<f64>,
}

/// A digital terrain model (port `aspect.dtm`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dtm {
    pub cells: usize,
}

/// A picture (port `camera.image`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Image {
    pub shots: u32,
}

include!(concat!(env!("OUT_DIR"), "/rover.rs"));

/// The bindings of `models/typed.ron`.
pub mod typed {
    include!(concat!(env!("OUT_DIR"), "/typed.rs"));
}

/// The bindings of `models/apart.ron`, whose async codel runs apart from its module
/// object.
pub mod apart {
    include!(concat!(env!("OUT_DIR"), "/apart.rs"));
}
