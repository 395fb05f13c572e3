//! The C side of the example: the C headers of rover.ron's GenoM3 components and their
//! Rust glue in one call (`bip_codegen::c::write_c_layer_bindings`, into `OUT_DIR`), then the codels (codels/*.c) compiled against the headers with the `cc`
//! crate. `BIP_C_SANITIZE=address` compiles them under AddressSanitizer (.ci/run).

use std::path::PathBuf;

/// robots/genom3's components, and the example's own.
const COMPONENTS: [&str; 4] = ["loco", "loc", "nav", "odo"];

fn main() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let robots = dir.join("../../robots/genom3");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let gens: Vec<PathBuf> = COMPONENTS
        .iter()
        .map(|c| match *c {
            "odo" => dir.join("odo.gen"),
            c => robots.join(format!("{c}.gen")),
        })
        .collect();
    // one glue for the layer: loc reads the `rover::speed` odo writes, one Rust type
    let include =
        match bip_codegen::c::write_c_layer_bindings(&gens, &[robots.join("idl")], &out, "rover") {
            Ok(written) => written.include,
            Err(e) => panic!("C bindings of the rover's components: {e}"),
        };
    let mut build = cc::Build::new();
    for c in COMPONENTS.iter().copied().chain(["hook"]) {
        let file = dir.join(format!("codels/{c}.c"));
        println!("cargo:rerun-if-changed={}", file.display());
        build.file(file);
    }
    for h in ["sim.h", "hook.h"] {
        println!(
            "cargo:rerun-if-changed={}",
            dir.join("codels").join(h).display()
        );
    }
    build
        .include(&include)
        .include(dir.join("codels"))
        .std("c11")
        .warnings(true)
        .extra_warnings(true)
        .warnings_into_errors(true);
    // BIP_C_SANITIZE=address: the codels under AddressSanitizer (.ci/run)
    for flag in bip_codegen::c::sanitizer_flags() {
        build.flag(flag);
    }
    build.compile("rover_codels");
    println!("cargo:rustc-link-lib=m");
}
