//! The `bip` command end to end (`check`, `engine`, `genom`, `response`, `sched`, `verify`: the binary
//! run as a user runs it, with SPIN as a cross-check where it is installed; `limits`: every
//! limit and Ctrl-C on wide models, in capped child processes), the architecture's layering
//! read from the sources (`layering`), and wide models within memory and time bounds
//! (`wide_models`), in one binary.

mod check;
mod common;
mod engine;
mod export;
mod genom;
mod layering;
mod limits;
mod response;
mod sched;
mod verify;
mod wide_models;
