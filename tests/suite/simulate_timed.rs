//! End-to-end tests of `bip simulate` on timed models (docs/engine.md, "Codel times"): the
//! engine runs the model's own timed semantics, its run replays with `bip replay`, and it
//! reports a deadline miss where `bip verify` finds one under the codels' WCETs, for the
//! same task, and none where the verifier proves there is none.

use crate::common::bip;
use std::path::Path;
use std::process::Output;

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A 500 µs codel every 10 ms after a start codel that takes no time, on a cooperative
/// CPU, with `time: Exact` or without (then `--codel-time` loads it as timed).
fn one_task(timed: bool) -> String {
    let time = if timed { "time: Exact," } else { "" };
    format!(
        r#"System(name: "one", tick_ms: 1, {time}
    cpus: [(name: "main", preemption: Job)],
    modules: [(name: "m", tasks: [(name: "t", period: 10, codels: [
        (state: "start", yields: ["pause::work"]),
        (state: "work", yields: ["pause::work"], wcet: "500us")])])])"#
    )
}

/// A codel of 1 to 3 ms with a deadline of 2 ms: late at its WCET.
const LATE: &str = r#"System(name: "late", tick_ms: 1, time: Exact,
    cpus: [(name: "main", preemption: Job)],
    modules: [(name: "m", tasks: [(name: "t", period: 4, deadline: "2ms", codels: [
        (state: "start", yields: ["pause::work"]),
        (state: "work", yields: ["pause::work"], bcet: "1ms", wcet: "3ms")])])])"#;

fn simulate(file: &str, codel_time: &str, seed: u64, trace: Option<&str>) -> (Option<i32>, String) {
    let seed = seed.to_string();
    let mut args = vec![
        "simulate",
        file,
        "--steps",
        "2000",
        "--seed",
        &seed,
        "--codel-time",
        codel_time,
    ];
    if let Some(t) = trace {
        args.extend(["--trace", t]);
    }
    let out = bip(&args);
    (out.status.code(), stdout(&out))
}

/// The tasks whose deadline invariant `bip verify` finds violated.
fn verified_misses(file: &str) -> Vec<String> {
    let out = bip(&["verify", file, "-q", "--method", "explicit"]);
    stdout(&out)
        .lines()
        .filter(|l| l.contains(" deadline ") && l.contains("FAILS"))
        .filter_map(|l| l.trim_start().split(' ').next().map(str::to_string))
        .collect()
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write");
    path.to_str().expect("utf-8").to_string()
}

#[test]
fn a_timed_model_simulates_and_its_run_replays() {
    let dir = tempfile::tempdir().expect("temp dir");
    for codel_time in ["zero", "wcet", "random"] {
        let trace = dir.path().join(format!("{codel_time}.ron"));
        let trace = trace.to_str().expect("utf-8");
        let (code, text) = simulate("robots/tests/timed.ron", codel_time, 5, Some(trace));
        assert_eq!(code, Some(0), "{text}");
        assert!(text.contains("2000 steps"), "{text}");
        assert!(text.contains("0 period's works past a deadline"), "{text}");
        let out = bip(&["replay", "robots/tests/timed.ron", trace]);
        let replayed = stdout(&out);
        assert_eq!(out.status.code(), Some(0), "{replayed}");
        assert!(
            replayed.contains("every step was allowed; the engine ends in the recorded state"),
            "{replayed}"
        );
    }
}

/// Where the verifier proves every deadline met, no run misses one, whatever the seed and
/// the codel times; where it finds a miss, the run at the WCETs (the worst case) reports
/// it, for the same task, and ends on its deadline invariant.
#[test]
fn the_engine_misses_a_deadline_where_the_verifier_finds_one() {
    let dir = tempfile::tempdir().expect("temp dir");
    let one = write(dir.path(), "one.ron", &one_task(true));
    for file in ["robots/tests/timed.ron", one.as_str()] {
        assert_eq!(verified_misses(file), Vec::<String>::new(), "{file}");
        for seed in 0..3 {
            for codel_time in ["wcet", "random"] {
                let (code, text) = simulate(file, codel_time, seed, None);
                assert_eq!(code, Some(0), "{text}");
                assert!(!text.contains("was late"), "{text}");
            }
        }
    }
    let late = write(dir.path(), "late.ron", LATE);
    assert_eq!(verified_misses(&late), ["m.t"]);
    let (code, text) = simulate(&late, "wcet", 0, None);
    assert_eq!(code, Some(1), "{text}");
    assert!(
        text.contains("invariant `m.t meets its 2 ms deadline` FAILS"),
        "{text}"
    );
    assert!(
        text.contains("task m.t was late: 3 ms after its release, deadline 2 ms"),
        "{text}"
    );
    // the verifier's shortest run to the miss replays through the engine to it
    let traces = dir.path().join("traces");
    let traces = traces.to_str().expect("utf-8");
    bip(&["verify", &late, "-q", "--trace-dir", traces]);
    let trace = format!("{traces}/m_t_meets_its_2_ms_deadline.trace.ron");
    let out = bip(&["replay", &late, &trace]);
    let replayed = stdout(&out);
    assert_eq!(out.status.code(), Some(1), "{replayed}");
    assert!(
        replayed.contains("result: m.t meets its 2 ms deadline fails"),
        "{replayed}"
    );
}

/// `--codel-time` on an untimed model runs it as timed: the 500 µs codel in a 10 ms period,
/// which the untimed engine's simulated CPUs once called late (even its start codel of no
/// time), meets its deadline in every run, as the verifier proves.
#[test]
fn codel_times_on_an_untimed_model_are_the_timed_semantics() {
    let dir = tempfile::tempdir().expect("temp dir");
    let untimed = write(dir.path(), "one.ron", &one_task(false));
    for seed in 0..3 {
        for codel_time in ["wcet", "random"] {
            let (code, text) = simulate(&untimed, codel_time, seed, None);
            assert_eq!(code, Some(0), "{text}");
            assert!(text.contains("held at every step"), "{text}");
            assert!(text.contains("0 period's works past a deadline"), "{text}");
            // the codel takes its time in the model: 500 µs at the WCET
            if codel_time == "wcet" {
                let work = text
                    .lines()
                    .find(|l| l.trim_start().starts_with("m.t.work"))
                    .expect("a row for the codel");
                assert!(work.contains("500 µs  500 µs  500 µs"), "{work}");
            }
        }
    }
}
