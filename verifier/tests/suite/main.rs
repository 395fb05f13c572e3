//! bip-verifier's integration tests, in one binary (one link instead of four):
//!
//! - `known_answers`: verdicts, state counts and trace lengths known independently of bip;
//! - `random_systems`: every worker count gives the same report, equal to a naive search;
//! - `symbolic_known_answers`: the symbolic method on models whose answers are known;
//! - `symbolic_verdicts`: the symbolic method never contradicts the explicit one.

mod known_answers;
mod random_systems;
mod symbolic_known_answers;
mod symbolic_verdicts;
