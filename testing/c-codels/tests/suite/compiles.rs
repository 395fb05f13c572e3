//! The glue bip-codegen generates for every GenoM3 file of robots/ (the rover's and the
//! drone's components: ports in and out, services' parameters and locals, bounded
//! sequences, records, arrays) compiles, as a library, against bip-engine and bip-genom-c
//! with every warning an error.

use std::path::Path;

use crate::tools::{run, rustc};

#[test]
fn the_glue_of_every_gen_file_of_robots_compiles() {
    let robots = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots");
    let include = [robots.join("genom3/idl"), robots.join("drone/idl")];
    let dir = tempfile::tempdir().expect("a temporary directory");
    let mut lib = String::new();
    for (folder, stem) in [
        ("genom3", "loco"),
        ("genom3", "loc"),
        ("genom3", "nav"),
        ("drone", "flight"),
        ("drone", "maneuver"),
        ("drone", "mocap"),
        ("drone", "pose"),
        ("drone", "rotorcraft"),
    ] {
        let gen = robots.join(folder).join(format!("{stem}.gen"));
        let spec = bip_lang::read_gen_file(&gen, &include).unwrap_or_else(|e| panic!("{e:?}"));
        let glue = bip_codegen::c::rust_glue(&spec).unwrap_or_else(|e| panic!("{stem}: {e}"));
        let file = dir.path().join(format!("{stem}_c.rs"));
        std::fs::write(&file, glue).expect("writes");
        lib.push_str(&format!("pub mod {stem}_c {{ include!({file:?}); }}\n"));
    }
    // and a component whose memory holds pointers (an unbounded sequence in its ids, an
    // unbounded string local): its module object still goes to a task thread
    let gen = dir.path().join("ptrs.gen");
    std::fs::write(
        &gen,
        "component ptrs {\n  ids { sequence<double> xs; };\n  task t { period 10 ms; };\n  activity A() {\n    task t;\n    local string name;\n    codel<start> p_a(inout xs, inout name) yield ether;\n  };\n};\n",
    )
    .expect("writes");
    let spec = bip_lang::read_gen_file(&gen, &[]).unwrap_or_else(|e| panic!("{e:?}"));
    let glue = bip_codegen::c::rust_glue(&spec).unwrap_or_else(|e| panic!("ptrs: {e}"));
    let file = dir.path().join("ptrs_c.rs");
    std::fs::write(&file, glue).expect("writes");
    lib.push_str(&format!(
        "pub mod ptrs_c {{ include!({file:?}); }}\npub fn bind(b: bip_genom_c::bip_engine::EngineBuilder) -> bip_genom_c::bip_engine::EngineBuilder {{ ptrs_c::ptrs::bind(b) }}\n"
    ));
    std::fs::write(dir.path().join("lib.rs"), lib).expect("writes");
    let (ok, said) = run(rustc()
        .args(["--crate-type", "lib", "-D", "warnings", "--out-dir"])
        .arg(dir.path())
        .arg(dir.path().join("lib.rs")));
    assert!(ok, "the glue does not compile:\n{said}");
}
