//! bip-lang's integration tests, in one binary: every kind of bad input with its message and
//! position (`diagnostics`, `genom`, `genom_terms`, `timing`), and the GenoM expansion on
//! random layers (`genom_random`); reproducers of crashes and hangs (`robustness`) and
//! mutated example models through the loader (`fuzz`).

mod data_types;
mod diagnostics;
mod fuzz;
mod gen3;
mod gen3_fuzz;
mod genom;
mod genom_random;
mod genom_terms;
mod response;
mod robustness;
mod support;
mod timing;
