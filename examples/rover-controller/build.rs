//! The rover's bindings, generated from the model into `OUT_DIR` (docs/codegen.md).

fn main() {
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../../robots/rover.ron");
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"))
        .join("rover.rs");
    if let Err(e) = bip_codegen::write_rust_bindings(model, &out) {
        panic!("bindings of {model}: {e}");
    }
}
