//! Codels that run at a request (docs/genom.md, "Codels at the request"): a function's
//! codel (its success the request's step, its failure a step of its own that accepts the
//! request and replies an exception) and a `validate` codel (its failure refuses the
//! request, and nothing else happens); the map, the names properties use, bad inputs, and
//! random layers explored against a naive interpreter of what the documentation says.

use crate::support;
use support::errors::assert_error;
use support::graphs::{reachable_graph, same_graph};

use std::collections::BTreeSet;

use bip_lang::{expand_str, load_str};
use bip_model::{Label, State, System};
use proptest::prelude::*;

/// A module `m` with a periodic task, an ids field `x`, a port `p`; a function `F` and an
/// activity `A` (`start` pauses into `main`, which ends), each part optional as `l` says.
#[derive(Clone, Debug)]
struct Layer {
    period: i64,
    /// F has a codel, which writes `p`, and `x`.
    f_codel: bool,
    f_writes_p: bool,
    f_writes_x: bool,
    f_validate: bool,
    a_validate: bool,
    /// A comes after F; F interrupts A; A's codels need `p` fresh.
    a_after_f: bool,
    f_interrupts_a: bool,
    fresh: bool,
}

fn layer() -> impl Strategy<Value = Layer> {
    (1..=2i64, prop::array::uniform8(any::<bool>())).prop_map(|(period, b)| Layer {
        period,
        f_codel: b[0],
        f_writes_p: b[0] && b[1],
        f_writes_x: b[0] && b[2],
        f_validate: b[3],
        a_validate: b[4],
        a_after_f: b[5],
        f_interrupts_a: b[6],
        fresh: b[7] && b[0] && b[1],
    })
}

fn model(l: &Layer) -> String {
    let writes: Vec<&str> = [(l.f_writes_p, "\"p\""), (l.f_writes_x, "\"x\"")]
        .iter()
        .filter(|w| w.0)
        .map(|w| w.1)
        .collect();
    let f_codel = if l.f_codel {
        format!(
            r#"codels: [(state: "start", yields: ["ether"], throws: ["bad"], writes: [{}])], "#,
            writes.join(", ")
        )
    } else {
        String::new()
    };
    let validate = |v: bool| {
        if v {
            r#"validate: (throws: ["no"]), "#
        } else {
            ""
        }
    };
    let interrupts = if l.f_interrupts_a {
        r#"interrupts: ["A"], "#
    } else {
        ""
    };
    let after = if l.a_after_f { r#"after: ["F"], "# } else { "" };
    let fresh = if l.fresh {
        r#"Fresh(service: "m.A", port: "m.p", max_age: 1)"#
    } else {
        ""
    };
    format!(
        r#"System(name: "at_request", modules: [(name: "m",
            ids: [(name: "x", ty: Int(0, 1), init: 0)],
            tasks: [(name: "t", period: {})], ports: [(name: "p")],
            services: [
                (name: "F", kind: Function, {interrupts}{f_codel}{}),
                (name: "A", kind: Activity, task: "t", {after}{}codels: [
                    (state: "start", yields: ["pause::main"]),
                    (state: "main", yields: ["ether"])]),
            ])],
        constraints: [{fresh}],
        properties: [DeadlockFree])"#,
        l.period,
        validate(l.f_validate),
        validate(l.a_validate),
    )
}

/// A at `main` (else at `ether`), its `req` and `paused`; `done_F`; `x`; `p`'s age (0 if
/// untracked); the ticks modulo the period.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
struct RefState {
    main: bool,
    req: bool,
    paused: bool,
    done_f: bool,
    x: i64,
    age: i64,
    phase: i64,
}

/// The age's cap: one more than the largest `max_age` compared with it.
const CAP: i64 = 2;

