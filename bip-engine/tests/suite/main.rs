//! bip-engine's integration tests, in one binary (the tests of process-wide state, the
//! allocator, the tracing subscriber and threads, are binaries of their own): scheduling,
//! requests, faults, replay, simulation, golden traces, the example controller, and the
//! differential property test.

mod api;
mod async_codels;
mod async_reference;
mod at_request;
mod bounded;
mod budgets;
mod common;
mod connections;
mod faults;
mod golden;
mod property;
mod replay;
mod requests;
mod response;
mod scheduling;
mod simulate;
mod soak;
mod timed;
