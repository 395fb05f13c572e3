//! The engine's runs do not change when its code is made faster: seeded runs on the
//! example models (random codel results and requests, each policy, default codels, task
//! threads, a codel that overruns, replay through `step_as`) each give one fingerprint of
//! what the engine did (every `step` result, every event, the recorded trace, the final
//! state), and the fingerprints are those of the engine before its optimisations.
//!
//! On most models the policy never has two steps to choose from (their runs under each
//! policy share a fingerprint); the satellite and the pipeline make it choose, and
//! `tests/scheduling.rs` checks the choices themselves.
//!
//! A change that makes a fingerprint differ changed the engine's behaviour (the steps
//! committed, their order, the policy's choices, the replies, faults or held reports) or
//! the `Debug` form of what is hashed (a new `Stats` counter, say). If
//! that is intended (a change of the semantics or of the scheduling), print the new
//! fingerprints with `BIP_GOLDEN_PRINT=1 cargo test -p bip-engine --test golden --
//! --nocapture` and say why in the commit.

use crate::common;

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::sync::{Arc, Mutex};

use bip_engine::replay::replay;
use bip_engine::*;
use bip_model::{Rng, System};
use common::*;

/// FNV-1a: stable across runs and platforms, unlike the standard library's hashers.
fn fnv(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

#[derive(Clone, Copy, Debug)]
enum Codels {
    /// Each codel yields its first yield.
    First,
    /// Random declared and undeclared outcomes, panics, ids writes in and out of range,
    /// port writes; now and then a codel takes longer than its period (an overrun).
    Random,
    /// `DefaultCodels::Random`.
    Default,
}

fn bind(
    system: &System,
    codels: Codels,
    rng: Arc<Mutex<Rng>>,
    clock: &VirtualClock,
) -> EngineBuilder {
    let b = Engine::builder(system.clone()).clock(clock.clone());
    match codels {
        Codels::First => first_yields(b, system),
        Codels::Random => random_codels(b, system, rng, Some(clock.clone())),
        Codels::Default => b.default_codels(DefaultCodels::Random(7)),
    }
}

/// Runs 1,500 calls of `step` with random requests in between; the fingerprint of all
/// the engine did.
fn fingerprint(
    system: &System,
    policy: Policy,
    codels: Codels,
    threads: bool,
    seed: u64,
    kinds: &mut BTreeSet<&'static str>,
) -> u64 {
    let rng = Arc::new(Mutex::new(Rng(seed)));
    let clock = VirtualClock::new();
    let mut e = bind(system, codels, rng.clone(), &clock)
        .policy(policy)
        .threads(threads)
        .record(10_000)
        .build()
        .expect("builds");
    let services: Vec<(&str, &str)> = system.requestable().collect();
    let mut log = String::new();
    for k in 0..1500 {
        let request = {
            let mut r = rng.lock().unwrap_or_else(|e| e.into_inner());
            (!services.is_empty() && r.below(12) == 0).then(|| services[r.below(services.len())])
        };
        if let Some((m, s)) = request {
            // untyped arguments go to activities that declare none: a function has no
            // codel to read them (the codels here read none)
            let untyped = system
                .genom
                .as_ref()
                .and_then(|g| g.service(m, s))
                .is_some_and(|x| !x.codels.is_empty() && x.args.is_none());
            let t = if !untyped {
                e.request(m, s, ())
            } else {
                e.request(m, s, k)
            };
            let t = t.expect("requestable");
            writeln!(log, "request {m}.{s} {t:?}").expect("writes");
        }
        let before = e.inspect().now_us();
        let stepped = e.step().expect("steps");
        // an idle step's time as the engine saw it (on a virtual clock, `step` then moves
        // time to the next tick)
        let at = match stepped {
            Stepped::Idle { .. } => before,
            _ => e.inspect().now_us(),
        };
        writeln!(log, "{stepped:?} at {at}").expect("writes");
        if let Stepped::Idle { next_tick_us } = stepped {
            match next_tick_us {
                Some(t) => e.wait_until(t),
                None if e.inspect().waiting_requests() == 0 && services.is_empty() => break,
                None => {}
            }
        }
        for ev in e.events() {
            // the time-budget reports came after these fingerprints were taken; they
            // add to the events without changing a step (tests/suite/budgets.rs)
            if matches!(
                ev,
                Event::WcetExceeded { .. } | Event::DeadlineMissed { .. }
            ) {
                continue;
            }
            kinds.insert(event_kind(&ev));
            if let Some(form) = fingerprint_form(&ev) {
                writeln!(log, "{form}").expect("writes");
            }
        }
    }
    // the counters the fingerprints were taken with, written as `Stats` printed them then
    let s = e.inspect().stats();
    writeln!(
        log,
        "Stats {{ steps: {}, ticks: {}, codels: {}, exceptions: {}, faults: {}, overruns: {}, requests_accepted: {}, requests_refused: {}, events_dropped: {} }}",
        s.steps, s.ticks, s.codels, s.exceptions, s.faults, s.overruns, s.requests_accepted,
        s.requests_refused, s.events_dropped
    )
    .expect("writes");
    writeln!(log, "{:?}", e.inspect().held().expect("evaluates")).expect("writes");
    writeln!(log, "{:?}", e.inspect().outstanding().expect("evaluates")).expect("writes");
    writeln!(log, "{:?}", e.inspect().state()).expect("writes");
    let trace = e.record();
    for s in &trace.steps {
        writeln!(log, "{}", s.step).expect("writes");
    }
    // the recording, replayed through a new engine with `step_as`
    let r = replay(system.clone(), &trace).expect("builds");
    assert!(r.refused.is_none(), "{:?}", r.refused);
    for s in &r.steps {
        writeln!(log, "{:?}", s.stepped).expect("writes");
    }
    fnv(&log)
}

/// An event as the fingerprints were taken: the `Debug` form the events had then, by
/// ids, when they did not name their codel or service, did not tell an interrupt from an
/// abort, and had no start (`None`: not written).
fn fingerprint_form(ev: &Event) -> Option<String> {
    let fault = |f: &Fault| {
        // a replayed error path named no codel then
        let codel = match f.kind {
            FaultKind::Replayed => CodelId(u32::MAX),
            _ => f.codel.id,
        };
        format!("Fault {{ codel: {codel:?}, kind: {:?} }}", f.kind)
    };
    Some(match ev {
        Event::Reply {
            ticket,
            service,
            reply,
        } => {
            let reply = match reply {
                Reply::Accepted => "Accepted".to_string(),
                Reply::Refused(r) => format!("Refused({r:?})"),
                Reply::Started => return None,
                Reply::Done { outcome, .. } => match outcome {
                    Outcome::Ether => "Done(Ether)".to_string(),
                    Outcome::Exception(x) => format!("Done(Exception({x:?}))"),
                    Outcome::Interrupted { .. } | Outcome::Aborted => {
                        "Done(Interrupted)".to_string()
                    }
                    Outcome::Fault(f) => format!("Done(Fault({}))", fault(f)),
                },
            };
            format!(
                "Reply {{ ticket: {ticket:?}, service: {:?}, reply: {reply} }}",
                service.id
            )
        }
        Event::Held {
            codel,
            ticket,
            reasons,
        } => format!(
            "Held {{ codel: {:?}, ticket: {ticket:?}, reasons: {reasons:?} }}",
            codel.id
        ),
        Event::Fault(f) => format!("Fault({})", fault(f)),
        Event::Overrun {
            codel,
            took_us,
            period_us,
        } => format!(
            "Overrun {{ codel: {:?}, took_us: {took_us}, period_us: {period_us} }}",
            codel.id
        ),
        other => format!("{other:?}"),
    })
}

/// The fingerprint of each case, and the kinds of events the cases saw.
fn cases() -> (Vec<(String, u64)>, BTreeSet<&'static str>) {
    let models: Vec<(&str, System)> = vec![
        ("rover", load("rover.ron")),
        ("rover-deadlock", load("rover-deadlock.ron")),
        ("satellite", load("satellite.ron")),
        ("mini", load("tests/mini.ron")),
        ("ids", load_text(IDS_MODEL)),
        ("philosophers", load("philosophers.ron")),
        ("pipeline", load("pipeline.ron")),
    ];
    let mut out = Vec::new();
    let mut kinds = BTreeSet::new();
    for (name, system) in &models {
        for (policy, codels, threads) in [
            (Policy::RoundRobin, Codels::First, false),
            (Policy::First, Codels::Random, false),
            (Policy::RoundRobin, Codels::Random, false),
            (Policy::Seeded(11), Codels::Random, false),
            (Policy::Seeded(12), Codels::Default, false),
            (Policy::Seeded(13), Codels::Random, true),
        ] {
            let label = format!("{name} {policy:?} {codels:?} threads={threads}");
            out.push((
                label,
                fingerprint(system, policy, codels, threads, 3, &mut kinds),
            ));
        }
    }
    (out, kinds)
}

const EXPECTED: &[(&str, u64)] = &[
    ("rover RoundRobin First threads=false", 0x42ebd12b22860a18),
    ("rover First Random threads=false", 0x43f893e86bfe24cc),
    ("rover RoundRobin Random threads=false", 0x43f893e86bfe24cc),
    ("rover Seeded(11) Random threads=false", 0x43f893e86bfe24cc),
    ("rover Seeded(12) Default threads=false", 0x3fa01ae7a50b7357),
    ("rover Seeded(13) Random threads=true", 0x43f893e86bfe24cc),
    (
        "rover-deadlock RoundRobin First threads=false",
        0xc315767ecfdc5146,
    ),
    (
        "rover-deadlock First Random threads=false",
        0xf76d6945fdb4b82b,
    ),
    (
        "rover-deadlock RoundRobin Random threads=false",
        0xf76d6945fdb4b82b,
    ),
    (
        "rover-deadlock Seeded(11) Random threads=false",
        0xf76d6945fdb4b82b,
    ),
    (
        "rover-deadlock Seeded(12) Default threads=false",
        0xdfcbed71d6818a42,
    ),
    (
        "rover-deadlock Seeded(13) Random threads=true",
        0xf76d6945fdb4b82b,
    ),
    (
        "satellite RoundRobin First threads=false",
        0x7feec003e7d6d301,
    ),
    ("satellite First Random threads=false", 0x34122aa2ba858399),
    (
        "satellite RoundRobin Random threads=false",
        0x90096e4f8a50741a,
    ),
    (
        "satellite Seeded(11) Random threads=false",
        0x2bbfa5fb5dceb001,
    ),
    (
        "satellite Seeded(12) Default threads=false",
        0x88233ee5d925740a,
    ),
    (
        "satellite Seeded(13) Random threads=true",
        0xddf47bdef84804f2,
    ),
    ("mini RoundRobin First threads=false", 0xcf31189939db81dd),
    ("mini First Random threads=false", 0xa3490dc200a26bab),
    ("mini RoundRobin Random threads=false", 0xa3490dc200a26bab),
    ("mini Seeded(11) Random threads=false", 0xa3490dc200a26bab),
    ("mini Seeded(12) Default threads=false", 0x28d04f6e47290f49),
    ("mini Seeded(13) Random threads=true", 0xa3490dc200a26bab),
    ("ids RoundRobin First threads=false", 0xde6966b100f648d4),
    ("ids First Random threads=false", 0x9598ba16d81ec848),
    ("ids RoundRobin Random threads=false", 0x9598ba16d81ec848),
    ("ids Seeded(11) Random threads=false", 0x9598ba16d81ec848),
    ("ids Seeded(12) Default threads=false", 0x6507664f8d1eaad9),
    ("ids Seeded(13) Random threads=true", 0x9598ba16d81ec848),
    (
        "philosophers RoundRobin First threads=false",
        0x74bb4e7bc75512ea,
    ),
    (
        "philosophers First Random threads=false",
        0x30e1993fde8f8747,
    ),
    (
        "philosophers RoundRobin Random threads=false",
        0x74bb4e7bc75512ea,
    ),
    (
        "philosophers Seeded(11) Random threads=false",
        0x4c8564187f5c009a,
    ),
    (
        "philosophers Seeded(12) Default threads=false",
        0x818441843400ab9f,
    ),
    (
        "philosophers Seeded(13) Random threads=true",
        0xb3a3a76f9a179423,
    ),
    (
        "pipeline RoundRobin First threads=false",
        0xc684685e25d2895f,
    ),
    ("pipeline First Random threads=false", 0x3b975d060a1d7705),
    (
        "pipeline RoundRobin Random threads=false",
        0xc684685e25d2895f,
    ),
    (
        "pipeline Seeded(11) Random threads=false",
        0xe8fdec8978def3cf,
    ),
    (
        "pipeline Seeded(12) Default threads=false",
        0x1c3a17df6638c0ab,
    ),
    (
        "pipeline Seeded(13) Random threads=true",
        0x1c3a17df6638c0ab,
    ),
];

#[test]
fn seeded_runs_give_the_fingerprints_of_the_engine_before_its_optimisations() {
    silence_injected_panics();
    let (got, kinds) = cases();
    // the fingerprints cover every kind of event but refusals by a connector of yours
    for k in [
        "accepted",
        "ether",
        "exception",
        "panic",
        "bad transition",
        "fault reply",
        "held",
        "interrupted",
        "overrun",
        "refused",
    ] {
        assert!(kinds.contains(k), "no {k} in {kinds:?}");
    }
    if std::env::var_os("BIP_GOLDEN_PRINT").is_some() {
        for (label, h) in &got {
            println!("    ({label:?}, {h:#018x}),");
        }
    }
    let differ: Vec<String> = got
        .iter()
        .zip(EXPECTED)
        .filter(|((label, h), (expected_label, e))| label != expected_label || h != e)
        .map(|((label, h), _)| format!("{label}: {h:#018x}"))
        .collect();
    assert_eq!(got.len(), EXPECTED.len(), "one fingerprint per case");
    assert!(
        differ.is_empty(),
        "the engine's behaviour changed: {differ:#?}"
    );
}
