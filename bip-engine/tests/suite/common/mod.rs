//! Helpers shared by the engine's tests.

#![allow(dead_code)]

use std::sync::{Arc, Mutex};

use bip_engine::{EngineBuilder, Event, FaultKind, Next, Outcome, Refusal, Reply, VirtualClock};
use bip_model::{PropertyKind, Rng, System, Trace};

pub fn load(name: &str) -> System {
    let p = format!("{}/../robots/{name}", env!("CARGO_MANIFEST_DIR"));
    bip_lang::load_file(std::path::Path::new(&p)).unwrap_or_else(|e| panic!("{}", e.summary()))
}

pub fn load_text(text: &str) -> System {
    bip_lang::load_str("test.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()))
}

/// A small layer for fault tests: an activity whose codel writes ids, throws, and loops.
pub const IDS_MODEL: &str = r#"System(
    name: "ids",
    tick_ms: 10,
    modules: [(
        name: "m",
        ids: [(name: "speed", ty: Int(0, 3), init: 1), (name: "on", ty: Bool)],
        tasks: [(name: "t", period: 2)],
        ports: [(name: "pose")],
        services: [
            (name: "Init", kind: Function),
            (name: "S", kind: Activity, task: "t", after: ["Init"], codels: [
                (state: "start", yields: ["pause::main"]),
                (state: "main", yields: ["pause::main", "ether"], throws: ["e_bad"],
                 writes: ["speed", "on", "pose"]),
            ]),
            (name: "Stop", kind: Function, interrupts: ["S"]),
        ],
    )],
    properties: [
        DeadlockFree,
        Invariant(name: "speed_in_range", expr: "m.speed >= 0 && m.speed <= 3"),
    ],
)"#;

/// Replays the trace with the step relation (not the engine): every step must be a step
/// of the model. Returns the states it passes through, the initial one first.
pub fn states_of(system: &System, trace: &Trace) -> Vec<bip_model::State> {
    let path = trace
        .replay(system)
        .unwrap_or_else(|e| panic!("the recorded trace is not a path of the model: {e}"));
    let mut out = vec![system.initial_state()];
    out.extend(path.into_iter().map(|(_, s)| s));
    out
}

/// Asserts every invariant of the model in every state.
pub fn assert_invariants(system: &System, states: &[bip_model::State]) {
    for (k, s) in states.iter().enumerate() {
        for p in &system.properties {
            if let PropertyKind::Invariant(e) = &p.kind {
                assert!(
                    system.holds(e, s, &p.name).expect("evaluates"),
                    "invariant {} fails after step {k}",
                    p.name
                );
            }
        }
    }
}

/// A `&'static str` for a codel's result (codels return static names).
pub fn leak(s: &str) -> &'static str {
    Box::leak(s.to_string().into_boxed_str())
}

/// Binds every codel of `system` to a closure that returns its first yield.
pub fn first_yields(mut b: EngineBuilder, system: &System) -> EngineBuilder {
    let Some(map) = &system.genom else { return b };
    for m in &map.modules {
        for s in &m.services {
            for c in &s.codels {
                let first = leak(&c.yields[0].target);
                b = b.codel((&m.name, &s.name, &c.state), move |_| Next::Yield(first));
            }
        }
    }
    b
}

/// Binds every codel of `system` to a closure that draws its result from `rng`: a
/// declared yield or exception, a bad transition, an undeclared exception, a panic; ids
/// writes in and out of range, port writes. With `overruns`, one run in forty also moves
/// that clock a second on (longer than any period: an overrun).
pub fn random_codels(
    mut b: EngineBuilder,
    system: &System,
    rng: Arc<Mutex<Rng>>,
    overruns: Option<VirtualClock>,
) -> EngineBuilder {
    let Some(map) = &system.genom else { return b };
    for m in &map.modules {
        for s in &m.services {
            for c in &s.codels {
                let yields: Vec<&'static str> = c.yields.iter().map(|y| leak(&y.target)).collect();
                let throws: Vec<&'static str> = c.throws.iter().map(|t| leak(t)).collect();
                let ids: Vec<(&'static str, i64, i64)> =
                    c.ids.iter().map(|f| (leak(&f.name), f.lo, f.hi)).collect();
                // a port of a declared type takes only that type: the random `u64` goes to
                // the others (and is drawn for every port, so that the runs stay the same)
                let typed = |p: &str| m.ports.iter().any(|x| x.name == p && x.ty.is_some());
                let ports: Vec<(&'static str, bool)> =
                    c.writes.iter().map(|p| (leak(p), typed(p))).collect();
                let rng = rng.clone();
                let overruns = overruns.clone();
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
                    for &(p, typed) in &ports {
                        let v = r.next_u64();
                        if !typed {
                            ctx.write_port(p, v);
                        }
                    }
                    if let Some(clock) = &overruns {
                        if r.below(40) == 0 {
                            clock.advance(1_000_000);
                        }
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

/// Keeps the panics the tests inject (their message says "injected") out of the output;
/// any other panic is reported as usual.
pub fn silence_injected_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let injected = info
                .payload()
                .downcast_ref::<&str>()
                .is_some_and(|m| m.contains("injected"))
                || info
                    .payload()
                    .downcast_ref::<String>()
                    .is_some_and(|m| m.contains("injected"));
            if !injected {
                default(info);
            }
        }));
    });
}

/// What an event is, in a word or two (a fault by its kind).
pub fn event_kind(e: &Event) -> &'static str {
    match e {
        Event::Reply { reply, .. } => match reply {
            Reply::Accepted => "accepted",
            Reply::Refused(Refusal::NotEnabled) => "refused (not enabled)",
            Reply::Refused(_) => "refused",
            Reply::Started => "started",
            Reply::Done { outcome, .. } => match outcome {
                Outcome::Ether => "ether",
                Outcome::Exception(_) => "exception",
                Outcome::Interrupted { .. } => "interrupted",
                Outcome::Aborted => "aborted",
                Outcome::Fault(_) => "fault reply",
            },
        },
        Event::Fault(f) => match f.kind {
            FaultKind::Panic(_) => "panic",
            FaultKind::BadTransition(_) => "bad transition",
            FaultKind::UndeclaredException(_) => "undeclared exception",
            FaultKind::IdsOutOfRange { .. } => "ids out of range",
            _ => "other fault",
        },
        Event::Held { .. } => "held",
        Event::Overrun { .. } => "overrun",
        Event::WcetExceeded { .. } => "over its WCET",
        Event::DeadlineMissed { .. } => "deadline missed",
        Event::ResponseLate { .. } => "response late",
    }
}
