//! Interrupts as GenoM3 applies them (docs/genom.md, "Interrupts"): the starvation of an
//! interrupting activity requested before its victim (`robots/tests/interrupts.ron`, its
//! module from `gripper.gen` and the same written in RON), and random modules explored
//! against a naive interpreter of what the documentation says requests, interrupts,
//! stop paths, periods and the declaration order do.

use std::collections::BTreeSet;

use crate::support::graphs::{reachable_graph, same_graph};
use std::path::Path;

use bip_lang::{expand_file, load_file, load_str};
use bip_model::{Label, State, System};
use proptest::prelude::*;

use crate::gen3::TempDir;

// ---- the fixture ----

fn fixture() -> System {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/tests/interrupts.ron");
    load_file(&path).unwrap_or_else(|e| panic!("{}", e.summary()))
}

/// The step named `step` from `s`, if it is enabled (the first one).
fn fire(sys: &System, s: &State, step: &str) -> Option<State> {
    let i = sys.interaction_index(step).expect("an interaction");
    sys.successors(s)
        .expect("no range error")
        .into_iter()
        .find(|(st, _)| st.label == Label::Interaction(i))
        .map(|(_, next)| next)
}

/// The names of the steps enabled in `s`.
fn enabled(sys: &System, s: &State) -> Vec<String> {
    sys.successors(s)
        .expect("no range error")
        .into_iter()
        .map(|(st, _)| sys.label_name(st.label))
        .collect()
}

fn location<'s>(sys: &'s System, s: &State, comp: &str) -> &'s str {
    let c = sys.component_index(comp).expect("a component");
    sys.location_name(s, c)
}

fn flag(sys: &System, s: &State, comp: &str, var: &str) -> bool {
    let c = sys.component_index(comp).expect("a component");
    let v = sys.atom_of(c).var_index(var).expect("a variable");
    sys.value(s, c, v) != 0
}

#[test]
fn an_interrupting_activity_requested_before_its_victim_is_not_starved() {
    let sys = fixture();
    for m in ["gripper", "hand"] {
        let (open, grasp) = (format!("{m}_Open"), format!("{m}_Grasp"));
        // `Open` is requested while `Grasp` is idle, then `Grasp`
        let s = sys.initial_state();
        let s = fire(&sys, &s, &format!("{open}_request")).expect("Open is accepted");
        let s = fire(&sys, &s, &format!("{grasp}_request")).expect("Grasp is accepted");
        assert!(flag(&sys, &s, &grasp, "req"));
        // before anything else, the pending `Open` interrupts the `Grasp` requested since
        assert_eq!(enabled(&sys, &s), [format!("{open}_interrupt")]);
        let s = fire(&sys, &s, &format!("{open}_interrupt")).expect("re-interrupts");
        assert!(!flag(&sys, &s, &grasp, "req") && location(&sys, &s, &grasp) == "ether");
        assert!(flag(&sys, &s, &open, "req"), "Open is still pending");
        // at the period boundary `Open` starts
        let s = fire(&sys, &s, "tick").expect("a tick");
        let s = fire(&sys, &s, "tick").expect("a tick");
        let s = fire(&sys, &s, &format!("{open}_start")).expect("Open starts");
        assert_eq!(location(&sys, &s, &open), "opening");
    }
}

#[test]
fn an_interrupting_activity_started_after_its_victim_interrupts_it() {
    let sys = fixture();
    for m in ["gripper", "hand"] {
        let (open, grasp) = (format!("{m}_Open"), format!("{m}_Grasp"));
        // `Grasp` runs; `Open` is requested: `Grasp` takes its stop path at once, and
        // `Open` starts once that has ended
        let s = sys.initial_state();
        let s = fire(&sys, &s, &format!("{grasp}_request")).expect("Grasp is accepted");
        let s = fire(&sys, &s, "tick").expect("a tick");
        let s = fire(&sys, &s, "tick").expect("a tick");
        let s = fire(&sys, &s, &format!("{grasp}_start")).expect("Grasp starts");
        let s = fire(&sys, &s, &format!("{open}_request")).expect("Open is accepted");
        assert_eq!(location(&sys, &s, &grasp), "stop");
        let s = fire(&sys, &s, "tick").expect("a tick");
        let s = fire(&sys, &s, "tick").expect("a tick");
        // the stop codel comes first (declaration order, and `Open` waits for it), then
        // `Open` starts
        assert_eq!(
            enabled(&sys, &s),
            [format!("{grasp}_stop"), format!("{grasp}_stop_fail")]
        );
        let s = fire(&sys, &s, &format!("{grasp}_stop")).expect("Grasp stops");
        let s = fire(&sys, &s, &format!("{open}_start")).expect("Open starts");
        assert_eq!(location(&sys, &s, &open), "opening");
        assert_eq!(location(&sys, &s, &grasp), "ether");
        // requested while `Open` runs, `Grasp` is not interrupted (GenoM3 sends the
        // interrupts of a request until it starts, not after)
        let s = fire(&sys, &s, &format!("{grasp}_request")).expect("Grasp is accepted");
        assert!(fire(&sys, &s, &format!("{open}_interrupt")).is_none());
    }
}

