//! What the bindings make a compile error: an undeclared yield, a missing codel, data of
//! another type on a port, arguments of another type, a port the codel does not write, a
//! plain `i64` where an `Int` is wanted, and a constant out of an `Int`'s range. Each case
//! is a small crate compiled by rustc against this crate's library (the one cargo built for
//! these tests), in a temporary directory, within a time bound; the test checks the
//! compiler's message names the mistake.

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

/// The compiler that built the library the cases use (another one cannot read it): the
/// one cargo built this crate with, as the build script recorded it, if it is still
/// there; else `$RUSTC`, else `rustc` on the path.
fn rustc() -> std::ffi::OsString {
    match option_env!("BIP_CASES_RUSTC") {
        Some(built_with) if std::path::Path::new(built_with).is_file() => built_with.into(),
        _ => std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into()),
    }
}

/// Whether `source`, a crate that uses `bip_rover_bindings`, compiles, and the
/// compiler's messages.
fn compile(source: &str) -> (bool, String) {
    let (lib, deps) = library();
    let dir = tempfile_dir();
    let file = dir.join("case.rs");
    std::fs::write(&file, source).expect("writes the case");
    let mut child = Command::new(rustc())
        // `link`, not `metadata`: an `Int` constant out of range is an error found when
        // the function that names it is compiled to code
        .args(["--edition", "2021", "--crate-type", "lib", "--emit", "link"])
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

#[test]
fn a_plain_integer_where_an_int_is_wanted_does_not_compile() {
    // Communicate takes an Int(1, 10): a `Bounded<1, 10>`, not an `i64`
    let request = "pub fn talk(engine: &mut bip_rover_bindings::bip_engine::Engine) {
    let _ = bip_rover_bindings::antenna::request_communicate(engine, 3i64);
}
";
    let errors = errors_of(request);
    assert_says(
        &errors,
        &["error[E0308]", "expected `Bounded<1, 10>`, found `i64`"],
    );
    assert_compiles(&request.replace("3i64", "bip_rover_bindings::bip_engine::Bounded::of::<3>()"));
    // a value known only at run time goes through `new` or `try_from`, which check it
    assert_compiles(&request.replace(
        "3i64",
        "bip_rover_bindings::bip_engine::Bounded::new(3).expect(\"in range\")",
    ));
}

#[test]
fn a_constant_out_of_an_ints_range_does_not_compile() {
    let request = "pub fn talk(engine: &mut bip_rover_bindings::bip_engine::Engine) {
    let packets = bip_rover_bindings::bip_engine::Bounded::of::<11>();
    let _ = bip_rover_bindings::antenna::request_communicate(engine, packets);
}
";
    let errors = errors_of(request);
    assert_says(
        &errors,
        &[
            "error[E0080]",
            "V is out of the range LO..=HI",
            "Bounded::<1, 10>::of::<11>",
        ],
    );
    assert_compiles(&request.replace("of::<11>", "of::<10>"));
}

#[test]
fn an_ids_value_out_of_range_has_no_way_through_the_context() {
    // gear of typed.ron's arm is an Int(-2, 3): its setter takes a `Bounded<-2, 3>`
    let arm = |value: &str| {
        format!(
            "use bip_rover_bindings::typed::arm;
use bip_rover_bindings::bip_engine::Bounded;
pub struct Arm;
impl arm::Codels for Arm {{
    fn move_start(&mut self, mut ctx: arm::MoveStartCtx<'_, '_>) -> arm::MoveStart {{
        ctx.set_ids_gear({value});
        ctx.set_ids_armed(true);
        arm::MoveStart::Main
    }}
    fn move_main(&mut self, _ctx: arm::MoveMainCtx<'_, '_>) -> arm::MoveMain {{
        arm::MoveMain::Ether
    }}
    fn calibrate_validate(&mut self, _ctx: arm::CalibrateValidateCtx<'_, '_>) -> arm::CalibrateValidate {{
        arm::CalibrateValidate::Ether
    }}
    fn calibrate_start(&mut self, _ctx: arm::CalibrateStartCtx<'_, '_>) -> arm::CalibrateStart {{
        arm::CalibrateStart::Ether
    }}
}}
"
        )
    };
    assert_says(
        &errors_of(&arm("7")),
        &["error[E0308]", "expected `Bounded<-2, 3>`, found integer"],
    );
    assert_says(
        &errors_of(&arm("Bounded::of::<7>()")),
        &["error[E0080]", "Bounded::<-2, 3>::of::<7>"],
    );
    assert_compiles(&arm("Bounded::of::<-2>()"));
}
