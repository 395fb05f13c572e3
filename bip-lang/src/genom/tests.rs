//! Tests of the expansion, checked by exploring the expanded systems with the one step
//! relation (`enabled_steps`, `fire`) and the one deadlock definition (`liveness`).

use std::collections::{HashMap, VecDeque};

use crate::load_str;
use crate::syntax::{PropertyDef, SystemDef};
use bip_model::State;
use bip_model::Steps;
use bip_model::{Liveness, LivenessChecker};
use bip_model::{PropertyKind, System};

/// What a breadth-first exploration found.
struct Explored {
    states: Vec<State>,
    /// For each state, its parent and the step name that led to it.
    parent: Vec<Option<(usize, String)>>,
    /// Deadlocks not excused by a `DeadlockFree` terminal condition.
    deadlocks: Vec<usize>,
    /// Invariants violated, with the first state violating each.
    violations: Vec<(String, usize)>,
    transitions: usize,
}

impl Explored {
    fn trace(&self, mut k: usize) -> Vec<String> {
        let mut out = Vec::new();
        while let Some((p, step)) = &self.parent[k] {
            out.push(step.clone());
            k = *p;
        }
        out.reverse();
        out
    }

    fn any(&self, sys: &System, expr: &str) -> bool {
        let e = compile_expr(sys, expr);
        self.states
            .iter()
            .any(|s| sys.eval(&e, s).expect("evaluates") != 0)
    }

    fn all(&self, sys: &System, expr: &str) -> bool {
        let e = compile_expr(sys, expr);
        self.states
            .iter()
            .all(|s| sys.eval(&e, s).expect("evaluates") != 0)
    }
}

/// Compiles a global expression, GenoM names allowed, over the model `sys` was loaded
/// from: it is added to the model as an invariant, which the expansion rewrites.
fn compile_expr(sys: &System, expr: &str) -> bip_model::eval::Expr {
    let mut def = MODELS
        .with(|d| d.borrow().get(&sys.name).cloned())
        .expect("the model was loaded with `load`");
    def.properties.push(PropertyDef::Invariant {
        name: "question".into(),
        expr: expr.into(),
    });
    let mut asked = crate::compile(&def).unwrap_or_else(|e| panic!("`{expr}`: {e:?}"));
    // a question must not change the model (an `age` nobody read before would add a slot)
    assert_eq!(
        asked.slot_ranges(),
        sys.slot_ranges(),
        "`{expr}` changes the state layout"
    );
    match asked.properties.pop().map(|p| p.kind) {
        Some(PropertyKind::Invariant(e)) => e,
        _ => unreachable!("the question is the last property"),
    }
}

thread_local! {
    static MODELS: std::cell::RefCell<HashMap<String, SystemDef>> =
        std::cell::RefCell::new(HashMap::new());
}

