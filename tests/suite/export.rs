//! End-to-end tests of `bip export --promela`: its size on the rover, SPIN's verdicts on
//! it against bip's (invariants as assertions, reachability under `-DREACH_`), and the
//! bound on unrolled quantifiers.

use std::path::Path;

use std::time::{Duration, Instant};

use crate::common;
use crate::common::bip;

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Exports `model` into `dir/model.pml` and returns its size in bytes.
fn export(model: &str, dir: &Path) -> u64 {
    let pml = dir.join("model.pml");
    let o = bip(&["export", model, "--promela", pml.to_str().expect("utf-8")]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    std::fs::metadata(&pml).expect("written").len()
}

/// bip's explicit verdicts: the states explored, and each property's name, kind and
/// verdict.
fn bip_verdicts(model: &str) -> (u64, Vec<(String, String, String)>) {
    let o = bip(&[
        "verify", model, "--method", "explicit", "--format", "json", "-q",
    ]);
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON document");
    let states = doc["stats"]["states"]
        .as_u64()
        .expect("bip reports its states");
    let properties = doc["properties"]
        .as_array()
        .expect("properties")
        .iter()
        .map(|p| {
            let s = |k: &str| p[k].as_str().unwrap_or_default().to_string();
            (s("name"), s("kind"), s("verdict"))
        })
        .collect();
    (states, properties)
}

/// SPIN checks what bip checks on `model`: the same states, an assertion violation exactly
/// when an invariant fails, and for each reachability property (its own run, switched on
/// with `-DREACH_name`) a violation exactly when bip finds a witness.
fn spin_agrees(model: &str, dir: &Path) {
    let (states, properties) = bip_verdicts(model);
    let (stored, pan) = common::spin(dir, "model.pml", &[]);
    assert_eq!(
        stored, states,
        "{model}: bip and SPIN count different states"
    );
    let invariant_fails = properties
        .iter()
        .any(|(_, kind, verdict)| kind == "invariant" && verdict == "fails");
    assert_eq!(
        pan.contains("assertion violated"),
        invariant_fails,
        "{model}: SPIN's invariants\n{pan}"
    );
    let mut reachables = 0;
    for (name, _, verdict) in properties.iter().filter(|(_, k, _)| k == "reachable") {
        reachables += 1;
        let (_, pan) = common::spin(dir, "model.pml", &[&format!("REACH_{name}")]);
        assert_eq!(
            pan.contains("assertion violated"),
            verdict == "holds",
            "{model}: SPIN's witness for {name}\n{pan}"
        );
    }
    assert!(reachables > 0, "{model}: no reachability property compared");
}

#[test]
fn the_rovers_export_is_small_and_spin_checks_its_properties() {
    let dir = tempfile::tempdir().expect("temp dir");
    let size = export("robots/rover.ron", dir.path());
    // one statement per interaction, its choices inside: some 60 kB (one d_step per
    // combination of choices wrote 395 MB)
    assert!(size < 1 << 20, "the rover exports into {size} bytes");
    if !common::spin_available("the_rovers_export_is_small_and_spin_checks_its_properties") {
        return;
    }
    spin_agrees("robots/rover.ron", dir.path());
}

#[test]
fn spin_finds_a_broken_invariant_and_misses_an_unreachable_state() {
    if !common::spin_available("spin_finds_a_broken_invariant_and_misses_an_unreachable_state") {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let model = std::fs::read_to_string("robots/philosophers.ron")
        .expect("the example")
        .replace(
            "forall i in 0..N: !(phil[i]@eating && phil[(i+1)%N]@eating)",
            "forall i in 0..N: !phil[i]@eating",
        )
        .replace(
            "exists i in 0..N: phil[i]@eating\"",
            "exists i in 0..N: phil[i]@eating && phil[(i+1)%N]@eating\"",
        );
    let path = dir.path().join("broken.ron");
    std::fs::write(&path, model).expect("written");
    let path = path.to_str().expect("utf-8");
    let (_, properties) = bip_verdicts(path);
    let verdict = |name: &str| {
        properties
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|(_, _, v)| v.clone())
    };
    assert_eq!(
        verdict("neighbours_never_both_eat").as_deref(),
        Some("fails")
    );
    assert_eq!(verdict("someone_eats").as_deref(), Some("fails"));
    export(path, dir.path());
    spin_agrees(path, dir.path());
}

#[test]
fn quantifiers_unroll_within_a_bound() {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = std::fs::read_to_string("robots/philosophers.ron")
        .expect("the example")
        .replace(
            "DeadlockFree,",
            // 4,000,000 bodies: within what a model may evaluate (docs/model.md), past what
            // the export unrolls
            "DeadlockFree, Invariant(name: \"wide\", expr: \"forall i in 0..2000: forall j in 0..2000: phil[(i + j) % N]@thinking || phil[0]@eating\"),",
        );
    let path = dir.path().join("wide.ron");
    std::fs::write(&path, model).expect("written");
    let start = Instant::now();
    let o = bip(&["export", path.to_str().expect("utf-8"), "--promela", "-"]);
    // a guard against the old unrolling (32 s and an abort), not a speed assertion
    assert!(start.elapsed() < Duration::from_secs(20));
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("more than 1000000 terms"),
        "{}",
        text(&o.stderr)
    );
    assert!(o.stdout.is_empty());
}

