//! `bip sched` end to end: the rover's tasks meet their deadlines on its two CPUs; a
//! deadline too short is missed, and deadline-monotonic priorities mend it; a WCET
//! raised past what the CPU gives never catches up; the JSON and the picture say the same.
//! robots/controllers.ron's atoms that stand for periodic tasks are analysed by `bip sched`
//! and by `bip verify`'s `Schedulable`.

use crate::common::bip;
use std::process::Output;

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The rover with `edit` applied, in a temporary file.
fn rover_with(edit: (&str, &str)) -> (tempfile::TempDir, String) {
    model_with("rover.ron", edit)
}

/// robots/`model` with `edit` applied, in a temporary file.
fn model_with(model: &str, edit: (&str, &str)) -> (tempfile::TempDir, String) {
    let file = format!("{}/robots/{model}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(file).expect("the model");
    assert!(text.contains(edit.0), "{}", edit.0);
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join(model);
    std::fs::write(&path, text.replacen(edit.0, edit.1, 1)).expect("write");
    let path = path.to_str().expect("utf-8").to_string();
    (dir, path)
}

#[test]
fn the_rover_is_schedulable_with_its_exact_demands() {
    let out = bip(&["sched", "robots/rover.ron"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(
        text.contains("exact: the most a run packs into a period (614191 states"),
        "{text}"
    );
    // the payload CPU: camera 45 ms every 100 ms above map, comm and heating every 200 ms
    let heating = text
        .lines()
        .find(|l| l.trim_start().starts_with("heating.thermal"))
        .expect("a row for heating");
    assert!(heating.contains("192 ms"), "{heating}");
    assert!(text.contains("CPU payload: utilisation 0.960"), "{text}");
    assert!(
        text.ends_with("result: schedulable: every task meets its deadline\n"),
        "{text}"
    );
}

#[test]
fn a_short_deadline_is_missed_and_deadline_monotonic_priorities_mend_it() {
    let (_dir, path) = rover_with((
        r#"(name: "thermal", period: 2, cpu: "payload")"#,
        r#"(name: "thermal", period: 2, cpu: "payload", deadline: "150ms")"#,
    ));
    let out = bip(&["sched", &path, "--demand", "bound"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(
        text.contains("not schedulable: heating.thermal misses its deadline by 42 ms (responds in 192 ms, deadline 150 ms)"),
        "{text}"
    );
    let out = bip(&["sched", &path, "--demand", "bound", "--assign", "dm"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("heating.thermal: 3"), "{text}");
}

#[test]
fn a_wcet_past_what_the_cpu_gives_never_catches_up() {
    let (_dir, path) = rover_with((r#"wcet: "45ms""#, r#"wcet: "50ms""#));
    let out = bip(&["sched", &path, "--demand", "bound"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("heating.thermal never catches up"), "{text}");
}

#[test]
fn json_and_svg_say_the_same() {
    let dir = tempfile::tempdir().expect("temp dir");
    let svg = dir.path().join("rover.svg");
    let out = bip(&[
        "sched",
        "robots/rover.ron",
        "--demand",
        "bound",
        "--format",
        "json",
        "--svg",
        svg.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(doc["schedulable"], true);
    assert_eq!(doc["demand"]["method"], "bound");
    let cpus = doc["cpus"].as_array().expect("cpus");
    assert_eq!(cpus.len(), 2);
    let tasks: Vec<&str> = cpus
        .iter()
        .flat_map(|c| c["tasks"].as_array().unwrap())
        .map(|t| t["name"].as_str().unwrap())
        .collect();
    assert_eq!(tasks.len(), 8);
    let heating = cpus[1]["tasks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["name"] == "heating.thermal")
        .expect("heating");
    assert_eq!(heating["response"]["us"], 192_000);
    let picture = std::fs::read_to_string(&svg).expect("the SVG");
    let xml = roxmltree::Document::parse(&picture).expect("XML");
    let lanes: Vec<&str> = xml
        .descendants()
        .filter(|n| n.attribute("class") == Some("task"))
        .filter_map(|n| n.text())
        .collect();
    for t in tasks {
        assert!(lanes.contains(&t), "{t} has no lane: {lanes:?}");
    }
}

#[test]
fn a_model_without_wcets_is_refused() {
    let out = bip(&["sched", "robots/philosophers.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no time budgets to analyse"));
}

/// `bip verify` checks the same as `Schedulable`: a short deadline fails with its miss
/// (the exact demands decide once the bound misses), and with the exact demands out of
/// reach a missing bound is inconclusive, never a failure.
#[test]
fn verify_checks_schedulability_too() {
    let (_dir, path) = rover_with((
        r#"(name: "thermal", period: 2, cpu: "payload")"#,
        r#"(name: "thermal", period: 2, cpu: "payload", deadline: "150ms")"#,
    ));
    let line = |text: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with("Schedulable"))
            .unwrap_or("")
            .to_string()
    };
    let out = bip(&["verify", &path, "--method", "explicit", "-q"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(line(&text).contains("FAILS"), "{text}");
    assert!(
        text.contains("heating.thermal misses its deadline by 42 ms"),
        "{text}"
    );
    let out = bip(&[
        "verify",
        &path,
        "--method",
        "explicit",
        "-q",
        "--max-states",
        "1000",
    ]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(3), "{text}");
    assert!(line(&text).contains("inconclusive"), "{text}");
    assert!(
        text.contains("the exact demands were not computed"),
        "{text}"
    );
}

/// Plain periodic tasks without GenoM modules: `bip sched` analyses the atoms' declared
/// work, `bip verify` proves the modes and `Schedulable` together, and a safety monitor
/// made heavier misses its deadline in both.
#[test]
fn periodic_atoms_are_scheduled_and_verified() {
    let out = bip(&["sched", "robots/controllers.ron"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(
        text.contains("demand per period: declared: each task's WCET per period"),
        "{text}"
    );
    assert!(text.contains("CPU control: utilisation 0.850"), "{text}");
    let safety = text
        .lines()
        .find(|l| l.trim_start().starts_with("safety"))
        .expect("a row for safety");
    assert!(
        safety.contains("36 ms") && safety.contains("14 ms"),
        "{safety}"
    );
    let line = |text: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with("Schedulable"))
            .unwrap_or("")
            .to_string()
    };
    let out = bip(&["verify", "robots/controllers.ron", "-q"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(line(&text).contains("holds"), "{text}");
    let (_dir, path) = model_with(
        "controllers.ron",
        (
            r#"wcet: "10ms", priority: 10"#,
            r#"wcet: "15ms", priority: 10"#,
        ),
    );
    let out = bip(&["sched", &path]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    let miss = "safety misses its deadline by 4 ms (responds in 54 ms, deadline 50 ms)";
    assert!(text.contains(miss), "{text}");
    let out = bip(&["verify", &path, "-q"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(line(&text).contains("FAILS"), "{text}");
    assert!(text.contains(miss), "{text}");
}

/// A task's machine runs in its task: its codels' WCETs count in the task's demand (here
/// `init`, `control` and `emergency` in one period, 100 + 400 + 200 µs, more than any
/// period's work of `Calibrate`, 500 µs, which the `Exclusive` keeps apart), and a simulated
/// run executes them with no request sent for it.
#[test]
fn a_task_machine_counts_in_its_tasks_demand() {
    let out = bip(&["sched", "robots/tests/task-machine.ron"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("flight.main    2 ms  700 µs"), "{text}");
    let out = bip(&[
        "simulate",
        "robots/tests/task-machine.ron",
        "--steps",
        "40",
        "--seed",
        "1",
    ]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("flight.main.control"), "{text}");
}
