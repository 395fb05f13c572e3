//! Aperiodic tasks (docs/genom.md, "Aperiodic tasks"): the fixture, its GenoM3 form and
//! its expansion; what it means, on its states (its codels run between ticks, `pause::`
//! waits for an event of the module, never for time); bad inputs; and random layers with
//! aperiodic and periodic tasks explored against a naive interpreter of the documentation.

use crate::support;
use support::errors::assert_error;

use std::collections::{BTreeSet, HashSet, VecDeque};

use crate::support::graphs::{reachable_graph, same_graph};
use std::path::Path;

use bip_lang::{expand_str, load_str};
use bip_model::{Label, State, System};
use proptest::prelude::*;

const FIXTURE: &str = include_str!("../../../robots/tests/aperiodic.ron");

fn load(text: &str) -> System {
    load_str("m.ron", text).unwrap_or_else(|e| panic!("{}\n{text}", e.summary()))
}

fn robots_tests() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/tests")
}

/// The interaction a step fires, by name.
fn step_name<'s>(sys: &'s System, label: &Label) -> &'s str {
    match label {
        Label::Interaction(i) => &sys.interactions[*i as usize].name,
        Label::Internal { .. } => panic!("a GenoM layer has no internal steps"),
    }
}

#[test]
fn the_gen_file_expands_to_the_ron_fixture() {
    let properties = FIXTURE
        .split("properties: [")
        .nth(1)
        .expect("the fixture's properties");
    let from_gen = format!(
        r#"System(name: "aperiodic", tick_ms: 10, modules: [Gen("genom3/aperiodic.gen")], properties: [{properties}"#
    );
    let name = robots_tests().join("from-gen.ron").display().to_string();
    let a = expand_str(&name, &from_gen).unwrap_or_else(|e| panic!("{}", e.summary()));
    let b = expand_str("aperiodic.ron", FIXTURE).unwrap_or_else(|e| panic!("{}", e.summary()));
    assert_eq!(a.to_ron().expect("prints"), b.to_ron().expect("prints"));
}