/// Loads a model (expanding its GenoM layer) and remembers it for `compile_expr`.
fn load(text: &str) -> System {
    let sys = load_str("test.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()));
    let def = crate::parse_str("test.ron", text).expect("parses");
    MODELS.with(|d| d.borrow_mut().insert(sys.name.clone(), def));
    sys
}

fn explore(sys: &System) -> Explored {
    let mut index: HashMap<State, usize> = HashMap::new();
    let mut ex = Explored {
        states: Vec::new(),
        parent: Vec::new(),
        deadlocks: Vec::new(),
        violations: Vec::new(),
        transitions: 0,
    };
    let init = sys.initial_state();
    index.insert(init.clone(), 0);
    ex.states.push(init);
    ex.parent.push(None);
    let mut queue = VecDeque::from([0usize]);
    let mut steps = Steps::new();
    let mut checker = LivenessChecker::default();
    let mut next = sys.initial_state();
    while let Some(k) = queue.pop_front() {
        let s = ex.states[k].clone();
        for p in &sys.properties {
            if let PropertyKind::Invariant(e) = &p.kind {
                if !sys.holds(e, &s, &p.name).expect("evaluates")
                    && !ex.violations.iter().any(|v| v.0 == p.name)
                {
                    ex.violations.push((p.name.clone(), k));
                }
            }
        }
        sys.enabled_steps(&s, &mut steps).expect("no range error");
        if sys
            .liveness(&s, &steps, &mut checker)
            .expect("no range error")
            == Liveness::Deadlock
        {
            let excused = sys.properties.iter().any(|p| match &p.kind {
                PropertyKind::DeadlockFree { terminal: Some(t) } => {
                    sys.holds(t, &s, "terminal").expect("evaluates")
                }
                _ => false,
            });
            if !excused {
                ex.deadlocks.push(k);
            }
        }
        for step in steps.iter() {
            sys.fire(&s, step, &mut next).expect("no range error");
            ex.transitions += 1;
            if !index.contains_key(&next) {
                let n = ex.states.len();
                index.insert(next.clone(), n);
                ex.states.push(next.clone());
                ex.parent.push(Some((k, sys.label_name(step.label))));
                queue.push_back(n);
            }
        }
    }
    ex
}

const MINI: &str = include_str!("../../../robots/tests/mini.ron");

#[test]
fn model_md_example_expands_and_holds() {
    let sys = load(MINI);
    let ex = explore(&sys);
    eprintln!(
        "mini: {} states, {} transitions",
        ex.states.len(),
        ex.transitions
    );
    assert!(ex.violations.is_empty(), "{:?}", ex.violations);
    assert!(
        ex.deadlocks.is_empty(),
        "{:?}",
        ex.deadlocks
            .iter()
            .map(|&d| ex.trace(d))
            .collect::<Vec<_>>()
    );
    assert!(ex.any(&sys, "rflex.TrackSpeed@main"));
}

/// A system around `modules`, `constraints` and the rest (atoms, components, connectors,
/// properties), in RON.
fn model(name: &str, modules: &str, rest: &str) -> String {
    format!("System(name: \"{name}\", modules: [{modules}], {rest})")
}

/// True if every step named `step` fires from a state where `expr` holds (and at least
/// one such step is reachable).
fn before_each(ex: &Explored, sys: &System, step: &str, expr: &str) -> bool {
    let steps = transitions_named(sys, ex, step);
    assert!(!steps.is_empty(), "no step `{step}` is reachable");
    steps.iter().all(|(from, _)| holds_in(sys, expr, from))
}

/// The parent links keep one way into each state; these tests need every transition.
fn transitions_named(sys: &System, ex: &Explored, step: &str) -> Vec<(State, State)> {
    let mut out = Vec::new();
    for s in &ex.states {
        for (st, next) in sys.successors(s).expect("no range error") {
            if sys.label_name(st.label) == step {
                out.push((s.clone(), next));
            }
        }
    }
    out
}

fn holds_in(sys: &System, expr: &str, s: &State) -> bool {
    sys.eval(&compile_expr(sys, expr), s).expect("evaluates") != 0
}

const CHAIN: &str = r#"(name: "m", tasks: [(name: "t", period: 3)], services: [
    (name: "S", kind: Activity, task: "t", codels: [
        (state: "start", yields: ["a"]),
        (state: "a",     yields: ["pause::b"]),
        (state: "b",     yields: ["pause::b", "ether"]),
    ]),
])"#;

#[test]
fn codel_chain_runs_within_a_cycle_and_pauses_to_the_period() {
    let sys = load(&model("chain", CHAIN, "properties: [DeadlockFree]"));
    let ex = explore(&sys);
    assert!(ex.deadlocks.is_empty());
    // the activity reaches each of its states, and `ether` again
    for e in [
        "m.S@a",
        "m.S@b",
        "pending(m.S)",
        "m.S@ether && !pending(m.S)",
    ] {
        assert!(ex.any(&sys, e), "{e} is never reached");
    }
    assert!(ex.any(&sys, "active(m.S)") && ex.all(&sys, "active(m.S) == !m.S@ether"));
    // `a` follows `start` in the same cycle: time never passes at `a`
    let at_a = compile_expr(&sys, "m.S@a");
    let mut steps = Steps::new();
    for s in ex
        .states
        .iter()
        .filter(|s| sys.eval(&at_a, s).unwrap() != 0)
    {
        sys.enabled_steps(s, &mut steps).unwrap();
        let names: Vec<String> = steps.iter().map(|st| sys.label_name(st.label)).collect();
        assert_eq!(
            names,
            ["m_S_a", "m_S_a_fail"],
            "at `a` only its codel may run (or fail)"
        );
    }
    // `start` and `b` run only on a period boundary of the task (every 3 ticks)
    assert!(before_each(&ex, &sys, "m_S_start", "clock.n == 0"));
    assert!(before_each(&ex, &sys, "m_S_b", "clock.n == 0"));
    // and `pause::b` waits for the next boundary: `b` runs once per period
    for (from, to) in transitions_named(&sys, &ex, "m_S_b") {
        if holds_in(&sys, "m.S@b", &to) {
            assert!(holds_in(&sys, "m_S.paused", &to) && holds_in(&sys, "!m_S.paused", &from));
        }
    }
}

