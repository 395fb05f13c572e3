//! Simulation (`bip_engine::simulate`): the rover keeps its invariants and deadlock
//! freedom under random requests and codel outcomes, a run is the same for a seed, its
//! trace replays through the engine, and the deadlocks of rover-deadlock.ron and of the
//! philosophers (a model without a GenoM layer, moved by its environment steps) are found.

use crate::common;

use bip_engine::replay::{replay, End};
use bip_engine::simulate::{simulate, SimulationEnd, SimulationOptions};
use bip_model::Verdict;
use common::*;

#[test]
fn the_rover_keeps_its_invariants_and_a_run_is_the_same_for_a_seed() {
    let options = SimulationOptions {
        steps: 3000,
        seed: 1,
    };
    let sim = simulate(load("rover.ron"), options).expect("builds");
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
    assert_eq!(sim.trace.steps.len(), 3000);
    assert_eq!(sim.trace.verdict, Verdict::None);
    let again = simulate(load("rover.ron"), options).expect("builds");
    assert_eq!(again.trace, sim.trace);
    assert_eq!(again.stats, sim.stats);
    let other = simulate(load("rover.ron"), SimulationOptions { seed: 2, ..options });
    assert_ne!(other.expect("builds").trace, sim.trace);
    // the run is a path of the model through the engine
    let r = replay(load("rover.ron"), &sim.trace).expect("builds");
    assert!(r.refused.is_none(), "{:?}", r.refused);
    assert_eq!(r.end, Some(End::Recording));
}

#[test]
fn the_deadlock_of_rover_deadlock_is_found_and_replays() {
    let options = SimulationOptions {
        steps: 5000,
        seed: 1,
    };
    let sim = simulate(load("rover-deadlock.ron"), options).expect("builds");
    assert_eq!(sim.end, SimulationEnd::Deadlock);
    assert!(sim.end.fails());
    assert_eq!(sim.trace.verdict, Verdict::Deadlock);
    let r = replay(load("rover-deadlock.ron"), &sim.trace).expect("builds");
    assert!(matches!(r.end, Some(End::Deadlock { .. })), "{:?}", r.end);
}

#[test]
fn a_model_without_a_genom_layer_moves_by_its_environment() {
    let options = SimulationOptions {
        steps: 5000,
        seed: 2,
    };
    let sim = simulate(load("philosophers.ron"), options).expect("builds");
    assert_eq!(sim.end, SimulationEnd::Deadlock);
    assert_eq!(sim.requests_sent, 0);
    let sim = simulate(load("philosophers-asymmetric.ron"), options).expect("builds");
    assert!(!sim.end.fails(), "{:?}", sim.end);
}
