//! Async codels (docs/genom.md, "Async codels"): the fixture's import, expansion and
//! meaning (an async codel lets its task run another activity), bad inputs, and random
//! activities explored against a naive interpreter of what the documentation says.

use crate::support;
use support::errors::assert_error;

use std::collections::BTreeSet;

use crate::support::graphs::{reachable_graph, same_graph};

use bip_lang::{expand_str, load_str};
use bip_model::{Label, State, System};
use proptest::prelude::*;

fn camera(properties: &str) -> String {
    format!(
        r#"System(name: "camera", tick_ms: 10, modules: [Gen("genom3/camera.gen")],
        properties: [{properties}])"#
    )
}

/// A model file's name in robots/tests, where the fixture's `Gen` paths start.
fn in_robots_tests() -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../robots/tests/camera.ron")
        .display()
        .to_string()
}

fn load(text: &str) -> System {
    load_str(&in_robots_tests(), text).unwrap_or_else(|e| panic!("{}\n{text}", e.summary()))
}

fn interaction_name(sys: &System, label: Label) -> &str {
    let Label::Interaction(i) = label else {
        panic!("a GenoM layer has no internal steps")
    };
    &sys.interactions[i as usize].name
}

#[test]
fn an_async_gen_codel_imports_as_an_async_codel() {
    let def = expand_str(&in_robots_tests(), &camera("DeadlockFree"))
        .expect("expands")
        .to_ron()
        .expect("prints");
    for connector in [
        "camera_Capture_wait_start",
        "camera_Capture_wait_return",
        "camera_Capture_wait",
        "camera_Capture_wait_fail",
    ] {
        assert!(def.contains(&format!("\"{connector}\"")), "{connector}");
    }
    // synchronous codels have no start or return of their own
    assert!(!def.contains("camera_Capture_publish_start"));
    assert!(def.contains(r#"(name: "busy", ty: Int(0, 1), init: 0)"#));
    let sys = load(&camera("DeadlockFree"));
    let map = sys.genom.as_ref().expect("a map");
    let wait = map.codel("camera", "Capture", "wait").expect("the codel");
    let apart = wait.apart.expect("async in the map");
    assert_eq!(
        sys.interactions[apart.start as usize].name,
        "camera_Capture_wait_start"
    );
    assert!(map
        .codel("camera", "Capture", "publish")
        .expect("the codel")
        .apart
        .is_none());
}

/// The property the issue asks for: while `Capture`'s grab runs apart, `Expose` (same
/// task) runs its codels, and time passes; the grab's outcome comes only after its return.
#[test]
fn an_async_codel_lets_its_task_run_another_activity() {
    let sys = load(&camera("DeadlockFree"));
    let capture = sys.component_index("camera_Capture").expect("Capture");
    let busy = sys.atom_of(capture).var_index("busy").expect("busy");
    let running = |s: &State| sys.value(s, capture, busy) != 0;
    let mut seen = std::collections::HashSet::from([sys.initial_state()]);
    let mut queue = vec![sys.initial_state()];
    let (mut expose_ran, mut tick_passed, mut outcome_without_return) = (false, false, false);
    while let Some(s) = queue.pop() {
        for (step, next) in sys.successors(&s).expect("no range error") {
            let name = interaction_name(&sys, step.label);
            if running(&s) {
                expose_ran |= name.starts_with("camera_Expose_") && name != "camera_Expose_request";
                tick_passed |= name == "tick";
                outcome_without_return |= name == "camera_Capture_wait";
            }
            if seen.insert(next.clone()) {
                queue.push(next);
            }
        }
    }
    assert!(expose_ran, "Expose never ran while the grab ran apart");
    assert!(tick_passed, "no time passed while the grab ran apart");
    assert!(!outcome_without_return, "an outcome came before the return");
}

/// The codel's conditions gate its start, never its outcome; `yield(m.S.s)` names the
/// outcome and `m.S@start` the activity waiting for an async `start`.
#[test]
fn constraints_gate_the_start_and_names_reach_the_outcome() {
    let text = r#"System(name: "plan", modules: [(name: "m", tasks: [(name: "t", period: 2)],
        services: [
            (name: "Plan", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["ether"], async: true)]),
            (name: "Map", kind: Activity, task: "t", codels: [
                (state: "start", yields: ["pause::start", "ether"])]),
        ])],
        constraints: [Requires(service: "m.Plan", active: ["m.Map"])],
        properties: [
            Reachable(name: "planning", expr: "m.Plan@start && !active(m.Map)"),
            Response(name: "planned", trigger: "request(m.Plan)", response: "yield(m.Plan.start, ether)", within: 9),
        ])"#;
    let sys = load(text);
    let map_active = |s: &State| {
        let c = sys.component_index("m_Map").expect("Map");
        sys.location_name(s, c) != "ether"
    };
    let mut seen = std::collections::HashSet::from([sys.initial_state()]);
    let mut queue = vec![sys.initial_state()];
    let (mut started, mut outcome_without_map) = (0, false);
    while let Some(s) = queue.pop() {
        for (step, next) in sys.successors(&s).expect("no range error") {
            match interaction_name(&sys, step.label) {
                "m_Plan_start_start" => {
                    assert!(map_active(&s), "the start was not gated");
                    started += 1;
                }
                "m_Plan_start" => outcome_without_map |= !map_active(&s),
                _ => {}
            }
            if seen.insert(next.clone()) {
                queue.push(next);
            }
        }
    }
    assert!(started > 0, "the async start never ran");
    assert!(outcome_without_map, "the outcome was gated too");
    let map = sys.genom.as_ref().expect("a map");
    let plan = map.codel("m", "Plan", "start").expect("the codel");
    assert_eq!(plan.gated(), plan.apart.expect("async").start);
    assert_eq!(plan.holds.len(), 1, "{:?}", plan.holds);
}

