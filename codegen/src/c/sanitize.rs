//! What a controller's build script adds to its codels' C flags when `BIP_C_SANITIZE`
//! names a sanitizer (`address` in .ci/run): the codels compiled under it and its runtime
//! linked into the controller; the Rust side is left as it is.

/// The C flags for the sanitizer `BIP_C_SANITIZE` names (none when it is unset), after
/// telling cargo to rebuild when it changes and to link the sanitizer's runtime. Called
/// from a build script.
pub fn sanitizer_flags() -> Vec<String> {
    println!("cargo:rerun-if-env-changed=BIP_C_SANITIZE");
    let Some(sanitizer) = std::env::var_os("BIP_C_SANITIZE") else {
        return Vec::new();
    };
    println!("cargo:rustc-link-lib=dylib=asan");
    vec![
        format!("-fsanitize={}", sanitizer.to_string_lossy()),
        "-fno-omit-frame-pointer".into(),
    ]
}
