//! The loader on mutated example models: every model of `robots/` and `robots/bench/`,
//! with byte and token mutations (deletions, duplications, swaps, digit changes, long lines,
//! deep nesting, long chains), through parsing, the GenoM expansion and compilation. Every
//! input must load or give diagnostics whose positions lie in the file and that print; none
//! may panic or run past a time bound.
//!
//! The cases run in a child process capped in memory (a mutation can declare a large
//! family). CI runs a few hundred; `BIP_FUZZ_CASES=20000 cargo test -p bip-lang --test
//! suite fuzz --release` runs more.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{mpsc, Mutex};
use std::time::Duration;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

use crate::robustness::render;
use bip_lang::{load_str, LoadError};

/// Cases when `BIP_FUZZ_CASES` is not set.
const CI_CASES: u32 = 300;
/// The child's address-space cap, in KiB.
const MEMORY_KIB: u64 = 4_000_000;
/// One input's time bound, in seconds (a debug build loading the largest bench model,
/// with a slow machine's margin).
const CASE_SECS: u64 = 60;

fn seeds() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots");
    let mut out = Vec::new();
    for dir in [root.clone(), root.join("bench")] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
            .expect("robots/ is readable")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "ron"))
            .collect();
        files.sort();
        for f in files {
            let text = std::fs::read_to_string(&f).expect("a model");
            if text.len() <= 64 * 1024 {
                out.push((f.display().to_string(), text));
            }
        }
    }
    assert!(out.len() >= 10, "the example models are found");
    out
}

