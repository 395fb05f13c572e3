//! Task machines (docs/genom.md, "Task machines"): the fixture's expansion and meaning,
//! bad inputs, and random machines explored against a naive interpreter of what the
//! documentation says they do.

use crate::support;
use support::errors::assert_error;

use std::collections::BTreeSet;

use crate::support::graphs::{reachable_graph, same_graph};

use bip_lang::{expand_str, load_str};
use bip_model::{Label, State, System};
use proptest::prelude::*;

const FIXTURE: &str = include_str!("../../../robots/tests/task-machine.ron");

fn load(text: &str) -> System {
    load_str("m.ron", text).unwrap_or_else(|e| panic!("{}\n{text}", e.summary()))
}

#[test]
fn a_task_machine_is_an_activity_without_request_interrupt_or_abort() {
    let printed = expand_str("task-machine.ron", FIXTURE)
        .expect("expands")
        .to_ron()
        .expect("prints");
    let atom = printed
        .split("\"Activity_flight_main\": Atom(")
        .nth(1)
        .expect("the machine's atom")
        .split("\"Activity_flight_Calibrate\"")
        .next()
        .expect("its text");
    assert!(
        atom.contains(r#"ports: ["tick", "start", "start_fail""#),
        "{atom}"
    );
    for port in ["\"request\"", "\"interrupt\"", "\"abort\""] {
        assert!(!atom.contains(port), "{port} in {atom}");
    }
    // pending and paused from the start: released at the first period boundary
    assert!(
        atom.contains(r#"(name: "req", ty: Bool, init: true)"#),
        "{atom}"
    );
    assert!(
        atom.contains(r#"(name: "paused", ty: Bool, init: true)"#),
        "{atom}"
    );
    assert!(!printed.contains("flight_main_request"));
    assert!(printed.contains("flight_Calibrate_request"));
    let sys = load(FIXTURE);
    let map = sys.genom.as_ref().expect("a map");
    let main = map
        .service("flight", "main")
        .expect("the machine in the map");
    assert_eq!(main.request, None);
    assert_eq!(
        map.codel("flight", "main", "control")
            .map(|c| c.state.as_str()),
        Some("control")
    );
    let requestable: Vec<_> = map.requestable().collect();
    assert_eq!(requestable, [("flight", "Calibrate")]);
}

/// The machine runs its codels with no request at all: its start at tick 2 (the period),
/// then `init` and `control` at the next boundaries.
#[test]
fn the_machine_runs_without_any_request() {
    let sys = load(FIXTURE);
    let main = sys.component_index("flight_main").expect("machine");
    let mut s = sys.initial_state();
    let mut names = Vec::new();
    for _ in 0..6 {
        let steps = sys.successors(&s).expect("no range error");
        // follow the normal outcomes, never a request
        let (step, next) = steps
            .iter()
            .find(|(st, _)| {
                let Label::Interaction(i) = st.label else {
                    return false;
                };
                let n = sys.interactions[i as usize].name.as_str();
                n == "tick" || (n.starts_with("flight_main_") && !n.ends_with("_fail"))
            })
            .expect("a step")
            .clone();
        let Label::Interaction(i) = step.label else {
            panic!()
        };
        names.push(sys.interactions[i as usize].name.clone());
        s = next;
    }
    assert_eq!(
        names,
        [
            "tick",
            "tick",
            "flight_main_start",
            "tick",
            "tick",
            "flight_main_init"
        ]
    );
    assert_ne!(sys.location_name(&s, main), "ether");
}

#[test]
fn bad_task_machines_are_errors_at_their_place() {
    let with = |from: &str, to: &str| {
        assert!(FIXTURE.contains(from), "{from}");
        FIXTURE.replacen(from, to, 1)
    };
    assert_error(
        &with(r#"(name: "Calibrate", kind"#, r#"(name: "main", kind"#),
        "task `main` runs a machine, and module `flight` has a service of that name",
        "main",
    );
    assert_error(
        &with(
            r#"yields: ["pause::init", "control"]"#,
            r#"yields: ["pause::init", "contrl"]"#,
        ),
        "codel `init` yields to `contrl`, which is not a codel state of `main`",
        "contrl",
    );
    assert_error(
        &with(
            r#"(state: "stop",      yields: ["ether"])"#,
            r#"(state: "stop",      yields: ["pause::stop"])"#,
        ),
        "no path from `stop` to `ether` in the machine of task `main`",
        "stop",
    );
    assert_error(
        &with(
            r#"task: "main",
                 codels"#,
            r#"task: "main", interrupts: ["main"],
                 codels"#,
        ),
        "`main` is the machine of task `main`",
        "main",
    );
    assert_error(
        &with(
            "DeadlockFree,",
            "DeadlockFree, Replies(service: \"flight.main\"),",
        ),
        "`flight.main` is a task's machine",
        "flight.main",
    );
    assert_error(
        &with(
            "DeadlockFree,",
            "DeadlockFree, Response(name: \"r\", trigger: \"request(flight.main)\", response: \"yield(flight.main.init)\", within: 2),",
        ),
        "`flight.main` is the machine of task `main`: nothing requests it",
        "flight.main",
    );
}

// ---- random machines against a naive interpreter ----

/// A machine of 1 to 3 codel states (`start`, `s1`, `s2`) and maybe a `stop`.
#[derive(Clone, Debug)]
struct Machine {
    period: i64,
    /// Per state: the yields, as (kind, target) with kind 0 go, 1 pause, 2 ether.
    yields: Vec<Vec<(u8, usize)>>,
    stop: bool,
}

fn state_name(k: usize) -> String {
    if k == 0 {
        "start".into()
    } else {
        format!("s{k}")
    }
}

fn machine() -> impl Strategy<Value = Machine> {
    (1usize..=3, 1i64..=3, any::<bool>())
        .prop_flat_map(|(n, period, stop)| {
            let extra = prop::collection::vec((0u8..3, 0..n), n);
            let chain = prop::collection::vec(any::<bool>(), n);
            (Just(n), Just(period), Just(stop), extra, chain)
        })
        .prop_map(|(n, period, stop, extra, chain)| {
            let mut yields = vec![Vec::new(); n];
            for k in 0..n {
                // each state reaches the next (plain or paused): every codel is reached
                if k + 1 < n {
                    yields[k].push((u8::from(chain[k]), k + 1));
                }
                // plain yields only forward, so that no loop lacks a pause
                let (kind, to) = extra[k];
                let y = match kind {
                    0 if to > k => (0, to),
                    0 | 1 => (1, to),
                    _ => (2, 0),
                };
                if !yields[k].contains(&y) {
                    yields[k].push(y);
                }
            }
            Machine {
                period,
                yields,
                stop,
            }
        })
}

fn machine_model(m: &Machine) -> String {
    let mut codels = Vec::new();
    for (k, ys) in m.yields.iter().enumerate() {
        let ys: Vec<String> = ys
            .iter()
            .map(|&(kind, to)| match kind {
                0 => format!("\"{}\"", state_name(to)),
                1 => format!("\"pause::{}\"", state_name(to)),
                _ => "\"ether\"".into(),
            })
            .collect();
        codels.push(format!(
            "(state: \"{}\", yields: [{}])",
            state_name(k),
            ys.join(", ")
        ));
    }
    if m.stop {
        codels.push(r#"(state: "stop", yields: ["ether"])"#.into());
    }
    format!(
        r#"System(name: "machines", modules: [(name: "m",
            tasks: [(name: "t", period: {}, codels: [{}])])],
        properties: [DeadlockFree])"#,
        m.period,
        codels.join(", ")
    )
}

/// Where the machine is, as the documentation describes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Where {
    /// Not yet released.
    Pending,
    At(usize),
    Ended,
}

/// (where, waiting for the next period boundary, ticks modulo the period)
type RefState = (Where, bool, i64);

/// A step: `tick`, or a codel's normal outcome or error path, by codel state.
type RefLabel = String;

/// The naive interpreter: the machine starts pending and waiting; a period boundary (every
/// `period` ticks from the start) ends the wait; an unwaiting machine runs its codel (a
/// normal outcome per yield, or its error path, which ends it); a plain yield goes on in
/// the same instant, `pause::` waits again, `ether` ends; time passes only when no codel
/// can run.
fn reference_successors(m: &Machine, (w, waiting, phase): RefState) -> Vec<(RefLabel, RefState)> {
    let mut out = Vec::new();
    let codel = match w {
        Where::Pending => Some(0),
        Where::At(k) => Some(k),
        Where::Ended => None,
    };
    if let Some(k) = codel.filter(|_| !waiting) {
        let name = state_name(k);
        for &(kind, to) in &m.yields[k] {
            let next = match kind {
                0 => (Where::At(to), false, phase),
                1 => (Where::At(to), true, phase),
                _ => (Where::Ended, false, phase),
            };
            out.push((name.clone(), next));
        }
        out.push((format!("{name}_fail"), (Where::Ended, false, phase)));
        return out;
    }
    let phase = (phase + 1) % m.period;
    out.push(("tick".into(), (w, waiting && phase != 0, phase)));
    out
}

fn reference_graph(m: &Machine) -> BTreeSet<(RefState, RefLabel, RefState)> {
    let first = (Where::Pending, true, 0);
    reachable_graph(first, |&s| reference_successors(m, s), |&s| s)
}

/// The expanded system's reachable graph, in the interpreter's terms.
fn system_graph(m: &Machine, sys: &System) -> BTreeSet<(RefState, RefLabel, RefState)> {
    let comp = sys.component_index("m_t").expect("the machine's component");
    let clock = sys.component_index("clock").expect("the clock");
    let flag = |s: &State, name: &str| {
        let v = sys.atom_of(comp).var_index(name).expect("a flag");
        sys.value(s, comp, v) != 0
    };
    let view = |s: &State| -> RefState {
        let w = match sys.location_name(s, comp) {
            "ether" if flag(s, "req") => Where::Pending,
            "ether" => Where::Ended,
            l => Where::At(
                (0..m.yields.len())
                    .find(|&k| state_name(k) == l)
                    .expect("a codel state"),
            ),
        };
        let phase = sys
            .atom_of(clock)
            .var_index("n")
            .map_or(0, |v| sys.value(s, clock, v));
        (w, flag(s, "paused"), phase)
    };
    let steps = |s: &State| {
        let successors = sys.successors(s).expect("no range error");
        successors
            .into_iter()
            .map(|(step, next)| {
                let Label::Interaction(i) = step.label else {
                    panic!("a GenoM layer has no internal steps")
                };
                let name = &sys.interactions[i as usize].name;
                (name.strip_prefix("m_t_").unwrap_or(name).to_string(), next)
            })
            .collect()
    };
    reachable_graph(sys.initial_state(), steps, view)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn random_machines_step_as_the_reference_says(m in machine()) {
        let text = machine_model(&m);
        let sys = load(&text);
        same_graph(&system_graph(&m, &sys), &reference_graph(&m), &text)?;
    }
}
