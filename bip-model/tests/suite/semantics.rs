//! One test per rule of the step semantics (docs/model.md, "Semantics: one step"), on small models written out in full.

use bip_lang::load_str;
use bip_model::{Label, Liveness, LivenessChecker, RangeErrorKind, State, Steps, System};

fn load(text: &str) -> System {
    match load_str("test.ron", text) {
        Ok(s) => s,
        Err(e) => panic!("model does not load:\n{}", e.summary()),
    }
}

/// The enabled steps of a state as sorted `name -> successor summary` strings.
fn steps_of(sys: &System, state: &State) -> Vec<String> {
    let mut out: Vec<String> = sys
        .successors(state)
        .expect("no range error")
        .into_iter()
        .map(|(step, next)| format!("{} => {}", sys.label_name(step.label), describe(sys, &next)))
        .collect();
    out.sort();
    out
}

fn describe(sys: &System, s: &State) -> String {
    (0..sys.slot_count() as u32)
        .map(|slot| format!("{}={}", sys.slot_name(slot), sys.trace_value(s, slot)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The state reached by firing the named steps in turn (the first enabled one of each name).
fn state_after(sys: &System, names: &[&str]) -> State {
    let mut s = sys.initial_state();
    let mut steps = Steps::new();
    for name in names {
        sys.enabled_steps(&s, &mut steps).expect("no range error");
        let step = steps
            .iter()
            .find(|st| sys.label_name(st.label) == *name)
            .unwrap_or_else(|| panic!("{name} is not enabled"));
        let mut next = s.clone();
        sys.fire(&s, step, &mut next).expect("no range error");
        s = next;
    }
    s
}

const PAIR: &str = r#"
System(
    name: "pair",
    atoms: {
        "A": Atom(
            locations: ["l0", "l1"],
            initial: "l0",
            ports: ["p", "q"],
            vars: [(name: "x", ty: Int(0, 3), init: 1)],
            transitions: [
                (from: "l0", port: "p", to: "l1", guard: "x > 0", action: "x = x - 1"),
                (from: "l1", port: "q", to: "l0"),
                (from: "l1", to: "l0", guard: "x == 0"),
            ],
        ),
    },
    components: [(name: "a", atom: "A"), (name: "b", atom: "A", vars_init: { "x": 0 })],
    connectors: [
        (name: "sync", ports: ["a.p", "b.p"]),
        (name: "solo", ports: ["a.p"]),
        (name: "back", ports: ["a.q", "b.q"]),
    ],
)
"#;

#[test]
fn rendezvous_needs_every_port_enabled() {
    let sys = load(PAIR);
    // b.x = 0 disables b.p, so only `solo` is enabled
    assert_eq!(
        steps_of(&sys, &sys.initial_state()),
        vec!["solo => a=l1 a.x=0 b=l0 b.x=0"]
    );
}

#[test]
fn internal_transitions_fire_alone_and_guards_read_own_variables() {
    let sys = load(PAIR);
    let s = state_after(&sys, &["solo"]);
    // a is at l1 with x = 0: its internal transition is enabled; `back` needs b at l1
    assert_eq!(
        steps_of(&sys, &s),
        vec!["a.internal => a=l0 a.x=0 b=l0 b.x=0"]
    );
}

#[test]
fn nondeterministic_atoms_give_one_step_per_combination() {
    let sys = load(
        r#"System(name: "nd",
        atoms: { "A": Atom(locations: ["s", "t", "u"], initial: "s", ports: ["p"],
            transitions: [(from: "s", port: "p", to: "t"), (from: "s", port: "p", to: "u")]) },
        components: [(name: "a", atom: "A", count: 2)],
        connectors: [(name: "both", ports: ["a[0].p", "a[1].p"])],
    )"#,
    );
    assert_eq!(
        steps_of(&sys, &sys.initial_state()),
        vec![
            "both => a[0]=t a[1]=t",
            "both => a[0]=t a[1]=u",
            "both => a[0]=u a[1]=t",
            "both => a[0]=u a[1]=u",
        ]
    );
}

const BROADCAST: &str = r#"
System(
    name: "bcast",
    atoms: {
        "Clock": Atom(locations: ["on"], initial: "on", ports: ["tick"],
            transitions: [(from: "on", port: "tick", to: "on")]),
        "R": Atom(locations: ["wait", "got"], initial: "wait", ports: ["hear"],
            vars: [(name: "n", ty: Int(0, 5))],
            transitions: [(from: "wait", port: "hear", to: "got", action: "n = n + 1")]),
    },
    components: [(name: "clock", atom: "Clock"), (name: "r", atom: "R", count: 3)],
    connectors: [
        (name: "tick", kind: Broadcast(trigger: "clock.tick"),
         ports: ["r[0].hear", "r[1].hear", "r[2].hear"]),
        (name: "reset1", ports: ["r[1].hear"]),
    ],
)
"#;

#[test]
fn broadcast_takes_every_enabled_receiver_and_never_waits_for_one() {
    let sys = load(BROADCAST);
    let steps = steps_of(&sys, &sys.initial_state());
    assert!(steps.contains(
        &"tick => clock=on r[0]=got r[0].n=1 r[1]=got r[1].n=1 r[2]=got r[2].n=1".to_string()
    ));
    // after r[1] heard alone, the broadcast goes on without it
    let s = state_after(&sys, &["reset1"]);
    let steps = steps_of(&sys, &s);
    assert_eq!(
        steps,
        vec!["tick => clock=on r[0]=got r[0].n=1 r[1]=got r[1].n=1 r[2]=got r[2].n=1"]
    );
    let s = state_after(&sys, &["tick"]);
    // nobody can receive: the trigger alone still fires
    assert_eq!(
        steps_of(&sys, &s),
        vec!["tick => clock=on r[0]=got r[0].n=1 r[1]=got r[1].n=1 r[2]=got r[2].n=1"]
    );
}

#[test]
fn connector_guard_and_action_order() {
    let sys = load(
        r#"System(name: "order",
        atoms: { "V": Atom(locations: ["l"], initial: "l", ports: ["p"],
            vars: [(name: "v", ty: Int(0, 100), init: 1)],
            transitions: [(from: "l", port: "p", to: "l", action: "v = v * 10")]) },
        components: [(name: "a", atom: "V"), (name: "b", atom: "V", vars_init: { "v": 2 })],
        connectors: [
            // the connector action runs first, then a's action, then b's (port order)
            (name: "xfer", ports: ["b.p", "a.p"], guard: "a.v < b.v", action: "a.v = b.v + 1"),
        ],
    )"#,
    );
    let s = sys.initial_state();
    // a.v = 2+1 = 3, then b: v = 20, then a: v = 30
    assert_eq!(steps_of(&sys, &s), vec!["xfer => a=l a.v=30 b=l b.v=20"]);
    let s = state_after(&sys, &["xfer"]);
    // 30 < 20 is false: the guard disables the connector
    assert!(steps_of(&sys, &s).is_empty());
}

const PRIO: &str = r#"
System(
    name: "prio",
    atoms: {
        "P": Atom(locations: ["l"], initial: "l", ports: ["a", "b", "c"],
            vars: [(name: "k", ty: Int(0, 3))],
            transitions: [
                (from: "l", port: "a", to: "l", action: "k = (k + 1) % 4"),
                (from: "l", port: "b", to: "l", guard: "k != 2"),
                (from: "l", port: "c", to: "l", guard: "k == 3"),
            ]),
    },
    components: [(name: "p", atom: "P")],
    connectors: [
        (name: "ca", ports: ["p.a"]),
        (name: "cb", ports: ["p.b"]),
        (name: "cc", ports: ["p.c"]),
    ],
    priorities: [
        (low: "ca", high: "cb", when: "p.k >= 1"),
        (low: "cb", high: "cc"),
    ],
)
"#;

#[test]
fn priorities_suppress_when_a_higher_interaction_is_enabled() {
    let sys = load(PRIO);
    let names = |s: &State| -> Vec<String> {
        let mut steps = Steps::new();
        sys.enabled_steps(s, &mut steps).expect("no range error");
        let mut v: Vec<String> = steps.iter().map(|st| sys.label_name(st.label)).collect();
        v.sort();
        v
    };
    // k = 0: ca < cb only when k >= 1, so both run
    assert_eq!(names(&sys.initial_state()), vec!["ca", "cb"]);
    // k = 1: ca is suppressed by cb
    let s = state_after(&sys, &["ca"]);
    assert_eq!(names(&s), vec!["cb"]);
    // k = 2: cb is disabled by its guard, so ca runs
    let mut s2 = s.clone();
    s2.slots_mut()[1] = 2;
    assert_eq!(names(&s2), vec!["ca"]);
    // k = 3: cc suppresses cb, and ca through the closure ca < cb < cc (when k >= 1)
    s2.slots_mut()[1] = 3;
    assert_eq!(names(&s2), vec!["cc"]);
    assert_eq!(
        sys.priorities.len(),
        3,
        "ca<cb, cb<cc and the derived ca<cc"
    );
}

#[test]
fn priority_on_one_instance_of_a_family() {
    let sys = load(
        r#"System(name: "inst",
        atoms: { "P": Atom(locations: ["l"], initial: "l", ports: ["go"],
            transitions: [(from: "l", port: "go", to: "l")]) },
        components: [(name: "p", atom: "P", count: 3)],
        connectors: [(name: "go", forall: "i in 0..3", ports: ["p[i].go"])],
        priorities: [(low: "go[0]", high: "go[2]"), (low: "go[1]", high: "go[2]")],
    )"#,
    );
    let mut steps = Steps::new();
    sys.enabled_steps(&sys.initial_state(), &mut steps)
        .unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<String> = steps.iter().map(|s| sys.label_name(s.label)).collect();
    // go[0] and go[1] are below go[2]
    assert_eq!(names, vec!["go[2]"]);
}

