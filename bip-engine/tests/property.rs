//! Random request sequences and random codel results (declared yields and exceptions,
//! bad transitions, undeclared exceptions, panics, ids writes in and out of range) on the
//! example models: every trace the engine records is accepted step by step by bip-model's
//! step relation, ends in the engine's state, and no invariant is ever violated. The
//! invariants checked are those `bip verify` proves on these models (tests/genom.rs and
//! tests/verify.rs at the root run it).

mod common;

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bip_engine::*;
use bip_model::System;
use common::*;
use proptest::prelude::*;

use bip_model::Rng;

fn leak(s: &str) -> &'static str {
    Box::leak(s.to_string().into_boxed_str())
}

/// Binds every codel of `system` to a closure that draws its result from `rng`.
fn random_codels(system: &System, rng: Arc<Mutex<Rng>>) -> EngineBuilder {
    let mut b = Engine::builder(system.clone());
    let Some(map) = &system.genom else { return b };
    for m in &map.modules {
        for s in &m.services {
            for c in &s.codels {
                let yields: Vec<&'static str> = c.yields.iter().map(|y| leak(&y.target)).collect();
                let throws: Vec<&'static str> = c.throws.iter().map(|t| leak(t)).collect();
                let ids: Vec<(&'static str, i64, i64)> =
                    c.ids.iter().map(|f| (leak(&f.name), f.lo, f.hi)).collect();
                let ports: Vec<&'static str> = c.writes.iter().map(|p| leak(p)).collect();
                let rng = rng.clone();
                b = b.codel((&m.name, &s.name, &c.state), move |ctx| {
                    let mut r = rng.lock().unwrap_or_else(|e| e.into_inner());
                    for &(name, lo, hi) in &ids {
                        if r.below(2) == 0 {
                            let span = (hi - lo + 1) as usize;
                            // one write in ten leaves the range
                            let v = if r.below(10) == 0 {
                                hi + 1
                            } else {
                                lo + r.below(span) as i64
                            };
                            ctx.set(name, v);
                        }
                    }
                    for &p in &ports {
                        ctx.write_port(p, r.next_u64());
                    }
                    let roll = r.below(100);
                    if roll < 3 {
                        drop(r);
                        panic!("injected fault");
                    }
                    if roll < 6 {
                        return Next::Yield("no_such_state");
                    }
                    if roll < 9 {
                        return Next::Throw("e_undeclared");
                    }
                    if roll < 20 && !throws.is_empty() {
                        return Next::Throw(throws[r.below(throws.len())]);
                    }
                    Next::Yield(yields[r.below(yields.len())])
                });
            }
        }
    }
    b
}

fn run_case(model: usize, seed: u64) -> Result<(), TestCaseError> {
    let system = match model {
        0 => load("rover.ron"),
        1 => load("rover-deadlock.ron"),
        2 => load("satellite.ron"),
        3 => load("tests/mini.ron"),
        _ => load_str(IDS_MODEL),
    };
    let rng = Arc::new(Mutex::new(Rng(seed)));
    let mut engine = random_codels(&system, rng.clone())
        .policy(Policy::Seeded(seed))
        .record(2000)
        .build()
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    let services: Vec<(&str, &str)> = system.requestable().collect();
    let mut done: HashMap<Ticket, usize> = HashMap::new();
    while engine.stats().steps < 600 {
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
                reply: Reply::Done(_) | Reply::Refused(_),
                ..
            } = ev
            {
                *done.entry(ticket).or_default() += 1;
            }
        }
    }
    prop_assert!(done.values().all(|&n| n == 1), "a request ended twice");
    let trace = engine.record();
    let states = states_of(&system, &trace);
    prop_assert_eq!(states.last(), Some(engine.state()));
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
}

/// The random codels must reach every kind of outcome, or the property proves little.
#[test]
fn random_runs_see_every_outcome() {
    silence_injected_panics();
    let mut kinds = std::collections::BTreeSet::new();
    for seed in 0..8 {
        let system = load_str(IDS_MODEL);
        let rng = Arc::new(Mutex::new(Rng(seed)));
        let mut e = random_codels(&system, rng).build().expect("builds");
        e.request("m", "Init", ()).expect("queued");
        for _ in 0..40 {
            e.request("m", "S", ()).expect("queued");
            e.run_until(Until::Ticks(3)).expect("runs");
        }
        for ev in e.events() {
            let k = match ev {
                Event::Fault(f) => match f.kind {
                    FaultKind::Panic(_) => "panic",
                    FaultKind::BadTransition(_) => "bad transition",
                    FaultKind::UndeclaredException(_) => "undeclared exception",
                    FaultKind::IdsOutOfRange { .. } => "ids out of range",
                    _ => "other fault",
                },
                Event::Reply {
                    reply: Reply::Done(Outcome::Ether),
                    ..
                } => "ether",
                Event::Reply {
                    reply: Reply::Done(Outcome::Exception(_)),
                    ..
                } => "exception",
                Event::Reply {
                    reply: Reply::Done(Outcome::Interrupted),
                    ..
                } => "interrupted",
                Event::Reply {
                    reply: Reply::Refused(_),
                    ..
                } => "refused",
                _ => continue,
            };
            kinds.insert(k);
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

fn silence_injected_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let injected = info
                .payload()
                .downcast_ref::<&str>()
                .is_some_and(|m| m.contains("injected"));
            if !injected {
                default(info);
            }
        }));
    });
}