const STOPPABLE: &str = r#"(name: "m", tasks: [(name: "t", period: 1)], ports: [(name: "p")], services: [
    (name: "W", kind: Activity, task: "t", codels: [
        (state: "start", yields: ["pause::w"]),
        (state: "w",     yields: ["pause::w", "ether"], writes: ["p"]),
    ]),
    (name: "A", kind: Activity, task: "t", codels: [
        (state: "start", yields: ["pause::main"]),
        (state: "main",  yields: ["pause::main", "ether"]),
        (state: "stop",  yields: ["pause::park"]),
        (state: "park",  yields: ["ether"]),
    ]),
    (name: "Halt", kind: Function, interrupts: ["A"]),
    (name: "B", kind: Activity, task: "t", after: ["A"], codels: [(state: "start", yields: ["ether"])]),
])"#;

#[test]
fn interrupt_with_a_stop_codel_runs_the_stop_path_ungated() {
    // `A` needs the port `W` writes, fresh: it is held once `W` has ended; the stop path
    // is not gated, so an interrupt still ends the activity
    let sys = load(&model(
        "stoppable",
        STOPPABLE,
        r#"constraints: [Fresh(service: "m.A", port: "m.p", max_age: 0)], properties: [DeadlockFree]"#,
    ));
    let ex = explore(&sys);
    let halts = transitions_named(&sys, &ex, "m_Halt_request");
    assert!(halts
        .iter()
        .any(|(a, b)| holds_in(&sys, "m.A@main", a) && holds_in(&sys, "m.A@stop", b)));
    assert!(
        ex.any(&sys, "m.A@park"),
        "the stop codel's yields are followed"
    );
    assert!(before_each(&ex, &sys, "m_A_main", "age(m.p) == 0"));
    assert!(
        !before_each(&ex, &sys, "m_A_stop", "age(m.p) == 0"),
        "the stop codel runs while `Fresh` fails"
    );
    // an interrupted activity whose stop path reaches `ether` has completed: `after` is met
    let ends = transitions_named(&sys, &ex, "m_A_park");
    assert!(!ends.is_empty() && ends.iter().all(|(_, b)| holds_in(&sys, "m_A.done", b)));
    assert!(!transitions_named(&sys, &ex, "m_B_start").is_empty());
    // held for a port nobody writes: a deadlock, and the shortest one is one request away
    assert!(!ex.deadlocks.is_empty());
    assert_eq!(ex.trace(ex.deadlocks[0]), ["m_A_request"]);
    assert!(ex
        .deadlocks
        .iter()
        .any(|&d| holds_in(&sys, "m.A@main", &ex.states[d])));
}

