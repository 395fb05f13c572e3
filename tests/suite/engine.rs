//! End-to-end tests of `bip simulate` and `bip replay`.

use crate::common::bip;
use std::process::{Command, Output};

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn simulate_checks_invariants_and_its_trace_replays_through_the_engine() {
    let dir = tempfile::tempdir().expect("temp dir");
    let trace = dir.path().join("run.ron");
    let trace = trace.to_str().expect("utf-8");
    let out = bip(&[
        "simulate",
        "robots/rover.ron",
        "--steps",
        "3000",
        "--seed",
        "7",
        "--trace",
        trace,
    ]);
    let text = stdout(&out);
    let summary = text.clone();
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(text.contains("3000 steps"), "{text}");
    assert!(
        text.contains("5 invariants and deadlock freedom held at every step"),
        "{text}"
    );
    // the same seed, the same run
    let again = bip(&[
        "simulate",
        "robots/rover.ron",
        "--steps",
        "3000",
        "--seed",
        "7",
    ]);
    assert_eq!(
        text.lines().nth(1),
        stdout(&again).lines().nth(1),
        "deterministic for a seed"
    );
    let out = bip(&["replay", "robots/rover.ron", trace]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert_eq!(text.matches("allowed: ").count(), 3000, "{text}");
    // the replay ran as many codels and ticks as the simulation reported
    let counted = |what: &str| -> usize {
        let stats = summary.lines().nth(1).expect("a statistics line");
        let before = stats.split(&format!(" {what}")).next().expect("the count");
        let n = before.rsplit(' ').next().expect("a number");
        n.parse().expect("a count")
    };
    assert_eq!(
        text.matches("allowed: codel ").count(),
        counted("codels"),
        "{text}"
    );
    assert_eq!(
        text.matches("allowed: tick ").count(),
        counted("ticks"),
        "{text}"
    );
    assert!(counted("codels") > 100, "{summary}");
    assert!(text.contains("result: every step was allowed"), "{text}");
}

#[test]
fn simulate_finds_the_rovers_deadlock_and_replay_shows_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let trace = dir.path().join("dl.ron");
    let trace = trace.to_str().expect("utf-8");
    let out = bip(&[
        "simulate",
        "robots/rover-deadlock.ron",
        "--steps",
        "5000",
        "--seed",
        "1",
        "--trace",
        trace,
    ]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("DEADLOCK after step"), "{text}");
    let out = bip(&["replay", "robots/rover-deadlock.ron", trace]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("deadlock reached after"), "{text}");
    assert!(
        text.contains("waiting: ndd.GoTo codel `start`")
            && text.contains("held by navigate_with_laser (line 145): Requires("),
        "{text}"
    );
    assert!(text.contains("result: DeadlockFree fails"), "{text}");
}

#[test]
fn simulate_runs_core_models_and_reports_their_deadlocks() {
    let out = bip(&[
        "simulate",
        "robots/philosophers-asymmetric.ron",
        "--steps",
        "500",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stdout(&out));
    let out = bip(&[
        "simulate",
        "robots/philosophers.ron",
        "--steps",
        "5000",
        "--seed",
        "2",
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stdout(&out));
    assert!(stdout(&out).contains("DEADLOCK"));
}

#[test]
fn replay_refuses_a_trace_the_model_does_not_allow_with_the_reason() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("bad.ron");
    std::fs::write(
        &path,
        r#"Trace(system: "rover_deadlock", verdict: None, steps: [
            (step: "ndd_GoTo_request", state: {"ndd_GoTo.req": true, "ndd_GoTo.paused": true}),
            (step: "tick", state: {"clock.n": 1, "ndd_GoTo.paused": false}),
            (step: "ndd_GoTo_start", state: {"ndd_GoTo": "move"}),
        ])"#,
    )
    .expect("writes");
    let out = bip(&[
        "replay",
        "robots/rover-deadlock.ron",
        path.to_str().expect("utf-8"),
    ]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(2), "{text}");
    assert!(text.contains("3  ndd_GoTo_start"), "{text}");
    assert!(text.contains("NOT ALLOWED"), "{text}");
    assert!(
        text.contains("because: navigate_with_laser (line 145): Requires("),
        "{text}"
    );
}

