//! The `bip` command end to end (`aperiodic`, `check`, `codegen`, `engine`, `explore`, `genom`, `genom3`, `graph`, `response`, `sched`, `sched_exact`, `simulate_timed`, `time_progress`, `trace`, `trace_timed`, `trace_timed_run`, `verify`, `verify_worst`: the binary
//! run as a user runs it, with SPIN as a cross-check where it is installed; `limits`: every
//! limit and Ctrl-C on wide models, in capped child processes; `memory_bounds`: the default
//! memory limit under `ulimit -v`, loading past the limit in every command, and the
//! symbolic method's time limit in long actions and wide invariant computations), the architecture's layering
//! read from the sources (`layering`), and wide models within memory and time bounds
//! (`wide_models`), in one binary.

mod agreement;
mod aperiodic;
mod check;
mod codegen;
mod common;
#[cfg(feature = "distributed")]
mod distributed;
mod docs;
mod engine;
mod explore;
mod export;
mod genom;
mod genom3;
mod graph;
mod layering;
mod limits;
mod memory_bounds;
mod replay;
mod response;
mod sched;
mod sched_exact;
mod simulate_timed;
mod time_progress;
mod trace;
mod trace_timed;
mod trace_timed_run;
mod verify;
mod verify_worst;
mod wide_models;