#[test]
fn an_async_codel_in_a_timed_model_is_refused_at_its_place() {
    let text = r#"System(name: "t", tick_ms: 10, time: Exact, cpus: [(name: "main", cores: 1, preemption: Job)],
        modules: [(name: "m", tasks: [(name: "t", period: 1)],
            services: [(name: "S", kind: Activity, task: "t",
                codels: [(state: "start", yields: ["ether"], wcet: "1ms", async: true)])])])"#;
    assert_error(text, "codel `start` of `m.S` is async", "start");
}

// ---- random activities against a naive interpreter ----

/// Activity `A` of task `t` (period `period`, aperiodic for 0) with codels `start` (maybe async), `s1`
/// (async) and maybe `stop` (maybe async), and activity `B` of the same task, whose
/// `start` ends at once. `A` may interrupt itself: its request while it runs takes it to
/// its stop path.
#[derive(Clone, Debug)]
struct Layer {
    /// 0: aperiodic, and then no codel pauses (no sleeper, so no wake-ups).
    period: i64,
    start_async: bool,
    /// `start` yields `s1` through a pause.
    start_pauses: bool,
    /// `s1` may pause back to itself (it always may end).
    s1_loops: bool,
    /// 0: no stop codel; 1: a synchronous one; 2: an async one.
    stop: u8,
    self_interrupt: bool,
}

fn layer() -> impl Strategy<Value = Layer> {
    (
        0i64..=3,
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        0u8..3,
        any::<bool>(),
    )
        .prop_map(
            |(period, start_async, start_pauses, s1_loops, stop, self_interrupt)| Layer {
                period,
                start_async,
                start_pauses: start_pauses && period > 0,
                s1_loops: s1_loops && period > 0,
                stop,
                self_interrupt,
            },
        )
}