#[test]
fn range_errors_are_values_with_their_place() {
    let sys = load(
        r#"System(name: "ranges",
        atoms: { "C": Atom(locations: ["l"], initial: "l", ports: ["inc", "div"],
            vars: [(name: "n", ty: Int(0, 2)), (name: "d", ty: Int(0, 1))],
            transitions: [
                (from: "l", port: "inc", to: "l", action: "n = n + 1"),
                (from: "l", port: "div", to: "l", action: "n = 4 / d"),
            ]) },
        components: [(name: "c", atom: "C")],
        connectors: [(name: "inc", ports: ["c.inc"]), (name: "div", ports: ["c.div"])],
    )"#,
    );
    let s = state_after(&sys, &["inc", "inc"]);
    let mut steps = Steps::new();
    sys.enabled_steps(&s, &mut steps).expect("guards are fine");
    let mut next = s.clone();
    let inc = steps
        .iter()
        .find(|st| sys.label_name(st.label) == "inc")
        .expect("inc");
    let err = sys
        .fire(&s, inc, &mut next)
        .expect_err("n = 3 is out of range");
    assert_eq!(
        err.kind,
        RangeErrorKind::OutOfRange {
            var: "c.n".into(),
            value: 3,
            lo: 0,
            hi: 2
        }
    );
    assert!(
        err.to_string()
            .contains("c.n = 3 is outside its range Int(0, 2)"),
        "{err}"
    );
    let div = steps
        .iter()
        .find(|st| sys.label_name(st.label) == "div")
        .expect("div");
    let err = sys.fire(&s, div, &mut next).expect_err("division by zero");
    assert_eq!(err.kind, RangeErrorKind::DivisionByZero);
}