/// The naive interpreter, as docs/genom.md says. A's codels are urgent, gated by
/// `Fresh`; when none can run, time passes or a request comes. A request of `F` is
/// accepted with its codel's success (it marks `F` done, writes `p` and any value of `x`)
/// or, with its failure, accepted without any of that; either way it interrupts `A` if it
/// does. A `validate` codel's failure refuses a request the model would accept: nothing
/// changes.
fn reference_successors(l: &Layer, s: &RefState) -> Vec<(String, RefState)> {
    let fresh = !l.fresh || s.age <= 1;
    let mut codels = Vec::new();
    if fresh && !s.main && s.req && !s.paused {
        let base = RefState { req: false, ..*s };
        codels.push((
            "A_start".to_string(),
            RefState {
                main: true,
                paused: true,
                ..base
            },
        ));
        codels.push((
            "A_start_fail".to_string(),
            RefState {
                paused: false,
                ..base
            },
        ));
    }
    if fresh && s.main && !s.paused {
        let end = RefState {
            main: false,
            paused: s.req,
            ..*s
        };
        codels.push(("A_main".to_string(), end));
        codels.push(("A_main_fail".to_string(), end));
    }
    if !codels.is_empty() {
        return codels;
    }
    let phase = (s.phase + 1) % l.period;
    let mut out = vec![(
        "tick".to_string(),
        RefState {
            paused: s.paused && phase != 0,
            age: if l.fresh { (s.age + 1).min(CAP) } else { 0 },
            phase,
            ..*s
        },
    )];
    out.extend(request_outcomes(l, s));
    out
}

/// The requests' outcomes from `s`: F's and A's, and their validations' refusals. They
/// depend on the module and A alone, not on time or on where A's codels are.
fn request_outcomes(l: &Layer, s: &RefState) -> Vec<(String, RefState)> {
    let mut out = Vec::new();
    // F: its interrupt of A, then its outcomes
    let interrupted = if l.f_interrupts_a {
        RefState {
            main: false,
            req: false,
            paused: false,
            ..*s
        }
    } else {
        *s
    };
    let mut ok = RefState {
        done_f: s.done_f || l.a_after_f,
        age: if l.fresh { 0 } else { s.age },
        ..interrupted
    };
    if l.f_writes_x {
        for x in 0..=1 {
            ok.x = x;
            out.push(("F_request".to_string(), ok));
        }
    } else {
        out.push(("F_request".to_string(), ok));
    }
    if l.f_codel {
        out.push(("F_start_fail".to_string(), interrupted));
    }
    if l.f_validate {
        out.push(("F_validate_fail".to_string(), *s));
    }
    // A: accepted only at rest, once F is done if it comes after F
    if !s.main && !s.req && (!l.a_after_f || s.done_f) {
        out.push((
            "A_request".to_string(),
            RefState {
                req: true,
                paused: true,
                ..*s
            },
        ));
        if l.a_validate {
            out.push(("A_validate_fail".to_string(), *s));
        }
    }
    out
}

fn reference_graph(l: &Layer) -> BTreeSet<(RefState, String, RefState)> {
    let first = RefState {
        main: false,
        req: false,
        paused: false,
        done_f: false,
        x: 0,
        age: if l.fresh { CAP } else { 0 },
        phase: 0,
    };
    reachable_graph(first, |s| reference_successors(l, s), |&s| s)
}

fn interaction_name(sys: &System, label: Label) -> &str {
    let Label::Interaction(i) = label else {
        panic!("a GenoM layer has no internal steps")
    };
    &sys.interactions[i as usize].name
}

/// The value of variable `name` of component `comp` in `s`, 0 if it has none.
fn value(sys: &System, s: &State, comp: u32, name: &str) -> i64 {
    sys.atom_of(comp)
        .var_index(name)
        .map_or(0, |v| sys.value(s, comp, v))
}

/// A state of the expanded system in the interpreter's terms.
fn viewer(sys: &System) -> impl Fn(&State) -> RefState + '_ {
    let a = sys.component_index("m_A").expect("A");
    let m = sys.component_index("m").expect("the module");
    let clock = sys.component_index("clock").expect("the clock");
    move |s: &State| RefState {
        main: sys.location_name(s, a) == "main",
        req: value(sys, s, a, "req") != 0,
        paused: value(sys, s, a, "paused") != 0,
        done_f: value(sys, s, m, "done_F") != 0,
        x: value(sys, s, m, "x"),
        age: value(sys, s, m, "age_p"),
        phase: value(sys, s, clock, "n"),
    }
}

