//! `bip sched --exact` end to end: a timed model explored, each task's exact worst
//! response beside the response-time analysis where it applies, the analysis' pessimism,
//! the exit code by the exploration's answer, the traces of the worst cases and misses,
//! the limits (inconclusive, with the most seen), and the loader's error on a preemptive
//! CPU, which timed models do not take yet.

use crate::common::bip;
use serde_json::Value;
use std::process::Output;

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

const PESSIMISM: &str = "robots/tests/pessimism.ron";

/// robots/tests/pessimism.ron with `edit` applied, in a temporary file.
fn pessimism_with(edit: (&str, &str)) -> (tempfile::TempDir, String) {
    let text = std::fs::read_to_string(format!("{}/{PESSIMISM}", env!("CARGO_MANIFEST_DIR")))
        .expect("the model");
    assert!(text.contains(edit.0), "{}", edit.0);
    written(&text.replacen(edit.0, edit.1, 1))
}

fn written(text: &str) -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("model.ron");
    std::fs::write(&path, text).expect("write");
    let path = path.to_str().expect("utf-8").to_string();
    (dir, path)
}

/// The cells of task `task`'s row, split on runs of two spaces.
fn row(text: &str, task: &str) -> Vec<String> {
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with(&format!("{task} ")))
        .unwrap_or_else(|| panic!("no row for {task}\n{text}"));
    line.split("  ")
        .map(str::trim)
        .filter(|c| !c.is_empty())
        .map(String::from)
        .collect()
}