#[test]
fn guard_that_cannot_be_evaluated_is_a_range_error_of_the_state() {
    let sys = load(
        r#"System(name: "g",
        constants: { "N": 2 },
        atoms: { "C": Atom(locations: ["l"], initial: "l", ports: ["p"],
            vars: [(name: "i", ty: Int(0, 3))],
            transitions: [(from: "l", port: "p", to: "l", action: "i = i + 1")]) },
        components: [(name: "c", atom: "C"), (name: "f", atom: "C", count: "N")],
        connectors: [(name: "go", ports: ["c.p"], guard: "f[c.i].i == 0")],
    )"#,
    );
    let s = state_after(&sys, &["go", "go"]); // c.i = 2, f has 2 members
    let mut steps = Steps::new();
    let err = sys
        .enabled_steps(&s, &mut steps)
        .expect_err("index 2 out of f[0..2]");
    assert!(
        matches!(
            err.kind,
            RangeErrorKind::IndexOutOfBounds {
                index: 2,
                count: 2,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.context.contains("guard of go"), "{}", err.context);
    assert!(
        err.to_string().starts_with(
            "index 2 is outside `f`, whose indices run from 0 to 1, in the guard of go"
        ),
        "{err}"
    );
}

#[test]
fn deadlock_is_no_enabled_step_without_time() {
    let sys = load(include_str!("../../../robots/philosophers.ron"));
    let all_hungry: Vec<&str> = vec!["left[0]", "left[1]", "left[2]", "left[3]", "left[4]"];
    let s = state_after(&sys, &all_hungry);
    let mut steps = Steps::new();
    sys.enabled_steps(&s, &mut steps).expect("ok");
    assert!(steps.is_empty());
    let mut checker = LivenessChecker::default();
    assert_eq!(
        sys.liveness(&s, &steps, &mut checker).expect("ok"),
        Liveness::Deadlock
    );
    sys.enabled_steps(&sys.initial_state(), &mut steps)
        .expect("ok");
    assert_eq!(
        sys.liveness(&sys.initial_state(), &steps, &mut checker)
            .expect("ok"),
        Liveness::Progress
    );
}

const TIMED: &str = r#"
System(
    name: "timed",
    atoms: {
        "Clock": Atom(locations: ["on"], initial: "on", ports: ["tick"],
            transitions: [(from: "on", port: "tick", to: "on")]),
        "W": Atom(locations: ["wait", "work", "stuck"], initial: "wait", ports: ["tick", "go", "req"],
            vars: [(name: "t", ty: Int(0, 2))],
            transitions: [
                (from: "wait", port: "tick", to: "wait", action: "t = t < 2 ? t + 1 : 2"),
                (from: "work", port: "tick", to: "work"),
                (from: "stuck", port: "tick", to: "stuck"),
                (from: "wait", port: "go", to: "work", guard: "t == 2"),
                (from: "work", port: "req", to: "stuck"),
            ]),
    },
    components: [(name: "clock", atom: "Clock"), (name: "w", atom: "W")],
    connectors: [
        (name: "tick", kind: Broadcast(trigger: "clock.tick"), ports: ["w.tick"], role: Time),
        (name: "go", ports: ["w.go"]),
        (name: "req", ports: ["w.req"], role: Environment),
    ],
)
"#;

#[test]
fn deadlock_looks_through_time_and_ignores_the_environment() {
    let sys = load(TIMED);
    let mut steps = Steps::new();
    let mut checker = LivenessChecker::default();
    let mut check = |s: &State| {
        sys.enabled_steps(s, &mut steps).expect("ok");
        sys.liveness(s, &steps, &mut checker).expect("ok")
    };
    // waiting: only the tick is enabled, but after two ticks `go` is
    assert_eq!(
        check(&sys.initial_state()),
        Liveness::AfterTime { ticks: 2 }
    );
    // working: a request may come, time may pass, but the system itself can do nothing
    let s = state_after(&sys, &["tick", "tick", "go"]);
    assert_eq!(check(&s), Liveness::Deadlock);
    let s = state_after(&sys, &["tick", "tick", "go", "req"]);
    assert_eq!(check(&s), Liveness::Deadlock);
    // a state remembered live answers at once
    assert!(matches!(
        check(&sys.initial_state()),
        Liveness::AfterTime { .. }
    ));
}

#[test]
fn labels_name_internal_steps_and_interactions() {
    let sys = load(PAIR);
    assert_eq!(
        sys.label_name(Label::Internal { component: 1 }),
        "b.internal"
    );
    assert_eq!(sys.label_name(Label::Interaction(0)), "sync");
}

#[test]
fn initial_values_defaults_and_self_index() {
    let sys = load(
        r#"System(name: "init",
        constants: { "B": 10, "FLAG": true, "HALF": "B / 2" },
        atoms: { "C": Atom(locations: ["l"], initial: "l",
            vars: [(name: "x", ty: Int(-1, "B")), (name: "y", ty: Int(0, "B"), init: "HALF"),
                   (name: "f", ty: Bool), (name: "g", ty: Bool, init: "FLAG && B > 3")]) },
        components: [(name: "c", atom: "C", count: 3, vars_init: { "x": "self_index * 2" })],
    )"#,
    );
    let s = sys.initial_state();
    let vals: Vec<String> = (0..sys.slot_count() as u32)
        .map(|k| format!("{}={}", sys.slot_name(k), sys.trace_value(&s, k)))
        .collect();
    assert_eq!(
        vals,
        vec![
            "c[0]=l",
            "c[0].x=0",
            "c[0].y=5",
            "c[0].f=false",
            "c[0].g=true",
            "c[1]=l",
            "c[1].x=2",
            "c[1].y=5",
            "c[1].f=false",
            "c[1].g=true",
            "c[2]=l",
            "c[2].x=4",
            "c[2].y=5",
            "c[2].f=false",
            "c[2].g=true",
        ]
    );
}

