//! The shared trace format: built from a path, written and read as RON, replayed with the
//! step relation, shown readably.

use bip_lang::load_str;
use bip_model::{OwnedStep, State, System, Trace, TraceValue, Verdict};

fn system(text: &str) -> System {
    load_str("t.ron", text).unwrap_or_else(|e| panic!("{}", e.summary()))
}

/// The path taking, at each state, the first enabled step whose name is given.
fn path(sys: &System, names: &[&str]) -> Vec<(OwnedStep, State)> {
    let mut s = sys.initial_state();
    let mut out = Vec::new();
    for name in names {
        let (step, next) = sys
            .successors(&s)
            .expect("no range error")
            .into_iter()
            .find(|(st, _)| sys.label_name(st.label) == *name)
            .unwrap_or_else(|| panic!("{name} not enabled"));
        out.push((step, next.clone()));
        s = next;
    }
    out
}

#[test]
fn philosophers_deadlock_trace_round_trips_and_replays() {
    let sys = system(include_str!("../../../robots/philosophers.ron"));
    let names = ["left[0]", "left[1]", "left[2]", "left[3]", "left[4]"];
    let p = path(&sys, &names);
    let trace = Trace::from_path(&sys, Verdict::Deadlock, &p);
    assert_eq!(trace.steps.len(), 5);
    assert_eq!(trace.steps[0].step, "left[0]");
    let changed: Vec<(&str, &TraceValue)> = trace.steps[0]
        .state
        .iter()
        .map(|(k, v)| (k.as_str(), v))
        .collect();
    assert_eq!(
        changed,
        vec![
            ("phil[0]", &TraceValue::Location("hungry".into())),
            ("fork[0]", &TraceValue::Location("taken".into()))
        ]
    );
    let text = bip_lang::trace_file::to_ron(&trace);
    assert!(text.starts_with("Trace("), "{text}");
    assert!(text.contains("verdict: Deadlock"), "{text}");
    let back = bip_lang::trace_file::from_ron(&text).expect("reads back");
    assert_eq!(back, trace);
    let replayed = back.replay(&sys).expect("replays");
    assert_eq!(replayed.len(), 5);
    assert_eq!(replayed.last().map(|(_, s)| s), p.last().map(|(_, s)| s));
}

#[test]
fn replay_rejects_a_step_that_is_not_enabled_or_leads_elsewhere() {
    let sys = system(include_str!("../../../robots/philosophers.ron"));
    let mut trace = Trace::from_path(&sys, Verdict::None, &path(&sys, &["left[0]", "left[1]"]));
    trace.steps[1].step = "right[0]".into(); // fork[1] is free but recorded changes differ
    let err = trace.replay(&sys).expect_err("wrong state");
    assert_eq!(err.step, 2);
    // each differing variable, with the recorded and the actual value
    assert!(
        err.message.contains(
            "`right[0]` is enabled but does not lead to the recorded state: \
             `phil[1]` recorded hungry, the step gives thinking"
        ),
        "{err}"
    );
    assert!(
        err.message
            .contains("`phil[0]` recorded unchanged (hungry), the step gives eating"),
        "{err}"
    );
    trace.steps[1].step = "release[3]".into();
    let err = trace.replay(&sys).expect_err("not enabled");
    assert!(err.message.contains("`release[3]` is not enabled"), "{err}");
    // a name no step has, with the closest one
    trace.steps[1].step = "lfet[1]".into();
    let err = trace.replay(&sys).expect_err("no such interaction");
    assert_eq!(
        err.message,
        "no such interaction: `lfet[1]` (did you mean `left[1]`?)"
    );
    trace.steps[1].step = "juggle".into();
    let err = trace.replay(&sys).expect_err("no such interaction");
    assert_eq!(err.message, "no such interaction: `juggle`");
    trace.steps[1].step = "release[3]".into();
    // the prefix that replays is kept
    let (prefix, err) = trace.replay_prefix(&sys);
    assert_eq!(prefix.len(), 1);
    assert_eq!(sys.label_name(prefix[0].0.label), "left[0]");
    assert_eq!(err.map(|e| e.step), Some(2));
    let mut trace = Trace::from_path(&sys, Verdict::None, &path(&sys, &["left[0]"]));
    trace.steps[0]
        .state
        .push("phil[9]".into(), TraceValue::Location("eating".into()));
    let err = trace.replay(&sys).expect_err("unknown name");
    assert!(
        err.message
            .contains("`phil[9]` is not a component or variable"),
        "{err}"
    );
}