#[test]
fn the_gen_component_expands_as_the_module_written_in_ron() {
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/tests");
    let model = std::fs::read_to_string(fixtures.join("interrupts.ron")).expect("the model");
    let gen = std::fs::read_to_string(fixtures.join("gripper.gen")).expect("the component");
    // the module `hand`, written in RON, is the component of `gripper.gen`
    let written = model
        .split("Gen(\"gripper.gen\"),")
        .nth(1)
        .and_then(|rest| rest.split("\n    ],\n    properties").next())
        .expect("the RON module")
        .replace("\"hand\"", "\"gripper\"");
    let dir = TempDir::new();
    dir.write("gripper.gen", &gen);
    let expand = |name: &str, modules: &str| {
        let path = dir.write(
            name,
            &format!("System(name: \"g\", tick_ms: 10, modules: [{modules}])"),
        );
        expand_file(&path)
            .unwrap_or_else(|e| panic!("{}", e.summary()))
            .to_ron()
            .expect("prints")
    };
    let from_gen = expand("gen.ron", "Gen(\"gripper.gen\")");
    assert!(
        from_gen.contains("\"gripper_Open_interrupt\""),
        "{from_gen}"
    );
    assert_eq!(from_gen, expand("written.ron", &written));
}

// ---- random modules against a naive interpreter ----

#[derive(Clone, Debug)]
struct Activity {
    /// Whether `start` may also yield `ether` (it always yields `pause::main`).
    start_ether: bool,
    /// The yields of `main`: `pause::main`, `ether`, `pause::start` (`ether` always).
    main: (bool, bool),
    /// 0: no stop codel; 1: `stop` yields `ether`; 2: `stop` pauses first.
    stop: u8,
    /// The activities (by index, itself included) it interrupts.
    interrupts: Vec<bool>,
}

#[derive(Clone, Debug)]
struct Module {
    period: i64,
    activities: Vec<Activity>,
    /// A function `F` interrupting these activities, if any.
    function: Option<Vec<bool>>,
}

fn module() -> impl Strategy<Value = Module> {
    (2usize..=3, 1i64..=2)
        .prop_flat_map(|(n, period)| {
            let activity = (
                any::<bool>(),
                (any::<bool>(), any::<bool>()),
                0u8..3,
                prop::collection::vec(prop::bool::weighted(0.4), n),
            )
                .prop_map(|(start_ether, main, stop, interrupts)| Activity {
                    start_ether,
                    main,
                    stop,
                    interrupts,
                });
            (
                Just(period),
                prop::collection::vec(activity, n),
                prop::option::of(prop::collection::vec(any::<bool>(), n)),
            )
        })
        .prop_map(|(period, activities, function)| Module {
            period,
            activities,
            function,
        })
}

fn quoted(names: &[String]) -> String {
    let q: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
    q.join(", ")
}

fn victims(list: &[bool]) -> Vec<usize> {
    (0..list.len()).filter(|&k| list[k]).collect()
}

