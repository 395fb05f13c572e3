//! Helpers shared by the engine's tests.

#![allow(dead_code)]

use bip_model::{PropertyKind, System, Trace};

pub fn load(name: &str) -> System {
    let p = format!("{}/../robots/{name}", env!("CARGO_MANIFEST_DIR"));
    bip_model::load_file(std::path::Path::new(&p)).unwrap_or_else(|e| panic!("{}", e.summary()))
}

pub fn load_str(text: &str) -> System {
    bip_model::load_str("test.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()))
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
