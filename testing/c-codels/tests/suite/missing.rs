//! A codel the C sources do not define is an error naming it when the controller is
//! linked: counter.c compiled with `counter_idle_start` renamed away, and a program that
//! binds counter through the generated glue, built with rustc against this crate's own
//! dependencies, fails to link with the linker's message naming the codel.

use std::path::Path;
use std::process::Command;

use crate::tools::{run, rustc};

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
        "mod glue {{ include!({:?}); }}\nfn main() {{\n    let bind: fn(bip_genom_c::bip_engine::EngineBuilder) -> bip_genom_c::bip_engine::EngineBuilder = glue::counter::bind;\n    std::hint::black_box(bind);\n}}\n",
        out.join("counter_c.rs")
    );
    std::fs::write(tmp.join("main.rs"), main).expect("writes");
    run(rustc()
        .args(["--crate-type", "bin", "-o"])
        .arg(tmp.join("main"))
        .arg(tmp.join("main.rs"))
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
