//! bip-verifier's integration tests, in one binary (one link instead of five):
//!
//! - `advance`: time steps of several units, in bounded response and range errors;
//! - `known_answers`: verdicts, state counts and trace lengths known independently of bip;
//! - `random_systems`: every worker count gives the same report, equal to a naive search;
//! - `response`: response properties against a naive search for unanswered triggers, on
//!   known models and random systems, with the truncation guardrail and vacuity;
//! - `response_worst`: a response property's worst response against the bounded search,
//!   on random timed layers;
//! - `schedulability`: each task's demand per period against an oracle walking every path
//!   between two ticks, and the analysis on top;
//! - `symbolic_known_answers`: the symbolic method on models whose answers are known;
//! - `symbolic_verdicts`: the symbolic method never contradicts the explicit one;
//! - `time_progress`: timelocks against a naive search for a tick from every state, the
//!   fuzzer's timelocks that made liveness properties hold, and the symbolic method;
//! - `timed_constraints`: `Exclusive` and `AtMost` with codels running at once on cores;
//! - `timed_oracle`: the timed expansion against a naive interpreter of the timed
//!   semantics, on random task sets;
//! - `timed_rta`: exploration against response-time analysis on one preemptive core.

mod advance;
mod known_answers;
mod random_systems;
mod response;
mod response_worst;
mod schedulability;
mod symbolic_known_answers;
mod symbolic_verdicts;
mod time_progress;
mod timed_constraints;
mod timed_oracle;
mod timed_rta;

/// The time units a trace spans: the sum of its time steps' `advance`.
fn trace_units(system: &bip_model::System, trace: &bip_model::Trace) -> u64 {
    let path = trace.replay(system).expect("the trace replays");
    let mut before = system.initial_state();
    let mut units = 0;
    for (step, after) in path {
        units += system
            .time_advance(&before, step.as_step())
            .expect("a step that fired has its advance");
        before = after;
    }
    units
}
