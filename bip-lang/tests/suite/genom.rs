//! The GenoM layer from the outside: bad input gets an error at the offending text, the
//! expanded model reloads with the same behaviour, and the engine's map fits the system.

use crate::support;
use support::errors::{assert_error, first_error};

use std::collections::HashSet;

use bip_lang::{expand_str, load_str, parse_str};
use bip_model::{State, System};

/// A valid model: `sick` and `ndd`, one constraint; each test breaks one thing.
const GOOD: &str = r#"System(
    name: "good",
    modules: [
        (
            name: "sick",
            tasks: [(name: "acquire", period: 1)],
            ports: [(name: "scan")],
            services: [
                (name: "Scan", kind: Activity, task: "acquire",
                 codels: [
                     (state: "start", yields: ["pause::scan"]),
                     (state: "scan",  yields: ["pause::scan", "ether"], writes: ["scan"]),
                 ]),
                (name: "Stop", kind: Function, interrupts: ["Scan"]),
            ],
        ),
        (
            name: "ndd",
            tasks: [(name: "nav", period: 2)],
            services: [
                (name: "Init", kind: Function),
                (name: "GoTo", kind: Activity, task: "nav", after: ["Init"],
                 codels: [
                     (state: "start", yields: ["move"]),
                     (state: "move",  yields: ["pause::move", "ether"]),
                     (state: "stop",  yields: ["ether"]),
                 ]),
            ],
        ),
    ],
    constraints: [
        Requires(service: "ndd.GoTo", active: ["sick.Scan"]),
    ],
    properties: [
        DeadlockFree,
        Invariant(name: "sees", expr: "ndd.GoTo@move => active(sick.Scan) || !active(sick.Scan)"),
    ],
)"#;

fn bad(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "`{from}` is not in the model");
    GOOD.replacen(from, to, 1)
}

#[test]
fn the_base_model_is_good() {
    let sys = load_str("good.ron", GOOD).unwrap_or_else(|e| panic!("{}", e.summary()));
    assert!(sys.genom.is_some());
}

#[test]
fn a_codel_yielding_to_an_undeclared_state() {
    let text = bad(
        r#"yields: ["pause::move", "ether"]"#,
        r#"yields: ["pause::mvoe", "ether"]"#,
    );
    assert_error(
        &text,
        "yields to `mvoe`, which is not a codel state",
        "pause::mvoe",
    );
    let (_, _, (line, col)) = first_error(&text);
    assert_eq!((line, col), (25, 49));
}

#[test]
fn no_path_to_ether() {
    // an activity that runs until interrupted is one GenoM3 accepts: only `stop` must end
    let text = bad(
        r#"(state: "move",  yields: ["pause::move", "ether"]),"#,
        r#"(state: "move",  yields: ["pause::move"]),"#,
    );
    load_str("forever.ron", &text).unwrap_or_else(|e| panic!("{}", e.summary()));
    let text = bad(
        r#"(state: "stop",  yields: ["ether"]),"#,
        r#"(state: "stop",  yields: ["pause::stop"]),"#,
    );
    assert_error(&text, "no path from `stop` to `ether`", "stop");
}