/// One mutation, with positions as fractions of the text so that they apply to any seed.
#[derive(Clone, Debug)]
pub(crate) enum Mutation {
    DeleteBytes(f64, usize),
    DuplicateBytes(f64, usize),
    SwapBytes(f64, f64, usize),
    DeleteToken(f64),
    DuplicateToken(f64, usize),
    SwapTokens(f64, f64),
    Digit(f64, u8),
    Number(f64, &'static str),
    Insert(f64, Insertion),
    /// An insertion inside a string (where expressions are): which string, and where in it.
    InString(f64, f64, Insertion),
}

#[derive(Clone, Debug)]
pub(crate) enum Insertion {
    LongLine(usize),
    Parens(usize),
    Nots(usize),
    Chain(&'static str, usize),
    Quantifier(&'static str),
    Text(&'static str),
}

const NUMBERS: &[&str] = &[
    "0",
    "-1",
    "9223372036854775807",
    "9223372036854775808",
    "-9223372036854775808",
    "18446744073709551616",
    "65536",
];

const SNIPPETS: &[&str] = &[
    "\"", "(", ")", "[", "]", "{", "}", ",", ":", ";", "..", "\r", "\u{feff}", "é", "//", "/*",
    "r#\"", "?", "@", "=>", "&&", "\\", "'",
];

pub(crate) fn mutation() -> impl Strategy<Value = Mutation> {
    let at = 0.0..1.0f64;
    prop_oneof![
        (at.clone(), 1..32usize).prop_map(|(a, n)| Mutation::DeleteBytes(a, n)),
        (at.clone(), 1..200usize).prop_map(|(a, n)| Mutation::DuplicateBytes(a, n)),
        (at.clone(), at.clone(), 1..16usize).prop_map(|(a, b, n)| Mutation::SwapBytes(a, b, n)),
        at.clone().prop_map(Mutation::DeleteToken),
        (at.clone(), 1..4usize).prop_map(|(a, n)| Mutation::DuplicateToken(a, n)),
        (at.clone(), at.clone()).prop_map(|(a, b)| Mutation::SwapTokens(a, b)),
        (at.clone(), 0..10u8).prop_map(|(a, d)| Mutation::Digit(a, d)),
        (at.clone(), prop::sample::select(NUMBERS)).prop_map(|(a, n)| Mutation::Number(a, n)),
        (at.clone(), insertion()).prop_map(|(a, i)| Mutation::Insert(a, i)),
        (at.clone(), at, insertion()).prop_map(|(a, b, i)| Mutation::InString(a, b, i)),
    ]
}

fn insertion() -> impl Strategy<Value = Insertion> {
    prop_oneof![
        prop::sample::select(vec![1_000usize, 70_000]).prop_map(Insertion::LongLine),
        (150..260usize).prop_map(Insertion::Parens),
        (150..260usize).prop_map(Insertion::Nots),
        (
            prop::sample::select(vec![" && true", " || false", " + 1", " * 1", " - 0"]),
            prop::sample::select(vec![10usize, 1_000, 20_000])
        )
            .prop_map(|(op, n)| Insertion::Chain(op, n)),
        prop::sample::select(vec![
            "forall i in 0..9223372036854775807: ",
            "sum i in -9223372036854775808..9223372036854775807: ",
            "count i in 0..100000: ",
            "exists i in 0..3: forall j in 0..3: forall k in 0..3: ",
        ])
        .prop_map(Insertion::Quantifier),
        prop::sample::select(SNIPPETS).prop_map(Insertion::Text),
    ]
}

/// Byte ranges of the text's tokens: words, numbers, strings, single punctuation.
fn tokens(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let start = i;
        let c = b[i];
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        if c.is_ascii_alphanumeric() || c == b'_' {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
        } else if c == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i = (i + 1).min(b.len());
        } else {
            i += text[i..].chars().next().map_or(1, char::len_utf8);
        }
        out.push((start, i));
    }
    out
}

fn floor(text: &str, mut i: usize) -> usize {
    i = i.min(text.len());
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn pos(text: &str, at: f64) -> usize {
    floor(text, (at * text.len() as f64) as usize)
}

fn range(text: &str, at: f64, n: usize) -> (usize, usize) {
    let a = pos(text, at);
    (a, floor(text, a + n))
}

pub(crate) fn apply(text: &mut String, m: &Mutation) {
    let toks = tokens(text);
    let tok = |at: f64| toks.get(((at * toks.len() as f64) as usize).min(toks.len().max(1) - 1));
    match *m {
        Mutation::DeleteBytes(at, n) => {
            let (a, b) = range(text, at, n);
            text.replace_range(a..b, "");
        }
        Mutation::DuplicateBytes(at, n) => {
            let (a, b) = range(text, at, n);
            let copy = text[a..b].to_string();
            text.insert_str(b, &copy);
        }
        Mutation::SwapBytes(x, y, n) => {
            let (mut a, mut b) = (range(text, x, n), range(text, y, n));
            if a.0 > b.0 {
                std::mem::swap(&mut a, &mut b);
            }
            if a.1 <= b.0 {
                let (sa, sb) = (text[a.0..a.1].to_string(), text[b.0..b.1].to_string());
                text.replace_range(b.0..b.1, &sa);
                text.replace_range(a.0..a.1, &sb);
            }
        }
        Mutation::DeleteToken(at) => {
            if let Some(&(a, b)) = tok(at) {
                text.replace_range(a..b, "");
            }
        }
        Mutation::DuplicateToken(at, n) => {
            if let Some(&(a, b)) = tok(at) {
                let copy = format!(" {}", &text[a..b]).repeat(n);
                text.insert_str(b, &copy);
            }
        }
        Mutation::SwapTokens(x, y) => {
            if let (Some(&p), Some(&q)) = (tok(x), tok(y)) {
                let (p, q) = if p.0 <= q.0 { (p, q) } else { (q, p) };
                if p.1 <= q.0 {
                    let (sp, sq) = (text[p.0..p.1].to_string(), text[q.0..q.1].to_string());
                    text.replace_range(q.0..q.1, &sp);
                    text.replace_range(p.0..p.1, &sq);
                }
            }
        }
        Mutation::Digit(at, d) => {
            let from = pos(text, at);
            if let Some(k) = text[from..].find(|c: char| c.is_ascii_digit()) {
                let k = from + k;
                text.replace_range(k..k + 1, &d.to_string());
            }
        }
        Mutation::Number(at, n) => {
            let from = pos(text, at);
            if let Some(k) = text[from..].find(|c: char| c.is_ascii_digit()) {
                let k = from + k;
                let end = text[k..]
                    .find(|c: char| !c.is_ascii_digit())
                    .map_or(text.len(), |e| k + e);
                text.replace_range(k..end, n);
            }
        }
        Mutation::Insert(at, ref what) => {
            let p = pos(text, at);
            text.insert_str(p, &insertion_text(what));
        }
        Mutation::InString(which, at, ref what) => {
            let strings: Vec<&(usize, usize)> = toks
                .iter()
                .filter(|(a, b)| b - a >= 2 && text.as_bytes()[*a] == b'"')
                .collect();
            if let Some(&&(a, b)) = strings.get((which * strings.len() as f64) as usize) {
                let p = floor(text, a + 1 + ((b - a - 2) as f64 * at) as usize);
                text.insert_str(p, &insertion_text(what));
            }
        }
    }
}

fn insertion_text(what: &Insertion) -> String {
    match *what {
        Insertion::LongLine(n) => " ".repeat(n),
        Insertion::Parens(n) => "(".repeat(n) + "true" + &")".repeat(n),
        Insertion::Nots(n) => "!".repeat(n),
        Insertion::Chain(op, n) => op.repeat(n),
        Insertion::Quantifier(q) => q.to_string(),
        Insertion::Text(t) => t.to_string(),
    }
}

/// Loads one input and checks what comes back. A hang ends the child at once, with the
/// input (shrinking would rerun it many times over).
fn check(name: &str, text: String) -> Result<(), TestCaseError> {
    let (tx, rx) = mpsc::channel();
    let input = text.clone();
    std::thread::spawn(move || {
        let result = load_str("fuzz.ron", &text);
        let rendered = result.as_ref().err().map(render);
        let _ = tx.send((text, result.err(), rendered));
    });
    let outcome = match rx.recv_timeout(Duration::from_secs(CASE_SECS)) {
        Ok(v) => v,
        Err(mpsc::RecvTimeoutError::Timeout) => {
            let path = std::env::temp_dir().join("bip-fuzz-hang.ron");
            let _ = std::fs::write(&path, &input);
            eprintln!(
                "{name}: a mutated model did not load within {CASE_SECS} s; it is in {}",
                path.display()
            );
            std::process::exit(3);
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            let at = LAST_PANIC.lock().map(|p| p.clone()).unwrap_or_default();
            return failure(&input, format!("{name}: the loader panicked at {at}"));
        }
    };
    let (text, err, rendered) = outcome;
    let Some(err) = err else {
        LOADED.fetch_add(1, Ordering::Relaxed);
        return Ok(());
    };
    REFUSED.fetch_add(1, Ordering::Relaxed);
    let LoadError::Model(m) = &err else {
        return failure(&text, format!("{name}: not a model error: {err}"));
    };
    if m.errors.is_empty() {
        return failure(&text, format!("{name}: an error without diagnostics"));
    }
    let shown = m.text.as_str();
    let inside = |s: &bip_lang::source::Span| {
        s.start <= s.end
            && s.end <= shown.len()
            && shown.is_char_boundary(s.start)
            && shown.is_char_boundary(s.end)
    };
    for e in &m.errors {
        if !inside(&e.span) || e.notes.iter().any(|(s, _)| !inside(s)) {
            let what = format!("{name}: a span of `{}` is outside the file", e.message);
            return failure(&text, what);
        }
        if e.span.is_none() && e.message != "the file is empty" {
            let mut n = UNPLACED.lock().expect("not poisoned");
            if n.len() < 20 && !n.contains(&e.message) {
                n.push(e.message.clone());
            }
        }
    }
    if !rendered.unwrap_or_default().contains("fuzz.ron") {
        return failure(&text, format!("{name}: the diagnostic does not print"));
    }
    Ok(())
}

/// A failed case: in a survey (`BIP_FUZZ_SURVEY=1`, a run by hand) it is recorded, one
/// input per kind, and the run goes on; otherwise the case fails and shrinks.
fn failure(input: &str, what: String) -> Result<(), TestCaseError> {
    if std::env::var_os("BIP_FUZZ_SURVEY").is_none() {
        return Err(TestCaseError::fail(what));
    }
    let mut found = FOUND.lock().expect("not poisoned");
    let kind = what.split(": ").skip(1).collect::<Vec<_>>().join(": ");
    if !found.iter().any(|(k, _)| *k == kind) {
        let path = std::env::temp_dir().join(format!("bip-fuzz-{}.ron", found.len()));
        let _ = std::fs::write(&path, input);
        eprintln!("fuzz: found {what} ({})", path.display());
        found.push((kind, path.display().to_string()));
    }
    Ok(())
}

static FOUND: Mutex<Vec<(String, String)>> = Mutex::new(Vec::new());
static UNPLACED: Mutex<Vec<String>> = Mutex::new(Vec::new());
static LAST_PANIC: Mutex<String> = Mutex::new(String::new());

fn run(cases: u32) {
    let seeds = seeds();
    let config = Config {
        cases,
        failure_persistence: None,
        max_shrink_iters: 200,
        ..Config::default()
    };
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &seed_bytes());
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if let (Some(l), Ok(mut last)) = (info.location(), LAST_PANIC.lock()) {
            *last = format!(
                "{}:{}: {}",
                l.file(),
                l.line(),
                info.payload()
                    .downcast_ref::<String>()
                    .map(String::as_str)
                    .or_else(|| info.payload().downcast_ref::<&str>().copied())
                    .unwrap_or("")
            );
        }
        if std::env::var_os("BIP_FUZZ_SURVEY").is_none() {
            hook(info);
        }
    }));
    let mut runner = TestRunner::new_with_rng(config, rng);
    let strategy = (0..seeds.len(), prop::collection::vec(mutation(), 1..4));
    let result = runner.run(&strategy, |(k, muts)| {
        let (name, seed) = &seeds[k];
        let mut text = seed.clone();
        for m in &muts {
            apply(&mut text, m);
        }
        check(name, text)
    });
    eprintln!(
        "fuzz: {cases} cases from {} models: {} loaded, {} refused with diagnostics",
        seeds.len(),
        LOADED.load(Ordering::Relaxed),
        REFUSED.load(Ordering::Relaxed)
    );
    for m in UNPLACED.lock().expect("not poisoned").iter() {
        eprintln!("fuzz: an error without a position: {m}");
    }
    if let Err(e) = result {
        panic!("{e}");
    }
}

