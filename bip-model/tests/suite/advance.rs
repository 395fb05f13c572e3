//! A `Time` connector's `advance` (docs/model.md, "Connectors"): the units its step stands
//! for, evaluated on the state the step leaves, read by its action, at least 1; and the
//! response watch counting units rather than ticks.

use bip_lang::load_str;
use bip_model::{
    Gate, GateStep, Label, OwnedStep, RangeErrorKind, ResponseWatch, State, Steps, System,
};

fn load(text: &str) -> System {
    match load_str("test.ron", text) {
        Ok(s) => s,
        Err(e) => panic!("model does not load:\n{}", e.summary()),
    }
}

/// `tick` stands for `c.step` units; its action first sets `step` to 1, then records the
/// advance: it must be the value before. `work` counts `step` down to 0, where the tick's
/// advance would be 0.
const CLOCKED: &str = r#"
System(
    name: "clocked",
    atoms: {
        "Clock": Atom(
            locations: ["run"],
            initial: "run",
            ports: ["tick", "work"],
            vars: [
                (name: "n", ty: Int(0, 20), init: 0),
                (name: "step", ty: Int(0, 3), init: 3),
                (name: "seen", ty: Int(0, 20), init: 0),
            ],
            transitions: [
                (from: "run", port: "tick", to: "run"),
                (from: "run", port: "work", to: "run", guard: "step > 0", action: "step = step - 1"),
            ],
        ),
    },
    components: [(name: "c", atom: "Clock")],
    connectors: [
        (name: "tick", ports: ["c.tick"], role: Time, guard: "c.n <= 10", advance: "c.step",
         action: "c.step = 1; c.seen = advance; c.n = c.n + advance"),
        (name: "work", ports: ["c.work"]),
    ],
)
"#;

fn step_named(sys: &System, s: &State, name: &str) -> OwnedStep {
    let mut steps = Steps::new();
    sys.enabled_steps(s, &mut steps).expect("no range error");
    let found = steps.iter().find(|st| sys.label_name(st.label) == name);
    found.expect("enabled").to_owned()
}

fn var(sys: &System, s: &State, name: &str) -> i64 {
    let c = &sys.components[0];
    let v = sys.atoms[c.atom as usize]
        .var_index(name)
        .expect("a variable");
    sys.value(s, 0, v)
}

#[test]
fn a_time_step_stands_for_its_advance_on_the_state_it_leaves() {
    let sys = load(CLOCKED);
    let init = sys.initial_state();
    let tick = step_named(&sys, &init, "tick");
    let work = step_named(&sys, &init, "work");
    assert_eq!(sys.time_advance(&init, tick.as_step()), Ok(3));
    assert_eq!(sys.time_advance(&init, work.as_step()), Ok(0));
    let mut next = init.clone();
    sys.fire(&init, tick.as_step(), &mut next).expect("fires");
    // the action set `step` to 1 before reading `advance`: it still read 3
    assert_eq!((var(&sys, &next, "seen"), var(&sys, &next, "n")), (3, 3));
    assert_eq!(var(&sys, &next, "step"), 1);
    assert_eq!(sys.time_advance(&next, tick.as_step()), Ok(1));
}

#[test]
fn an_advance_below_one_is_a_range_error_of_the_step() {
    let sys = load(CLOCKED);
    let mut s = sys.initial_state();
    for _ in 0..3 {
        let work = step_named(&sys, &s, "work");
        let mut next = s.clone();
        sys.fire(&s, work.as_step(), &mut next).expect("fires");
        s = next;
    }
    assert_eq!(var(&sys, &s, "step"), 0);
    let tick = step_named(&sys, &s, "tick");
    let err = sys.time_advance(&s, tick.as_step()).expect_err("0 units");
    assert_eq!(err.kind, RangeErrorKind::AdvanceBelowOne { value: 0 });
    let mut next = s.clone();
    let fired = sys
        .fire(&s, tick.as_step(), &mut next)
        .expect_err("a range error");
    assert_eq!(
        fired.to_string(),
        "advance = 0 is below 1 (a time step stands for at least one unit) in the advance of tick"
    );
    // a gate committing the step by its plan checks it too
    let mut gate = Gate::new(sys.clone(), 0).expect("evaluates");
    gate.set_state(&s).expect("evaluates");
    let set = gate.enabled();
    let st = set
        .steps()
        .find(|st| st.label == tick.label)
        .expect("tick is enabled");
    let Label::Interaction(interaction) = st.label else {
        unreachable!()
    };
    let at = set.pool_position(st.picks).expect("a pooled step");
    let width = st.picks.len() as u32;
    let committed = gate.commit(GateStep::Pooled {
        interaction,
        at,
        width,
    });
    let err = committed.expect_err("a range error");
    assert_eq!(
        err.range_error().kind,
        RangeErrorKind::AdvanceBelowOne { value: 0 }
    );
}

/// Each tick stands for 3 units; the trigger `k == 1` waits for `k == 3`, two ticks later:
/// 6 units.
fn stepper(advance: &str, within: u64) -> String {
    format!(
        r#"
System(
    name: "stepper",
    atoms: {{
        "S": Atom(locations: ["s"], initial: "s", ports: ["tick"],
            vars: [(name: "k", ty: Int(0, 5), init: 0)],
            transitions: [(from: "s", port: "tick", to: "s", guard: "k < 5", action: "k = k + 1")]),
    }},
    components: [(name: "c", atom: "S")],
    connectors: [(name: "tick", ports: ["c.tick"], role: Time{advance})],
    properties: [Response(name: "r", trigger: "c.k == 1", response: "c.k == 3", within: {within})],
)
"#
    )
}

/// Runs the watch of property `r` along the ticks of `sys` until it passes the bound or
/// the run ends: the tick (1, 2, …) that passed it.
fn late_at(sys: &System) -> Option<usize> {
    let spec = sys.properties[0].kind.response_spec().expect("a response");
    let mut s = sys.initial_state();
    let mut watch = ResponseWatch::start(sys, spec, &s, "r").expect("evaluates");
    for n in 1..=5 {
        let tick = step_named(sys, &s, "tick");
        let mut next = s.clone();
        sys.fire(&s, tick.as_step(), &mut next).expect("fires");
        if watch
            .observe(sys, spec, &s, tick.as_step(), &next, "r")
            .expect("evaluates")
        {
            return Some(n);
        }
        s = next;
    }
    None
}

#[test]
fn the_response_watch_counts_units() {
    // the trigger comes with tick 1, the response with tick 3, 2 ticks and 6 units later
    assert_eq!(late_at(&load(&stepper(", advance: \"3\"", 5))), Some(3));
    assert_eq!(late_at(&load(&stepper(", advance: \"3\"", 6))), None);
    assert_eq!(late_at(&load(&stepper("", 1))), Some(3));
    assert_eq!(late_at(&load(&stepper("", 2))), None);
}