#[test]
fn the_analysis_is_pessimistic_where_activities_exclude_each_other() {
    let out = bip(&["sched", "--exact", PESSIMISM]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    // task, period, deadline, analysis, exact, pessimism
    assert_eq!(
        row(&text, "arm.servo"),
        ["arm.servo", "10 ms", "6 ms", "8 ms misses", "5 ms", "3 ms"]
    );
    assert_eq!(
        row(&text, "arm.log"),
        ["arm.log", "20 ms", "20 ms", "3 ms", "3 ms", "0 µs"]
    );
    assert!(
        text.ends_with("result: schedulable: every task meets its deadline in every run\n"),
        "{text}"
    );
    // without --exact, the analysis alone refuses a timed model
    let out = bip(&["sched", PESSIMISM]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("`bip sched --exact` explores it"));
}

#[test]
fn json_says_the_same() {
    let out = bip(&["sched", "--exact", PESSIMISM, "--format", "json"]);
    assert_eq!(out.status.code(), Some(0));
    let doc: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let servo = &doc["tasks"][0];
    assert_eq!(servo["name"], "arm.servo");
    assert_eq!(servo["analysis"]["us"], 8000);
    assert_eq!(servo["exact"]["us"], 5000);
    assert_eq!(servo["pessimism_us"], 3000);
    assert_eq!(servo["misses"], false);
    assert_eq!(doc["schedulable"], true);
    assert_eq!(doc["exploration"]["complete"], true);
    assert_eq!(doc["exploration"]["states"], 1402);
}

#[test]
fn where_the_analysis_does_not_apply_it_says_why() {
    let out = bip(&["sched", "--exact", "robots/tests/timed.ron"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert_eq!(
        row(&text, "nav.plan"),
        [
            "nav.plan",
            "8 ms",
            "8 ms",
            "n/a (multi-core)",
            "3.5 ms",
            "-"
        ]
    );
    // one core, EDF, two tasks on it
    let (_dir, path) = pessimism_with((
        r#"(name: "arm", preemption: Job), (name: "io", preemption: Job)"#,
        r#"(name: "arm", policy: Edf, preemption: Job), (name: "io", preemption: Job)"#,
    ));
    let text = stdout(&bip(&["sched", "--exact", &path]));
    assert_eq!(row(&text, "arm.servo")[3], "n/a (EDF)", "{text}");
    // one core, fixed priorities, two tasks that run their jobs to the end
    let (_dir, path) = pessimism_with((
        r#"(name: "log", period: 20, cpu: "io")"#,
        r#"(name: "log", period: 20, cpu: "arm", priority: 1)"#,
    ));
    let edited = std::fs::read_to_string(&path).expect("the model").replacen(
        r#"cpu: "arm", deadline: "6ms")"#,
        r#"cpu: "arm", deadline: "6ms", priority: 2)"#,
        1,
    );
    std::fs::write(&path, edited).expect("write");
    let text = stdout(&bip(&["sched", "--exact", &path]));
    assert_eq!(row(&text, "arm.log")[3], "n/a (non-preemptive)", "{text}");
}

#[test]
fn a_miss_decides_and_its_trace_and_the_worst_cases_are_saved() {
    let (dir, path) = pessimism_with((r#"deadline: "6ms""#, r#"deadline: "4ms""#));
    let traces = dir.path().join("traces");
    let out = bip(&[
        "sched",
        "--exact",
        &path,
        "--trace-dir",
        traces.to_str().expect("utf-8"),
    ]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert_eq!(row(&text, "arm.servo")[4], "5 ms misses", "{text}");
    assert!(
        text.contains(
            "result: not schedulable: arm.servo misses its 4 ms deadline (worst response 5 ms)"
        ),
        "{text}"
    );
    for file in [
        "arm_servo_meets_its_4_ms_deadline.trace.ron",
        "arm_servo_meets_its_4_ms_deadline.schedule.svg",
        "arm_servo_worst_response.trace.ron",
        "arm_servo_worst_response.schedule.svg",
        "arm_log_worst_response.trace.ron",
    ] {
        assert!(traces.join(file).exists(), "{file}\n{text}");
    }
    // the model's other properties are not sched's: their traces are not saved
    assert!(!traces.join("DeadlockFree.trace.ron").exists());
}

/// A job that runs past a second release of its task (three codels of a period each, in
/// a row): the model counts the boundaries as one, and the figure is a lower bound, two
/// periods, never one that may be too small.
#[test]
fn a_job_past_a_second_release_is_at_least_two_periods() {
    let (_dir, path) = written(
        r#"System(name: "overrun", tick_ms: 1, time: Exact,
    cpus: [(name: "main", preemption: Job)],
    modules: [(name: "m", tasks: [
        (name: "t", period: 2, codels: [
            (state: "start", yields: ["more"], bcet: "2ms", wcet: "2ms"),
            (state: "more", yields: ["last"], bcet: "2ms", wcet: "2ms"),
            (state: "last", yields: ["pause::start"], bcet: "2ms", wcet: "2ms")])])])"#,
    );
    let out = bip(&["sched", "--exact", &path]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert_eq!(row(&text, "m.t")[4], "≥ 4 ms misses", "{text}");
    assert!(
        text.contains("note: m.t: at least 2 periods (4 ms): its job runs past a second release, which the model coalesces"),
        "{text}"
    );
}

#[test]
fn a_limit_gives_an_inconclusive_answer_with_the_most_seen() {
    let out = bip(&["sched", "--exact", PESSIMISM, "--max-states", "300"]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(3), "{text}");
    assert!(
        text.contains("result: inconclusive: the state limit (300 states) was reached"),
        "{text}"
    );
    // a figure seen is a lower bound, never more than the exact one
    let exact = &row(&text, "arm.servo")[4];
    let bound: f64 = exact
        .strip_prefix("≥ ")
        .and_then(|e| e.strip_suffix(" ms"))
        .and_then(|e| e.parse().ok())
        .unwrap_or_else(|| panic!("{exact}\n{text}"));
    assert!(bound <= 5.0, "{text}");
}

/// A CPU written as a name alone is one preemptive core: both tasks on it, the analysis
/// applies to each, and the log task, preempted by the servo, waits for the servo's
/// costliest period twice in the analysis (3 + 8 + 8 = 19 ms) and never more than one
/// real job's 5 ms in a run (8 ms).
#[test]
fn a_preemptive_cpu_has_both_columns() {
    let (_dir, path) = written(
        &std::fs::read_to_string(format!("{}/{PESSIMISM}", env!("CARGO_MANIFEST_DIR")))
            .expect("the model")
            .replacen(
                r#"(name: "arm", preemption: Job), (name: "io", preemption: Job)"#,
                r#""arm""#,
                1,
            )
            .replacen(r#"cpu: "io""#, r#"cpu: "arm""#, 1),
    );
    let out = bip(&["sched", "--exact", &path]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(
        text.contains("CPU arm: 1 core, fixed priorities, preemptive"),
        "{text}"
    );
    assert_eq!(
        row(&text, "arm.servo")[3..],
        ["8 ms misses", "5 ms", "3 ms"],
        "{text}"
    );
    assert_eq!(
        row(&text, "arm.log")[3..],
        ["19 ms", "8 ms", "11 ms"],
        "{text}"
    );
}

/// A lock shared across two CPUs: the log task waits for the servo's `move` codel, which
/// the analysis of the log's CPU does not see: a run takes 4 ms more than its response.
#[test]
fn a_lock_held_on_another_cpu_makes_the_analysis_optimistic() {
    let text = std::fs::read_to_string(format!("{}/{PESSIMISM}", env!("CARGO_MANIFEST_DIR")))
        .expect("the model")
        .replacen(
            r#"cpus: [(name: "arm", preemption: Job), (name: "io", preemption: Job)]"#,
            r#"cpus: ["arm", "io"]"#,
            1,
        )
        .replacen(
            r#"bcet: "2ms", wcet: "4ms"),"#,
            r#"bcet: "2ms", wcet: "4ms", uses: ["calib"]),"#,
            1,
        )
        .replacen(
            r#"yields: ["ether"], wcet: "3ms"),"#,
            r#"yields: ["ether"], wcet: "3ms", uses: ["calib"]),"#,
            1,
        );
    assert_eq!(text.matches("calib").count(), 2);
    let (_dir, path) = written(&text);
    let out = bip(&["sched", "--exact", &path]);
    let report = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{report}");
    assert_eq!(
        row(&report, "arm.log"),
        ["arm.log", "20 ms", "20 ms", "3 ms", "7 ms", "-4 ms"]
    );
    assert!(
        report
            .contains("note: arm.log: a run of the model takes longer than the analysis' response"),
        "{report}"
    );
    // under a state limit, a run already past the analysis' response bounds the pessimism
    let out = bip(&[
        "sched",
        "--exact",
        &path,
        "--max-states",
        "1600",
        "--format",
        "json",
    ]);
    let doc: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let log = &doc["tasks"][1];
    assert_eq!(log["name"], "arm.log");
    assert_eq!(doc["exploration"]["complete"], false);
    assert_eq!(log["exact"]["at_least_us"], 4000, "{log}");
    assert_eq!(log["pessimism_at_most_us"], -1000);
    assert!(log["pessimism_us"].is_null());
}
