//! bip-lang's integration tests, in one binary: every kind of bad input with its message and
//! position (`diagnostics`, `genom`, `genom_terms`, `timing`), and the GenoM expansion on
//! random layers (`genom_random`).

mod diagnostics;
mod genom;
mod genom_random;
mod genom_terms;
mod support;
mod timing;