fn module_model(m: &Module) -> String {
    let mut services = Vec::new();
    for (i, a) in m.activities.iter().enumerate() {
        let mut start = vec!["pause::main".to_string()];
        if a.start_ether {
            start.push("ether".into());
        }
        let mut main = vec!["ether".to_string()];
        if a.main.0 {
            main.push("pause::main".into());
        }
        if a.main.1 {
            main.push("pause::start".into());
        }
        let mut codels = vec![
            format!("(state: \"start\", yields: [{}])", quoted(&start)),
            format!("(state: \"main\", yields: [{}])", quoted(&main)),
        ];
        match a.stop {
            1 => codels.push(r#"(state: "stop", yields: ["ether"])"#.into()),
            2 => codels.push(r#"(state: "stop", yields: ["pause::stop", "ether"])"#.into()),
            _ => {}
        }
        let names: Vec<String> = victims(&a.interrupts)
            .iter()
            .map(|k| format!("A{k}"))
            .collect();
        services.push(format!(
            "(name: \"A{i}\", kind: Activity, task: \"t\", interrupts: [{}], codels: [{}])",
            quoted(&names),
            codels.join(", ")
        ));
    }
    if let Some(f) = &m.function {
        let names: Vec<String> = victims(f).iter().map(|k| format!("A{k}")).collect();
        services.push(format!(
            "(name: \"F\", kind: Function, interrupts: [{}])",
            quoted(&names)
        ));
    }
    format!(
        r#"System(name: "interrupts", modules: [(name: "m",
            tasks: [(name: "t", period: {})],
            services: [{}])])"#,
        m.period,
        services.join(",\n")
    )
}

/// One activity as the documentation describes it: where it is (`ether` or a codel
/// state), whether a request waits (pending at `ether`, a restart queued elsewhere),
/// whether it waits for its task's next period boundary, whether it runs its stop path.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
struct Act {
    at: &'static str,
    req: bool,
    paused: bool,
    stopping: bool,
}

/// (the activities, ticks modulo the period)
type RefState = (Vec<Act>, i64);

const IDLE: Act = Act {
    at: "ether",
    req: false,
    paused: false,
    stopping: false,
};

/// An interrupt: a pending request is cancelled; a running activity takes its stop path
/// (ends at once without a stop codel); a stop path goes on, without a queued restart.
fn interrupt(m: &Module, k: usize, a: &mut Act) {
    if a.at == "ether" {
        a.req = false;
        a.paused = false;
    } else if m.activities[k].stop == 0 {
        *a = IDLE;
    } else {
        a.at = "stop";
        a.stopping = true;
        a.req = false;
    }
}

/// A request of activity `k`: refused if one is pending or running, unless `k`
/// interrupts itself (the request then replaces a pending one, or queues a restart of a
/// running one, whose stop path starts, or which ends at once without a stop codel).
fn request(m: &Module, k: usize, a: &Act) -> Option<Act> {
    let self_interrupt = m.activities[k].interrupts[k];
    let mut a = a.clone();
    if a.at == "ether" {
        if a.req && !self_interrupt {
            return None;
        }
        if !a.req {
            a.req = true;
            a.paused = true;
        }
    } else if !self_interrupt {
        return None;
    } else if m.activities[k].stop == 0 {
        a = Act {
            at: "ether",
            req: true,
            paused: true,
            stopping: false,
        };
    } else {
        a.at = "stop";
        a.stopping = true;
        a.req = true;
    }
    Some(a)
}

/// What a victim of a pending activity needs: a request outstanding, or a run outside its
/// stop path.
fn to_interrupt(a: &Act) -> bool {
    a.req || (a.at != "ether" && !a.stopping)
}

/// The yields of codel `state` of activity `k`, as (target, paused); `ether` as target.
fn yields(m: &Module, k: usize, state: &str) -> Vec<(&'static str, bool)> {
    let a = &m.activities[k];
    match state {
        "start" => {
            let mut out = vec![("main", true)];
            if a.start_ether {
                out.push(("ether", false));
            }
            out
        }
        "main" => {
            let mut out = vec![("ether", false)];
            if a.main.0 {
                out.push(("main", true));
            }
            if a.main.1 {
                out.push(("start", true));
            }
            out
        }
        _ if a.stop == 2 => vec![("stop", true), ("ether", false)],
        _ => vec![("ether", false)],
    }
}

