//! The limits hold outside the exploration's inner loops too: under `ulimit -v` with no
//! `--max-memory` (the default limit counts the address-space limit), while loading a
//! model at the documented maxima (every command stops at the memory limit with a message,
//! never an abort), and in the symbolic method's encoding of one long action and its
//! invariant computations on a wide model (`--timeout` ends them). Each run is a child
//! process under `ulimit -v`; the time bounds guard against a hang, they assert no speed.

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// `bip ARGS` under `ulimit -v KIB`, with the wall time it took.
fn capped(kib: u64, args: &[&str]) -> (Output, Duration) {
    let mut line = format!("ulimit -v {kib}; exec '{}'", env!("CARGO_BIN_EXE_bip"));
    for a in args {
        line.push_str(&format!(" '{a}'"));
    }
    let started = Instant::now();
    let out = Command::new("bash").arg("-c").arg(&line).output().unwrap();
    (out, started.elapsed())
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The JSON report of a `verify --format json` run.
fn report(out: &Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "no JSON report ({e}), exit {:?}\n{}\n{}",
            out.status.code(),
            text(&out.stdout),
            text(&out.stderr)
        )
    })
}

fn write(dir: &Path, name: &str, model: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, model).unwrap();
    path.display().to_string()
}

/// `count` independent components of two locations, each free to move at any time.
fn wide(dir: &Path, count: u64) -> String {
    write(
        dir,
        "wide.ron",
        &format!(
            r#"System(name: "wide",
  atoms: {{ "C": Atom(locations: ["a", "b"], initial: "a",
                     transitions: [(from: "a", to: "b"), (from: "b", to: "a")]) }},
  components: [(name: "c", atom: "C", count: {count})])"#
        ),
    )
}

#[test]
fn the_default_memory_limit_counts_the_address_space_limit() {
    let dir = tempfile::tempdir().unwrap();
    let model = wide(dir.path(), 10_000);
    // no --max-memory: the run must end inconclusive with its report, not by SIGABRT when
    // an allocation passes the 1 GB of address space (it did: "memory allocation of
    // 493092864 bytes failed", exit 134)
    let (out, took) = capped(
        1_000_000,
        &["verify", &model, "--method", "explicit", "--format", "json"],
    );
    let doc = report(&out);
    assert_eq!(out.status.code(), Some(3), "{doc}");
    assert_eq!(doc["stopped"]["reason"], "max_memory", "{doc}");
    for p in doc["properties"].as_array().unwrap() {
        assert_ne!(p["verdict"], "holds", "{p}");
    }
    assert!(took < Duration::from_secs(120), "{took:?}");
}

/// A model at the documented maxima: ten million components and a connector of ten
/// million instances (a 300-byte file).
fn at_the_maxima(dir: &Path) -> String {
    write(
        dir,
        "max.ron",
        r#"System(name: "max",
  atoms: { "A": Atom(locations: ["a", "b"], initial: "a", ports: ["p"],
    transitions: [(from: "a", port: "p", to: "b"), (from: "b", port: "p", to: "a")]) },
  components: [(name: "c", atom: "A", count: 10000000)],
  connectors: [(name: "k", forall: "i in 0..10000000", ports: ["c[i].p"])])"#,
    )
}

/// The run ended at the memory limit with a message naming it, not by a signal.
fn stopped_at_the_limit(what: &str, out: &Output, code: i32) {
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(code), "{what}: {err}");
    assert!(
        err.contains("the memory limit") || err.contains("out of memory"),
        "{what}: {err}"
    );
    assert!(err.contains("help:"), "{what}: {err}");
}

#[test]
fn loading_stops_at_the_memory_limit_in_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let model = at_the_maxima(dir.path());
    let (out, took) = capped(4_000_000, &["verify", &model, "--max-memory", "300M"]);
    stopped_at_the_limit("verify --max-memory 300M", &out, 3);
    assert!(
        text(&out.stderr).contains("while loading the model"),
        "{}",
        text(&out.stderr)
    );
    assert!(took < Duration::from_secs(120), "{took:?}");
    // the default limit, under an address-space limit
    let svg = dir.path().join("max.svg").display().to_string();
    for args in [
        vec!["check", model.as_str()],
        vec!["export", model.as_str(), "--promela", "-"],
        vec![
            "graph",
            model.as_str(),
            "--level",
            "core",
            "-o",
            svg.as_str(),
        ],
    ] {
        let (out, took) = capped(1_000_000, &args);
        stopped_at_the_limit(&args.join(" "), &out, 2);
        assert!(took < Duration::from_secs(120), "{args:?}: {took:?}");
    }
}

#[test]
fn the_time_limit_holds_while_encoding_one_long_action() {
    let dir = tempfile::tempdir().unwrap();
    // 200,000 assignments in one action, each reading a variable none of them writes:
    // their encoding was quadratic (50 s for 100,000 under --timeout 5)
    let action: Vec<String> = (0..200_000)
        .map(|i| format!("y = (x + {}) % 7", i % 5))
        .collect();
    let model = write(
        dir.path(),
        "long.ron",
        &format!(
            r#"System(name: "long",
  atoms: {{ "A": Atom(locations: ["a", "b"], initial: "a",
    vars: [(name: "x", ty: Int(0, 6), init: 0), (name: "y", ty: Int(0, 6), init: 0)],
    transitions: [(from: "a", to: "b", action: "{}"), (from: "b", to: "a")]) }},
  components: [(name: "c", atom: "A", count: 1)],
  properties: [DeadlockFree])"#,
            action.join("; ")
        ),
    );
    let (out, _) = capped(
        4_000_000,
        &[
            "verify",
            &model,
            "--method",
            "symbolic",
            "--timeout",
            "2",
            "--format",
            "json",
        ],
    );
    let doc = report(&out);
    // decided within the time, or stopped by it: never far past it
    let seconds = doc["seconds"].as_f64().unwrap();
    assert!(seconds < 15.0, "--timeout 2 ran {seconds} s: {doc}");
    match out.status.code() {
        Some(0) => {}
        Some(3) => assert_eq!(doc["stopped"]["reason"], "timeout", "{doc}"),
        code => panic!("exit {code:?}: {doc}"),
    }
}

#[test]
fn the_time_limit_holds_while_computing_invariants_of_a_wide_model() {
    let dir = tempfile::tempdir().unwrap();
    // 65,536 philosophers taking both forks at once: their semiflows were deduplicated in
    // quadratic time (32 s symbolic, 57 s auto under --timeout 5)
    let model = std::fs::read_to_string(format!(
        "{}/robots/philosophers-atomic.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace("\"N\": 5", "\"N\": 65536");
    let model = write(dir.path(), "philosophers.ron", &model);
    for method in ["symbolic", "auto"] {
        let (out, _) = capped(
            4_000_000,
            &[
                "verify",
                &model,
                "--method",
                method,
                "--timeout",
                "2",
                "--format",
                "json",
            ],
        );
        let doc = report(&out);
        let seconds = doc["seconds"].as_f64().unwrap();
        assert!(
            seconds < 15.0,
            "{method}: --timeout 2 ran {seconds} s: {doc}"
        );
        assert_eq!(out.status.code(), Some(3), "{method}: {doc}");
        assert_eq!(doc["stopped"]["reason"], "timeout", "{method}: {doc}");
    }
}
