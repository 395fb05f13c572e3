//! What the engine takes by itself: internal transitions are progress steps, like the
//! connectors of a model without a GenoM layer.

use crate::common;

use bip_engine::*;
use common::*;

#[test]
fn internal_transitions_are_taken_as_progress_then_the_engine_is_idle() {
    let system = load_text(
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
    let system = load_text(
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

/// A codel connector extended by an atom with two transitions on its port: each yield of
/// the codel has two steps, and the policy chooses between them.
const TWO_STEPS_PER_YIELD: &str = r#"System(
    name: "dice",
    tick_ms: 10,
    atoms: {
        "Dice": Atom(
            locations: ["l"],
            initial: "l",
            ports: ["roll"],
            vars: [(name: "x", ty: Int(0, 1))],
            transitions: [
                (from: "l", port: "roll", to: "l", action: "x = 0"),
                (from: "l", port: "roll", to: "l", action: "x = 1"),
            ],
        ),
    },
    components: [(name: "dice", atom: "Dice")],
    modules: [(
        name: "m",
        tasks: [(name: "t", period: 1)],
        services: [
            (name: "S", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["pause::main"]),
                (state: "main", yields: ["pause::main", "ether"]),
            ]),
        ],
    )],
    connectors: [(name: "m_S_main", ports: ["dice.roll"])],
)"#;

/// The values the dice takes at each run of `main`, under `policy`.
fn rolls(policy: Policy) -> Vec<i64> {
    let system = load_text(TWO_STEPS_PER_YIELD);
    let dice = system.component_index("dice").expect("dice");
    let x = system.atom_of(dice).var_index("x").expect("x");
    let mut e = Engine::builder(system.clone())
        .codel(("m", "S", "start"), |_| Next::Yield("pause::main"))
        .codel(("m", "S", "main"), |_| Next::Yield("pause::main"))
        .policy(policy)
        .build()
        .expect("builds");
    let main = e.inspect().codel_id("m", "S", "main").expect("main");
    e.request("m", "S", ()).expect("queued");
    let mut out = Vec::new();
    while out.len() < 8 {
        match e.step().expect("steps") {
            Stepped::Codel { codel, failed } if codel == main => {
                assert!(!failed);
                out.push(system.value(e.inspect().state(), dice, x));
            }
            Stepped::Idle {
                next_tick_us: Some(t),
            } => e.wait_until(t),
            _ => {}
        }
    }
    out
}

#[test]
fn the_policy_chooses_among_the_steps_of_a_codels_yield() {
    assert_eq!(rolls(Policy::First), [0; 8]);
    assert_eq!(rolls(Policy::RoundRobin), [1, 0, 1, 0, 1, 0, 1, 0]);
    let seeded = rolls(Policy::Seeded(3));
    assert!(seeded.contains(&0) && seeded.contains(&1), "{seeded:?}");
    assert_eq!(seeded, rolls(Policy::Seeded(3)));
}

/// The values `x` takes at each of four ticks of a clock whose port has two transitions
/// (`x = 0`, `x = 1`), under `policy`.
fn ticks(policy: Policy) -> Vec<i64> {
    let system = load_text(
        r#"System(
            name: "coin",
            tick_ms: 1,
            atoms: {
                "Coin": Atom(
                    locations: ["l"],
                    initial: "l",
                    ports: ["tick"],
                    vars: [(name: "x", ty: Int(0, 1))],
                    transitions: [
                        (from: "l", port: "tick", to: "l", action: "x = 0"),
                        (from: "l", port: "tick", to: "l", action: "x = 1"),
                    ],
                ),
            },
            components: [(name: "coin", atom: "Coin")],
            connectors: [(name: "tick", ports: ["coin.tick"], role: Time)],
        )"#,
    );
    let coin = system.component_index("coin").expect("coin");
    let x = system.atom_of(coin).var_index("x").expect("x");
    let mut e = Engine::builder(system.clone())
        .policy(policy)
        .build()
        .expect("builds");
    let mut out = Vec::new();
    while out.len() < 4 {
        match e.step().expect("steps") {
            Stepped::Tick => out.push(system.value(e.inspect().state(), coin, x)),
            Stepped::Idle {
                next_tick_us: Some(t),
            } => e.wait_until(t),
            other => panic!("{other:?}"),
        }
    }
    out
}

/// A tick with several steps goes through the policy like any other choice (a tick with
/// one step is copied without asking it).
#[test]
fn the_policy_chooses_among_the_steps_of_a_tick() {
    assert_eq!(ticks(Policy::First), [0; 4]);
    assert_eq!(ticks(Policy::RoundRobin), [1, 0, 1, 0]);
    assert_eq!(ticks(Policy::Seeded(5)), ticks(Policy::Seeded(5)));
}
