//! Random request sequences and random codel results (declared yields and exceptions,
//! bad transitions, undeclared exceptions, panics, ids writes in and out of range) on the
//! example models: every trace the engine records is accepted step by step by bip-model's
//! step relation, ends in the engine's state, and no invariant is ever violated. The
//! invariants checked are those `bip verify` proves on these models (tests/genom.rs and
//! tests/verify.rs at the root run it).

use crate::common;

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bip_engine::*;
use common::*;
use proptest::prelude::*;

use bip_model::Rng;

/// What one random run left.
struct Run {
    system: bip_model::System,
    trace: bip_model::Trace,
    /// Every event, as text.
    events: Vec<String>,
    state: bip_model::State,
    cache: CacheStats,
}

/// A random run of 600 steps on example model `model`: random requests, random codel
/// results, the engine's state cache holding up to `cache` states; with `half_tables`,
/// every other interaction without its step table (its steps are computed, and fired
/// without a plan).
fn run(model: usize, seed: u64, cache: usize, half_tables: bool) -> Result<Run, TestCaseError> {
    let mut system = match model {
        0 => load("rover.ron"),
        1 => load("rover-deadlock.ron"),
        2 => load("satellite.ron"),
        3 => load("tests/mini.ron"),
        _ => load_text(IDS_MODEL),
    };
    if half_tables {
        system.drop_step_tables(|i| i % 2 == 0);
    }
    let rng = Arc::new(Mutex::new(Rng(seed)));
    let mut engine = random_codels(Engine::builder(system.clone()), &system, rng.clone(), None)
        .policy(Policy::Seeded(seed))
        .record(2000)
        .state_cache(cache)
        .build()
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    let services: Vec<(&str, &str)> = system.requestable().collect();
    let mut done: HashMap<Ticket, usize> = HashMap::new();
    let mut events = Vec::new();
    while engine.inspect().stats().steps < 600 {
        let (request, chunk) = {
            let mut r = rng.lock().unwrap_or_else(|e| e.into_inner());
            let request = (!services.is_empty() && r.below(3) == 0)
                .then(|| services[r.below(services.len())]);
            (request, 1 + r.below(12) as u64)
        };
        if let Some((m, s)) = request {
            engine
                .request(m, s, ())
                .map_err(|e| TestCaseError::fail(e.to_string()))?;
        }
        engine
            .run_until(Until::Steps(chunk))
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        for ev in engine.events() {
            if let Event::Reply {
                ticket,
                reply: Reply::Done { .. } | Reply::Refused(_),
                ..
            } = ev
            {
                *done.entry(ticket).or_default() += 1;
            }
            events.push(format!("{ev:?}"));
        }
    }
    prop_assert!(done.values().all(|&n| n == 1), "a request ended twice");
    Ok(Run {
        trace: engine.record(),
        state: engine.inspect().state().clone(),
        cache: engine.inspect().cache_stats(),
        system,
        events,
    })
}

fn run_case(model: usize, seed: u64) -> Result<(), TestCaseError> {
    let Run {
        system,
        trace,
        state,
        ..
    } = run(model, seed, DEFAULT_STATE_CACHE, seed.is_multiple_of(4))?;
    let states = states_of(&system, &trace);
    prop_assert_eq!(states.last(), Some(&state));
    assert_invariants(&system, &states);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 120, ..ProptestConfig::default() })]

    #[test]
    fn recorded_traces_are_model_paths_that_keep_the_invariants(model in 0..5usize, seed in any::<u64>()) {
        silence_injected_panics();
        run_case(model, seed)?;
    }

    /// The state cache changes nothing the engine does: the same run with no cache, with
    /// one too small for it and with the default records the same trace and the same
    /// events; with all the step tables, and with half of them (steps fired without a
    /// plan, which the cache does not know, and steps computed outside the tables, which
    /// it does not keep).
    #[test]
    fn the_state_cache_changes_nothing(model in 0..5usize, seed in any::<u64>(), half_tables: bool) {
        silence_injected_panics();
        let plain = run(model, seed, 0, half_tables)?;
        prop_assert_eq!(plain.cache.hits, 0);
        for cache in [3, DEFAULT_STATE_CACHE] {
            let cached = run(model, seed, cache, half_tables)?;
            prop_assert!(cached.cache.states <= cache);
            prop_assert_eq!(&cached.trace, &plain.trace);
            prop_assert_eq!(&cached.events, &plain.events);
            prop_assert_eq!(&cached.state, &plain.state);
        }
    }
}

/// The random runs come back to states they saw, or the comparison above proves little.
#[test]
fn random_runs_take_steps_from_the_cache() {
    silence_injected_panics();
    for model in 0..5 {
        let mut hits = 0;
        for seed in 0..5 {
            hits += run(model, seed, DEFAULT_STATE_CACHE, seed.is_multiple_of(2))
                .expect("runs")
                .cache
                .hits;
        }
        assert!(hits > 300, "model {model}: {hits} hits in five runs");
    }
}

/// The random codels must reach every kind of outcome, or the property proves little.
#[test]
fn random_runs_see_every_outcome() {
    silence_injected_panics();
    let mut kinds = std::collections::BTreeSet::new();
    for seed in 0..8 {
        let system = load_text(IDS_MODEL);
        let rng = Arc::new(Mutex::new(Rng(seed)));
        let mut e = random_codels(Engine::builder(system.clone()), &system, rng, None)
            .build()
            .expect("builds");
        e.request("m", "Init", ()).expect("queued");
        for _ in 0..40 {
            e.request("m", "S", ()).expect("queued");
            e.run_until(Until::Ticks(3)).expect("runs");
        }
        for ev in e.events() {
            kinds.insert(event_kind(&ev));
        }
    }
    for k in [
        "panic",
        "bad transition",
        "undeclared exception",
        "ids out of range",
        "ether",
        "exception",
        "refused",
    ] {
        assert!(kinds.contains(k), "no {k} in {kinds:?}");
    }
}
