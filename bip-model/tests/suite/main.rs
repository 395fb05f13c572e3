//! bip-model's integration tests, in one binary (one link instead of five):
//!
//! - `reference`: the step relation against a naive interpreter of the semantics, on
//!   thousands of random systems;
//! - `semantics`: one test per rule of the semantics;
//! - `incremental`: `EnabledSet` and fire plans against the relation along random walks;
//! - `state_cache`: the state cache against the relation;
//! - `trace`: the trace format and replay.

mod gate;
mod incremental;
mod reference;
mod semantics;
mod state_cache;
mod trace;
