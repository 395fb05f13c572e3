//! End-to-end tests of response properties: a lasso counterexample printed with its cycle
//! marked, saved with its loop start and replayed through the engine; a trace whose cycle
//! does not close refused; a truncated run inconclusive (exit 3); a vacuous property
//! warned about; late responses in a simulation and a replay; the rover's mission answered
//! in time, and not without its operator.

use crate::common::bip;

use std::path::Path;

/// Three philosophers, the last taking its right fork first: nobody deadlocks, but
/// philosopher 0 may starve.
fn philosophers(dir: &Path) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/robots/philosophers-asymmetric.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace("\"N\": 5", "\"N\": 3");
    let at = text.rfind("properties: [").unwrap();
    let text = format!(
        r#"{}properties: [
        LeadsTo(name: "phil0_eats", from: "phil[0]@hungry", to: "phil[0]@eating"),
        LeadsTo(name: "someone_eats", from: "exists i in 0..N: phil[i]@hungry", to: "exists i in 0..N: phil[i]@eating"),
        LeadsTo(name: "nobody_eats_twice", from: "phil[0]@eating && phil[1]@eating", to: "true"),
    ],
)
"#,
        &text[..at]
    );
    let path = dir.join("starving.ron");
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

fn out(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn a_lasso_is_printed_saved_and_replayed_with_its_cycle() {
    let dir = tempfile::tempdir().unwrap();
    let model = philosophers(dir.path());
    let traces = dir.path().join("traces");
    let o = bip(&["verify", &model, "--trace-dir", traces.to_str().unwrap()]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(
        text.contains("phil0_eats") && text.contains("FAILS"),
        "{text}"
    );
    assert!(
        text.contains("┌ the cycle: the steps below repeat forever"),
        "{text}"
    );
    assert!(text.contains("└ back to the state after step"), "{text}");
    let file = traces.join("phil0_eats.trace.ron");
    let saved = std::fs::read_to_string(&file).unwrap();
    assert!(saved.contains("loop_start: "), "{saved}");
    // the chart beside it and `bip trace show` mark the same cycle
    let chart = std::fs::read_to_string(traces.join("phil0_eats.svg")).unwrap();
    assert!(
        chart.contains(r#"<g class="loop"><title>the run repeats from here</title>"#),
        "{chart}"
    );
    let shown = out(&bip(&["trace", "show", &model, file.to_str().unwrap()]));
    let stem: usize = saved
        .split("loop_start: ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.trim().parse().ok())
        .unwrap();
    let lines: Vec<&str> = shown.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.contains("┌ the cycle: the steps below repeat forever"))
        .unwrap_or_else(|| panic!("{shown}"));
    assert!(
        lines[at + 1]
            .trim_start()
            .starts_with(&format!("{} ", stem + 1)),
        "{shown}"
    );
    let o = bip(&["replay", &model, file.to_str().unwrap()]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    assert!(text.contains("forever"), "{text}");
    assert!(text.contains("result: phil0_eats fails"), "{text}");
    // the engine's replay names the cycle's steps, the first being step `stem + 1`
    let first = lines[at + 1].split_whitespace().nth(1).unwrap();
    assert!(text.contains(&format!("forever ({first}")), "{text}");
    // a cycle that does not close is not a lasso of the model
    let k: usize = saved
        .split("loop_start: ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|n| n.trim().parse().ok())
        .unwrap();
    let moved = saved.replace(
        &format!("loop_start: {k},"),
        &format!("loop_start: {},", k + 1),
    );
    assert_ne!(moved, saved);
    let bad = dir.path().join("moved.trace.ron");
    std::fs::write(&bad, moved).unwrap();
    let o = bip(&["replay", &model, bad.to_str().unwrap()]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(
        text.contains("does not return to the state where the loop starts"),
        "{text}"
    );
}

#[test]
fn a_truncated_run_is_inconclusive_and_a_vacuous_property_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let model = philosophers(dir.path());
    let o = bip(&[
        "verify",
        &model,
        "--method",
        "explicit",
        "--max-states",
        "4",
    ]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(3), "{text}");
    assert!(text.contains("inconclusive"), "{text}");
    assert!(!text.contains("FAILS"), "{text}");
    let o = bip(&["verify", &model]);
    let text = out(&o);
    assert!(
        text.contains("warning: nobody_eats_twice holds vacuously: its trigger never happens"),
        "{text}"
    );
}

#[test]
fn a_simulation_reports_the_bounded_responses_that_are_late() {
    let model = format!("{}/robots/served.ron", env!("CARGO_MANIFEST_DIR"));
    let o = bip(&["simulate", &model, "--steps", "40", "--seed", "3"]);
    let text = out(&o);
    // a late response is reported, not a failed check of the simulation
    assert_eq!(o.status.code(), Some(0), "{text}");
    assert!(
        text.contains("2 bounded response properties watched at every step:"),
        "{text}"
    );
    let late: Vec<&str> = text.lines().filter(|l| l.contains("no response")).collect();
    assert!(!late.is_empty(), "{text}");
    for l in &late {
        assert!(
            l.contains(
                "answered_in_one: no response 2 ticks after its trigger, past its bound of 1"
            ),
            "{text}"
        );
    }
    assert!(!text.contains("answered_in_two:"), "{text}");
    assert!(
        text.contains(&format!("watched at every step: {} late", late.len())),
        "{text}"
    );
}

#[test]
fn a_bound_passed_replays_with_the_engine_monitor_reporting_it() {
    let dir = tempfile::tempdir().unwrap();
    let model = format!("{}/robots/served.ron", env!("CARGO_MANIFEST_DIR"));
    let traces = dir.path().join("traces");
    let o = bip(&["verify", &model, "--trace-dir", traces.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", out(&o));
    let file = traces.join("answered_in_one.trace.ron");
    let o = bip(&["replay", &model, file.to_str().unwrap()]);
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    // the counterexample's last step is the tick past the bound, and the engine sees it
    let n = text.lines().filter(|l| l.contains("allowed:")).count();
    assert!(
        text.contains(&format!(
            "after step {n}, the engine's monitor: response late: answered_in_one: no response 2 ticks after its trigger, past its bound of 1"
        )),
        "{text}"
    );
    assert_eq!(text.matches("the engine's monitor").count(), 1, "{text}");
    assert!(text.contains("result: answered_in_one fails"), "{text}");
}

/// robots/rover-mission.ron with only the GoTo replies among its properties (the verdicts
/// the README shows), and with its operator's bound on goals or without it.
fn rover_mission(dir: &Path, bounded_goals: bool) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/robots/rover-mission.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let operator =
        "        (name: \"ndd_GoTo_request\", ports: [\"operator.goal\"], role: Environment),\n";
    assert!(text.contains(operator), "the operator sends the goals");
    let text = if bounded_goals {
        text
    } else {
        text.replace(operator, "")
    };
    let at = text.rfind("properties: [").unwrap();
    let text = format!(
        r#"{}properties: [
        Replies(service: "ndd.GoTo"),
        Replies(service: "ndd.GoTo", within: 8),
        Replies(name: "goto_in_7", service: "ndd.GoTo", within: 7),
    ],
)
"#,
        &text[..at]
    );
    let path = dir.join(if bounded_goals {
        "mission.ron"
    } else {
        "unbounded.ron"
    });
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

#[test]
fn the_rover_mission_gets_its_replies_in_time_and_not_without_its_operator() {
    let dir = tempfile::tempdir().unwrap();
    let caps = [
        "--method",
        "explicit",
        "--max-states",
        "8000000",
        "--max-memory",
        "3G",
    ];
    let model = rover_mission(dir.path(), true);
    let o = bip(&[&["verify", &model][..], &caps].concat());
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    let verdict = |name: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with(name))
            .unwrap_or_else(|| panic!("no {name} in {text}"))
            .to_string()
    };
    assert!(verdict("Replies(ndd.GoTo) ").contains("holds"), "{text}");
    assert!(
        verdict("Replies(ndd.GoTo, within: 8)").contains("holds"),
        "{text}"
    );
    let tight = verdict("goto_in_7");
    assert!(
        tight.contains("FAILS") && tight.contains("the response does not come within 7 ticks"),
        "{text}"
    );
    assert!(text.contains("5813697 states"), "{text}");
    // without the operator, goals come for ever: the infinite-interrupt lasso
    let model = rover_mission(dir.path(), false);
    let o = bip(&[&["verify", &model][..], &caps].concat());
    let text = out(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    let goto = text
        .lines()
        .find(|l| l.trim_start().starts_with("Replies(ndd.GoTo) "))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        goto.contains("FAILS") && goto.contains("a cycle of 8 steps repeats forever"),
        "{text}"
    );
    let cycle = text
        .split("┌ the cycle: the steps below repeat forever")
        .nth(1)
        .and_then(|rest| rest.split("└ back to").next())
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        cycle.contains("ndd_GoTo_start") && cycle.contains("ndd_GoTo_request"),
        "a new goal interrupts the running one in the cycle: {text}"
    );
}