#[test]
fn packed_states_round_trip_on_examples() {
    for text in [
        include_str!("../../../robots/philosophers.ron"),
        include_str!("../../../robots/pipeline.ron"),
    ] {
        let sys = load(text);
        let mut frontier = vec![sys.initial_state()];
        for _ in 0..6 {
            let mut next = Vec::new();
            for s in &frontier {
                let packed = sys.layout.pack(s);
                assert_eq!(packed.len(), sys.layout.bytes());
                assert_eq!(&sys.layout.unpack(&packed), s);
                next.extend(sys.successors(s).expect("ok").into_iter().map(|(_, n)| n));
            }
            frontier = next;
        }
    }
}

#[test]
fn property_expressions_evaluate_on_states() {
    let sys = load(include_str!("../../../robots/philosophers.ron"));
    let someone_eats = sys
        .properties
        .iter()
        .find(|p| p.name == "someone_eats")
        .expect("declared");
    let bip_model::PropertyKind::Reachable(expr) = &someone_eats.kind else {
        panic!("a Reachable property")
    };
    assert!(!sys.holds(expr, &sys.initial_state(), "test").expect("ok"));
    let s = state_after(&sys, &["left[2]", "right[2]"]);
    assert!(sys.holds(expr, &s, "test").expect("ok"));
}
