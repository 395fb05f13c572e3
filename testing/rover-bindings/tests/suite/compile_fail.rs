//! What the bindings make a compile error: an undeclared yield, a missing codel, data of
//! another type on a port, arguments of another type, and a port the codel does not
//! write. Each case is a small crate compiled by rustc against this crate's library (the
//! one cargo built for these tests), in a temporary directory, within a time bound; the
//! test checks the compiler's message names the mistake.

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The library this test binary was built with, and the folder of its dependencies:
/// cargo puts both in the folder of the test binary.
fn library() -> (PathBuf, PathBuf) {
    let exe = std::env::current_exe().expect("the test binary's path");
    let deps = exe.parent().expect("in cargo's deps folder").to_path_buf();
    let newest = std::fs::read_dir(&deps)
        .expect("reads the deps folder")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("libbip_rover_bindings-") && n.ends_with(".rlib"))
        })
        .max_by_key(|p| p.metadata().and_then(|m| m.modified()).ok())
        .expect("cargo built the library beside the tests");
    (newest, deps)
}

/// Whether `source`, a crate that uses `bip_rover_bindings`, compiles, and the
/// compiler's messages.
fn compile(source: &str) -> (bool, String) {
    let (lib, deps) = library();
    let dir = tempfile_dir();
    let file = dir.join("case.rs");
    std::fs::write(&file, source).expect("writes the case");
    let rustc = std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    let mut child = Command::new(rustc)
        .args([
            "--edition",
            "2021",
            "--crate-type",
            "lib",
            "--emit",
            "metadata",
        ])
        .arg("--out-dir")
        .arg(&dir)
        .arg("--extern")
        .arg(format!("bip_rover_bindings={}", lib.display()))
        .arg("-L")
        .arg(format!("dependency={}", deps.display()))
        .arg(&file)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs rustc");
    let start = Instant::now();
    while child.try_wait().expect("waits for rustc").is_none() {
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("rustc took over two minutes on\n{source}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().expect("rustc's output");
    let _ = std::fs::remove_dir_all(&dir);
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The compiler's errors for `source`, which must not compile.
fn errors_of(source: &str) -> String {
    let (compiled, messages) = compile(source);
    assert!(!compiled, "compiled, yet must not:\n{source}");
    messages
}

/// A case must fail for its mistake alone: the same crate, corrected, compiles.
fn assert_compiles(source: &str) {
    let (compiled, messages) = compile(source);
    assert!(compiled, "the corrected case does not compile:\n{messages}");
}

/// A fresh folder under the system's temporary one.
fn tempfile_dir() -> PathBuf {
    static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("bip-compile-fail-{}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("creates a temporary folder");
    dir
}

fn assert_says(errors: &str, wants: &[&str]) {
    for want in wants {
        assert!(errors.contains(want), "no `{want}` in\n{errors}");
    }
}

/// The wheels, with `start` and `track` as given.
fn wheels(start: &str, track: &str) -> String {
    format!(
        "use bip_rover_bindings::*;
pub struct Wheels;
impl rflex::Codels for Wheels {{
    fn track_speed_start(&mut self, _ctx: rflex::TrackSpeedStartCtx<'_, '_>) -> rflex::TrackSpeedStart {{
        {start}
    }}
{track}
}}
"
    )
}

const TRACK: &str = "    fn track_speed_track(&mut self, _ctx: rflex::TrackSpeedTrackCtx<'_, '_>) -> rflex::TrackSpeedTrack {
        rflex::TrackSpeedTrack::PauseTrack
    }";

fn track(body: &str) -> String {
    format!(
        "    fn track_speed_track(&mut self, mut ctx: rflex::TrackSpeedTrackCtx<'_, '_>) -> rflex::TrackSpeedTrack {{
        {body}
        rflex::TrackSpeedTrack::PauseTrack
    }}"
    )
}

#[test]
fn the_correct_wheels_compile() {
    assert_compiles(&wheels(
        "rflex::TrackSpeedStart::PauseTrack",
        &track("ctx.write_odo(Odometry::default());"),
    ));
}

#[test]
fn an_undeclared_yield_does_not_compile() {
    // `start` of TrackSpeed yields only `pause::track`
    let errors = errors_of(&wheels("rflex::TrackSpeedStart::Ether", TRACK));
    assert_says(
        &errors,
        &["error[E0599]", "no variant", "`Ether`", "`TrackSpeedStart`"],
    );
}

#[test]
fn a_missing_codel_does_not_compile() {
    let errors = errors_of(&wheels("rflex::TrackSpeedStart::PauseTrack", ""));
    assert_says(&errors, &["error[E0046]", "missing: `track_speed_track`"]);
}

#[test]
fn data_of_another_type_on_a_port_does_not_compile() {
    // rflex.odo holds an Odometry
    let errors = errors_of(&wheels(
        "rflex::TrackSpeedStart::PauseTrack",
        &track("ctx.write_odo(Pose { x: 1.0 });"),
    ));
    assert_says(
        &errors,
        &["error[E0308]", "expected `Odometry`, found `Pose`"],
    );
}

#[test]
fn a_port_the_codel_does_not_write_has_no_writer() {
    // track writes rflex.odo, not pom.pose
    let errors = errors_of(&wheels(
        "rflex::TrackSpeedStart::PauseTrack",
        &track("ctx.write_pose(Pose { x: 1.0 });"),
    ));
    assert_says(&errors, &["error[E0599]", "no method named `write_pose`"]);
}

#[test]
fn arguments_of_another_type_do_not_compile() {
    // TrackSpeed takes a Float: an f64, not an f32
    let request = "pub fn drive(engine: &mut bip_rover_bindings::bip_engine::Engine) {
    let _ = bip_rover_bindings::rflex::request_track_speed(engine, 0.5f32);
}
";
    let errors = errors_of(request);
    assert_says(&errors, &["error[E0308]", "expected `f64`, found `f32`"]);
    // and a codel reads them as the model's type
    let errors = errors_of(&wheels(
        "rflex::TrackSpeedStart::PauseTrack",
        &track("let _speed: Option<&f32> = ctx.args();"),
    ));
    assert_says(
        &errors,
        &[
            "error[E0308]",
            "expected `Option<&f32>`, found `Option<&f64>`",
        ],
    );
    assert_compiles(&request.replace("0.5f32", "0.5"));
}