/// The expanded system's reachable graph, in the interpreter's terms.
fn system_graph(sys: &System) -> BTreeSet<(RefState, String, RefState)> {
    let view = viewer(sys);
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

fn load(text: &str) -> System {
    load_str("at_request.ron", text).unwrap_or_else(|e| panic!("{}\n{text}", e.summary()))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn random_request_codels_step_as_the_reference_says(l in layer()) {
        let text = model(&l);
        let sys = load(&text);
        same_graph(&system_graph(&sys), &reference_graph(&l), &text)?;
    }
}

/// `l` as a timed model: A's codels take up to a unit of 1 ms on one cooperative core.
fn timed_model(l: &Layer) -> String {
    model(l)
        .replace(
            r#"System(name: "at_request", "#,
            r#"System(name: "at_request", tick_ms: 1, time: Exact, cpus: [(name: "c", preemption: Job)], "#,
        )
        .replace(r#"yields: ["pause::main"])"#, r#"yields: ["pause::main"], wcet: "1ms")"#)
        .replace(r#"(state: "main", yields: ["ether"])"#, r#"(state: "main", yields: ["ether"], wcet: "1ms")"#)
}

/// The request steps of `l`'s timed model: from every reachable state, exactly the
/// outcomes the untimed reference gives from its module and A (they take no time and no
/// core: the task's atom and the clock unchanged), at any instant, while A's codel runs
/// too. Returns how many were taken while a codel ran.
fn timed_requests_step_as_the_reference_says(l: &Layer) -> Result<usize, TestCaseError> {
    let text = timed_model(l);
    let sys = load(&text);
    let clock = sys.component_index("clock").expect("the clock");
    let task = sys.component_index("m_t_task").expect("the task's atom");
    // the phase counts units of the timed model, which the requests leave as they are
    let untimed = viewer(&sys);
    let view = |s: &State| RefState {
        phase: 0,
        ..untimed(s)
    };
    let timing = |s: &State| {
        let vars = |comp: u32| {
            let atom = sys.atom_of(comp);
            (0..atom.vars.len())
                .map(|v| sys.value(s, comp, v as u32))
                .collect::<Vec<_>>()
        };
        (vars(task), vars(clock))
    };
    let requests = [
        "F_request",
        "F_start_fail",
        "F_validate_fail",
        "A_request",
        "A_validate_fail",
    ];
    let mut seen = std::collections::HashSet::from([sys.initial_state()]);
    let mut queue = std::collections::VecDeque::from([sys.initial_state()]);
    let mut while_running = 0;
    while let Some(s) = queue.pop_front() {
        let mut got = BTreeSet::new();
        for (step, next) in sys.successors(&s).expect("no range error") {
            let name = interaction_name(&sys, step.label);
            let name = name.strip_prefix("m_").unwrap_or(name).to_string();
            if requests.contains(&name.as_str()) {
                prop_assert_eq!(timing(&s), timing(&next), "{} took time\n{}", name, text);
                while_running += usize::from(value(&sys, &s, task, "codel") != 0);
                got.insert((name, view(&next)));
            }
            if seen.insert(next.clone()) {
                queue.push_back(next);
            }
        }
        let want: BTreeSet<_> = request_outcomes(l, &view(&s)).into_iter().collect();
        prop_assert_eq!(&got, &want, "from {:?}\n{}", view(&s), text);
    }
    Ok(while_running)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_request_codels_in_a_timed_model_take_no_time(l in layer()) {
        timed_requests_step_as_the_reference_says(&l)?;
    }
}

const ALL: Layer = Layer {
    period: 2,
    f_codel: true,
    f_writes_p: true,
    f_writes_x: true,
    f_validate: true,
    a_validate: true,
    a_after_f: true,
    f_interrupts_a: true,
    fresh: true,
};

/// With every part, requests come while A's codels run.
#[test]
fn requests_come_while_a_timed_codel_runs() {
    let n = timed_requests_step_as_the_reference_says(&ALL).expect("as the reference says");
    assert!(n > 0);
}

#[test]
fn the_map_has_the_request_codels_and_their_steps() {
    let sys = load(&model(&ALL));
    let map = sys.genom.as_ref().expect("a map");
    let name = |i: u32| sys.interactions[i as usize].name.as_str();
    let f = map.service("m", "F").expect("F");
    let codel = f.function.as_ref().expect("F's codel");
    assert_eq!(codel.state, "start");
    assert_eq!(Some(codel.run), f.request);
    assert_eq!(name(codel.fail), "m_F_start_fail");
    assert_eq!(codel.throws, ["bad"]);
    assert_eq!(codel.writes, ["p"]);
    // one transition of the module's `F` port per value of `x`
    assert_eq!(codel.ids_transitions.len(), 2);
    assert_eq!(codel.yields.len(), 1);
    assert_eq!(codel.yields[0].target, "ether");
    let v = f.validate.as_ref().expect("F's validation");
    assert_eq!(
        (name(v.fail), v.throws.as_slice()),
        ("m_F_validate_fail", &["no".to_string()][..])
    );
    let a = map.service("m", "A").expect("A");
    assert!(a.function.is_none());
    let v = a.validate.as_ref().expect("A's validation");
    assert_eq!(Some(v.run), a.request);
    assert_eq!(name(v.fail), "m_A_validate_fail");
    assert_eq!(v.yields.len(), 1);
    assert!(v.yields[0].target == "ether" && v.yields[0].transitions.is_empty());
    assert!(
        map.codel("m", "A", "validate").is_none(),
        "not a codel state"
    );
    // without them, no such steps
    let plain = load(&model(&Layer {
        f_codel: false,
        f_writes_p: false,
        f_writes_x: false,
        f_validate: false,
        a_validate: false,
        fresh: false,
        ..ALL
    }));
    let f = plain.genom.as_ref().unwrap().service("m", "F").unwrap();
    assert!(f.function.is_none() && f.validate.is_none());
    assert!(plain.interaction_index("m_F_start_fail").is_none());
}

#[test]
fn a_function_may_take_arguments_and_give_an_output_with_a_codel() {
    let text = model(&ALL).replace(
        r#"(name: "F", kind: Function, "#,
        r#"(name: "F", kind: Function, args: Float, output: Int(0, 9), "#,
    );
    let sys = load(&text);
    let f = sys.genom.as_ref().unwrap().service("m", "F").unwrap();
    assert!(f.args.is_some() && f.output.is_some());
    // a validation reads the arguments; without a codel there is no output
    let plain = model(&Layer {
        f_codel: false,
        f_writes_p: false,
        f_writes_x: false,
        fresh: false,
        ..ALL
    });
    let with_args = plain.replace(
        r#"(name: "F", kind: Function, "#,
        r#"(name: "F", kind: Function, args: Float, "#,
    );
    load(&with_args);
    assert_error(
        &plain.replace(
            r#"(name: "F", kind: Function, "#,
            r#"(name: "F", kind: Function, output: Float, "#,
        ),
        "`F` is not an activity and has no codel for an output",
        "F",
    );
}

#[test]
fn properties_name_the_request_codels() {
    let text = model(&ALL).replace(
        "properties: [DeadlockFree]",
        r#"properties: [
            LeadsTo(name: "fn", from: "yield(m.F.start, ether)", to: "true"),
            LeadsTo(name: "va", from: "yield(m.A.validate)", to: "true"),
            Replies(service: "m.F")]"#,
    );
    let def = expand_str("at_request.ron", &text)
        .expect("expands")
        .to_ron()
        .expect("prints");
    assert!(
        def.contains("fires(m_F_request) || fires(m_F_start_fail)"),
        "{def}"
    );
    load(&text);
    assert_error(
        &text.replace("yield(m.A.validate)", "yield(m.A.validate, ether)"),
        "codel `validate` of `m.A` does not yield this",
        "ether",
    );
}

#[test]
fn bad_request_codels_are_errors() {
    let base = model(&ALL);
    assert_error(
        &base.replace(
            r#"codels: [(state: "start", yields: ["ether"], throws: ["bad"]"#,
            r#"codels: [(state: "start", yields: ["ether"]), (state: "two", yields: ["ether"], throws: ["bad"]"#,
        ),
        "it has one codel, at `start`, yielding `ether`",
        "two",
    );
    assert_error(
        &base.replace(
            r#"(state: "main", yields: ["ether"])"#,
            r#"(state: "main", yields: ["validate"]), (state: "validate", yields: ["ether"])"#,
        ),
        "`A` has a `validate` codel, and a codel state of that name",
        "validate",
    );
    assert_error(
        &base.replace(
            r#"validate: (throws: ["no"]), codels"#,
            r#"validate: (throws: ["no", "no"]), codels"#,
        ),
        "no",
        "no",
    );
    assert_error(
        &base.replace(
            r#"(name: "F", kind: Function, "#,
            r#"(name: "fail_A_validate", kind: Function), (name: "F", kind: Function, "#,
        ),
        "a function or attribute cannot be named `fail_A_validate`",
        "fail_A_validate",
    );
}