/// A model of `n` counters, one interaction each, `a{i}` below `a{i+1}` when counter `i`
/// is not 1 (a chain of priorities with `when`), and `extra` priorities (RON text) added.
fn priority_chain(n: usize, extra: &str) -> String {
    let connectors: Vec<String> = (0..n)
        .map(|i| format!("(name: \"a{i}\", ports: [\"c[{i}].p\"])"))
        .collect();
    let priorities: Vec<String> = (0..n - 1)
        .map(|i| {
            format!(
                "(low: \"a{i}\", high: \"a{}\", when: \"c[{i}].x != 1\")",
                i + 1
            )
        })
        .collect();
    format!(
        "System(name: \"chain\",
  atoms: {{ \"C\": Atom(locations: [\"l\"], initial: \"l\", ports: [\"p\"],
    vars: [(name: \"x\", ty: Int(0, 3), init: 0)],
    transitions: [(from: \"l\", port: \"p\", to: \"l\", action: \"x = (x + 1) % 4\")]) }},
  components: [(name: \"c\", atom: \"C\", count: {n})],
  connectors: [{}],
  priorities: [{}{extra}],
  properties: [DeadlockFree,
    Invariant(name: \"first_below_3\", expr: \"c[0].x < 3\"),
    Reachable(name: \"all_2\", expr: \"forall i in 0..{n}: c[i].x == 2\")])",
        connectors.join(", "),
        priorities.join(", ")
    )
}

#[test]
fn a_chain_of_priorities_with_when_exports_in_linear_size() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("chain.ron");
    std::fs::write(&path, priority_chain(800, "")).expect("written");
    let start = Instant::now();
    let size = export(path.to_str().expect("utf-8"), dir.path());
    // one macro per group above which priorities lie: some 330 kB (the closure written
    // out per interaction grew with the cube: 203 MB at 400, an abort at 800)
    assert!(size < 1 << 20, "800 priorities export into {size} bytes");
    assert!(start.elapsed() < Duration::from_secs(30));
}

#[test]
fn spin_agrees_on_priorities_with_when_along_several_paths() {
    if !common::spin_available("spin_agrees_on_priorities_with_when_along_several_paths") {
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("chain.ron");
    // two ways up from a0 to a3 (one without `when`), and a1 below a4 when counter 3 is 2
    let extra = ", (low: \"a0\", high: \"a2\"), (low: \"a1\", high: \"a4\", when: \"c[3].x == 2\")";
    std::fs::write(&path, priority_chain(6, extra)).expect("written");
    let path = path.to_str().expect("utf-8");
    export(path, dir.path());
    spin_agrees(path, dir.path());
}
