//! Generates robots/rover.ron's bindings into `OUT_DIR`, as a user's build script would,
//! and those of `models/typed.ron`, which has the types the rover lacks (ids, an `Int`
//! port, an `Int` output), and those of `models/apart.ron`, whose async codel runs apart
//! from its module object. Tells the compile-fail tests which rustc cargo builds with.

fn main() {
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    for (model, file) in [
        (
            concat!(env!("CARGO_MANIFEST_DIR"), "/../../robots/rover.ron"),
            "rover.rs",
        ),
        (
            concat!(env!("CARGO_MANIFEST_DIR"), "/models/typed.ron"),
            "typed.rs",
        ),
        (
            concat!(env!("CARGO_MANIFEST_DIR"), "/models/apart.ron"),
            "apart.rs",
        ),
    ] {
        if let Err(e) = bip_codegen::write_rust_bindings(model, out.join(file)) {
            panic!("bindings of {model}: {e}");
        }
    }
    // the compiler of this build, for the compile-fail cases to be compiled by the same
    // one as the library they use (cargo sets `RUSTC` for build scripts)
    if let Some(rustc) = std::env::var_os("RUSTC") {
        println!(
            "cargo:rustc-env=BIP_CASES_RUSTC={}",
            rustc.to_string_lossy()
        );
    }
    println!("cargo:rerun-if-env-changed=RUSTC");
}
