//! Every limit holds for every method, whatever the model's width: `--max-memory`,
//! `--timeout` and `--max-states` end a run on a wide model near their bound (exit 3, the
//! partial report), and so does Ctrl-C.
//!
//! Each run is a child process under `ulimit -v` (and a `--max-memory` of its own), so a
//! limit that does not hold fails the test instead of taking the machine down. The wide
//! models are 10,000 independent two-location components (every state has 10,000
//! successors: one batch of the exploration would need gigabytes) and the shipped
//! philosophers-10000 bench; the symbolic and auto methods' is a million components (the
//! symbolic encoding alone outgrows the limits; ten thousand it proves at once). The time bounds below guard against a hang; they assert no
//! speed.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The virtual memory a child may reserve (KiB): far above every limit tested, far below
/// what would hurt the machine.
const ULIMIT_KIB: u64 = 4_000_000;

fn robot(name: &str) -> String {
    format!("{}/robots/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// `count` independent components of two locations, each free to move at any time.
fn wide_model(dir: &Path, count: u64) -> String {
    let path = dir.join(format!("wide-{count}.ron"));
    std::fs::write(
        &path,
        format!(
            r#"System(
    name: "wide",
    atoms: {{ "C": Atom(locations: ["a", "b"], initial: "a",
                       transitions: [(from: "a", to: "b"), (from: "b", to: "a")]) }},
    components: [(name: "c", atom: "C", count: {count})],
)"#
        ),
    )
    .unwrap();
    path.display().to_string()
}

/// `bip verify MODEL ARGS --format json` under `ulimit -v`, with the wall time it took.
fn capped_verify(model: &str, args: &[&str]) -> (Output, serde_json::Value, Duration) {
    let mut line = format!(
        "ulimit -v {ULIMIT_KIB}; exec '{}' verify '{model}' --format json",
        env!("CARGO_BIN_EXE_bip")
    );
    for a in args {
        line.push_str(&format!(" '{a}'"));
    }
    let started = Instant::now();
    let out = Command::new("bash").arg("-c").arg(&line).output().unwrap();
    let took = started.elapsed();
    let text = String::from_utf8_lossy(&out.stdout);
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap_or_else(|e| {
        panic!(
            "{line}: no JSON report ({e}), exit {:?}\n{text}\n{}",
            out.status.code(),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    (out, doc, took)
}

/// The run ended inconclusive for `reason`, every property undecided or decided, none
/// claimed to hold without a look.
fn assert_stopped(what: &str, out: &Output, doc: &serde_json::Value, reason: &str) {
    assert_eq!(out.status.code(), Some(3), "{what}: {doc}");
    assert_eq!(doc["stopped"]["reason"], reason, "{what}: {doc}");
    assert_eq!(doc["outcome"], "inconclusive", "{what}: {doc}");
    for p in doc["properties"].as_array().unwrap() {
        assert_ne!(p["verdict"], "holds", "{what}: {p}");
    }
}

fn peak(doc: &serde_json::Value) -> u64 {
    doc["peak_memory_bytes"].as_u64().expect("a peak on Linux")
}

/// The three limits on one wide model with one method; prints the figures measured.
fn limits_hold(model: &str, method: &str, memory_mib: u64, with_states: bool) {
    let name = Path::new(model).file_name().unwrap().to_string_lossy();
    let limit = format!("{memory_mib}M");
    let (out, doc, took) = capped_verify(model, &["--method", method, "--max-memory", &limit]);
    assert_stopped(
        &format!("{name} {method} --max-memory {limit}"),
        &out,
        &doc,
        "max_memory",
    );
    let bytes = peak(&doc);
    eprintln!(
        "{name} --method {method} --max-memory {limit}: peak {} MiB, {:.2} s",
        bytes >> 20,
        took.as_secs_f64()
    );
    assert!(
        bytes <= (memory_mib << 20) * 3 / 2,
        "{name} {method}: peak {bytes} bytes with --max-memory {limit}"
    );

    let (out, doc, took) = capped_verify(
        model,
        &["--method", method, "--timeout", "1", "--max-memory", "2G"],
    );
    assert_stopped(
        &format!("{name} {method} --timeout 1"),
        &out,
        &doc,
        "timeout",
    );
    eprintln!(
        "{name} --method {method} --timeout 1: ended after {:.2} s (run {:.2} s), peak {} MiB",
        took.as_secs_f64(),
        doc["seconds"].as_f64().unwrap_or(0.0),
        peak(&doc) >> 20
    );
    // the run's own clock, which starts once the model is loaded
    assert!(
        doc["seconds"].as_f64().unwrap() < 3.0,
        "{name} {method}: --timeout 1 ran {} s",
        doc["seconds"]
    );

    if with_states {
        let (out, doc, took) = capped_verify(
            model,
            &[
                "--method",
                method,
                "--max-states",
                "20000",
                "--max-memory",
                "2G",
            ],
        );
        assert_stopped(
            &format!("{name} {method} --max-states 20000"),
            &out,
            &doc,
            "max_states",
        );
        let states = doc["stats"]["states"].as_u64().unwrap();
        eprintln!(
            "{name} --method {method} --max-states 20000: {states} states, {:.2} s, peak {} MiB",
            took.as_secs_f64(),
            peak(&doc) >> 20
        );
        assert!(
            (20_000..=22_000).contains(&states),
            "{name} {method}: {states} states stored with --max-states 20000"
        );
    }
}

#[test]
fn limits_hold_for_the_explicit_method_on_ten_thousand_components() {
    let dir = tempfile::tempdir().unwrap();
    limits_hold(&wide_model(dir.path(), 10_000), "explicit", 200, true);
}

#[test]
fn limits_hold_for_the_explicit_method_on_ten_thousand_philosophers() {
    limits_hold(
        &robot("bench/philosophers-10000.ron"),
        "explicit",
        200,
        true,
    );
}

/// Auto hands what its explicit phase leaves open to the symbolic one (which proves ten
/// thousand components deadlock-free): on a million, both phases meet the limits. The
/// state limit concerns the explicit phase alone, tested above.
#[test]
fn limits_hold_for_the_auto_method_on_a_million_components() {
    let dir = tempfile::tempdir().unwrap();
    limits_hold(&wide_model(dir.path(), 1_000_000), "auto", 300, false);
}

#[test]
fn limits_hold_for_the_symbolic_method_on_a_million_components() {
    let dir = tempfile::tempdir().unwrap();
    limits_hold(&wide_model(dir.path(), 1_000_000), "symbolic", 300, false);
}

/// A `bip verify` child with `-v`, its stderr read line by line.
struct Running {
    child: Child,
    stderr: BufReader<std::process::ChildStderr>,
    seen: String,
}

impl Running {
    fn start(args: &[&str]) -> Running {
        let mut child = Command::new(env!("CARGO_BIN_EXE_bip"))
            .arg("verify")
            .args(args)
            .args(["-v", "--max-memory", "1G"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let stderr = BufReader::new(child.stderr.take().unwrap());
        Running {
            child,
            stderr,
            seen: String::new(),
        }
    }

    /// Reads stderr until a line containing `text`.
    fn wait_for(&mut self, text: &str) {
        let mut line = String::new();
        loop {
            line.clear();
            let n = self.stderr.read_line(&mut line).unwrap();
            self.seen.push_str(&line);
            assert!(
                n > 0,
                "the run ended before printing {text:?}:\n{}",
                self.seen
            );
            if line.contains(text) {
                return;
            }
        }
    }

    fn interrupt(&self) {
        // SAFETY: kill(2) on our own child's pid.
        let r = unsafe { libc::kill(self.child.id() as libc::pid_t, libc::SIGINT) };
        assert_eq!(r, 0);
    }

    /// Waits for the child (at most `limit`, a guard against a hang); its exit code and
    /// stdout.
    fn finish(mut self, limit: Duration) -> (Option<i32>, String) {
        let mut stdout = String::new();
        let mut pipe = self.child.stdout.take().unwrap();
        let reader = std::thread::spawn(move || {
            let _ = pipe.read_to_string(&mut stdout);
            stdout
        });
        let started = Instant::now();
        let status = loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                break status;
            }
            if started.elapsed() > limit {
                let _ = self.child.kill();
                panic!("the run did not end within {limit:?} of Ctrl-C");
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let mut rest = String::new();
        let _ = self.stderr.read_to_string(&mut rest);
        self.seen.push_str(&rest);
        (status.code(), reader.join().unwrap())
    }
}

/// Ctrl-C during a run of `method` on the rover, once it has reported progress: exit 3,
/// the partial report (undecided properties "interrupted", never "holds" for what was
/// not decided), the JUnit file and the trace directory written.
fn ctrl_c_ends_the_run_like_a_limit(method: &str, progress: &str) {
    let dir = tempfile::tempdir().unwrap();
    let junit = dir.path().join("report.xml");
    let traces = dir.path().join("traces");
    let mut run = Running::start(&[
        &robot("rover.ron"),
        "--method",
        method,
        "--junit",
        junit.to_str().unwrap(),
        "--trace-dir",
        traces.to_str().unwrap(),
    ]);
    run.wait_for(progress);
    run.interrupt();
    let (code, stdout) = run.finish(Duration::from_secs(30));
    assert_eq!(code, Some(3), "{stdout}");
    assert!(
        stdout.contains("stopped: the run was interrupted"),
        "{stdout}"
    );
    assert!(
        stdout.contains("inconclusive  the run was interrupted")
            || stdout.contains(": the run was interrupted"),
        "{stdout}"
    );
    assert!(!stdout.contains("time limit"), "{stdout}");
    assert!(stdout.contains("result: inconclusive"), "{stdout}");
    let xml = std::fs::read_to_string(&junit).expect("the JUnit report is written");
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let cases = doc
        .descendants()
        .filter(|n| n.has_tag_name("testcase"))
        .count();
    // the rover's 8 properties, time progress, range errors, and its schedulability
    assert_eq!(cases, 11, "{xml}");
    assert!(xml.contains("interrupted"), "{xml}");
    assert!(traces.is_dir());
}

#[test]
fn ctrl_c_ends_an_explicit_run() {
    ctrl_c_ends_the_run_like_a_limit("explicit", "progress:");
}

#[test]
fn ctrl_c_ends_an_auto_run() {
    ctrl_c_ends_the_run_like_a_limit("auto", "progress:");
}

#[test]
fn ctrl_c_ends_a_symbolic_run() {
    ctrl_c_ends_the_run_like_a_limit("symbolic", "progress: symbolic:");
}

/// Ctrl-C reaches a symbolic run inside a long solver call (z3 must not take SIGINT over):
/// a nonlinear invariant keeps the solver busy until its own limit, a minute away.
#[test]
fn ctrl_c_reaches_a_symbolic_run_inside_a_solver_call() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("fermat.ron");
    std::fs::write(
        &model,
        r#"System(
    name: "fermat",
    atoms: { "C": Atom(locations: ["s"], initial: "s",
        vars: [(name: "a", ty: Int(1, 100000)), (name: "b", ty: Int(1, 100000)),
               (name: "c", ty: Int(1, 100000))],
        transitions: [
            (from: "s", to: "s", guard: "a < 100000", action: "a = a + 1"),
            (from: "s", to: "s", guard: "b < 100000", action: "b = b + 1"),
            (from: "s", to: "s", guard: "c < 100000", action: "c = c + 1"),
        ]) },
    components: [(name: "x", atom: "C")],
    properties: [Invariant(name: "fermat",
                           expr: "x.a * x.a * x.a + x.b * x.b * x.b != x.c * x.c * x.c")],
)"#,
    )
    .unwrap();
    let mut run = Running::start(&[
        model.to_str().unwrap(),
        "--method",
        "symbolic",
        "--solver-timeout",
        "60",
    ]);
    run.wait_for("fermat: implied by the invariants?");
    std::thread::sleep(Duration::from_millis(500));
    run.interrupt();
    let (code, stdout) = run.finish(Duration::from_secs(30));
    assert_eq!(code, Some(3), "{stdout}");
    assert!(
        stdout.contains("fermat        inconclusive  the run was interrupted")
            || stdout.contains("fermat       inconclusive  the run was interrupted")
            || stdout
                .lines()
                .any(|l| l.trim_start().starts_with("fermat")
                    && l.ends_with("the run was interrupted")),
        "{stdout}"
    );
    assert!(
        stdout.contains("stopped: the run was interrupted"),
        "{stdout}"
    );
}

/// A counter that ticks to 100,000: its bounded response fails only at depth 100,000, and
/// k-induction cannot prove it, so the symbolic method's observer encoding runs deeper and
/// deeper until a limit ends it.
fn deep_response(dir: &Path) -> String {
    let path = dir.join("deep-response.ron");
    std::fs::write(
        &path,
        r#"System(
    name: "deep",
    atoms: { "Counter": Atom(locations: ["s"], initial: "s", ports: ["tick"],
        vars: [(name: "n", ty: Int(0, 100000))],
        transitions: [(from: "s", port: "tick", to: "s", guard: "n < 100000", action: "n = n + 1")]) },
    components: [(name: "x", atom: "Counter")],
    connectors: [(name: "tick", ports: ["x.tick"], role: Time)],
    properties: [Response(name: "late", trigger: "x.n == 99999", response: "false", within: 0)],
)"#,
    )
    .unwrap();
    path.display().to_string()
}

#[test]
fn the_time_limit_holds_in_the_symbolic_response_encoding() {
    let dir = tempfile::tempdir().unwrap();
    let model = deep_response(dir.path());
    let (out, doc, _) = capped_verify(
        &model,
        &[
            "--method",
            "symbolic",
            "--max-depth",
            "100000",
            "--timeout",
            "2",
            "--max-memory",
            "1G",
        ],
    );
    assert_eq!(out.status.code(), Some(3), "{doc}");
    assert_eq!(doc["stopped"]["reason"], "timeout", "{doc}");
    let late = doc["properties"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "late")
        .unwrap();
    assert_eq!(late["verdict"], "inconclusive", "{doc}");
    assert!(
        doc["seconds"].as_f64().unwrap() < 5.0,
        "--timeout 2 ran {} s",
        doc["seconds"]
    );
}

#[test]
fn ctrl_c_ends_a_symbolic_response_proof() {
    let dir = tempfile::tempdir().unwrap();
    let model = deep_response(dir.path());
    let mut run = Running::start(&[&model, "--method", "symbolic", "--max-depth", "100000"]);
    run.wait_for("late: bounded model checking of the observer");
    std::thread::sleep(Duration::from_millis(500));
    run.interrupt();
    let (code, stdout) = run.finish(Duration::from_secs(30));
    assert_eq!(code, Some(3), "{stdout}");
    assert!(
        stdout
            .lines()
            .any(|l| l.trim_start().starts_with("late") && l.ends_with("the run was interrupted")),
        "{stdout}"
    );
    assert!(
        stdout.contains("stopped: the run was interrupted"),
        "{stdout}"
    );
}