#[test]
fn the_expansion_starts_at_once_and_wakes_on_events() {
    let printed = expand_str("aperiodic.ron", FIXTURE)
        .expect("expands")
        .to_ron()
        .expect("prints");
    let atom = |name: &str| -> String {
        printed
            .split(&format!("\"{name}\": Atom("))
            .nth(1)
            .expect("the atom")
            .split("\n        ),")
            .next()
            .expect("its text")
            .to_string()
    };
    // a request for an activity of the aperiodic task does not wait for a boundary
    let grab = atom("Activity_cam_Grab");
    assert!(
        grab.contains(r#"guard: "!req", action: "req = true; paused = false""#),
        "{grab}"
    );
    // the machine is pending and released from the start
    let machine = atom("Activity_cam_events");
    assert!(
        machine.contains(r#"(name: "req", ty: Bool, init: true)"#),
        "{machine}"
    );
    assert!(
        machine.contains(r#"(name: "paused", ty: Bool, init: false)"#),
        "{machine}"
    );
    // the sleeper is woken, the others record their events
    assert!(
        machine.contains(r#"port: "wake", to: "serve", action: "paused = false""#),
        "{machine}"
    );
    let stream = atom("Activity_cam_Stream");
    assert!(
        stream.contains(r#"action: "woke = true; paused = req""#),
        "{stream}"
    );
    assert!(
        printed.contains(r#"name: "cam_wake","#)
            && printed
                .contains(r#"ports: ["cam_events.wake", "cam_Grab.wake", "cam_Stream.wake"]"#),
        "{printed}"
    );
    assert!(
        printed.contains(r#"ports: ["cam.Configure", "cam_events.wake"]"#),
        "{printed}"
    );
    // the tick releases the periodic task only
    let tick = printed
        .split(r#"name: "tick","#)
        .nth(1)
        .expect("the tick")
        .split("\n        ),")
        .next()
        .expect("its text");
    assert!(
        tick.contains("cam_Stream.paused = cam_Stream.paused"),
        "{tick}"
    );
    assert!(!tick.contains("cam_events.paused"), "{tick}");
    assert!(!tick.contains("cam_Grab.paused"), "{tick}");
    let sys = load(FIXTURE);
    let map = sys.genom.as_ref().expect("a map");
    let tasks: Vec<Option<u32>> = map.modules[0].tasks.iter().map(|t| t.period).collect();
    assert_eq!(tasks, [Some(5), None]);
}

/// Every reachable state and its successors.
fn graph(sys: &System) -> Vec<(State, Vec<(String, State)>)> {
    let mut seen = HashSet::from([sys.initial_state()]);
    let mut queue = VecDeque::from([sys.initial_state()]);
    let mut out = Vec::new();
    while let Some(s) = queue.pop_front() {
        let mut next = Vec::new();
        for (step, t) in sys.successors(&s).expect("no range error") {
            next.push((step_name(sys, &step.label).to_string(), t.clone()));
            if seen.insert(t.clone()) {
                queue.push_back(t);
            }
        }
        out.push((s, next));
        assert!(out.len() < 100_000);
    }
    out
}

/// Its codels run between ticks; asleep, the machine lets time pass and stays asleep;
/// a function's request wakes it, and it serves before any tick.
#[test]
fn the_aperiodic_task_runs_between_ticks_and_sleeps_until_an_event() {
    let sys = load(FIXTURE);
    let machine = sys.component_index("cam_events").expect("the machine");
    let grab = sys.component_index("cam_Grab").expect("Grab");
    let paused = |s: &State, c: u32| {
        let v = sys.atom_of(c).var_index("paused").expect("paused");
        sys.value(s, c, v) != 0
    };
    let asleep = |s: &State| sys.location_name(s, machine) == "serve" && paused(s, machine);
    let g = graph(&sys);
    // at the start, the machine runs before time passes
    let first: Vec<&str> = g[0].1.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(first, ["cam_events_start", "cam_events_start_fail"]);
    let (mut ticks_asleep, mut wakes) = (0, 0);
    for (s, next) in &g {
        let names: Vec<&str> = next.iter().map(|(n, _)| n.as_str()).collect();
        // a pending Grab runs before any tick, as does a woken machine
        let pending = sys.location_name(s, grab) == "ether"
            && sys.value(s, grab, sys.atom_of(grab).var_index("req").expect("req")) != 0;
        if pending || (sys.location_name(s, machine) == "serve" && !paused(s, machine)) {
            assert!(!names.contains(&"tick"), "{names:?}");
        }
        for (n, t) in next {
            if asleep(s) && n == "tick" {
                ticks_asleep += 1;
                assert!(asleep(t), "time woke the machine");
            }
            if asleep(s) && n == "cam_Configure_request" {
                wakes += 1;
                assert!(!paused(t, machine), "the request did not wake the machine");
                let after: Vec<&str> = sys
                    .successors(t)
                    .expect("no range error")
                    .iter()
                    .map(|(st, _)| step_name(&sys, &st.label))
                    .collect();
                assert_eq!(after, ["cam_events_serve", "cam_events_serve_fail"]);
            }
        }
    }
    assert!(ticks_asleep > 0 && wakes > 0, "{ticks_asleep} {wakes}");
}

#[test]
fn bad_aperiodic_tasks_are_errors_at_their_place() {
    let with = |from: &str, to: &str| {
        assert!(FIXTURE.contains(from), "{from}");
        FIXTURE.replacen(from, to, 1)
    };
    assert_error(
        &with(r#"(name: "events","#, r#"(name: "events", delay: 1,"#),
        "task `events` has a delay but no period",
        "1",
    );
    assert_error(
        &with(
            r#"(name: "events","#,
            r#"(name: "events", deadline: "5ms","#,
        ),
        "task `cam.events` has a deadline but no period",
        "5ms",
    );
    assert_error(
        &with(
            r#"(state: "serve", yields: ["pause::serve"])"#,
            r#"(state: "serve", yields: ["pause::wake"]), (state: "wake", yields: ["pause::serve"])"#,
        ),
        "a codel state cannot be named `wake`",
        "wake",
    );
    assert_error(
        &with(
            r#"(name: "frames", period: 5)"#,
            r#"(name: "frames", period: 0)"#,
        ),
        "task `frames` has period 0",
        "0",
    );
}

// ---- random layers against a naive interpreter ----

/// An activity of 1 to 3 codel states (`start`, `s1`, `s2`): per state, its yields as
/// (kind, target), kind 0 go, 1 pause, 2 ether.
type Codels = Vec<Vec<(u8, usize)>>;

/// Module `m`: task `t` without a period, maybe with a machine, and activity `A` in it,
/// with maybe a `stop` codel (1: it yields `ether`; 2: `pause::stop` too); task `p` with
/// a period and activity `B` in it; function `Poke`, and function `Halt` that interrupts
/// `A`.
#[derive(Clone, Debug)]
struct Layer {
    machine: Option<Codels>,
    a: Codels,
    a_stop: u8,
    b: Codels,
    period: i64,
}

/// The location of a `stop` codel, among the codel states' indices.
const STOP: usize = usize::MAX;

fn codels() -> impl Strategy<Value = Codels> {
    (1usize..=3)
        .prop_flat_map(|n| {
            let extra = prop::collection::vec((0u8..3, 0..n), n);
            let chain = prop::collection::vec(any::<bool>(), n);
            (Just(n), extra, chain)
        })
        .prop_map(|(n, extra, chain)| {
            let mut yields = vec![Vec::new(); n];
            for k in 0..n {
                if k + 1 < n {
                    yields[k].push((u8::from(chain[k]), k + 1));
                }
                // plain yields only forward: no loop of one activity lacks a pause
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
            yields
        })
}

fn layer() -> impl Strategy<Value = Layer> {
    (
        prop::option::of(codels()),
        codels(),
        0u8..3,
        codels(),
        1i64..=3,
    )
        .prop_map(|(machine, a, a_stop, b, period)| Layer {
            machine,
            a,
            a_stop,
            b,
            period,
        })
}

fn state_name(k: usize) -> String {
    match k {
        0 => "start".into(),
        STOP => "stop".into(),
        k => format!("s{k}"),
    }
}

/// The yields of `A`'s `stop` codel.
fn stop_yields(stop: u8) -> Vec<(u8, usize)> {
    match stop {
        1 => vec![(2, 0)],
        _ => vec![(1, STOP), (2, 0)],
    }
}

fn codels_text(c: &Codels, stop: u8) -> String {
    let mut out = Vec::new();
    let stop = (stop > 0).then(|| (STOP, stop_yields(stop)));
    for (k, ys) in c.iter().cloned().enumerate().chain(stop) {
        let ys: Vec<String> = ys
            .iter()
            .map(|&(kind, to)| match kind {
                0 => format!("\"{}\"", state_name(to)),
                1 => format!("\"pause::{}\"", state_name(to)),
                _ => "\"ether\"".into(),
            })
            .collect();
        out.push(format!(
            "(state: \"{}\", yields: [{}])",
            state_name(k),
            ys.join(", ")
        ));
    }
    out.join(", ")
}

fn model(l: &Layer) -> String {
    let machine = l.machine.as_ref().map_or(String::new(), |c| {
        format!(", codels: [{}]", codels_text(c, 0))
    });
    format!(
        r#"System(name: "aperiodic", modules: [(name: "m",
            tasks: [(name: "t"{machine}), (name: "p", period: {})],
            services: [
                (name: "Poke", kind: Function),
                (name: "Halt", kind: Function, interrupts: ["A"]),
                (name: "A", kind: Activity, task: "t", codels: [{}]),
                (name: "B", kind: Activity, task: "p", codels: [{}]),
            ])],
        properties: [DeadlockFree])"#,
        l.period,
        codels_text(&l.a, l.a_stop),
        codels_text(&l.b, 0)
    )
}

/// One activity as the documentation describes it: where it is (`None`: `ether`),
/// whether a request waits, whether it is paused, whether it is on its stop path.
type Act = (Option<usize>, bool, bool, bool);

/// The machine (if any), `A`, `B`, and the ticks modulo `B`'s period.
type RefState = (Option<Act>, Act, Act, i64);

/// A step: `tick`, a request (`A_request`), or a codel's outcome (`A_s1`, `A_s1_fail`).
type RefLabel = String;

/// The naive interpreter. An activity runs its codel when it is not paused (from
/// `ether`, when requested); only the first that can run does (machine, `A`, `B`: the
/// order of declaration); time passes and requests come only when none can. A request
/// for `A` (no period) makes it ready at once; one for `B` waits for `B`'s next period
/// boundary, every `period` ticks. A plain yield goes on, `pause::` pauses, `ether` and
/// the error path end. `pause::` in the aperiodic task waits for an event: any
/// transition of another activity of the module but a pause, or the request of a
/// function. `Halt` interrupts `A`: to its `stop` codel, ready at once, or to `ether`
/// without one; on its stop path, `A` only forgets its request and its pause.
fn successors(l: &Layer, s: RefState) -> Vec<(RefLabel, RefState)> {
    let (machine, a, b, phase) = s;
    let mut out = Vec::new();
    let codels: [Option<&Codels>; 3] = [l.machine.as_ref(), Some(&l.a), Some(&l.b)];
    let acts: [Option<Act>; 3] = [machine, Some(a), Some(b)];
    let names = ["t", "A", "B"];
    // the activities that sleep until an event: in `t`, with some pause
    let sleeps = |i: usize| {
        let pauses = |ys: &[(u8, usize)]| ys.iter().any(|&(kind, _)| kind == 1);
        i < 2
            && (codels[i].is_some_and(|c| c.iter().any(|ys| pauses(ys)))
                || (i == 1 && l.a_stop == 2))
    };
    let build = |acts: [Option<Act>; 3], phase: i64| -> RefState {
        (acts[0], acts[1].expect("A"), acts[2].expect("B"), phase)
    };
    // the request of a function: every sleeper wakes
    let all_woken = |mut acts: [Option<Act>; 3]| {
        for j in (0..3).filter(|&j| sleeps(j)) {
            if let Some(act) = acts[j].as_mut() {
                act.2 = false;
            }
        }
        acts
    };
    let ready = |act: Act| match act {
        (None, req, paused, _) => req && !paused,
        (Some(_), _, paused, _) => !paused,
    };
    if let Some(i) = (0..3).find(|&i| acts[i].is_some_and(ready)) {
        let (at, _, _, stopping) = acts[i].expect("ready");
        let k = at.unwrap_or(0);
        let yields = match k {
            STOP => stop_yields(l.a_stop),
            k => codels[i].expect("codels")[k].clone(),
        };
        let mut outcomes: Vec<(String, Option<usize>, bool)> = yields
            .iter()
            .map(|&(kind, to)| match kind {
                0 => (state_name(k), Some(to), false),
                1 => (state_name(k), Some(to), true),
                _ => (state_name(k), None, false),
            })
            .collect();
        outcomes.push((format!("{}_fail", state_name(k)), None, false));
        for (label, to, pause) in outcomes {
            let mut next = acts;
            next[i] = Some((to, false, pause, stopping && to.is_some()));
            if !pause {
                // an event: the other sleepers wake
                for j in (0..3).filter(|&j| j != i && sleeps(j)) {
                    if let Some(act) = next[j].as_mut() {
                        act.2 = false;
                    }
                }
            }
            out.push((format!("{}_{label}", names[i]), build(next, phase)));
        }
        return out;
    }
    // time
    let phase2 = (phase + 1) % l.period;
    let mut ticked = acts;
    if let Some(bb) = ticked[2].as_mut() {
        bb.2 = bb.2 && phase2 != 0;
    }
    out.push(("tick".into(), build(ticked, phase2)));
    // requests
    if a.0.is_none() && !a.1 {
        let mut next = acts;
        next[1] = Some((None, true, false, false));
        out.push(("A_request".into(), build(next, phase)));
    }
    if b.0.is_none() && !b.1 {
        let mut next = acts;
        next[2] = Some((None, true, true, false));
        out.push(("B_request".into(), build(next, phase)));
    }
    out.push(("Poke_request".into(), build(all_woken(acts), phase)));
    let mut halted = all_woken(acts);
    halted[1] = Some(match a {
        (Some(_), _, _, false) if l.a_stop > 0 => (Some(STOP), false, false, true),
        (Some(at), _, _, true) => (Some(at), false, false, true),
        _ => (None, false, false, false),
    });
    out.push(("Halt_request".into(), build(halted, phase)));
    out
}

fn reference_graph(l: &Layer) -> BTreeSet<(RefState, RefLabel, RefState)> {
    let machine = l.machine.as_ref().map(|_| (None, true, false, false));
    let first = (
        machine,
        (None, false, false, false),
        (None, false, false, false),
        0,
    );
    reachable_graph(first, |&s| successors(l, s), |&s| s)
}

/// The expanded system's reachable graph in the interpreter's terms, a codel step and
/// the wake-up it leads to (above every other step) as one.
fn system_graph(l: &Layer, sys: &System) -> BTreeSet<(RefState, RefLabel, RefState)> {
    let comp = |n: &str| sys.component_index(n);
    let (machine, a, b) = (
        comp("m_t"),
        comp("m_A").expect("A"),
        comp("m_B").expect("B"),
    );
    let clock = comp("clock").expect("the clock");
    let flag = |s: &State, c: u32, name: &str| {
        sys.atom_of(c)
            .var_index(name)
            .is_some_and(|v| sys.value(s, c, v) != 0)
    };
    let act = |s: &State, c: u32, codels: &Codels| -> Act {
        let at = match sys.location_name(s, c) {
            "ether" => None,
            "stop" => Some(STOP),
            loc => Some(
                (0..codels.len())
                    .find(|&k| state_name(k) == loc)
                    .expect("a codel state"),
            ),
        };
        (
            at,
            flag(s, c, "req"),
            flag(s, c, "paused"),
            flag(s, c, "stopping"),
        )
    };
    let view = |s: &State| -> RefState {
        for c in [machine, Some(a), Some(b)].into_iter().flatten() {
            assert!(!flag(s, c, "woke"), "an event left undelivered");
        }
        let phase = sys
            .atom_of(clock)
            .var_index("n")
            .map_or(0, |v| sys.value(s, clock, v));
        (
            machine.map(|c| act(s, c, l.machine.as_ref().expect("codels"))),
            act(s, a, &l.a),
            act(s, b, &l.b),
            phase,
        )
    };
    let wake = sys.interaction_index("m_wake");
    let steps = |s: &State| {
        let successors = sys.successors(s).expect("no range error");
        successors
            .into_iter()
            .map(|(step, mut next)| {
                let name = step_name(sys, &step.label);
                let label = name.strip_prefix("m_").unwrap_or(name).to_string();
                assert_ne!(
                    Some(step.label),
                    wake.map(Label::Interaction),
                    "a wake-up without an event"
                );
                // the wake-up, if the step made an event, is the only step after it
                let after = sys.successors(&next).expect("no range error");
                if let Some(w) = wake.filter(|&w| {
                    after
                        .iter()
                        .any(|(st, _)| st.label == Label::Interaction(w))
                }) {
                    assert_eq!(after.len(), 1, "the wake-up is above every step");
                    assert_eq!(after[0].0.label, Label::Interaction(w));
                    next = after[0].1.clone();
                }
                (label, next)
            })
            .collect()
    };
    reachable_graph(sys.initial_state(), steps, view)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn random_aperiodic_layers_step_as_the_reference_says(l in layer()) {
        let text = model(&l);
        let sys = load(&text);
        same_graph(&system_graph(&l, &sys), &reference_graph(&l), &text)?;
    }
}