#[test]
fn data_changes_are_recorded_with_their_types() {
    let sys = system(include_str!("../../../robots/pipeline.ron"));
    let p = path(&sys, &["tick", "put"]);
    let trace = Trace::from_path(&sys, Verdict::Witness("x".into()), &p);
    let put = &trace.steps[1];
    let names: Vec<&str> = put.state.iter().map(|(k, _)| k.as_str()).collect();
    assert_eq!(names, vec!["prod", "prod.seq", "buf.items"]);
    assert_eq!(
        put.state.iter().nth(1).map(|(_, v)| v),
        Some(&TraceValue::Int(1))
    );
    let text = bip_lang::trace_file::to_ron(&trace);
    assert_eq!(bip_lang::trace_file::from_ron(&text).expect("reads"), trace);
    trace.replay(&sys).expect("replays");
}

#[test]
fn display_shows_old_and_new_values() {
    let sys = system(include_str!("../../../robots/pipeline.ron"));
    let trace = Trace::from_path(
        &sys,
        Verdict::Violation("p".into()),
        &path(&sys, &["tick", "put"]),
    );
    let shown = trace.display(Some(&sys)).to_string();
    assert!(shown.starts_with("violation of p after 2 steps"), "{shown}");
    assert!(shown.contains("prod: making → ready"), "{shown}");
    assert!(shown.contains("buf.items: 0 → 1"), "{shown}");
    let bare = trace.display(None).to_string();
    assert!(bare.contains("buf.items = 1"), "{bare}");
}

#[test]
fn malformed_trace_text_is_an_error() {
    assert!(bip_lang::trace_file::from_ron("Trace(system: \"x\")").is_err());
    assert!(bip_lang::trace_file::from_ron("not ron at all").is_err());
}

#[test]
fn a_value_changed_in_a_trace_is_named() {
    let sys = system(include_str!("../../../robots/pipeline.ron"));
    let mut trace = Trace::from_path(&sys, Verdict::None, &path(&sys, &["tick", "put"]));
    trace.steps[1]
        .state
        .push("buf.items".into(), TraceValue::Int(2));
    let err = trace.replay(&sys).expect_err("tampered");
    assert_eq!(err.step, 2);
    assert!(
        err.message.ends_with(
            "does not lead to the recorded state: `buf.items` recorded 2, the step gives 1"
        ),
        "{err}"
    );
}

/// The GenoM expansion's `req` and `paused` are shown only when asked.
#[test]
fn bookkeeping_variables_are_shown_on_request() {
    let sys = system(include_str!("../../../robots/tests/mini.ron"));
    let init = sys.initial_state();
    let request = sys
        .successors(&init)
        .expect("no range error")
        .into_iter()
        .find(|(_, next)| {
            sys.diff(&init, next)
                .iter()
                .any(|(k, _)| k.ends_with(".req"))
        })
        .expect("a request to an activity is enabled");
    let trace = Trace::from_path(&sys, Verdict::None, &[request]);
    let all = trace.display(Some(&sys)).all_variables(true).to_string();
    assert!(all.contains(".req: false → true"), "{all}");
    let short = trace.display(Some(&sys)).to_string();
    assert!(
        !short.contains(".req") && !short.contains(".paused"),
        "{short}"
    );
    assert!(short.starts_with("recording after 1 step\n"), "{short}");
}

