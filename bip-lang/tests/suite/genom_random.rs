//! Random GenoM layers, explored: every one loads, keeps the activity life cycle's
//! invariants in every reachable state, enforces its constraint, has an engine map that
//! names the yield of every codel step, and reloads from its printed expansion with the
//! same reachable states.

use std::collections::{HashSet, VecDeque};

use bip_lang::{expand_str, load_str};
use bip_model::{Label, State, System};
use proptest::prelude::*;

#[derive(Clone, Debug)]
struct Activity {
    /// Codel states besides `start`: 0 to 2.
    extra: usize,
    /// For each state but the last, whether it reaches the next one through a pause.
    chain_pause: Vec<bool>,
    /// For each state, whether it may also yield `ether` (the last always does).
    ether: Vec<bool>,
    /// For each state, a state it may pause back to.
    back: Vec<Option<usize>>,
    /// 0: no stop codel; 1: `stop` yields `ether`; 2: `stop` pauses first.
    stop: u8,
    throws: bool,
    slow: bool,
    self_interrupt: bool,
    halted: bool,
}

#[derive(Clone, Debug)]
struct Layer {
    activities: Vec<Activity>,
    /// 0: none; 1: Exclusive(A0, A1); 2: AtMost(1, all); 3: Requires(A0, [A1]).
    constraint: u8,
    /// Whether task `fast` runs a machine of its own (`start`, then `run` each period
    /// until it yields `ether`), before the activities in each instant.
    machine: bool,
}

fn activity() -> impl Strategy<Value = Activity> {
    (0usize..=2)
        .prop_flat_map(|extra| {
            let n = extra + 1;
            (
                Just(extra),
                prop::collection::vec(any::<bool>(), n - 1),
                prop::collection::vec(any::<bool>(), n),
                prop::collection::vec(prop::option::of(0..n), n),
                0u8..3,
                any::<bool>(),
                any::<bool>(),
                any::<bool>(),
                any::<bool>(),
            )
        })
        .prop_map(
            |(extra, chain_pause, ether, back, stop, throws, slow, self_interrupt, halted)| {
                Activity {
                    extra,
                    chain_pause,
                    ether,
                    back,
                    stop,
                    throws,
                    slow,
                    self_interrupt,
                    halted,
                }
            },
        )
}

fn layer() -> impl Strategy<Value = Layer> {
    (
        prop::collection::vec(activity(), 2..=3),
        0u8..4,
        any::<bool>(),
    )
        .prop_map(|(activities, constraint, machine)| Layer {
            activities,
            constraint,
            machine,
        })
}

fn state_name(k: usize) -> String {
    if k == 0 {
        "start".into()
    } else {
        format!("s{k}")
    }
}

fn model(l: &Layer) -> String {
    let mut services = Vec::new();
    let mut halted = Vec::new();
    for (i, a) in l.activities.iter().enumerate() {
        let n = a.extra + 1;
        let mut codels = Vec::new();
        for k in 0..n {
            let mut yields: Vec<String> = Vec::new();
            if k + 1 < n {
                let next = state_name(k + 1);
                yields.push(if a.chain_pause[k] {
                    format!("pause::{next}")
                } else {
                    next
                });
            }
            if a.ether[k] || k + 1 == n {
                yields.push("ether".into());
            }
            if let Some(b) = a.back[k] {
                let y = format!("pause::{}", state_name(b));
                if !yields.contains(&y) {
                    yields.push(y);
                }
            }
            let yields: Vec<String> = yields.iter().map(|y| format!("\"{y}\"")).collect();
            let throws = if a.throws && k + 1 == n {
                r#", throws: ["e"]"#
            } else {
                ""
            };
            codels.push(format!(
                "(state: \"{}\", yields: [{}]{throws})",
                state_name(k),
                yields.join(", ")
            ));
        }
        match a.stop {
            1 => codels.push(r#"(state: "stop", yields: ["ether"])"#.into()),
            2 => codels.push(r#"(state: "stop", yields: ["pause::stop", "ether"])"#.into()),
            _ => {}
        }
        let interrupts = if a.self_interrupt {
            format!(r#"interrupts: ["A{i}"], "#)
        } else {
            String::new()
        };
        let task = if a.slow { "slow" } else { "fast" };
        services.push(format!(
            "(name: \"A{i}\", kind: Activity, task: \"{task}\", {interrupts}codels: [{}])",
            codels.join(", ")
        ));
        if a.halted {
            halted.push(format!("\"A{i}\""));
        }
    }
    if !halted.is_empty() {
        services.push(format!(
            "(name: \"Halt\", kind: Function, interrupts: [{}])",
            halted.join(", ")
        ));
    }
    let constraint = match l.constraint {
        1 => r#"Exclusive(services: ["m.A0", "m.A1"])"#.to_string(),
        2 => {
            let all: Vec<String> = (0..l.activities.len())
                .map(|i| format!("\"m.A{i}\""))
                .collect();
            format!("AtMost(max: 1, services: [{}])", all.join(", "))
        }
        3 => r#"Requires(service: "m.A0", active: ["m.A1"])"#.to_string(),
        _ => String::new(),
    };
    let machine = if l.machine {
        r#", codels: [(state: "start", yields: ["pause::run"]), (state: "run", yields: ["pause::run", "ether"])]"#
    } else {
        ""
    };
    format!(
        r#"System(name: "random", modules: [(name: "m",
            tasks: [(name: "fast", period: 1{machine}), (name: "slow", period: 2)],
            services: [{}])],
        constraints: [{constraint}],
        properties: [DeadlockFree])"#,
        services.join(",\n")
    )
}