/// The steps of activity `k` that run without waiting for time: its pending request's
/// interrupts sent again, and its codels (each yield, and the error path).
fn urgent(m: &Module, k: usize, (acts, phase): &RefState) -> Vec<(String, RefState)> {
    let mut out = Vec::new();
    let a = &acts[k];
    let others: Vec<usize> = victims(&m.activities[k].interrupts)
        .into_iter()
        .filter(|&v| v != k)
        .collect();
    if a.at == "ether" && a.req && others.iter().any(|&v| to_interrupt(&acts[v])) {
        let mut next = acts.clone();
        for &v in &others {
            interrupt(m, v, &mut next[v]);
        }
        out.push((format!("m_A{k}_interrupt"), (next, *phase)));
    }
    if a.paused {
        return out;
    }
    // the codel that runs: `start` from a pending request once what it interrupts has
    // ended, or the codel of the state it is at
    let (state, mut base) = if a.at == "ether" {
        if !a.req || others.iter().any(|&v| acts[v].at != "ether") {
            return out;
        }
        (
            "start",
            Act {
                req: false,
                ..a.clone()
            },
        )
    } else {
        (a.at, a.clone())
    };
    let end = |b: &Act| Act {
        at: "ether",
        req: b.req,
        paused: b.req,
        stopping: false,
    };
    for (to, paused) in yields(m, k, state) {
        let mut next = acts.clone();
        next[k] = if to == "ether" {
            end(&base)
        } else {
            Act {
                at: to,
                paused,
                ..base.clone()
            }
        };
        out.push((format!("m_A{k}_{state}"), (next, *phase)));
    }
    let mut next = acts.clone();
    base = end(&base);
    next[k] = base;
    out.push((format!("m_A{k}_{state}_fail"), (next, *phase)));
    out
}

/// The naive interpreter: the steps of the first activity (in declaration order) that has
/// any come first; then, with none, a tick (a period boundary every `period` ticks ends
/// the waits) or a request.
fn reference_successors(m: &Module, s: &RefState) -> Vec<(String, RefState)> {
    for k in 0..m.activities.len() {
        let out = urgent(m, k, s);
        if !out.is_empty() {
            return out;
        }
    }
    let (acts, phase) = s;
    let mut out = Vec::new();
    let next_phase = (phase + 1) % m.period;
    let ticked = acts
        .iter()
        .map(|a| Act {
            paused: a.paused && next_phase != 0,
            ..a.clone()
        })
        .collect();
    out.push(("tick".to_string(), (ticked, next_phase)));
    for k in 0..m.activities.len() {
        let Some(mine) = request(m, k, &acts[k]) else {
            continue;
        };
        let mut next = acts.clone();
        next[k] = mine;
        for v in victims(&m.activities[k].interrupts) {
            if v != k {
                interrupt(m, v, &mut next[v]);
            }
        }
        out.push((format!("m_A{k}_request"), (next, *phase)));
    }
    if let Some(f) = &m.function {
        let mut next = acts.clone();
        for v in victims(f) {
            interrupt(m, v, &mut next[v]);
        }
        out.push(("m_F_request".to_string(), (next, *phase)));
    }
    out
}

fn reference_graph(m: &Module) -> BTreeSet<(RefState, String, RefState)> {
    let first: RefState = (vec![IDLE; m.activities.len()], 0);
    reachable_graph(first, |s| reference_successors(m, s), |s| s.clone())
}

/// The expanded system's reachable graph, in the interpreter's terms.
fn system_graph(m: &Module, sys: &System) -> BTreeSet<(RefState, String, RefState)> {
    let comps: Vec<u32> = (0..m.activities.len())
        .map(|k| {
            sys.component_index(&format!("m_A{k}"))
                .expect("an activity")
        })
        .collect();
    let clock = sys.component_index("clock").expect("the clock");
    let view = |s: &State| -> RefState {
        let acts = comps
            .iter()
            .map(|&c| {
                let flag = |name: &str| {
                    sys.atom_of(c)
                        .var_index(name)
                        .is_some_and(|v| sys.value(s, c, v) != 0)
                };
                let at = match sys.location_name(s, c) {
                    "ether" => "ether",
                    "start" => "start",
                    "main" => "main",
                    "stop" => "stop",
                    l => panic!("no location {l}"),
                };
                Act {
                    at,
                    req: flag("req"),
                    paused: flag("paused"),
                    stopping: flag("stopping"),
                }
            })
            .collect();
        let phase = sys
            .atom_of(clock)
            .var_index("n")
            .map_or(0, |v| sys.value(s, clock, v));
        (acts, phase)
    };
    let steps = |s: &State| {
        let successors = sys.successors(s).expect("no range error");
        successors
            .into_iter()
            .map(|(step, next)| (sys.label_name(step.label), next))
            .collect()
    };
    reachable_graph(sys.initial_state(), steps, view)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn random_interrupts_step_as_the_reference_says(m in module()) {
        let text = module_model(&m);
        let sys = load_str("interrupts.ron", &text)
            .unwrap_or_else(|e| panic!("{}\n{text}", e.summary()));
        same_graph(&system_graph(&m, &sys), &reference_graph(&m), &text)?;
    }
}
