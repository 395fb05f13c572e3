//! The bindings bip-codegen generates for robots/rover.ron, compiled under the workspace's
//! lints (`clippy -D warnings`): that they compile, warning-free, is the test, and
//! `tests/rover.rs` runs the rover through them.

include!(concat!(env!("OUT_DIR"), "/rover.rs"));
