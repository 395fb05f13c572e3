//! The transcripts of the README and docs/ run as tests, so that what they show is what the
//! commands print. A transcript is a ```` ```console ```` block: `$ ` lines are commands,
//! run by `sh` in a scratch folder that sees the repository's `robots/` and `docs/`, with
//! this build's `bip` first on the PATH, standard error after standard output; the lines
//! below a command are its output, matched as snapbox matches (a line `...` stands for any
//! lines, `[..]` for any text within a line), so that figures that vary are masked where
//! they are shown. The block's info string may say more, after commas:
//! - `server`: its last command serves until it is stopped; its first output lines are
//!   matched, then it is killed;
//! - `release`: too slow for a debug build; run by `docs_transcripts_in_release`, which
//!   `.ci/run` runs on a release build.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The longest a shown command may take in a test.
const TIMEOUT_SECS: u32 = 900;

struct Transcript {
    file: PathBuf,
    line: usize,
    server: bool,
    release: bool,
    /// Each command with the line it is on and the output shown below it.
    commands: Vec<(usize, String, String)>,
}

fn repository() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn documents() -> Vec<PathBuf> {
    let mut files = vec![repository().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(repository().join("docs"))
        .expect("docs/ is there")
        .map(|e| e.expect("a docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

fn transcripts(file: &Path) -> Vec<Transcript> {
    let text = std::fs::read_to_string(file).expect("a doc is readable");
    let mut found = Vec::new();
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    while let Some((line, fence)) = lines.next() {
        let Some(info) = fence.strip_prefix("```console") else {
            continue;
        };
        let options: Vec<&str> = info.split(',').map(str::trim).collect();
        let mut transcript = Transcript {
            file: file.to_path_buf(),
            line,
            server: options.contains(&"server"),
            release: options.contains(&"release"),
            commands: Vec::new(),
        };
        for (n, l) in lines.by_ref() {
            if l.starts_with("```") {
                break;
            }
            if let Some(command) = l.strip_prefix("$ ") {
                transcript
                    .commands
                    .push((n, command.to_string(), String::new()));
            } else {
                let (_, _, output) = transcript
                    .commands
                    .last_mut()
                    .unwrap_or_else(|| panic!("{}:{n}: output before a command", file.display()));
                output.push_str(l);
                output.push('\n');
            }
        }
        found.push(transcript);
    }
    found
}

/// A scratch folder that sees the repository's examples and docs.
fn scratch() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("a scratch folder");
    for name in ["robots", "docs"] {
        std::os::unix::fs::symlink(repository().join(name), dir.path().join(name))
            .expect("links the repository's folders");
    }
    dir
}

fn shell(command: &str, dir: &Path) -> Command {
    let bin = Path::new(env!("CARGO_BIN_EXE_bip"))
        .parent()
        .expect("the binary's folder");
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut sh = Command::new("timeout");
    sh.arg(TIMEOUT_SECS.to_string())
        .arg("sh")
        .arg("-c")
        .arg(format!("exec 2>&1; {command}"))
        .current_dir(dir)
        .env("PATH", path)
        .env_remove("RUST_LOG")
        .env("NO_COLOR", "1")
        .stdin(Stdio::null());
    sh
}

/// What `command` printed; for a server, its first `lines` lines, then it is killed.
fn run(command: &str, dir: &Path, server_lines: Option<usize>) -> String {
    let mut sh = shell(command, dir);
    let Some(lines) = server_lines else {
        let out = sh.output().expect("sh runs");
        return String::from_utf8_lossy(&out.stdout).into_owned();
    };
    let mut child = sh.stdout(Stdio::piped()).spawn().expect("sh runs");
    let stdout = child.stdout.take().expect("piped");
    let mut printed = String::new();
    for line in BufReader::new(stdout).lines().take(lines) {
        let Ok(line) = line else { break };
        printed.push_str(&line);
        printed.push('\n');
    }
    // `timeout` passes the signal on to the command it runs (a kill would leave that running)
    // SAFETY: `kill` is given the pid of a child this process has not yet waited for.
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    let _ = child.wait();
    printed
}

/// Runs the transcripts that `select` selects and fails with every difference found.
fn check(select: impl Fn(&Transcript) -> bool) {
    let assert = snapbox::Assert::new().palette(snapbox::report::Palette::plain());
    let mut differences = Vec::new();
    let mut ran = 0;
    for file in documents() {
        for transcript in transcripts(&file).into_iter().filter(|t| select(t)) {
            assert!(
                !transcript.commands.is_empty(),
                "{}:{}: a console block without a command",
                file.display(),
                transcript.line
            );
            let dir = scratch();
            let last = transcript.commands.len() - 1;
            for (i, (line, command, shown)) in transcript.commands.iter().enumerate() {
                let server = (transcript.server && i == last).then(|| shown.lines().count());
                let printed = run(command, dir.path(), server);
                ran += 1;
                // trailing blanks are invisible in a doc, and editors drop them
                let [shown, printed] = [shown.as_str(), &printed].map(|text| {
                    text.lines()
                        .map(str::trim_end)
                        .collect::<Vec<_>>()
                        .join("\n")
                });
                if let Err(e) = assert.try_eq(
                    Some(&command),
                    snapbox::Data::text(printed),
                    snapbox::Data::text(shown),
                ) {
                    let place = transcript.file.strip_prefix(repository()).unwrap_or(&file);
                    differences.push(format!("{}:{line}: `{command}`\n{e}", place.display()));
                }
            }
        }
    }
    assert!(ran > 0, "no transcript ran");
    assert!(
        differences.is_empty(),
        "{} of {ran} shown commands print something else:\n\n{}",
        differences.len(),
        differences.join("\n")
    );
}

#[test]
fn docs_transcripts() {
    check(|t| !t.release);
}

/// The transcripts of runs that take minutes in a debug build; `.ci/run` runs them in
/// release (`cargo test --release --no-default-features --test suite docs_transcripts_in_release
/// -- --ignored`, as `.ci/run` does).
#[test]
#[ignore = "minutes in a debug build: .ci/run runs it in release"]
fn docs_transcripts_in_release() {
    check(|t| t.release);
}

/// The example files the docs print in full are the files the transcripts run.
#[test]
fn docs_examples_are_shown_as_they_are() {
    let model = std::fs::read_to_string(repository().join("docs/model.md")).expect("reads");
    let buffer =
        std::fs::read_to_string(repository().join("docs/examples/buffer.ron")).expect("reads");
    assert!(
        model.contains(&format!("```ron\n{buffer}```")),
        "docs/model.md no longer shows docs/examples/buffer.ron as it is"
    );
}