#[test]
fn interrupt_without_a_stop_codel_ends_the_activity_at_once() {
    let no_stop = STOPPABLE
        .replace(r#"(state: "stop",  yields: ["pause::park"]),"#, "")
        .replace(r#"(state: "park",  yields: ["ether"]),"#, "");
    let sys = load(&model("nostop", &no_stop, "properties: [DeadlockFree]"));
    let ex = explore(&sys);
    let halts = transitions_named(&sys, &ex, "m_Halt_request");
    assert!(halts
        .iter()
        .any(|(a, b)| holds_in(&sys, "m.A@main", a)
            && holds_in(&sys, "m.A@ether && !pending(m.A)", b)));
    // interrupted is not completed: `B` (after A) is accepted only once A reached `ether`
    // by itself
    for (from, _) in transitions_named(&sys, &ex, "m_B_request") {
        assert!(holds_in(&sys, "m_A.done", &from));
    }
    assert!(ex.deadlocks.is_empty());
}

#[test]
fn a_request_waits_for_the_activities_it_interrupts() {
    let modules = r#"(name: "m", tasks: [(name: "t", period: 2)], services: [
        (name: "A", kind: Activity, task: "t", codels: [
            (state: "start", yields: ["pause::main"]),
            (state: "main",  yields: ["pause::main", "ether"]),
            (state: "stop",  yields: ["pause::stop", "ether"]),
        ]),
        (name: "B", kind: Activity, task: "t", interrupts: ["A", "B"], codels: [
            (state: "start", yields: ["pause::main"]),
            (state: "main",  yields: ["pause::main", "ether"]),
        ]),
    ])"#;
    let sys = load(&model("waits", modules, "properties: [DeadlockFree]"));
    let ex = explore(&sys);
    assert!(ex.deadlocks.is_empty());
    // B pending while A runs its stop path, then B starts
    assert!(ex.any(&sys, "pending(m.B) && m.A@stop"));
    assert!(before_each(&ex, &sys, "m_B_start", "m.A@ether"));
    // a new request for B while B runs restarts it (B interrupts itself)
    let restarts = transitions_named(&sys, &ex, "m_B_request");
    assert!(restarts
        .iter()
        .any(|(a, b)| holds_in(&sys, "active(m.B)", a) && holds_in(&sys, "pending(m.B)", b)));
}

#[test]
fn after_refuses_requests_until_the_service_completed() {
    let modules = r#"(name: "m", tasks: [(name: "t", period: 1)], services: [
        (name: "Init", kind: Function),
        (name: "Go", kind: Activity, task: "t", after: ["Init"], codels: [
            (state: "start", yields: ["pause::main"]),
            (state: "main",  yields: ["pause::main", "ether"]),
        ]),
    ])"#;
    let sys = load(&model(
        "after",
        modules,
        r#"properties: [DeadlockFree, Invariant(name: "init_first", expr: "active(m.Go) => m.done_Init")]"#,
    ));
    let ex = explore(&sys);
    assert!(ex.violations.is_empty() && ex.deadlocks.is_empty());
    assert!(ex.any(&sys, "active(m.Go)"));
    let requests = transitions_named(&sys, &ex, "m_Go_request");
    assert!(!requests.is_empty());
    assert!(requests
        .iter()
        .all(|(a, _)| holds_in(&sys, "m.done_Init", a)));
    // and the engine's map names the reason
    let map = sys.genom.as_ref().expect("a GenoM map");
    let go = map.service("m", "Go").expect("service");
    let refusing: Vec<String> = go
        .refused_by(&sys, &sys.initial_state())
        .unwrap()
        .iter()
        .map(|c| c.reason.to_string())
        .collect();
    assert_eq!(refusing, ["after m.Init"]);
}

/// Two independent activities and a third, for the constraint tests.
const THREE: &str = r#"(name: "m", tasks: [(name: "t", period: 1)], ports: [(name: "p")], services: [
    (name: "A", kind: Activity, task: "t", codels: [
        (state: "start", yields: ["pause::main"]),
        (state: "main",  yields: ["pause::main", "ether"]),
    ]),
    (name: "B", kind: Activity, task: "t", codels: [
        (state: "start", yields: ["pause::main"]),
        (state: "main",  yields: ["pause::main", "ether"], writes: ["p"]),
    ]),
    (name: "C", kind: Activity, task: "t", codels: [
        (state: "start", yields: ["pause::main"]),
        (state: "main",  yields: ["pause::main", "ether"]),
    ]),
])"#;

