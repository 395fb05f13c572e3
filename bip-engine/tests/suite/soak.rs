//! The soak test (`.ci/run` runs it in release: `cargo test --release -p bip-engine --test
//! suite soak -- --ignored`): ten million steps of the rover under random requests and
//! random codel results, faults included (panics, undeclared yields and exceptions, ids
//! written out of range), with every invariant checked after every step, the resident
//! memory flat after a warm-up, and the recording's window replayed by the step relation
//! at intervals. A time guard stops a hang; it asserts no speed.

use crate::common;

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bip_engine::*;
use bip_model::{PropertyKind, Rng};
use common::*;

const STEPS: u64 = 10_000_000;
/// Steps before the memory baseline is taken (caches filled, vectors at their size).
const WARM_UP: u64 = 1_000_000;
/// Growth of the resident memory allowed past the baseline.
const MAX_GROWTH: u64 = 16 << 20;
/// Steps between two checks of the recording (and samples of the memory).
const CHECK_EVERY: u64 = 500_000;
const GUARD: Duration = Duration::from_secs(300);

/// The process's resident memory, from /proc/self/status.
fn resident_bytes() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status");
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .expect("VmRSS in kB")
        * 1024
}

#[test]
#[ignore = "ten million steps: run in release by .ci/run"]
fn ten_million_random_steps_keep_every_invariant_in_flat_memory() {
    silence_injected_panics();
    let system = load("rover.ron");
    let invariants: Vec<_> = system
        .properties
        .iter()
        .filter_map(|p| match &p.kind {
            PropertyKind::Invariant(e) => Some((p.name.clone(), e.clone())),
            _ => None,
        })
        .collect();
    assert!(!invariants.is_empty());
    let services: Vec<(String, String)> = system
        .requestable()
        .map(|(m, s)| (m.to_string(), s.to_string()))
        .collect();
    let seed = 0x50a6;
    let rng = Arc::new(Mutex::new(Rng(seed)));
    let mut engine = random_codels(Engine::builder(system.clone()), &system, rng, None)
        .policy(Policy::Seeded(seed))
        .record_window(5_000)
        .event_capacity(0)
        .build()
        .expect("builds");
    let mut requests = Rng(seed ^ 0x5eed);
    let start = Instant::now();
    let mut baseline = None;
    let mut peak = 0;
    let mut windows = 0;
    while engine.inspect().stats().steps < STEPS {
        assert!(
            start.elapsed() < GUARD,
            "the soak has not ended after {GUARD:?} ({} steps)",
            engine.inspect().stats().steps
        );
        if requests.below(4) == 0 {
            let (m, s) = &services[requests.below(services.len())];
            engine.request(m, s, ()).expect("a service of the model");
        }
        let before = engine.inspect().stats().steps;
        match engine.step().expect("no range error in the rover") {
            Stepped::Idle {
                next_tick_us: Some(t),
            } => engine.wait_until(t),
            Stepped::Idle { next_tick_us: None } => panic!("the rover stops: no tick to come"),
            _ => {}
        }
        let steps = engine.inspect().stats().steps;
        if steps == before {
            continue;
        }
        let view = engine.inspect();
        for (name, e) in &invariants {
            assert!(
                view.system()
                    .holds(e, view.state(), name)
                    .expect("evaluates"),
                "invariant {name} fails after step {steps}"
            );
        }
        if steps.is_multiple_of(CHECK_EVERY) {
            // the recording's last steps are steps of the model, ending in the engine's state
            let window = engine.record_window();
            let path = window
                .trace
                .replay_from(&system, window.start.clone())
                .unwrap_or_else(|e| panic!("the window before step {steps}: {e}"));
            assert!(window.trace.steps.len() >= 5_000);
            assert_eq!(window.skipped + window.trace.steps.len() as u64, steps);
            assert_eq!(path.last().map(|(_, s)| s), Some(engine.inspect().state()));
            windows += 1;
            let rss = resident_bytes();
            if steps >= WARM_UP {
                let base = *baseline.get_or_insert(rss);
                peak = peak.max(rss);
                assert!(
                    rss <= base + MAX_GROWTH,
                    "resident memory grew from {base} to {rss} bytes by step {steps}"
                );
            }
        }
    }
    let stats = engine.inspect().stats();
    assert!(
        stats.faults > 1000 && stats.exceptions > 1000 && stats.requests_accepted > 1000,
        "{stats:?}"
    );
    assert_eq!(windows, STEPS / CHECK_EVERY);
    eprintln!(
        "soak: {STEPS} steps in {:.1?}, {} faults, {} exceptions, resident memory {} MiB after warm-up, at most {} MiB",
        start.elapsed(),
        stats.faults,
        stats.exceptions,
        baseline.unwrap_or(0) >> 20,
        peak >> 20
    );
}
