//! The `bip` command end to end (`check`, `engine`, `genom`, `sched`, `verify`: the binary run as a
//! user runs it, with SPIN as a cross-check where it is installed), and the architecture's
//! layering read from the sources (`layering`), in one binary.

mod check;
mod common;
mod engine;
mod export;
mod genom;
mod layering;
mod sched;
mod verify;