#[test]
fn an_unknown_service_in_a_constraint() {
    let text = bad(r#"active: ["sick.Scan"]"#, r#"active: ["sick.Scna"]"#);
    assert_error(&text, "module `sick` has no service `Scna`", "Scna");
    let text = bad(r#"service: "ndd.GoTo""#, r#"service: "nav.GoTo""#);
    assert_error(&text, "unknown module `nav`", "nav");
    let text = bad(r#"service: "ndd.GoTo""#, r#"service: "GoTo""#);
    assert_error(&text, "expected `module.Service`", "GoTo");
}

#[test]
fn a_task_period_of_zero() {
    let text = bad(r#"(name: "nav", period: 2)"#, r#"(name: "nav", period: 0)"#);
    assert_error(&text, "task `nav` has period 0", "0");
    let (_, _, (line, _)) = first_error(&text);
    assert_eq!(line, 19);
}

#[test]
fn codel_automaton_errors() {
    let cases = [
        // missing start
        (
            r#"(state: "start", yields: ["move"]),"#,
            "",
            "has no `start` codel",
            "GoTo",
        ),
        // pause::ether
        (
            r#"yields: ["pause::move", "ether"]"#,
            r#"yields: ["pause::ether"]"#,
            "`pause::ether` is not a yield",
            "pause::ether",
        ),
        // a codel nobody reaches
        (
            r#"(state: "stop",  yields: ["ether"]),"#,
            r#"(state: "stop",  yields: ["ether"]), (state: "lost", yields: ["ether"]),"#,
            "never reached",
            "lost",
        ),
        // a codel state named like a generated port
        (
            r#"(state: "stop",  yields: ["ether"]),"#,
            r#"(state: "stop",  yields: ["ether", "tick"]), (state: "tick", yields: ["ether"]),"#,
            "cannot be named `tick`",
            "tick",
        ),
        // duplicate yields and codel states
        (
            r#"yields: ["pause::move", "ether"]"#,
            r#"yields: ["ether", "ether"]"#,
            "duplicate yield",
            "ether",
        ),
        // an activity without task, a task that does not exist
        (
            r#"kind: Activity, task: "nav", after"#,
            r#"kind: Activity, after"#,
            "has no `task`",
            "GoTo",
        ),
        (
            r#"kind: Activity, task: "nav", after"#,
            r#"kind: Activity, task: "navi", after"#,
            "no task `navi`",
            "navi",
        ),
        // a function has one codel, at `start`, yielding `ether`, and no task
        (
            r#"(name: "Init", kind: Function)"#,
            r#"(name: "Init", kind: Function, codels: [(state: "main", yields: ["ether"])])"#,
            "not an activity; it has one codel, at `start`, yielding `ether`",
            "main",
        ),
        (
            r#"(name: "Init", kind: Function)"#,
            r#"(name: "Init", kind: Function, codels: [(state: "start", yields: ["ether"], async: true)])"#,
            "the codel of `Init` cannot be async",
            "start",
        ),
        // a written port (or ids field) that does not exist
        (
            r#"writes: ["scan"]"#,
            r#"writes: ["scna"]"#,
            "no out port or ids field `scna`",
            "scna",
        ),
    ];
    for (from, to, words, covered) in cases {
        assert_error(&bad(from, to), words, covered);
    }
}

#[test]
fn service_reference_errors() {
    let cases = [
        (
            r#"after: ["Init"]"#,
            r#"after: ["Inti"]"#,
            "module `ndd` has no service `Inti`",
            "Inti",
        ),
        // a service of another module: `after` names this module's services alone
        (
            r#"after: ["Init"]"#,
            r#"after: ["sick.Scan"]"#,
            "`after` names services of the same module, by their names alone",
            "sick.Scan",
        ),
        (
            r#"interrupts: ["Scan"]"#,
            r#"interrupts: ["Stop"]"#,
            "`Stop` is not an activity",
            "Stop",
        ),
        (
            r#"active: ["sick.Scan"]"#,
            r#"active: ["sick.Stop"]"#,
            "`sick.Stop` is not an activity",
            "sick.Stop",
        ),
        (
            r#"Requires(service: "ndd.GoTo", active: ["sick.Scan"]),"#,
            r#"Fresh(service: "ndd.GoTo", port: "sick.pose", max_age: 2),"#,
            "module `sick` has no port `pose`",
            "pose",
        ),
        (
            r#"Requires(service: "ndd.GoTo", active: ["sick.Scan"]),"#,
            r#"AtMost(max: 0, services: ["ndd.GoTo", "sick.Scan"]),"#,
            "`max` is 0",
            "0",
        ),
        (
            r#"Requires(service: "ndd.GoTo", active: ["sick.Scan"]),"#,
            r#"Exclusive(services: ["ndd.GoTo", "ndd.Init"]),"#,
            "`ndd.Init` is not an activity",
            "ndd.Init",
        ),
    ];
    for (from, to, words, covered) in cases {
        assert_error(&bad(from, to), words, covered);
    }
}

#[test]
fn genom_names_in_expressions() {
    let inv = "ndd.GoTo@move => active(sick.Scan) || !active(sick.Scan)";
    let cases = [
        ("ndd.GoTo@mvoe", "has no codel state `mvoe`", "mvoe"),
        ("ndd.GoTo@start", "never rests at `start`", "start"),
        ("active(ndd.Init)", "`ndd.Init` is not an activity", "Init"),
        (
            "active(ndd.Goto)",
            "module `ndd` has no service `Goto`",
            "Goto",
        ),
        (
            "age(sick.scan) + 1 > 2",
            "may only be compared with a constant",
            "age(sick.scan)",
        ),
        (
            "age(sick.scan) < ndd_GoTo.req",
            "may only be compared with a constant",
            "ndd_GoTo.req",
        ),
        (
            "age(sick.scna) < 2",
            "module `sick` has no port `scna`",
            "scna",
        ),
        ("sick.Scan", "is a service, not a value", "Scan"),
        ("sick.scan > 0", "is a port, not a value", "scan"),
    ];
    for (expr, words, covered) in cases {
        assert_error(&bad(inv, expr), words, covered);
    }
}

#[test]
fn generated_names_are_reserved() {
    // a user component named like a module's component
    let text = bad(
        "    properties: [",
        r#"    atoms: {"A": Atom(locations: ["l"], initial: "l")},
    components: [(name: "sick", atom: "A")],
    properties: ["#,
    );
    assert_error(
        &text,
        "component `sick` has the name generated for module `sick`",
        "sick",
    );
    // two generated names that collide: module `a_b` service `C` and module `a` service `b_C`
    let collide = r#"System(name: "c", modules: [
        (name: "a_b", tasks: [(name: "t", period: 1)], services: [
            (name: "C", kind: Activity, task: "t", codels: [(state: "start", yields: ["ether"])])]),
        (name: "a", tasks: [(name: "t", period: 1)], services: [
            (name: "b_C", kind: Activity, task: "t", codels: [(state: "start", yields: ["ether"])])]),
    ])"#;
    assert_error(collide, "would generate `Activity_a_b_C` twice", "b_C");
    // a user connector that runs a codel outside its gate
    let text = bad(
        "    properties: [",
        r#"    connectors: [(name: "sneak", ports: ["ndd_GoTo.move"])],
    properties: ["#,
    );
    assert_error(
        &text,
        "`ndd_GoTo.move` is a generated port",
        "ndd_GoTo.move",
    );
    // but aborting an activity is open to any component
    let text = bad(
        "    properties: [",
        r#"    connectors: [(name: "halt", ports: ["ndd_GoTo.abort"])],
    properties: ["#,
    );
    assert!(load_str("ok.ron", &text).is_ok());
}

#[test]
fn bad_input_never_panics() {
    // cut the model at many places and drop single characters: errors, never a panic
    let rover = include_str!("../../../robots/rover.ron");
    for cut in (0..rover.len()).step_by(97) {
        if rover.is_char_boundary(cut) {
            let _ = load_str("cut.ron", &rover[..cut]);
            let mut dropped = rover.to_string();
            dropped.remove(cut);
            let _ = load_str("dropped.ron", &dropped);
        }
    }
}

/// Every state reachable in `sys` (a small model), by breadth-first search.
fn reachable(sys: &System) -> HashSet<State> {
    let mut seen = HashSet::from([sys.initial_state()]);
    let mut todo = vec![sys.initial_state()];
    while let Some(s) = todo.pop() {
        for (_, next) in sys.successors(&s).expect("no range error") {
            if seen.insert(next.clone()) {
                todo.push(next);
            }
        }
    }
    seen
}

#[test]
fn the_expanded_model_reloads_with_the_same_behaviour() {
    for (name, text) in [
        ("good", GOOD.to_string()),
        (
            "mini",
            include_str!("../../../robots/tests/mini.ron").to_string(),
        ),
    ] {
        let sys = load_str(name, &text).unwrap_or_else(|e| panic!("{}", e.summary()));
        let expanded = expand_str(name, &text).expect("expands");
        assert!(expanded.modules.is_empty() && expanded.constraints.is_empty());
        let printed = expanded.to_ron().expect("prints");
        let again = load_str("expanded.ron", &printed)
            .unwrap_or_else(|e| panic!("{}\n{printed}", e.summary()));
        assert!(again.genom.is_none(), "the printed model is plain core");
        assert_eq!(again.slot_ranges(), sys.slot_ranges());
        let (a, b) = (reachable(&sys), reachable(&again));
        assert!(a.len() > 50, "{name}: {} states", a.len());
        assert_eq!(a, b, "{name}: the same reachable states");
        // and printing is stable
        assert_eq!(
            parse_str("x", &printed)
                .expect("parses")
                .to_ron()
                .expect("prints"),
            printed
        );
    }
}

#[test]
fn the_engine_map_names_every_codel_and_yield() {
    let sys = load_str("good.ron", GOOD).expect("loads");
    let map = sys.genom.as_ref().expect("a map");
    assert_eq!(map.modules.len(), 2);
    assert_eq!(sys.interactions[map.tick as usize].name, "tick");
    let goto = map.service("ndd", "GoTo").expect("GoTo");
    assert_eq!(
        map.module("ndd").expect("ndd").tasks[goto.task.expect("task")].period,
        Some(2)
    );
    assert_eq!(
        sys.interactions[goto.request.expect("GoTo has a request") as usize].name,
        "ndd_GoTo_request"
    );
    let comp = goto.component.expect("an activity has a component");
    let atom = sys.atom_of(comp);
    for c in &goto.codels {
        assert_eq!(
            sys.interactions[c.run as usize].name,
            format!("ndd_GoTo_{}", c.state)
        );
        for y in &c.yields {
            assert!(!y.transitions.is_empty());
            for &t in &y.transitions {
                let tr = &atom.transitions[t as usize];
                assert_eq!(atom.ports[tr.port.expect("a port") as usize], c.state);
                let target = y.target.strip_prefix("pause::").unwrap_or(&y.target);
                assert_eq!(
                    atom.locations[tr.to as usize], target,
                    "{} yields {}",
                    c.state, y.target
                );
                // `pause::` is the yield that sets `paused`
                let pauses = tr.action.iter().any(|a| {
                    matches!(a.target, bip_model::Target::Local(v) if atom.vars[v as usize].name == "paused")
                        && a.value.is_const()
                });
                assert_eq!(
                    pauses,
                    y.target.starts_with("pause::"),
                    "{} yields {}",
                    c.state,
                    y.target
                );
            }
        }
    }
    // start runs from `ether` only (nothing yields `start`); the others from their location
    assert_eq!(goto.codels[0].yields[0].transitions.len(), 1);
    let held = map.codel("ndd", "GoTo", "move").expect("move");
    assert_eq!(held.holds.len(), 1);
    assert!(
        held.holds[0].text.contains("sick_Scan@ether"),
        "{}",
        held.holds[0].text
    );
    // a fresh system: GoTo is refused (Init has not run), Init is accepted
    let s = sys.initial_state();
    assert_eq!(goto.refused_by(&sys, &s).expect("evaluates").len(), 1);
    assert!(map
        .service("ndd", "Init")
        .expect("Init")
        .refused_by(&sys, &s)
        .expect("evaluates")
        .is_empty());
}

#[test]
fn errors_in_user_texts_point_into_them_through_rewriting_and_merging() {
    let model = |extra: &str, constraint: &str, invariant: &str| {
        GOOD.replace(
            "        Requires(service: \"ndd.GoTo\", active: [\"sick.Scan\"]),",
            &format!("        Requires(service: \"ndd.GoTo\", active: [\"sick.Scan\"]),\n        {constraint}"),
        )
        .replace(
            "    properties: [",
            &format!("    atoms: {{\"Door\": Atom(locations: [\"shut\", \"open\"], initial: \"shut\", ports: [\"see\"],\n        vars: [(name: \"seen\", ty: Bool)], transitions: [(from: \"shut\", port: \"see\", to: \"shut\")])}},\n    components: [(name: \"door\", atom: \"Door\")],\n    connectors: [{extra}],\n    properties: ["),
        )
        .replace(
            "ndd.GoTo@move => active(sick.Scan) || !active(sick.Scan)",
            invariant,
        )
    };
    let ok = model("", "", "true");
    assert!(
        load_str("ok.ron", &ok).is_ok(),
        "{}",
        load_str("ok.ron", &ok)
            .err()
            .map(|e| e.summary())
            .unwrap_or_default()
    );
    let cases = [
        // a `Guard` condition, rewritten, inside a codel connector's guard
        (
            "",
            r#"Guard(service: "ndd.GoTo", when: "active(sick.Scan) && door@opne"),"#,
            "true",
            "no location `opne`",
            "opne",
        ),
        // unchanged, inside a function's request guard
        (
            "",
            r#"Guard(service: "sick.Stop", when: "dor@open"),"#,
            "true",
            "unknown component `dor`",
            "dor",
        ),
        // an extension's guard and action, merged with generated ones
        (
            r#"(name: "ndd_GoTo_move", ports: ["door.see"], guard: "door.sen")"#,
            "",
            "true",
            "no variable `sen`",
            "sen",
        ),
        (
            r#"(name: "ndd_GoTo_move", ports: ["door.see"], action: "door.seen = active(sick.Scan) && ndd.Init")"#,
            "",
            "true",
            "is a service, not a value",
            "Init",
        ),
        (
            r#"(name: "ndd_GoTo_move", ports: ["door.see"], action: "door.seen = active(sick.Scan) + 1")"#,
            "",
            "true",
            "needs an integer",
            "active(sick.Scan)",
        ),
        // a property, rewritten, and DeadlockFree's terminal, merged with the idle excuse
        (
            "",
            "",
            "pending(ndd.GoTo) + 1 > 0",
            "needs an integer",
            "pending(ndd.GoTo)",
        ),
    ];
    for (extra, constraint, invariant, words, covered) in cases {
        assert_error(&model(extra, constraint, invariant), words, covered);
    }
    let terminal = ok.replace(
        "DeadlockFree,",
        r#"DeadlockFree(terminal: "active(sick.Scan) && door@ajar"),"#,
    );
    assert_error(&terminal, "no location `ajar`", "ajar");
}

/// The state reached from the initial one by the enabled steps named `names`, in order.
fn after_steps(sys: &System, names: &[&str]) -> State {
    let mut state = sys.initial_state();
    for name in names {
        let (_, next) = sys
            .successors(&state)
            .expect("no range error")
            .into_iter()
            .find(|(step, _)| sys.label_name(step.label) == *name)
            .unwrap_or_else(|| panic!("`{name}` is not enabled"));
        state = next;
    }
    state
}

#[test]
fn a_stuck_codel_names_the_constraints_that_hold_it() {
    let text = include_str!("../../../robots/rover-deadlock.ron");
    let sys = load_str("rover-deadlock.ron", text).expect("the model loads");
    let genom = sys.genom.as_ref().expect("a GenoM model");
    // at rest nothing waits, so nothing is stuck
    assert!(genom
        .stuck(&sys, &sys.initial_state())
        .expect("no range error")
        .is_empty());
    // GoTo requested while the laser is off: its start codel waits for Requires and Fresh
    let state = after_steps(&sys, &["ndd_GoTo_request"]);
    let stuck = genom.stuck(&sys, &state).expect("no range error");
    assert_eq!(stuck.len(), 1, "{stuck:?}");
    let s = &stuck[0];
    assert_eq!((s.module, s.service, s.codel), ("ndd", "GoTo", "start"));
    assert_eq!(s.after_ticks, 1, "the request waits for the next period");
    let kinds: Vec<String> = s.held_by.iter().map(|c| c.reason.to_string()).collect();
    // each by its name, its line and as written
    assert_eq!(
        kinds,
        [
            r#"navigate_with_laser (line 145): Requires(service: "ndd.GoTo", active: ["sick.Scan"])"#,
            r#"fresh_pose (line 146): Fresh(service: "ndd.GoTo", port: "pom.pose", max_age: 2)"#
        ],
        "{s}"
    );
    // once the laser scans, only the stale pose holds it
    let scanning = after_steps(
        &sys,
        &[
            "sick_Scan_request",
            "tick",
            "sick_Scan_start",
            "ndd_GoTo_request",
        ],
    );
    let held: Vec<String> = genom
        .stuck(&sys, &scanning)
        .expect("no range error")
        .iter()
        .filter(|s| s.service == "GoTo")
        .flat_map(|s| s.held_by.iter().map(|c| c.reason.to_string()))
        .collect();
    assert_eq!(held.len(), 1);
    assert!(
        held[0].starts_with("fresh_pose (line 146): Fresh("),
        "{held:?}"
    );
}