fn model(l: &Layer) -> String {
    let asynchronous = |a: bool| if a { ", async: true" } else { "" };
    let start = if l.start_pauses { "pause::s1" } else { "s1" };
    let s1 = if l.s1_loops {
        r#""pause::s1", "ether""#
    } else {
        r#""ether""#
    };
    let stop = match l.stop {
        0 => String::new(),
        k => format!(
            r#", (state: "stop", yields: ["ether"]{})"#,
            asynchronous(k == 2)
        ),
    };
    let interrupts = if l.self_interrupt {
        r#"interrupts: ["A"], "#
    } else {
        ""
    };
    let task = match l.period {
        0 => r#"(name: "t")"#.to_string(),
        p => format!(r#"(name: "t", period: {p})"#),
    };
    format!(
        r#"System(name: "apart", modules: [(name: "m", tasks: [{task}],
            services: [
                (name: "A", kind: Activity, task: "t", {interrupts}codels: [
                    (state: "start", yields: ["{start}"]{}),
                    (state: "s1", yields: [{s1}], async: true){stop}]),
                (name: "B", kind: Activity, task: "t", codels: [(state: "start", yields: ["ether"])]),
            ])],
        properties: [DeadlockFree])"#,
        asynchronous(l.start_async),
    )
}

/// Where `A` is: `ether`, or at the state of one of its codels (0 `start`, 1 `s1`, 2
/// `stop`).
type Where = Option<u8>;

/// A's (where, req, paused, stopping, which async codel runs: 0 none or 1 + its codel,
/// returned), B's (req, paused), and the ticks modulo the period.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
struct RefState {
    a: Where,
    req: bool,
    paused: bool,
    stopping: bool,
    busy: u8,
    returned: bool,
    b_req: bool,
    b_paused: bool,
    phase: i64,
}

const CODELS: [&str; 3] = ["start", "s1", "stop"];

fn is_async(l: &Layer, k: u8) -> bool {
    match k {
        0 => l.start_async,
        1 => true,
        _ => l.stop == 2,
    }
}

/// The yields of A's codel `k`: (to, pauses), with `None` for `ether`.
fn yields(l: &Layer, k: u8) -> Vec<(Where, bool)> {
    match k {
        0 => vec![(Some(1), l.start_pauses)],
        1 if l.s1_loops => vec![(Some(1), true), (None, false)],
        _ => vec![(None, false)],
    }
}

/// The number an async codel has in the activity's `busy`: 1 + its rank among the
/// activity's async codels.
fn number(l: &Layer, k: u8) -> u8 {
    1 + (0..k).filter(|&j| is_async(l, j)).count() as u8
}