#[test]
fn bad_input_is_exit_2() {
    let out = bip(&["replay", "robots/rover.ron", "no/such/trace.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read"));
    let out = bip(&["replay", "robots/rover.ron", "robots/rover.ron"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a trace"));
    let out = bip(&["simulate", "robots/tests/nope.ron"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn simulate_stops_at_the_first_state_that_breaks_an_invariant() {
    // a codel writes `speed` (any value in 0..=3); the invariant says it stays below 3
    let model = std::fs::read_to_string("robots/tests/mini.ron")
        .expect("reads")
        .replace(
            r#"writes: ["pose"]"#,
            r#"writes: ["pose", "speed"]"#,
        )
        .replace(
            "        DeadlockFree,\n",
            "        DeadlockFree,\n        Invariant(name: \"slow\", expr: \"rflex.speed < 3\"),\n",
        );
    assert!(model.contains("\"slow\"") && model.contains("\"speed\"]"));
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("fast.ron");
    std::fs::write(&path, model).expect("writes");
    let trace = dir.path().join("fast.trace.ron");
    let out = bip(&[
        "simulate",
        path.to_str().expect("utf-8"),
        "--steps",
        "20000",
        "--seed",
        "3",
        "--trace",
        trace.to_str().expect("utf-8"),
    ]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(text.contains("invariant `slow` FAILS after step"), "{text}");
    assert!(
        text.contains("rflex.speed: ") && text.contains("→ 3"),
        "{text}"
    );
    // the saved run ends where the invariant fails, and replay shows it
    let out = bip(&[
        "replay",
        path.to_str().expect("utf-8"),
        trace.to_str().expect("utf-8"),
    ]);
    let text = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(
        text.contains("invariant `slow` fails in the last state"),
        "{text}"
    );
}

/// Run in a shell under a memory cap (KiB of address space), from the repository.
fn capped(cap_kib: u64, args: &str) -> Command {
    let mut c = Command::new("sh");
    c.arg("-c")
        .arg(format!(
            "ulimit -v {cap_kib}; exec {} {args}",
            env!("CARGO_BIN_EXE_bip")
        ))
        .current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

/// Without `--trace` a simulation keeps only its last steps: three million steps run in
/// 200 MB of address space (they took some 600 bytes each, 1.8 GB).
#[test]
fn simulate_runs_in_constant_memory() {
    let out = capped(
        200_000,
        "simulate robots/pipeline.ron --steps 3000000 --seed 1",
    )
    .output()
    .expect("sh runs");
    let text = stdout(&out);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("3000000 steps"), "{text}");
    assert!(text.contains("held at every step"), "{text}");
}

/// Ctrl-C ends a simulation of (nearly) endless steps with its report so far, exit 3,
/// and the trace streamed so far, complete and replayable.
#[cfg(unix)]
#[test]
fn ctrl_c_ends_a_simulation_with_its_report_and_trace() {
    let dir = tempfile::tempdir().expect("temp dir");
    let trace = dir.path().join("run.ron");
    let trace = trace.to_str().expect("utf-8");
    let child = capped(
        400_000,
        &format!("simulate robots/rover.ron --steps 18446744073709551615 --trace {trace}"),
    )
    .stdout(std::process::Stdio::piped())
    .stderr(std::process::Stdio::piped())
    .spawn()
    .expect("spawns");
    // wait until the run is under way (its trace is being written), then interrupt it
    let start = std::time::Instant::now();
    while std::fs::metadata(trace).map_or(0, |m| m.len()) < 100_000 {
        assert!(
            start.elapsed().as_secs() < 60,
            "the simulation does not start"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(kill.success());
    let out = child.wait_with_output().expect("ends");
    let text = stdout(&out);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("interrupted after"), "{text}");
    assert!(text.contains("held at every step until then"), "{text}");
    assert!(text.contains("trace saved in"), "{text}");
    let steps: u64 = text
        .lines()
        .nth(1)
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{text}"));
    let out = bip(&["replay", "robots/rover.ron", trace]);
    let replayed = stdout(&out);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        &replayed[..replayed.len().min(2000)]
    );
    assert_eq!(replayed.matches("allowed: ").count() as u64, steps);
}

/// The GenoM expansion's bookkeeping (`req`, `paused`) shows only with `--all-variables`,
/// in simulate's, replay's and verify's traces alike; plurals agree with their numbers.
#[test]
fn traces_show_bookkeeping_only_on_request() {
    let dir = tempfile::tempdir().expect("temp dir");
    let trace = dir.path().join("dl.ron");
    let trace = trace.to_str().expect("utf-8");
    let args = [
        "simulate",
        "robots/rover-deadlock.ron",
        "--steps",
        "5000",
        "--seed",
        "1",
        "--trace",
        trace,
    ];
    let short = stdout(&bip(&args));
    let all = stdout(&bip(&[&args[..], &["--all-variables"]].concat()));
    assert!(all.contains(".req: false → true"), "{all}");
    assert!(
        !short.contains(".req") && !short.contains(".paused"),
        "{short}"
    );
    let short = stdout(&bip(&["replay", "robots/rover-deadlock.ron", trace]));
    let all = stdout(&bip(&[
        "replay",
        "robots/rover-deadlock.ron",
        trace,
        "--all-variables",
    ]));
    assert!(all.contains(".paused: "), "{all}");
    assert!(
        !short.contains(".req") && !short.contains(".paused"),
        "{short}"
    );
    let verify = [
        "verify",
        "robots/rover-deadlock.ron",
        "-q",
        "--method",
        "explicit",
    ];
    let short = stdout(&bip(&verify));
    let all = stdout(&bip(&[&verify[..], &["--all-variables"]].concat()));
    assert!(
        short.contains("deadlock after 1 step\n  1  ndd_GoTo_request\n"),
        "{short}"
    );
    assert!(all.contains("ndd_GoTo.req: false → true"), "{all}");
    let one = stdout(&bip(&[
        "simulate",
        "robots/philosophers.ron",
        "--steps",
        "1",
    ]));
    assert!(one.contains("  1 step: 0 ticks, 0 codels"), "{one}");
}

/// A misspelt step and a tampered value, through `bip replay`.
#[test]
fn replay_names_a_misspelt_step_and_a_tampered_value() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("bad.ron");
    let write = |steps: &str| {
        std::fs::write(
            &path,
            format!("Trace(system: \"philosophers\", steps: [{steps}], verdict: Recording)"),
        )
        .expect("writes")
    };
    let replay = || {
        let out = bip(&[
            "replay",
            "robots/philosophers.ron",
            path.to_str().expect("utf-8"),
        ]);
        assert_eq!(out.status.code(), Some(2));
        stdout(&out)
    };
    write(r#"(step: "lfet[0]", state: {"phil[0]": "hungry", "fork[0]": "taken"})"#);
    let text = replay();
    assert!(
        text.contains("NOT ALLOWED: no such interaction: `lfet[0]` (did you mean `left[0]`?)"),
        "{text}"
    );
    write(r#"(step: "left[0]", state: {"phil[0]": "eating", "fork[0]": "taken"})"#);
    let text = replay();
    assert!(
        text.contains(
            "does not lead to the recorded state: `phil[0]` recorded eating, the step gives hungry"
        ),
        "{text}"
    );
}

/// `--codel-time wcet` runs the rover as a timed model, each codel for its WCET on its
/// CPU's one preemptive core, as `bip sched` assumes: the rover, schedulable, misses
/// nothing; with the map's `fuse` raised from 70 to 120 ms the payload CPU is overloaded
/// (`bip sched`: antenna.comm never catches up) and the run fails the antenna's deadline
/// (exit 1). Without simulated times the codels are instants, and their runs are still
/// counted.
#[test]
fn simulated_codel_times_show_the_misses_of_an_overloaded_cpu() {
    let run_with = |file: &str, codel_time: &str, code: i32| {
        let out = bip(&[
            "simulate",
            file,
            "--steps",
            "20000",
            "--seed",
            "1",
            "--codel-time",
            codel_time,
        ]);
        let text = stdout(&out);
        assert_eq!(out.status.code(), Some(code), "{text}");
        text
    };
    let run = |file: &str, codel_time: &str| run_with(file, codel_time, 0);
    let text = run("robots/rover.ron", "zero");
    assert!(text.contains("codel times (none simulated"), "{text}");
    assert!(
        text.contains("0 codel runs past a WCET, 0 period's works past a deadline"),
        "{text}"
    );
    let text = run("robots/rover.ron", "wcet");
    let fuse = text
        .lines()
        .find(|l| l.trim_start().starts_with("aspect.Build.fuse"))
        .expect("a row for fuse");
    assert!(fuse.contains("70 ms"), "{fuse}");
    assert!(
        text.contains("0 codel runs past a WCET, 0 period's works past a deadline"),
        "{text}"
    );
    let rover = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/robots/rover.ron"))
        .expect("the rover");
    let dir = tempfile::tempdir().expect("temp dir");
    let heavy = dir.path().join("rover.ron");
    std::fs::write(
        &heavy,
        rover.replacen(r#"wcet: "70ms""#, r#"wcet: "120ms""#, 1),
    )
    .expect("write");
    let heavy = heavy.to_str().expect("utf-8");
    let sched = stdout(&bip(&["sched", heavy, "--demand", "bound"]));
    assert!(sched.contains("antenna.comm never catches up"), "{sched}");
    let text = run_with(heavy, "wcet", 1);
    assert!(text.contains("task antenna.comm was late"), "{text}");
    assert!(
        text.contains("invariant `antenna.comm meets its 200 ms deadline` FAILS"),
        "{text}"
    );
    assert!(text.contains("0 codel runs past a WCET"), "{text}");
    assert!(
        !text.contains(" 0 period's works past a deadline"),
        "{text}"
    );
}