/// The last steps of a run are shown with their numbers in the run and replay from the
/// state they start in.
#[test]
fn a_window_of_a_run_shows_and_replays_from_its_start() {
    let sys = system(include_str!("../../../robots/philosophers.ron"));
    let p = path(&sys, &["left[0]", "right[0]", "release[0]", "left[1]"]);
    let start = p[1].1.clone();
    let window = Trace::from_path_at(&sys, &start, Verdict::None, &p[2..]);
    let shown = window.display(Some(&sys)).from(&start, 2).to_string();
    assert!(
        shown.starts_with("recording after 4 steps (the last 2 shown)\n"),
        "{shown}"
    );
    assert!(
        shown.contains("3  release[0]  phil[0]: eating → thinking"),
        "{shown}"
    );
    let replayed = window.replay_from(&sys, start.clone()).expect("replays");
    assert_eq!(replayed.last().map(|(_, s)| s), p.last().map(|(_, s)| s));
    assert!(window.replay(&sys).is_err(), "not from the initial state");
}

/// The file format: the verdict last, a recording's verdict written `Recording`; files of
/// the earlier format (verdict first, `r#None`) still read.
#[test]
fn trace_files_read_in_both_formats() {
    let sys = system(include_str!("../../../robots/philosophers.ron"));
    let trace = Trace::from_path(&sys, Verdict::None, &path(&sys, &["left[0]"]));
    let text = bip_lang::trace_file::to_ron(&trace);
    assert_eq!(
        text,
        "Trace(\n    system: \"philosophers\",\n    steps: [\n        \
         (step: \"left[0]\", state: {\"phil[0]\": \"hungry\", \"fork[0]\": \"taken\"}),\n    \
         ],\n    verdict: Recording,\n)\n"
    );
    assert_eq!(bip_lang::trace_file::from_ron(&text), Ok(trace.clone()));
    let old = "Trace(\n    system: \"philosophers\",\n    verdict: r#None,\n    steps: [\n        \
               (step: \"left[0]\", state: {\"phil[0]\": \"hungry\", \"fork[0]\": \"taken\"}),\n    ],\n)\n";
    assert_eq!(bip_lang::trace_file::from_ron(old), Ok(trace));
}

/// A run of a timed model says so in its file (`timed: true`, after the system's name) and
/// reads back the same; the model loaded untimed refuses it, saying why. An untimed run's
/// file does not say it.
#[test]
fn a_timed_run_says_so_and_replays_on_the_timed_model_only() {
    const TIMED: &str = r#"System(name: "t", tick_ms: 1, time: Exact, cpus: ["c"],
        modules: [(name: "m", tasks: [(name: "p", period: 2, cpu: "c")],
            services: [(name: "S", kind: Activity, task: "p", codels: [
                (state: "start", yields: ["pause::start", "ether"], wcet: "1ms")])])])"#;
    let timed = system(TIMED);
    let untimed = system(&TIMED.replacen("time: Exact, ", "", 1));
    assert!(timed.is_timed() && !untimed.is_timed());
    // a request, time up to its task's period, the release and the dispatch
    let run = path(&timed, &["m_S_request", "tick", "release", "m_p_dispatch"]);
    let trace = Trace::from_path(&timed, Verdict::None, &run);
    assert!(trace.timed);
    let text = bip_lang::trace_file::to_ron(&trace);
    assert!(
        text.starts_with("Trace(\n    system: \"t\",\n    timed: true,\n    steps: [\n"),
        "{text}"
    );
    assert_eq!(bip_lang::trace_file::from_ron(&text), Ok(trace.clone()));
    assert_eq!(trace.replay(&timed).expect("replays").len(), 4);
    let refused = trace.replay(&untimed).expect_err("the untimed model");
    assert_eq!(refused.step, 0);
    assert!(refused.message.contains("timed model"), "{refused}");

    let plain = Trace::from_path(&untimed, Verdict::None, &[]);
    assert!(!plain.timed);
    assert!(!bip_lang::trace_file::to_ron(&plain).contains("timed"));
}
