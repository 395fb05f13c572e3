//! Aperiodic tasks and busy loops end to end (docs/genom.md, "Aperiodic tasks";
//! docs/model.md, "Time progress"): what `bip verify` says of the fixtures and of their
//! variants, the traces `bip replay` confirms, `bip simulate` on an aperiodic task, and
//! what `bip sched` does with one.

use std::path::{Path, PathBuf};

use crate::common::bip;

/// A copy of fixture `name` with `from` replaced by `to`, in `dir`.
fn variant(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(name))
        .expect("reads the fixture");
    assert!(text.contains(from), "{from}");
    let path = dir.join(Path::new(name).file_name().expect("a file name"));
    std::fs::write(&path, text.replacen(from, to, 1)).expect("writes");
    path
}

fn verify(model: &str, extra: &[&str]) -> (Option<i32>, String) {
    let mut args = vec!["verify", model, "--method", "explicit", "--jobs", "1"];
    args.extend_from_slice(extra);
    let out = bip(&args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

/// The verdict line of `property` in a report.
fn verdict<'a>(report: &'a str, property: &str) -> &'a str {
    report
        .lines()
        .find(|l| l.trim_start().starts_with(&format!("{property} ")))
        .unwrap_or_else(|| panic!("no {property} in\n{report}"))
}

#[test]
fn an_aperiodic_task_answers_between_two_ticks_and_a_periodic_one_does_not() {
    let (code, report) = verify("robots/tests/aperiodic.ron", &[]);
    assert_eq!(code, Some(0), "{report}");
    assert!(verdict(&report, "grabbed_at_once").contains("holds"));
    assert!(verdict(&report, "TimeProgress").contains("holds"));
    // the same activity in the periodic task waits for its period boundary
    let dir = tempfile::tempdir().expect("a directory");
    let periodic = variant(
        dir.path(),
        "robots/tests/aperiodic.ron",
        r#"(name: "Grab", kind: Activity, task: "events","#,
        r#"(name: "Grab", kind: Activity, task: "frames","#,
    );
    let (code, report) = verify(&periodic.display().to_string(), &[]);
    assert_eq!(code, Some(1), "{report}");
    assert!(
        verdict(&report, "grabbed_at_once").contains("FAILS"),
        "{report}"
    );
}

#[test]
fn the_engine_runs_the_aperiodic_task_as_verified() {
    let out = bip(&[
        "simulate",
        "robots/tests/aperiodic.ron",
        "--steps",
        "300",
        "--seed",
        "2",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("held at every step"), "{stdout}");
    // the machine served after the events that woke it, and the bound was never late
    assert!(stdout.contains("cam.events.serve"), "{stdout}");
    assert!(stdout.contains("0 late"), "{stdout}");
}

#[test]
fn a_loop_of_plain_yields_fails_time_progress_with_its_lasso() {
    let dir = tempfile::tempdir().expect("a directory");
    let traces = dir.path().join("traces");
    let (code, report) = verify(
        "robots/tests/busy-loop.ron",
        &["--trace-dir", &traces.display().to_string()],
    );
    assert_eq!(code, Some(1), "{report}");
    let line = verdict(&report, "TimeProgress");
    assert!(
        line.contains("FAILS") && line.contains("a busy loop"),
        "{line}"
    );
    assert!(
        report.contains("the cycle: the steps below repeat forever"),
        "{report}"
    );
    assert!(
        verdict(&report, "DeadlockFree").contains("holds"),
        "{report}"
    );
    // the engine confirms the lasso
    let trace = traces.join("TimeProgress.trace.ron");
    let out = bip(&[
        "replay",
        "robots/tests/busy-loop.ron",
        &trace.display().to_string(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("(a busy loop)"), "{stdout}");
    assert!(stdout.contains("result: TimeProgress fails"), "{stdout}");
    // pausing in the loop lets time pass
    let fixed = variant(
        dir.path(),
        "robots/tests/busy-loop.ron",
        r#"(state: "check", yields: ["check", "ether"])"#,
        r#"(state: "check", yields: ["pause::check", "ether"])"#,
    );
    let (code, report) = verify(&fixed.display().to_string(), &[]);
    assert_eq!(code, Some(0), "{report}");
    assert!(verdict(&report, "TimeProgress").contains("holds"));
    // in a task without a period, the loop is as busy
    let aperiodic = variant(
        dir.path(),
        "robots/tests/busy-loop.ron",
        r#"tasks: [(name: "t", period: 2)]"#,
        r#"tasks: [(name: "t")]"#,
    );
    let (code, report) = verify(&aperiodic.display().to_string(), &[]);
    assert_eq!(code, Some(1), "{report}");
    assert!(
        verdict(&report, "TimeProgress").contains("a busy loop"),
        "{report}"
    );
}

#[test]
fn the_symbolic_method_does_not_claim_time_progress_over_a_busy_loop() {
    let (code, report) = verify("robots/tests/busy-loop.ron", &[]);
    assert_eq!(code, Some(1), "{report}");
    let out = bip(&[
        "verify",
        "robots/tests/busy-loop.ron",
        "--method",
        "symbolic",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = verdict(&stdout, "TimeProgress");
    assert!(line.contains("inconclusive"), "{stdout}");
    assert!(line.contains("busy loop"), "{stdout}");
}

#[test]
fn bip_sched_leaves_an_aperiodic_task_out_or_says_why_it_cannot() {
    let dir = tempfile::tempdir().expect("a directory");
    // WCETs on the periodic task only: the aperiodic one takes no time, and is named
    let periodic_only = variant(
        dir.path(),
        "robots/tests/aperiodic.ron",
        r#"(state: "send", yields: ["pause::send", "ether"]),"#,
        r#"(state: "send", yields: ["pause::send", "ether"], wcet: "2ms"),"#,
    );
    let out = bip(&["sched", &periodic_only.display().to_string()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("cam.frames"), "{stdout}");
    assert!(
        stdout.contains("note: left out, without a period and with no wcet on their codels (they take no time here): cam.events"),
        "{stdout}"
    );
    // a WCET on the aperiodic task: no bound, no analysis, and the reason
    let budgeted = variant(
        dir.path(),
        "robots/tests/aperiodic.ron",
        r#"(state: "start", yields: ["ether"]),"#,
        r#"(state: "start", yields: ["ether"], wcet: "1ms"),"#,
    );
    let out = bip(&["sched", &budgeted.display().to_string()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("task `cam.events`: it has no period, and its codels declare WCETs"),
        "{stderr}"
    );
    let (code, report) = verify(&budgeted.display().to_string(), &[]);
    assert_eq!(code, Some(3), "{report}");
    assert!(
        verdict(&report, "Schedulable").contains("inconclusive"),
        "{report}"
    );
}