static LOADED: AtomicUsize = AtomicUsize::new(0);
static REFUSED: AtomicUsize = AtomicUsize::new(0);

/// The same cases on every run unless `BIP_FUZZ_SEED` says otherwise.
fn seed_bytes() -> [u8; 32] {
    let n: u64 = std::env::var("BIP_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(19);
    let mut out = [0u8; 32];
    out[..8].copy_from_slice(&n.to_le_bytes());
    out
}

/// The cases themselves, run only as the child of [`mutated_models_load_or_fail_cleanly`].
#[test]
#[ignore = "run by mutated_models_load_or_fail_cleanly in a memory-capped child"]
fn fuzz_child() {
    let cases = std::env::var("BIP_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(CI_CASES);
    run(cases);
}

#[test]
fn mutated_models_load_or_fail_cleanly() {
    let exe = std::env::current_exe().expect("the test binary");
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -v {MEMORY_KIB}; exec \"$0\" fuzz::fuzz_child --exact --ignored --nocapture"
        ))
        .arg(exe)
        .output()
        .expect("bash runs the child");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprintln!(
        "{}",
        stderr
            .lines()
            .filter(|l| l.starts_with("fuzz:"))
            .collect::<Vec<_>>()
            .join("\n")
    );
    assert!(
        out.status.success() && stdout.contains("1 passed"),
        "the fuzz cases failed ({}):\n{stdout}\n{stderr}",
        out.status
    );
}
