//! Simulation (`bip_engine::simulate`): the rover keeps its invariants and deadlock
//! freedom under random requests and codel outcomes, a run is the same for a seed, its
//! trace replays through the engine, and the deadlocks of rover-deadlock.ron and of the
//! philosophers (a model without a GenoM layer, moved by its environment steps) are found.
//! A run keeps only its last steps and streams the rest, and can be stopped.

use crate::common;

use bip_engine::replay::{replay, End};
use bip_engine::CodelTime;
use std::cell::Cell;

use bip_engine::simulate::{
    simulate, simulate_with, Hooks, Simulation, SimulationEnd, SimulationOptions, SEGMENT,
};
use bip_model::{System, Trace, Verdict};
use common::*;

/// A simulation with its whole run, joined from the segments it streams.
pub(crate) fn streamed(system: System, options: SimulationOptions) -> (Simulation, Trace) {
    let mut whole = Trace::new(&system, Verdict::None, Vec::new());
    let mut on_steps = |segment: &Trace| whole.steps.extend(segment.steps.iter().cloned());
    let hooks = Hooks {
        stop: None,
        on_steps: Some(&mut on_steps),
    };
    let sim = simulate_with(system, options, hooks).expect("builds");
    whole.verdict = sim.last_steps.trace.verdict.clone();
    (sim, whole)
}
#[test]
fn the_rover_keeps_its_invariants_and_a_run_is_the_same_for_a_seed() {
    let options = SimulationOptions {
        steps: 3000,
        seed: 1,
        codel_time: CodelTime::Zero,
    };
    let (sim, trace) = streamed(load("rover.ron"), options);
    assert_eq!(sim.end, SimulationEnd::Completed);
    assert!(
        sim.deadlock_checked && sim.invariants == 5,
        "{}",
        sim.invariants
    );
    assert_eq!(sim.stats.steps, 3000);
    assert!(
        sim.stats.codels > 100 && sim.requests_sent > 10,
        "{:?}",
        sim.stats
    );
    assert_eq!(trace.steps.len(), 3000);
    assert_eq!(trace.verdict, Verdict::None);
    let (again, again_trace) = streamed(load("rover.ron"), options);
    assert_eq!(again_trace, trace);
    assert_eq!(again.stats, sim.stats);
    let (_, other) = streamed(load("rover.ron"), SimulationOptions { seed: 2, ..options });
    assert_ne!(other, trace);
    // without a stream, the same run keeps only its last steps, which are its streamed end
    let kept = simulate(load("rover.ron"), options)
        .expect("builds")
        .last_steps;
    let n = kept.trace.steps.len();
    assert!((SEGMENT..2 * SEGMENT).contains(&n), "{n}");
    assert_eq!(kept.skipped + n as u64, 3000);
    assert_eq!(kept.trace.steps[..], trace.steps[3000 - n..]);
    kept.trace
        .replay_from(&load("rover.ron"), kept.start.clone())
        .expect("the window replays from its start");
    // the run is a path of the model through the engine
    let r = replay(load("rover.ron"), &trace).expect("builds");
    assert!(r.refused.is_none(), "{:?}", r.refused);
    assert_eq!(r.end, Some(End::Recording));
}

#[test]
fn the_deadlock_of_rover_deadlock_is_found_and_replays() {
    let options = SimulationOptions {
        steps: 5000,
        seed: 1,
        codel_time: CodelTime::Zero,
    };
    let (sim, trace) = streamed(load("rover-deadlock.ron"), options);
    assert_eq!(sim.end, SimulationEnd::Deadlock);
    assert!(sim.end.fails());
    assert_eq!(trace.verdict, Verdict::Deadlock);
    let r = replay(load("rover-deadlock.ron"), &trace).expect("builds");
    assert!(matches!(r.end, Some(End::Deadlock { .. })), "{:?}", r.end);
}

#[test]
fn a_model_without_a_genom_layer_moves_by_its_environment() {
    let options = SimulationOptions {
        steps: 5000,
        seed: 2,
        codel_time: CodelTime::Zero,
    };
    let sim = simulate(load("philosophers.ron"), options).expect("builds");
    assert_eq!(sim.end, SimulationEnd::Deadlock);
    assert_eq!(sim.requests_sent, 0);
    let sim = simulate(load("philosophers-asymmetric.ron"), options).expect("builds");
    assert!(!sim.end.fails(), "{:?}", sim.end);
}

#[test]
fn a_stopped_run_ends_as_interrupted_with_its_steps_so_far() {
    let polls = Cell::new(0u32);
    let stop = || {
        polls.set(polls.get() + 1);
        polls.get() > 2500
    };
    let mut steps = 0usize;
    let mut on_steps = |segment: &Trace| steps += segment.steps.len();
    let hooks = Hooks {
        stop: Some(&stop),
        on_steps: Some(&mut on_steps),
    };
    let options = SimulationOptions {
        steps: 1_000_000,
        seed: 3,
        codel_time: CodelTime::Zero,
    };
    let sim = simulate_with(load("rover.ron"), options, hooks).expect("builds");
    assert_eq!(sim.end, SimulationEnd::Interrupted);
    assert!(!sim.end.fails());
    assert!(sim.stats.steps > 0 && sim.stats.steps < 1_000_000);
    assert_eq!(steps as u64, sim.stats.steps);
    assert_eq!(sim.last_steps.trace.verdict, Verdict::None);
}
