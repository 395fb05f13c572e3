//! Writes counter.gen's C headers into `OUT_DIR/include` and its Rust glue into
//! `OUT_DIR/counter_c.rs` in one call, as a controller's build script does, and compiles
//! the component's codels (codels/*.c) against the headers with the `cc` crate: a codel
//! of another prototype than the `.gen` file gives is a compile error here; the same for
//! camera.gen (`OUT_DIR/camera_c.rs`, codels/camera.c) and apart.gen, whose async codel runs
//! apart from its module object (`OUT_DIR/apart_c.rs`, codels/apart.c). Writes the
//! `#[repr(C)]` mirrors of mirrors.gen's types, for the layout tests.

use std::path::PathBuf;

fn main() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let include = match bip_codegen::c::write_c_bindings(dir.join("counter.gen"), &[], &out) {
        Ok(written) => written.include,
        Err(e) => panic!("C bindings of counter.gen: {e}"),
    };
    for gen in ["camera.gen", "apart.gen"] {
        if let Err(e) = bip_codegen::c::write_c_bindings(dir.join(gen), &[], &out) {
            panic!("C bindings of {gen}: {e}");
        }
    }
    // the Rust mirrors of mirrors.gen's C types
    let spec = match bip_lang::read_gen_file(&dir.join("mirrors.gen"), &[]) {
        Ok(spec) => spec,
        Err(e) => panic!("mirrors.gen: {e:?}"),
    };
    let text = match bip_codegen::c::rust_mirrors(&spec) {
        Ok(text) => text,
        Err(e) => panic!("Rust mirrors of mirrors.gen: {e}"),
    };
    println!(
        "cargo:rerun-if-changed={}",
        dir.join("mirrors.gen").display()
    );
    if let Err(e) = std::fs::write(out.join("mirrors_types.rs"), text) {
        panic!("mirrors_types.rs: {e}");
    }
    let codels = [
        dir.join("codels/counter.c"),
        dir.join("codels/camera.c"),
        dir.join("codels/apart.c"),
    ];
    for c in &codels {
        println!("cargo:rerun-if-changed={}", c.display());
    }
    let mut build = cc::Build::new();
    build
        .files(&codels)
        .include(&include)
        .std("c11")
        .warnings(true)
        .extra_warnings(true)
        .warnings_into_errors(true);
    // BIP_C_SANITIZE=address: the codels under AddressSanitizer (.ci/run)
    for flag in bip_codegen::c::sanitizer_flags() {
        build.flag(flag);
    }
    build.compile("counter_codels");
}