/// Explores THREE with `constraint`, then without it; returns both.
fn with_and_without(constraint: &str, rest: &str) -> ((System, Explored), (System, Explored)) {
    let with = load(&model(
        "with",
        THREE,
        &format!("constraints: [{constraint}], {rest}"),
    ));
    let without = load(&model("without", THREE, rest));
    let (a, b) = (explore(&with), explore(&without));
    ((with, a), (without, b))
}

#[test]
fn exclusive_never_lets_two_be_active() {
    let prop = r#"properties: [Invariant(name: "excl", expr: "!(active(m.A) && active(m.B))")]"#;
    let ((_, with), (_, without)) =
        with_and_without(r#"Exclusive(services: ["m.A", "m.B"])"#, prop);
    assert!(with.violations.is_empty());
    assert_eq!(
        without.violations.len(),
        1,
        "the invariant needs the constraint"
    );
}

#[test]
fn at_most_bounds_the_active_ones() {
    let count = "(active(m.A) ? 1 : 0) + (active(m.B) ? 1 : 0) + (active(m.C) ? 1 : 0)";
    let prop = format!(
        r#"properties: [Invariant(name: "budget", expr: "{count} <= 2"), Reachable(name: "two", expr: "{count} == 2")]"#
    );
    let ((sys, with), (_, without)) =
        with_and_without(r#"AtMost(max: 2, services: ["m.A", "m.B", "m.C"])"#, &prop);
    assert!(with.violations.is_empty());
    assert!(with.any(&sys, &format!("{count} == 2")));
    assert_eq!(without.violations.len(), 1);
}

#[test]
fn requires_gates_every_codel_but_the_stop_path() {
    let ((sys, with), (sys2, without)) =
        with_and_without(r#"Requires(service: "m.A", active: ["m.B"])"#, "");
    assert!(before_each(&with, &sys, "m_A_start", "active(m.B)"));
    assert!(before_each(&with, &sys, "m_A_main", "active(m.B)"));
    assert!(!before_each(&without, &sys2, "m_A_main", "active(m.B)"));
}

#[test]
fn fresh_gates_on_the_age_of_a_port() {
    // the property only makes the port's age part of the model without the constraint
    let ((sys, with), (sys2, without)) = with_and_without(
        r#"Fresh(service: "m.A", port: "m.p", max_age: 1)"#,
        r#"properties: [Reachable(name: "stale", expr: "age(m.p) > 1")]"#,
    );
    assert!(before_each(&with, &sys, "m_A_main", "age(m.p) <= 1"));
    assert!(with.any(&sys, "age(m.p) == 0") && with.any(&sys, "age(m.p) > 1"));
    assert!(!before_each(&without, &sys2, "m_A_main", "age(m.p) <= 1"));
}

#[test]
fn guard_gates_on_any_expression() {
    // a user atom that opens and closes a door on its own
    let rest = r#"atoms: {"Door": Atom(locations: ["shut", "open"], initial: "shut",
        transitions: [(from: "shut", to: "open"), (from: "open", to: "shut")])},
        components: [(name: "door", atom: "Door")]"#;
    let ((sys, with), (sys2, without)) =
        with_and_without(r#"Guard(service: "m.A", when: "door@open")"#, rest);
    assert!(before_each(&with, &sys, "m_A_start", "door@open"));
    assert!(before_each(&with, &sys, "m_A_main", "door@open"));
    assert!(!before_each(&without, &sys2, "m_A_main", "door@open"));
}

#[test]
fn ids_are_readable_and_attributes_are_requests() {
    let modules = |mode: i64| {
        format!(
            r#"(name: "m", ids: [(name: "mode", ty: Int(0, 2), init: {mode})],
            tasks: [(name: "t", period: 1)], services: [
            (name: "Set", kind: Attribute),
            (name: "S", kind: Activity, task: "t", after: ["Set"], codels: [
                (state: "start", yields: ["pause::main"]),
                (state: "main",  yields: ["pause::main", "ether"]),
            ]),
        ])"#
        )
    };
    let rest =
        r#"constraints: [Guard(service: "m.S", when: "m.mode == 1")], properties: [DeadlockFree]"#;
    let sys = load(&model("ids1", &modules(1), rest));
    let ex = explore(&sys);
    assert!(ex.any(&sys, "active(m.S)") && ex.all(&sys, "m.mode == 1"));
    assert!(ex.deadlocks.is_empty());
    assert!(transitions_named(&sys, &ex, "m_S_request")
        .iter()
        .all(|(a, _)| holds_in(&sys, "m.done_Set", a)));
    // the guard never holds: a request is accepted and never served, a deadlock
    let sys = load(&model("ids0", &modules(0), rest));
    let ex = explore(&sys);
    assert!(!ex.any(&sys, "active(m.S)"));
    assert_eq!(ex.trace(ex.deadlocks[0]), ["m_Set_request", "m_S_request"]);
}

#[test]
fn a_codel_that_writes_ids_takes_every_value_and_errors_write_nothing() {
    let modules = r#"(name: "m", ids: [(name: "speed", ty: Int(0, 3), init: 1), (name: "on", ty: Bool)],
        tasks: [(name: "t", period: 1)], ports: [(name: "p")], services: [
        (name: "S", kind: Activity, task: "t", codels: [
            (state: "start", yields: ["pause::main"]),
            (state: "main",  yields: ["pause::main", "ether"], writes: ["speed", "p", "on"]),
        ]),
    ])"#;
    let rest = r#"properties: [DeadlockFree, Reachable(name: "written", expr: "age(m.p) == 0")]"#;
    let sys = load(&model("ids_w", modules, rest));
    let ex = explore(&sys);
    // every value of both fields is reached, and only the main codel's steps change them
    for v in 0..=3 {
        assert!(
            ex.any(&sys, &format!("m.speed == {v} && m.on")),
            "speed {v}"
        );
        assert!(
            ex.any(&sys, &format!("m.speed == {v} && !m.on")),
            "speed {v}"
        );
    }
    for s in &ex.states {
        for (st, next) in sys.successors(s).expect("no range error") {
            let name = sys.label_name(st.label);
            let changed = s
                .slots()
                .iter()
                .zip(next.slots())
                .enumerate()
                .any(|(slot, (a, b))| {
                    a != b && ["m.speed", "m.on"].contains(&sys.slot_name(slot as u32).as_str())
                });
            if changed {
                assert_eq!(
                    name, "m_S_main",
                    "only the codel's normal outcomes write ids"
                );
            }
        }
    }
    // the map: one run step per yield and combination of values, and the transition for
    // given values is the one whose step writes them
    let map = sys.genom.as_ref().expect("a GenoM layer");
    let codel = map.codel("m", "S", "main").expect("bound");
    assert_eq!(
        codel
            .ids
            .iter()
            .map(|f| (f.name.as_str(), f.lo, f.hi, f.stride))
            .collect::<Vec<_>>(),
        [("speed", 0, 3, 2), ("on", 0, 1, 1)]
    );
    assert_eq!(codel.ids_transitions.len(), 8);
    assert_eq!(codel.ids_transition(|k| [4, 0][k]), None);
    // the module's fields say which is a Bool (generated bindings read it as a `bool`)
    assert_eq!(
        map.module("m")
            .expect("module")
            .ids
            .iter()
            .map(|f| (f.name.as_str(), f.is_bool))
            .collect::<Vec<_>>(),
        [("speed", false), ("on", true)]
    );
    let module = map.module("m").expect("module").component;
    let t = codel.ids_transition(|k| [2, 1][k]).expect("in range");
    let running = ex
        .states
        .iter()
        .find(|s| holds_in(&sys, "m.S@main && !m_S.paused", s))
        .expect("the main codel runs");
    let (_, next) = sys
        .successors(running)
        .expect("no range error")
        .into_iter()
        .find(|(st, _)| {
            st.picks
                .iter()
                .any(|p| p.component == module && p.transition == t)
        })
        .expect("a step writes those values");
    assert!(holds_in(
        &sys,
        "m.speed == 2 && m.on && age(m.p) == 0",
        &next
    ));
    // the start codel and the error path write nothing: they have no module pick
    assert!(map.codel("m", "S", "start").expect("bound").ids.is_empty());
}

