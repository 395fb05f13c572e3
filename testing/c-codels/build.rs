//! Writes counter.gen's C headers into `OUT_DIR/include`, as a controller's build script
//! would, and compiles the component's codels (codels/*.c) against them with the `cc`
//! crate: a codel of another prototype than the `.gen` file gives is a compile error here.
//! Writes the `#[repr(C)]` mirrors of counter.gen's and mirrors.gen's types.

use std::path::PathBuf;

fn main() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let include = out.join("include");
    if let Err(e) = bip_codegen::write_c_headers(dir.join("counter.gen"), &[], &include) {
        panic!("C headers of counter.gen: {e}");
    }
    // the Rust mirrors of the components' C types
    for (gen, file) in [
        ("counter.gen", "counter_types.rs"),
        ("mirrors.gen", "mirrors_types.rs"),
    ] {
        let spec = match bip_lang::read_gen_file(&dir.join(gen), &[]) {
            Ok(spec) => spec,
            Err(e) => panic!("{gen}: {e:?}"),
        };
        let text = match bip_codegen::c::rust_mirrors(&spec) {
            Ok(text) => text,
            Err(e) => panic!("Rust mirrors of {gen}: {e}"),
        };
        println!("cargo:rerun-if-changed={}", dir.join(gen).display());
        if let Err(e) = std::fs::write(out.join(file), text) {
            panic!("{file}: {e}");
        }
    }
    let codels = dir.join("codels/counter.c");
    println!("cargo:rerun-if-changed={}", codels.display());
    let mut build = cc::Build::new();
    build
        .file(&codels)
        .include(&include)
        .std("c11")
        .warnings(true)
        .extra_warnings(true)
        .warnings_into_errors(true);
    // BIP_C_SANITIZE=address: the codels under AddressSanitizer (.ci/run), its runtime
    // linked into the tests; the Rust side is left as it is
    println!("cargo:rerun-if-env-changed=BIP_C_SANITIZE");
    if let Some(sanitizer) = std::env::var_os("BIP_C_SANITIZE") {
        let sanitizer = sanitizer.to_string_lossy();
        build
            .flag(format!("-fsanitize={sanitizer}"))
            .flag("-fno-omit-frame-pointer");
        println!("cargo:rustc-link-lib=dylib=asan");
    }
    build.compile("counter_codels");
}