/// The naive interpreter, as docs/genom.md says: codels are urgent and `A`'s run before
/// `B`'s; a synchronous codel runs where its activity is, unpaused, with no async codel of
/// the activity running; an async codel starts there (the activity stays) and returns
/// whenever the world lets it (with requests and ticks, below every codel); where the
/// activity still waits for it, its outcome waits for the task's next period boundary
/// and is then the codel's normal outcome or error path; elsewhere it is dropped. A
/// request of a self-interrupting `A` while it runs takes it to `stop` (or `ether`),
/// dropping an outcome that waits, never the running codel. An aperiodic task has no
/// boundaries: what a periodic one leaves for its next boundary (a start, a queued
/// restart, a stop path, an outcome) is ready at once.
fn reference_successors(l: &Layer, s: &RefState) -> Vec<(String, RefState)> {
    let periodic = l.period > 0;
    let mut codels = Vec::new();
    let outcome = |codels: &mut Vec<(String, RefState)>, label: String, k: u8, base: RefState| {
        for (to, pauses) in yields(l, k) {
            let mut n = base;
            match to {
                Some(t) => {
                    n.a = Some(t);
                    n.paused = pauses;
                }
                None => {
                    n.a = None;
                    n.stopping = false;
                    n.paused = n.req && periodic;
                }
            }
            codels.push((label.clone(), n));
        }
        let mut n = base;
        n.a = None;
        n.stopping = false;
        n.paused = n.req && periodic;
        codels.push((format!("{label}_fail"), n));
    };
    // A's codel at `k`, from `ether` (its start) or its location
    let runs_from = match s.a {
        None if s.req && !s.paused && s.busy == 0 => Some((0, true)),
        Some(k) if !s.paused && (s.busy == 0 || s.returned) => Some((k, false)),
        _ => None,
    };
    if let Some((k, from_ether)) = runs_from {
        let name = format!("A_{}", CODELS[k as usize]);
        let mut base = *s;
        if from_ether {
            base.req = false;
        }
        if !is_async(l, k) {
            outcome(&mut codels, name, k, base);
        } else if s.returned {
            base.returned = false;
            outcome(&mut codels, name, k, base);
        } else {
            base.a = Some(k);
            base.busy = number(l, k);
            codels.push((format!("{name}_start"), base));
        }
    }
    if codels.is_empty() && s.b_req && !s.b_paused {
        for label in ["B_start", "B_start_fail"] {
            let n = RefState {
                b_req: false,
                b_paused: false,
                ..*s
            };
            codels.push((label.to_string(), n));
        }
    }
    if !codels.is_empty() {
        return codels;
    }
    let mut out = Vec::new();
    let phase = (s.phase + 1) % l.period.max(1);
    out.push((
        "tick".to_string(),
        RefState {
            paused: s.paused && phase != 0,
            b_paused: s.b_paused && phase != 0,
            phase,
            ..*s
        },
    ));
    if !s.b_req {
        out.push((
            "B_request".into(),
            RefState {
                b_req: true,
                b_paused: periodic,
                ..*s
            },
        ));
    }
    match s.a {
        None if !s.req => out.push((
            "A_request".into(),
            RefState {
                req: true,
                paused: periodic,
                ..*s
            },
        )),
        None if l.self_interrupt => out.push(("A_request".into(), *s)),
        Some(_) if l.self_interrupt => {
            let mut n = RefState { req: true, ..*s };
            if l.stop == 0 {
                n.a = None;
                n.paused = periodic;
                n.returned = false;
            } else {
                if !s.stopping {
                    n.a = Some(2);
                    n.stopping = true;
                    n.returned = false;
                }
                n.paused &= periodic;
            }
            out.push(("A_request".into(), n));
        }
        _ => {}
    }
    if s.busy != 0 {
        let k = (0..3u8)
            .find(|&k| is_async(l, k) && number(l, k) == s.busy)
            .expect("a running codel");
        let mut n = RefState { busy: 0, ..*s };
        if s.a == Some(k) {
            n.returned = true;
            n.paused = periodic;
        }
        out.push((format!("A_{}_return", CODELS[k as usize]), n));
    }
    out
}

fn reference_graph(l: &Layer) -> BTreeSet<(RefState, String, RefState)> {
    let first = RefState {
        a: None,
        req: false,
        paused: false,
        stopping: false,
        busy: 0,
        returned: false,
        b_req: false,
        b_paused: false,
        phase: 0,
    };
    reachable_graph(first, |s| reference_successors(l, s), |&s| s)
}

/// The expanded system's reachable graph, in the interpreter's terms.
fn system_graph(sys: &System) -> BTreeSet<(RefState, String, RefState)> {
    let a = sys.component_index("m_A").expect("A");
    let b = sys.component_index("m_B").expect("B");
    let clock = sys.component_index("clock").expect("the clock");
    let value = |s: &State, comp: u32, name: &str| {
        sys.atom_of(comp)
            .var_index(name)
            .map_or(0, |v| sys.value(s, comp, v))
    };
    let view = |s: &State| RefState {
        a: match sys.location_name(s, a) {
            "ether" => None,
            l => Some(CODELS.iter().position(|c| *c == l).expect("a codel state") as u8),
        },
        req: value(s, a, "req") != 0,
        paused: value(s, a, "paused") != 0,
        stopping: value(s, a, "stopping") != 0,
        busy: value(s, a, "busy") as u8,
        returned: value(s, a, "returned") != 0,
        b_req: value(s, b, "req") != 0,
        b_paused: value(s, b, "paused") != 0,
        phase: value(s, clock, "n"),
    };
    let steps = |s: &State| {
        sys.successors(s)
            .expect("no range error")
            .into_iter()
            .map(|(step, next)| {
                let name = interaction_name(sys, step.label);
                (name.strip_prefix("m_").unwrap_or(name).to_string(), next)
            })
            .collect()
    };
    reachable_graph(sys.initial_state(), steps, view)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn random_async_codels_step_as_the_reference_says(l in layer()) {
        let text = model(&l);
        let sys = load(&text);
        same_graph(&system_graph(&sys), &reference_graph(&l), &text)?;
    }
}