/// The reachable states and every transition between them, by breadth-first search.
fn explore(sys: &System) -> (Vec<State>, Vec<(usize, bip_model::OwnedStep, State)>) {
    let mut seen = HashSet::from([sys.initial_state()]);
    let mut states = vec![sys.initial_state()];
    let mut queue = VecDeque::from([0usize]);
    let mut transitions = Vec::new();
    while let Some(k) = queue.pop_front() {
        let s = states[k].clone();
        for (step, next) in sys.successors(&s).expect("no range error") {
            if seen.insert(next.clone()) {
                states.push(next.clone());
                queue.push_back(states.len() - 1);
            }
            transitions.push((k, step, next));
        }
        assert!(states.len() < 200_000, "a random layer should stay small");
    }
    (states, transitions)
}

/// The value of variable `var` of component `comp`, or `None` if it has none.
fn var(sys: &System, s: &State, comp: u32, name: &str) -> Option<bool> {
    sys.atom_of(comp)
        .var_index(name)
        .map(|v| sys.value(s, comp, v) != 0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    #[test]
    fn random_layers_expand_soundly(l in layer()) {
        let text = model(&l);
        let sys = load_str("random.ron", &text).unwrap_or_else(|e| panic!("{}\n{text}", e.summary()));
        let map = sys.genom.as_ref().expect("a map");
        let (states, transitions) = explore(&sys);
        let comps: Vec<u32> = (0..l.activities.len())
            .map(|i| sys.component_index(&format!("m_A{i}")).expect("an activity component"))
            .collect();
        let active = |s: &State, i: usize| sys.location_name(s, comps[i]) != "ether";
        let machine = sys.component_index("m_fast");
        prop_assert_eq!(machine.is_some(), l.machine);
        // nothing requests the machine; it runs (its `start` codel fires) in some run
        prop_assert!(sys.interaction_index("m_fast_request").is_none());
        if l.machine {
            let start = sys.interaction_index("m_fast_start").expect("the machine's start");
            prop_assert!(
                transitions.iter().any(|(_, st, _)| st.label == Label::Interaction(start)),
                "the machine never starts\n{}", text
            );
        }
        for s in &states {
            for &c in comps.iter().chain(&machine) {
                let idle = sys.location_name(s, c) == "ether";
                let req = var(&sys, s, c, "req").expect("req");
                let paused = var(&sys, s, c, "paused").expect("paused");
                let stopping = var(&sys, s, c, "stopping").unwrap_or(false);
                prop_assert!(!(idle && stopping), "stopping at ether\n{text}");
                prop_assert!(!(idle && !req && paused), "paused with nothing to do\n{text}");
            }
            match l.constraint {
                1 => prop_assert!(!(active(s, 0) && active(s, 1)), "Exclusive broken\n{text}"),
                2 => prop_assert!((0..comps.len()).filter(|&i| active(s, i)).count() <= 1, "AtMost broken\n{text}"),
                _ => {}
            }
        }
        let a0 = map.service("m", "A0").expect("A0");
        for (from, step, _) in &transitions {
            let Label::Interaction(i) = step.label else { continue };
            for service in &map.modules[0].services {
                for codel in &service.codels {
                    if codel.run != i {
                        continue;
                    }
                    // every codel step takes one of the codel's yields
                    let comp = service.component.expect("an activity");
                    let pick = step.picks.iter().find(|p| p.component == comp).expect("the activity takes part");
                    let y = codel.yield_of(pick.transition);
                    prop_assert!(y.is_some(), "no yield for a step of {}\n{text}", codel.state);
                    // `Requires` holds for every gated step of A0
                    if l.constraint == 3 && service.name == a0.name {
                        let stopping = var(&sys, &states[*from], comp, "stopping").unwrap_or(false);
                        prop_assert!(stopping || active(&states[*from], 1), "Requires broken\n{text}");
                    }
                }
            }
        }
        // the printed expansion reloads with the same reachable states
        let printed = expand_str("random.ron", &text).expect("expands").to_ron().expect("prints");
        let again = load_str("expanded.ron", &printed).expect("reloads");
        let (states2, _) = explore(&again);
        let a: HashSet<State> = states.into_iter().collect();
        let b: HashSet<State> = states2.into_iter().collect();
        prop_assert_eq!(a, b);
    }
}
