//! The `bip` command end to end (`check`, `engine`, `genom`, `verify`: the binary run as a
//! user runs it, with SPIN as a cross-check where it is installed; `limits`: every limit
//! and Ctrl-C on wide models, in capped child processes), and the architecture's layering
//! read from the sources (`layering`), in one binary.

mod check;
mod common;
mod engine;
mod genom;
mod layering;
mod limits;
mod verify;
