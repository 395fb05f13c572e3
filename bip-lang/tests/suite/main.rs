//! bip-lang's integration tests, in one binary: every kind of bad input with its message and
//! position (`diagnostics`, `genom`, `genom_terms`, `timing`), and the GenoM expansion on
//! random layers (`genom_random`), interrupts against a naive interpreter (`interrupts`); GenoM3 files (`gen3`, in a model `gen3_layer`, their
//! IDL types `gen3_types`, mutated `gen3_fuzz`); reproducers of crashes and hangs
//! (`robustness`) and mutated example models through the loader (`fuzz`).

mod aperiodic;
mod async_codels;
mod connections;
mod data_types;
mod diagnostics;
mod fuzz;
mod gen3;
mod gen3_constructs;
mod gen3_fuzz;
mod gen3_layer;
mod gen3_types;
mod genom;
mod genom_random;
mod genom_terms;
mod interrupts;
mod request_codels;
mod response;
mod robustness;
mod support;
mod task_machines;
mod timed;
mod timed_expansion;
mod timing;
