//! bip-model's integration tests, in one binary (one link instead of seven):
//!
//! - `advance`: the time units of a `Time` connector's steps;
//! - `reference`: the step relation against a naive interpreter of the semantics, on
//!   thousands of random systems;
//! - `semantics`: one test per rule of the semantics;
//! - `incremental`: `EnabledSet` and fire plans against the relation along random walks;
//! - `priorities`: the priority masks against the search of the priority graph;
//! - `state_cache`: the state cache against the relation;
//! - `trace`: the trace format and replay.

mod advance;
mod gate;
mod incremental;
mod priorities;
mod reference;
mod semantics;
mod state_cache;
mod trace;
