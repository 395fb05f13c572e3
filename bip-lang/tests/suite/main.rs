//! bip-lang's integration tests, in one binary: every kind of bad input with its message and
//! position (`diagnostics`, `genom`), and the GenoM expansion on random layers
//! (`genom_random`); reproducers of crashes and hangs (`robustness`).

mod diagnostics;
mod genom;
mod genom_random;
mod robustness;
mod support;
