//! End-to-end tests of `bip verify` and `bip export --promela`.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bip(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bip"))
        .args(args)
        .output()
        .unwrap()
}

fn robot(name: &str) -> String {
    format!("{}/robots/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn write_model(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

#[test]
fn exit_codes_follow_the_verdicts() {
    let o = bip(&["verify", &robot("philosophers.ron")]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("DeadlockFree") && text.contains("deadlock after 5 steps"),
        "{text}"
    );
    assert!(
        text.contains("left[") && text.contains("thinking → hungry"),
        "{text}"
    );
    assert!(text.contains("82 states"), "{text}");
    let o = bip(&["verify", &robot("philosophers-asymmetric.ron"), "-j", "1"]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    assert!(stdout(&o).contains("result: all 5 properties hold"));
}

#[test]
fn json_report_is_one_document() {
    let o = bip(&[
        "verify",
        &robot("philosophers.ron"),
        "--method",
        "explicit",
        "--format",
        "json",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).is_empty(),
        "JSON mode writes nothing on stderr: {}",
        stderr(&o)
    );
    let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(doc["model"], "philosophers");
    assert_eq!(doc["method"], "explicit");
    assert_eq!(doc["outcome"], "some_fail");
    assert_eq!(doc["stats"]["states"], 82);
    assert_eq!(doc["stats"]["complete"], true);
    let props = doc["properties"].as_array().unwrap();
    assert_eq!(props.len(), 4);
    let dl = props.iter().find(|p| p["name"] == "DeadlockFree").unwrap();
    assert_eq!(dl["verdict"], "fails");
    assert_eq!(dl["trace"]["verdict"], "Deadlock");
    assert_eq!(dl["trace"]["steps"].as_array().unwrap().len(), 5);
    let w = props.iter().find(|p| p["name"] == "someone_eats").unwrap();
    assert_eq!(w["verdict"], "holds");
    assert_eq!(w["witness"]["steps"].as_array().unwrap().len(), 2);
}

#[test]
fn junit_report_has_one_case_per_property() {
    let dir = tempfile::tempdir().unwrap();
    let junit = dir.path().join("report.xml");
    let o = bip(&[
        "verify",
        &robot("philosophers.ron"),
        "-q",
        "--junit",
        junit.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let xml = std::fs::read_to_string(&junit).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let cases: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("testcase"))
        .collect();
    assert_eq!(cases.len(), 4);
    let failed: Vec<_> = cases
        .iter()
        .filter(|c| c.children().any(|n| n.has_tag_name("failure")))
        .map(|c| c.attribute("name").unwrap())
        .collect();
    assert_eq!(failed, vec!["DeadlockFree"]);
    let suite = doc
        .descendants()
        .find(|n| n.has_tag_name("testsuite"))
        .unwrap();
    assert_eq!(suite.attribute("failures"), Some("1"));
}

#[test]
fn traces_are_saved_and_replay() {
    let dir = tempfile::tempdir().unwrap();
    let traces = dir.path().join("traces/nested");
    let o = bip(&[
        "verify",
        &robot("philosophers.ron"),
        "--trace-dir",
        traces.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let system = bip_lang::load_file(robot("philosophers.ron")).unwrap();
    let text = std::fs::read_to_string(traces.join("DeadlockFree.trace.ron")).unwrap();
    let trace = bip_lang::trace_file::from_ron(&text).unwrap();
    assert_eq!(trace.verdict, bip_model::Verdict::Deadlock);
    assert_eq!(trace.replay(&system).unwrap().len(), 5);
    assert!(traces.join("someone_eats.trace.ron").exists());
    assert!(!traces.join("neighbours_never_both_eat.trace.ron").exists());
}

#[test]
fn output_errors_are_messages_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, "").unwrap();
    // a trace directory below a regular file cannot be created
    let bad_dir: PathBuf = file.join("traces");
    let o = bip(&[
        "verify",
        &robot("philosophers.ron"),
        "--trace-dir",
        bad_dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("cannot create the trace directory"),
        "{}",
        stderr(&o)
    );
    // a full disk
    if Path::new("/dev/full").exists() {
        let o = bip(&["verify", &robot("philosophers.ron"), "--junit", "/dev/full"]);
        assert_eq!(o.status.code(), Some(2));
        assert!(
            stderr(&o).contains("cannot write the JUnit report"),
            "{}",
            stderr(&o)
        );
        assert!(!stderr(&o).contains("panicked"));
    }
    let o = bip(&[
        "export",
        &robot("philosophers.ron"),
        "--promela",
        bad_dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn bad_properties_are_load_errors_with_positions() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(robot("philosophers.ron"))
        .unwrap()
        .replace(
            "exists i in 0..N: phil[i]@eating",
            "exists i in 0..N: phil[i]@eatin",
        );
    let path = write_model(dir.path(), "bad.ron", &text);
    let o = bip(&["verify", &path]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("eatin") && err.contains("bad.ron:"), "{err}");
    let o = bip(&["verify", "/nonexistent/model.ron"]);
    assert_eq!(o.status.code(), Some(2));
    let o = bip(&["verify", &robot("philosophers.ron"), "--max-memory", "12Q"]);
    assert_eq!(o.status.code(), Some(2));
}

/// Eight counters of ten values each: 10^8 states, past every limit the tests set.
fn huge_model(dir: &Path) -> String {
    write_model(
        dir,
        "huge.ron",
        r#"System(
            name: "huge",
            atoms: { "C": Atom(locations: ["s"], initial: "s", vars: [(name: "v", ty: Int(0, 9))],
                               transitions: [(from: "s", to: "s", action: "v = (v + 1) % 10")]) },
            components: [(name: "c", atom: "C", count: 8)],
        )"#,
    )
}

#[test]
fn a_hundred_million_states_under_a_state_limit_end_inconclusive() {
    let dir = tempfile::tempdir().unwrap();
    let path = huge_model(dir.path());
    let start = std::time::Instant::now();
    let o = bip(&[
        "verify",
        &path,
        "--method",
        "explicit",
        "--max-states",
        "100000",
        "--format",
        "json",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(start.elapsed().as_secs() < 60);
    let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(doc["outcome"], "inconclusive");
    assert_eq!(doc["stopped"]["reason"], "max_states");
    assert_eq!(doc["properties"][0]["verdict"], "inconclusive");
    let o = bip(&[
        "verify",
        &path,
        "--method",
        "explicit",
        "--timeout",
        "0.2",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(3));
    assert!(stdout(&o).contains("time limit"), "{}", stdout(&o));
}

/// `--method symbolic` and `--method auto` through the binary: exit codes follow the
/// verdicts, auto says which method decided, and a deadlock the invariants cannot exclude
/// is "possible" (exit 3) when confirmation is off, never "holds".
#[test]
fn symbolic_and_auto_methods() {
    let o = bip(&[
        "verify",
        &robot("philosophers-asymmetric.ron"),
        "--method",
        "symbolic",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    assert!(stdout(&o).contains("symbolic proofs"), "{}", stdout(&o));
    let o = bip(&[
        "verify",
        &robot("philosophers.ron"),
        "--method",
        "symbolic",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    assert!(
        stdout(&o).contains("deadlock after 5 steps"),
        "{}",
        stdout(&o)
    );
    let dir = tempfile::tempdir().unwrap();
    // two counters kept equal by their connector; too many values for refined places
    let weak = write_model(
        dir.path(),
        "weak.ron",
        r#"System(
            name: "weak",
            atoms: { "Counter": Atom(locations: ["run", "done"], initial: "run",
                vars: [(name: "x", ty: Int(0, 100))], ports: ["tick", "end", "restart"],
                transitions: [
                    (from: "run", port: "tick", to: "run", guard: "x < 100", action: "x = x + 1"),
                    (from: "run", port: "end", to: "done", guard: "x == 100"),
                    (from: "done", port: "restart", to: "run", action: "x = 0"),
                ]) },
            components: [(name: "a", atom: "Counter"), (name: "b", atom: "Counter")],
            connectors: [
                (name: "step", ports: ["a.tick", "b.tick"]),
                (name: "finish", ports: ["a.end", "b.end"]),
                (name: "again", ports: ["a.restart", "b.restart"]),
            ],
        )"#,
    );
    let o = bip(&[
        "verify",
        &weak,
        "--method",
        "symbolic",
        "--confirm-states",
        "0",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stdout(&o));
    assert!(stdout(&o).contains("possible deadlock"), "{}", stdout(&o));
    let o = bip(&["verify", &weak, "--method", "explicit", "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    // auto: past its state budget the explicit method hands over to the symbolic one
    let huge = huge_model(dir.path());
    let o = bip(&["verify", &huge, "--max-states", "10000", "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    assert!(stdout(&o).contains("[symbolic]"), "{}", stdout(&o));
    let o = bip(&["verify", &robot("philosophers.ron"), "-q"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stdout(&o).contains("[explicit]"), "{}", stdout(&o));
}

/// SPIN on the exported Promela finds the same number of states and the same deadlock
/// verdict. `spin -o2` keeps SPIN from merging states that differ only in variables it
/// finds dead (bip keeps every variable).
#[test]
fn spin_agrees_on_the_examples() {
    if !common::spin_available("spin_agrees_on_the_examples") {
        return;
    }
    for (model, deadlocks) in [
        ("philosophers.ron", true),
        ("philosophers-asymmetric.ron", false),
        ("philosophers-atomic.ron", false),
        ("pipeline.ron", false),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let pml = dir.path().join("model.pml");
        let o = bip(&["export", &robot(model), "--promela", pml.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let (stored, pan) = common::spin(dir.path(), "model.pml", &[]);
        let errors = pan
            .lines()
            .any(|l| l.starts_with("pan:") && l.contains("invalid end state"));
        // every invariant of these examples holds, as SPIN's assertions say
        assert!(!pan.contains("assertion violated"), "{model}: {pan}");
        let o = bip(&["verify", &robot(model), "--format", "json"]);
        let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        assert_eq!(
            doc["stats"]["states"], stored,
            "{model}: bip and SPIN count different states"
        );
        assert_eq!(errors, deadlocks, "{model}: SPIN's deadlock verdict\n{pan}");
        let dl = doc["properties"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == "DeadlockFree")
            .unwrap()
            .clone();
        assert_eq!(dl["verdict"] == "fails", deadlocks, "{model}");
    }
}

/// Arguments that cannot be meant, and outputs that cannot be written, fail before the run
/// (exit 2, at once), not after it.
#[test]
fn arguments_and_outputs_are_checked_before_the_run() {
    let started = std::time::Instant::now();
    let o = bip(&["verify", &robot("rover.ron"), "--max-memory", "10"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("10G"), "{}", stderr(&o));
    let o = bip(&["verify", &robot("rover.ron"), "--jobs", "100000"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("1 to 1024"), "{}", stderr(&o));
    let o = bip(&[
        "verify",
        &robot("rover.ron"),
        "--junit",
        "/no/such/dir/x.xml",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("cannot write the JUnit report /no/such/dir/x.xml"),
        "{}",
        stderr(&o)
    );
    // the rover takes seconds to verify: none of these started it
    assert!(started.elapsed().as_secs() < 10);
    // a JUnit path checked but not yet written is not left behind
    let dir = tempfile::tempdir().unwrap();
    let junit = dir.path().join("x.xml");
    let o = bip(&[
        "verify",
        &robot("philosophers.ron"),
        "--junit",
        junit.to_str().unwrap(),
        "--jobs",
        "0",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!junit.exists());
}

/// With `--format json`, a model that does not load is a JSON document of its
/// diagnostics on stdout, exit 2.
#[test]
fn a_model_error_in_json_mode_is_a_json_document() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(robot("philosophers.ron"))
        .unwrap()
        .replace(
            "exists i in 0..N: phil[i]@eating",
            "exists i in 0..N: phil[i]@eatin",
        );
    let path = write_model(dir.path(), "bad.ron", &text);
    let o = bip(&["verify", &path, "--format", "json"]);
    assert_eq!(o.status.code(), Some(2));
    let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(doc["outcome"], "error");
    let e = &doc["errors"][0];
    assert_eq!(e["file"], path.as_str());
    assert!(e["message"].as_str().unwrap().contains("eatin"), "{e}");
    assert!(e["line"].as_u64().unwrap() > 1 && e["column"].as_u64().unwrap() > 1);
    let line = text.lines().position(|l| l.contains("@eatin\"")).unwrap() as u64 + 1;
    assert_eq!(e["line"].as_u64(), Some(line));
    let o = bip(&["verify", "/no/such/model.ron", "--format", "json"]);
    assert_eq!(o.status.code(), Some(2));
    let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(doc["outcome"], "error");
    assert!(doc["errors"][0]["line"].is_null());
}

/// The deadlock "why" of a GenoM model is in the JSON and JUnit reports as in the text.
#[test]
fn json_and_junit_carry_the_deadlock_why() {
    let dir = tempfile::tempdir().unwrap();
    let junit = dir.path().join("report.xml");
    let o = bip(&[
        "verify",
        &robot("rover-deadlock.ron"),
        "--method",
        "explicit",
        "--stop-at-first",
        "--format",
        "json",
        "--junit",
        junit.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let dl = doc["properties"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "DeadlockFree")
        .unwrap();
    let why: Vec<&str> = dl["why"]
        .as_array()
        .expect("a why")
        .iter()
        .map(|l| l.as_str().unwrap())
        .collect();
    assert!(
        why.iter()
            .any(|l| l.contains("ndd.GoTo codel start is ready") && l.contains("held by")),
        "{why:?}"
    );
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(
        xml.contains("why:") && xml.contains("ndd.GoTo codel start"),
        "{xml}"
    );
}

/// Two properties whose names make the same file name each get their own trace file.
#[test]
fn trace_files_have_unique_names() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(robot("philosophers.ron")).unwrap();
    let start = text.find("properties: [").expect("a property list") + "properties: [".len();
    let mut model = text.clone();
    model.insert_str(
        start,
        r#"Reachable(name: "p!", expr: "phil[0]@eating"), Reachable(name: "p?", expr: "phil[1]@eating"),"#,
    );
    let path = write_model(dir.path(), "named.ron", &model);
    let traces = dir.path().join("traces");
    let o = bip(&["verify", &path, "--trace-dir", traces.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}{}", stdout(&o), stderr(&o));
    let first = std::fs::read_to_string(traces.join("p_.trace.ron")).unwrap();
    // the second gets its name's hash: `p_-` and 16 hexadecimal digits
    let hashed: Vec<String> = std::fs::read_dir(&traces)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("p_-") && n.ends_with(".trace.ron"))
        .collect();
    assert_eq!(hashed.len(), 1, "{hashed:?}");
    assert_eq!(hashed[0].len(), "p_-".len() + 16 + ".trace.ron".len());
    let second = std::fs::read_to_string(traces.join(&hashed[0])).unwrap();
    assert!(
        first.contains("p!") && second.contains("p?"),
        "{first}\n{second}"
    );
    assert!(stdout(&o).contains("saved as") && stdout(&o).contains(&hashed[0]));
}

/// `bip check` counts the properties `bip verify` lists; the report's words agree with
/// their numbers; a `-v` log into a pipe has no colour codes.
#[test]
fn counts_and_words_agree() {
    let o = bip(&["check", &robot("rover.ron")]);
    assert!(
        stdout(&o).contains("properties    11 checked"),
        "{}",
        stdout(&o)
    );
    let o = bip(&[
        "verify",
        &robot("philosophers.ron"),
        "-v",
        "--method",
        "explicit",
    ]);
    let listed = stdout(&o)
        .lines()
        .take_while(|l| !l.is_empty())
        .filter(|l| l.starts_with("  "))
        .count();
    assert_eq!(listed, 4);
    let o2 = bip(&["check", &robot("philosophers.ron")]);
    assert!(
        stdout(&o2).contains("properties    4 checked"),
        "{}",
        stdout(&o2)
    );
    assert!(!stderr(&o).contains('\u{1b}'), "{}", stderr(&o));
    assert!(!stdout(&o).contains(" 1 steps"), "{}", stdout(&o));
}

/// A range error made by firing a step: the counterexample lists that step last, marked
/// as the error and named by its connector, with either method.
#[test]
fn a_range_error_trace_ends_with_the_step_that_makes_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_model(
        dir.path(),
        "buf.ron",
        r#"System(
            name: "buf",
            atoms: {
                "Buf": Atom(locations: ["on"], initial: "on", vars: [(name: "n", ty: Int(0, 3))],
                            ports: ["put"],
                            transitions: [(from: "on", port: "put", to: "on", action: "n = n + 1")]),
                "Src": Atom(locations: ["s"], initial: "s", ports: ["give"],
                            transitions: [(from: "s", port: "give", to: "s")]),
            },
            components: [(name: "buf", atom: "Buf"), (name: "src", atom: "Src")],
            connectors: [(name: "put", ports: ["src.give", "buf.put"])],
        )"#,
    );
    let o = bip(&["verify", &path, "--method", "explicit", "-q"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stdout(&o).contains("  3  put  buf.n: 2 → 3\n  4  put  ✗ firing it makes the range error"),
        "{}",
        stdout(&o)
    );
    for method in ["explicit", "symbolic"] {
        let o = bip(&["verify", &path, "--method", method, "--format", "json"]);
        let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        let range = doc["properties"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == "RangeErrors")
            .unwrap();
        assert_eq!(range["error_step"], "put", "{method}: {range}");
        assert_eq!(range["trace"]["steps"].as_array().unwrap().len(), 3);
    }
}

/// `--method auto` says which methods ran and gives each phase's figures, then the whole
/// run's: the explicit phase's seconds are its own, within the run's.
#[test]
fn auto_reports_each_phase_and_the_whole_run() {
    let dir = tempfile::tempdir().unwrap();
    let huge = huge_model(dir.path());
    let o = bip(&["verify", &huge, "--max-states", "10000"]);
    assert_eq!(o.status.code(), Some(0), "{}", stdout(&o));
    let text = stdout(&o);
    assert!(
        text.contains("auto: explicit-state exploration") && text.contains("then symbolic proofs"),
        "{text}"
    );
    assert!(
        text.contains("\nexplicit: ") && text.contains("\nsymbolic: "),
        "{text}"
    );
    assert!(text.contains(" s in all, peak memory "), "{text}");
    let o = bip(&["verify", &huge, "--max-states", "10000", "--format", "json"]);
    let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let explicit = doc["stats"]["seconds"].as_f64().unwrap();
    let symbolic = doc["symbolic"]["seconds"].as_f64().unwrap();
    let all = doc["seconds"].as_f64().unwrap();
    assert!(explicit + symbolic <= all + 0.01, "{doc}");
    assert!(doc["peak_memory_bytes"].as_u64().unwrap() > 0);
    // a model the explicit phase decides: no symbolic proof, and the header says so
    let o = bip(&["verify", &robot("philosophers.ron")]);
    assert!(
        stdout(&o).contains("it decided every property") && !stdout(&o).contains("\nsymbolic: "),
        "{}",
        stdout(&o)
    );
}