#[test]
fn writes_naming_ids_are_checked() {
    let bad = |writes: &str, extra: &str| {
        let text = model(
            "bad",
            &format!(
                r#"(name: "m", ids: [(name: "x", ty: Int(0, 2000)), (name: "p", ty: Bool), (name: "y", ty: Int(0, 600))],
                tasks: [(name: "t", period: 1)], ports: [(name: "p")], services: [
                (name: "S", kind: Activity, task: "t", codels: [
                    (state: "start", yields: ["ether"], writes: [{writes}]),
                ]),
                {extra}
            ])"#
            ),
            "",
        );
        load_str("bad.ron", &text)
            .map(|_| String::new())
            .unwrap_or_else(|e| e.summary())
    };
    assert!(bad(r#""x""#, "").contains("1024"), "{}", bad(r#""x""#, ""));
    assert!(bad(r#""y""#, "").is_empty());
    assert!(bad(r#""y", "p""#, "").contains("both an out port and an ids field"));
    assert!(bad(r#""z""#, "").contains("no out port or ids field `z`"));
    assert!(bad(r#""y""#, r#"(name: "write_S_start", kind: Function)"#)
        .contains("cannot be named `write_S_start`"));
}

/// A task's period boundaries are the ticks `delay + k * period`: for every period and
/// delay of a small range, a paused codel runs exactly where the reference says (the
/// clock's phase `n` counts ticks modulo the period here), and at least once.
#[test]
fn delay_offsets_the_period_boundaries() {
    for period in 1..=4i64 {
        for delay in 0..period {
            let modules = CHAIN.replace("period: 3", &format!("period: {period}, delay: {delay}"));
            let sys = load(&model(
                &format!("delay_{period}_{delay}"),
                &modules,
                "properties: [DeadlockFree]",
            ));
            let ex = explore(&sys);
            assert!(ex.deadlocks.is_empty());
            let boundary = if period == 1 {
                "true".to_string()
            } else {
                format!("clock.n == {delay}")
            };
            for step in ["m_S_start", "m_S_b"] {
                assert!(
                    before_each(&ex, &sys, step, &boundary),
                    "period {period}, delay {delay}: `{step}` runs off its boundaries"
                );
            }
        }
    }
}

#[test]
fn a_delay_is_below_the_period() {
    let modules = CHAIN.replace("period: 3", "period: 3, delay: 3");
    let e = load_str(
        "test.ron",
        &model("late", &modules, "properties: [DeadlockFree]"),
    )
    .expect_err("a delay of a whole period");
    assert!(
        e.summary().contains("task `t` has delay 3"),
        "{}",
        e.summary()
    );
}

/// `before` is `after` seen from the other side: the two spellings expand to the same
/// core, and the request waits for the completion.
#[test]
fn before_is_the_dual_of_after() {
    let with = |init: &str, go: &str| {
        model(
            "order",
            &format!(
                r#"(name: "m", tasks: [(name: "t", period: 1)], services: [
                    (name: "Init", kind: Function{init}),
                    (name: "Go", kind: Activity, task: "t"{go}, codels: [
                        (state: "start", yields: ["pause::main"]),
                        (state: "main",  yields: ["pause::main", "ether"]),
                    ]),
                ])"#
            ),
            r#"properties: [DeadlockFree, Invariant(name: "init_first", expr: "active(m.Go) => m.done_Init")]"#,
        )
    };
    let after = with("", r#", after: ["Init"]"#);
    let before = with(r#", before: ["Go"]"#, "");
    let expand = |text: &str| {
        let def = crate::expand_str("test.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()));
        def.to_ron().expect("prints")
    };
    assert_eq!(expand(&before), expand(&after));
    let sys = load(&before);
    let ex = explore(&sys);
    assert!(ex.violations.is_empty() && ex.deadlocks.is_empty());
    assert!(ex.any(&sys, "active(m.Go)"));
    let e = load_str("test.ron", &with(r#", before: ["Init"]"#, "")).expect_err("before itself");
    assert!(
        e.summary().contains("cannot come before itself"),
        "{}",
        e.summary()
    );
}
