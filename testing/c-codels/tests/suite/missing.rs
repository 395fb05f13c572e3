//! A codel the C sources do not define is an error naming it when the controller is
//! linked: counter.c compiled with `counter_idle_start` renamed away, and a program that
//! binds counter through the generated glue, built with rustc against this crate's own
//! dependencies, fails to link with the linker's message naming the codel.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The newest `lib{name}-*.rlib` in `deps`.
fn rlib(deps: &Path, name: &str) -> PathBuf {
    let prefix = format!("lib{name}-");
    std::fs::read_dir(deps)
        .expect("the deps folder")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(&prefix) && n.ends_with(".rlib"))
        })
        .max_by_key(|p| p.metadata().and_then(|m| m.modified()).ok())
        .unwrap_or_else(|| panic!("no {prefix}*.rlib in {}", deps.display()))
}

fn run(cmd: &mut Command) -> (bool, String) {
    let out = cmd.output().unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    let said =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    (out.status.success(), said)
}

/// Compiles counter.c (with `defines`) into a static library and links a program that
/// binds counter through the generated glue against it: whether it linked, and what the
/// tools said.
fn link(tmp: &Path, defines: &[&str]) -> (bool, String) {
    let out = Path::new(env!("OUT_DIR"));
    let codels = Path::new(env!("CARGO_MANIFEST_DIR")).join("codels/counter.c");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let (ok, said) = run(Command::new(&cc)
        .args(["-std=c11", "-c", "-o"])
        .arg(tmp.join("counter.o"))
        .arg(&codels)
        .arg("-I")
        .arg(out.join("include"))
        .args(defines));
    assert!(ok, "counter.c does not compile:\n{said}");
    let _ = std::fs::remove_file(tmp.join("libcodels.a"));
    let (ok, said) = run(Command::new("ar")
        .arg("rcs")
        .arg(tmp.join("libcodels.a"))
        .arg(tmp.join("counter.o")));
    assert!(ok, "ar:\n{said}");
    let main = format!(
        "mod glue {{ include!({:?}); }}\nfn main() {{\n    let bind: fn(bip_engine::EngineBuilder) -> bip_engine::EngineBuilder = glue::counter::bind;\n    std::hint::black_box(bind);\n}}\n",
        out.join("counter_c.rs")
    );
    std::fs::write(tmp.join("main.rs"), main).expect("writes");
    let exe = std::env::current_exe().expect("the test's path");
    let deps = exe.parent().expect("its folder");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    run(Command::new(rustc)
        .args(["--edition", "2021", "--crate-type", "bin", "-o"])
        .arg(tmp.join("main"))
        .arg(tmp.join("main.rs"))
        .arg("--extern")
        .arg(format!("bip_engine={}", rlib(deps, "bip_engine").display()))
        .arg("--extern")
        .arg(format!(
            "bip_genom_c={}",
            rlib(deps, "bip_genom_c").display()
        ))
        .arg("-L")
        .arg(format!("dependency={}", deps.display()))
        .arg("-L")
        .arg(format!("native={}", tmp.display()))
        .args(["-l", "static=codels"]))
}

#[test]
fn a_missing_codel_is_a_link_error_naming_it() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    // every codel defined: the program links
    let (ok, said) = link(dir.path(), &[]);
    assert!(
        ok,
        "the glue does not link with every codel defined:\n{said}"
    );
    // the codel defined under another name: its symbol is missing
    let (ok, said) = link(dir.path(), &["-Dcounter_idle_start=counter_idle_elsewhere"]);
    assert!(!ok, "linked without counter_idle_start");
    assert!(
        said.contains("undefined reference to `counter_idle_start'")
            || said.contains("undefined symbol: counter_idle_start"),
        "the link error does not name the codel:\n{said}"
    );
}
