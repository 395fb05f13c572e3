//! Traces of a model that does not say `time: Exact`, run as a timed model by `bip sched
//! --exact` and `bip simulate --codel-time`: the trace says so (`timed: true`), and the
//! commands that read it against the model (`bip trace show` and its drawings, `bip
//! replay`) load the model timed (docs/model.md, "Traces"). `bip explore --trace` is in
//! explore.rs, beside the explorer's other tests.

use std::path::{Path, PathBuf};

use crate::common::bip;

/// robots/tests/pessimism.ron without `time: Exact`, its CPUs written as names (an untimed
/// model's CPUs are preemptive), the servo's deadline at `deadline` (6 ms in the file, met;
/// a run misses 4 ms).
pub fn untimed_pessimism(dir: &Path, deadline: &str) -> PathBuf {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/tests/pessimism.ron"),
    )
    .expect("the model");
    let mut edited = text.clone();
    for (from, to) in [
        ("    time: Exact,\n", ""),
        (
            r#"cpus: [(name: "arm", preemption: Job), (name: "io", preemption: Job)],"#,
            r#"cpus: ["arm", "io"],"#,
        ),
        (r#"deadline: "6ms""#, &format!("deadline: {deadline:?}")),
    ] {
        assert!(edited.contains(from), "{from}");
        edited = edited.replacen(from, to, 1);
    }
    let path = dir.join("model.ron");
    std::fs::write(&path, edited).expect("writes");
    path
}

fn text(out: &std::process::Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// `bip sched --exact --trace-dir DIR`'s traces of the untimed model: its miss trace and
/// its worst case; the directory is kept by the returned guard.
pub fn exact_traces() -> (tempfile::TempDir, PathBuf, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = untimed_pessimism(dir.path(), "4ms");
    let traces = dir.path().join("traces");
    let out = bip(&[
        "sched",
        "--exact",
        model.to_str().expect("utf-8"),
        "--trace-dir",
        traces.to_str().expect("utf-8"),
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out));
    let miss = traces.join("arm_servo_meets_its_4_ms_deadline.trace.ron");
    let worst = traces.join("arm_servo_worst_response.trace.ron");
    (dir, model, miss, worst)
}

#[test]
fn sched_exact_traces_of_an_untimed_model_are_shown_and_replayed() {
    let (dir, model, miss, worst) = exact_traces();
    let model = model.to_str().expect("utf-8");
    for trace in [&miss, &worst] {
        let saved = std::fs::read_to_string(trace).expect("saved");
        assert!(saved.contains("\n    timed: true,\n"), "{saved}");
        let schedule = dir.path().join("again.schedule.svg");
        let out = bip(&[
            "trace",
            "show",
            model,
            trace.to_str().expect("utf-8"),
            "--schedule",
            schedule.to_str().expect("utf-8"),
        ]);
        let shown = text(&out);
        assert_eq!(out.status.code(), Some(0), "{shown}");
        // the timed model's own steps, in the user's names
        assert!(shown.contains("dispatch arm.servo"), "{shown}");
        assert!(shown.contains("time passes "), "{shown}");
        let svg = std::fs::read_to_string(&schedule).expect("the schedule is drawn");
        assert!(svg.contains("arm.servo"), "{svg}");
    }
    // the miss is reached through the engine, each step allowed
    let out = bip(&["replay", model, miss.to_str().expect("utf-8")]);
    let replayed = text(&out);
    assert_eq!(out.status.code(), Some(1), "{replayed}");
    assert!(
        replayed.contains("result: arm.servo meets its 4 ms deadline fails"),
        "{replayed}"
    );

    // so is the worst case, its last step the job end the verifier measured; cut short,
    // the run no longer ends a job
    let out = bip(&["replay", model, worst.to_str().expect("utf-8")]);
    let replayed = text(&out);
    assert_eq!(out.status.code(), Some(1), "{replayed}");
    assert!(
        replayed.contains("result: witness for arm.servo worst response"),
        "{replayed}"
    );
    let mut cut: bip_model::Trace =
        bip_lang::trace_file::from_ron(&std::fs::read_to_string(&worst).expect("saved"))
            .expect("a trace");
    cut.steps.pop();
    let short = dir.path().join("short.trace.ron");
    std::fs::write(&short, bip_lang::trace_file::to_ron(&cut)).expect("writes");
    let out = bip(&["replay", model, short.to_str().expect("utf-8")]);
    let replayed = text(&out);
    assert!(
        replayed.contains("the last step does not end a job of `arm.servo`"),
        "{replayed}"
    );

    // without the mark, the model is loaded as it says, untimed, and the trace does not fit
    let unmarked = dir.path().join("unmarked.trace.ron");
    let saved = std::fs::read_to_string(&miss).expect("saved");
    std::fs::write(&unmarked, saved.replacen("    timed: true,\n", "", 1)).expect("writes");
    let out = bip(&["trace", "show", model, unmarked.to_str().expect("utf-8")]);
    let refused = text(&out);
    assert_eq!(out.status.code(), Some(2), "{refused}");
    assert!(refused.contains("does not fit the model"), "{refused}");
}

#[test]
fn simulate_codel_time_traces_of_an_untimed_model_are_shown_and_replayed() {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = untimed_pessimism(dir.path(), "6ms");
    let model = model.to_str().expect("utf-8");
    let trace = dir.path().join("run.trace.ron");
    let trace = trace.to_str().expect("utf-8");
    let out = bip(&[
        "simulate",
        model,
        "--steps",
        "200",
        "--seed",
        "1",
        "--codel-time",
        "wcet",
        "--trace",
        trace,
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let saved = std::fs::read_to_string(trace).expect("saved");
    assert!(saved.contains("\n    timed: true,\n"), "{saved}");
    let out = bip(&["trace", "show", model, trace]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(text(&out).contains("time passes "), "{}", text(&out));
    let out = bip(&["replay", model, trace]);
    let replayed = text(&out);
    assert_eq!(out.status.code(), Some(0), "{replayed}");
    assert!(replayed.contains("every step was allowed"), "{replayed}");
}
