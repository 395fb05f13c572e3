//! The `.gen` parser on mutated example components: the repository's `.gen` files (and
//! the IDL file they include, and the constructs fixture) with random token and byte edits, through the preprocessor,
//! the parser, the mapping and the module checks (`import_gen_file`). Every input must
//! import or give diagnostics whose positions lie in one of its files and that print; none
//! may panic or run past a time bound.
//!
//! The cases run in a child process capped in memory, as `fuzz` does. CI runs a few
//! hundred; `BIP_FUZZ_CASES=20000 cargo test -p bip-lang --test suite gen3_fuzz --release`
//! runs more.

use std::path::Path;
use std::process::Command;
use std::sync::mpsc;
use std::time::Duration;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

use crate::fuzz::{apply, mutation};
use crate::gen3::TempDir;
use crate::robustness::render;
use bip_lang::{import_gen_file, LoadError};

const CI_CASES: u32 = 300;
const MEMORY_KIB: u64 = 4_000_000;
const CASE_SECS: u64 = 60;

/// The example files, by name: the rover's components and their IDL, and the fixture of
/// the constructs the rover does not use (interfaces provided, used and refined, `before`,
/// `delay`, `wcet`, ...).
fn seeds() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    [
        ("../robots/genom3", "loco.gen"),
        ("../robots/genom3", "loc.gen"),
        ("../robots/genom3", "nav.gen"),
        ("../robots/genom3", "idl/rover.idl"),
        ("tests/gen3", "constructs.gen"),
    ]
    .iter()
    .map(|(dir, f)| {
        let text = std::fs::read_to_string(root.join(dir).join(f)).expect("an example .gen file");
        (f.to_string(), text)
    })
    .collect()
}

/// Imports `nav.gen` with one file of the set replaced by `text`.
fn check(seeds: &[(String, String)], k: usize, text: String) -> Result<(), TestCaseError> {
    let dir = TempDir::new();
    for (i, (name, seed)) in seeds.iter().enumerate() {
        dir.write(name, if i == k { &text } else { seed });
    }
    let main = if seeds[k].0.ends_with(".gen") {
        seeds[k].0.clone()
    } else {
        "nav.gen".to_string()
    };
    let path = dir.0.join(&main);
    let include = vec![dir.0.join("idl")];
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let result = import_gen_file(&path, &include);
        let rendered = result.as_ref().err().map(render);
        let _ = tx.send((result.err(), rendered));
    });
    let (err, _) = match rx.recv_timeout(Duration::from_secs(CASE_SECS)) {
        Ok(v) => v,
        Err(mpsc::RecvTimeoutError::Timeout) => {
            let keep = std::env::temp_dir().join("bip-gen3-fuzz-hang.gen");
            let _ = std::fs::write(&keep, &text);
            eprintln!(
                "gen3 fuzz: a mutated file did not import within {CASE_SECS} s: {}",
                keep.display()
            );
            std::process::exit(3);
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            return Err(TestCaseError::fail(format!(
                "the parser panicked on:\n{text}"
            )));
        }
    };
    let Some(err) = err else {
        return Ok(());
    };
    let LoadError::Model(m) = &err else {
        return Err(TestCaseError::fail(format!("not a model error: {err}")));
    };
    prop_assert!(!m.errors.is_empty(), "an error without diagnostics");
    for e in &m.errors {
        if e.span.is_none() {
            continue;
        }
        let placed = m.files.locate(e.span).is_some_and(|(f, local)| {
            local.start <= local.end
                && local.end <= f.text.len()
                && f.text.is_char_boundary(local.start)
                && f.text.is_char_boundary(local.end)
        });
        prop_assert!(placed, "`{}` points outside its files", e.message);
    }
    Ok(())
}

/// The cases themselves, run only as the child of [`mutated_gen_files_import_or_fail_cleanly`].
#[test]
#[ignore = "run by mutated_gen_files_import_or_fail_cleanly in a memory-capped child"]
fn gen3_fuzz_child() {
    let cases = std::env::var("BIP_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(CI_CASES);
    let seeds = seeds();
    let config = Config {
        cases,
        failure_persistence: None,
        max_shrink_iters: 100,
        ..Config::default()
    };
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &[23; 32]);
    let mut runner = TestRunner::new_with_rng(config, rng);
    let strategy = (0..seeds.len(), prop::collection::vec(mutation(), 1..4));
    let result = runner.run(&strategy, |(k, muts)| {
        let mut text = seeds[k].1.clone();
        for m in &muts {
            apply(&mut text, m);
        }
        check(&seeds, k, text)
    });
    if let Err(e) = result {
        panic!("{e}");
    }
}

#[test]
fn mutated_gen_files_import_or_fail_cleanly() {
    let exe = std::env::current_exe().expect("the test binary");
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -v {MEMORY_KIB}; exec \"$0\" gen3_fuzz::gen3_fuzz_child --exact --ignored --nocapture"
        ))
        .arg(exe)
        .output()
        .expect("bash runs the child");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stdout.contains("1 passed"),
        "the gen3 fuzz cases failed ({}):\n{stdout}\n{stderr}",
        out.status
    );
}
