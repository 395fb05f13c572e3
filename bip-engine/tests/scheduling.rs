//! What the engine takes by itself: internal transitions are progress steps, like the
//! connectors of a model without a GenoM layer.

mod common;

use bip_engine::*;
use common::*;

#[test]
fn internal_transitions_are_taken_as_progress_then_the_engine_is_idle() {
    let system = load_str(
        r#"System(
            name: "internal",
            atoms: {
                "A": Atom(
                    locations: ["l0", "l1", "l2"],
                    initial: "l0",
                    ports: ["p"],
                    transitions: [
                        (from: "l0", to: "l1"),
                        (from: "l1", port: "p", to: "l2"),
                    ],
                ),
            },
            components: [(name: "a", atom: "A")],
            connectors: [(name: "solo", ports: ["a.p"])],
        )"#,
    );
    let mut e = Engine::builder(system).record(4).build().expect("builds");
    assert_eq!(e.step().expect("steps"), Stepped::Other);
    assert_eq!(e.step().expect("steps"), Stepped::Other);
    assert_eq!(
        e.step().expect("steps"),
        Stepped::Idle { next_tick_us: None }
    );
    let steps: Vec<String> = e.record().steps.iter().map(|s| s.step.clone()).collect();
    assert_eq!(steps, ["a.internal", "solo"]);
}

#[test]
fn a_tick_fires_the_first_enabled_time_connector() {
    let system = load_str(
        r#"System(
            name: "two_clocks",
            tick_ms: 1,
            atoms: {
                "A": Atom(
                    locations: ["l0"],
                    initial: "l0",
                    ports: ["p", "q"],
                    vars: [(name: "x", ty: Int(0, 3))],
                    transitions: [
                        (from: "l0", port: "p", to: "l0", guard: "x < 2", action: "x = x + 1"),
                        (from: "l0", port: "q", to: "l0"),
                    ],
                ),
            },
            components: [(name: "a", atom: "A")],
            connectors: [
                (name: "tp", ports: ["a.p"], role: Time),
                (name: "tq", ports: ["a.q"], role: Time),
            ],
        )"#,
    );
    let mut e = Engine::builder(system).record(8).build().expect("builds");
    e.run_until(Until::Ticks(4)).expect("runs");
    let steps: Vec<String> = e.record().steps.iter().map(|s| s.step.clone()).collect();
    assert_eq!(steps, ["tp", "tp", "tq", "tq"]);
}
