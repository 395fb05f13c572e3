//! Async codels (docs/genom.md, "Async codels"): the fixture's import, expansion and
//! meaning (an async codel lets its task run another activity), bad inputs, and random
//! activities explored against a naive interpreter of what the documentation says.

use crate::support;
use support::errors::assert_error;

use std::collections::BTreeSet;

use crate::support::graphs::{reachable_graph, same_graph};

use bip_lang::{expand_str, load_str};
use bip_model::{Label, State, System};
use bip_random_systems::genom_async::{model, reference_successors, step_name, Layer, RefState};
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
            |(period, start_async, start_pauses, s1_loops, stop, interrupt)| {
                Layer::new(period, start_async, start_pauses, s1_loops, stop, interrupt)
            },
        )
}

fn reference_graph(l: &Layer) -> BTreeSet<(RefState, String, RefState)> {
    reachable_graph(RefState::FIRST, |s| reference_successors(l, s), |&s| s)
}

/// The expanded system's reachable graph, in the interpreter's terms.
fn system_graph(sys: &System) -> BTreeSet<(RefState, String, RefState)> {
    let steps = |s: &State| {
        sys.successors(s)
            .expect("no range error")
            .into_iter()
            .map(|(step, next)| (step_name(sys, step.label), next))
            .collect()
    };
    reachable_graph(sys.initial_state(), steps, |s| RefState::of(sys, s))
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
