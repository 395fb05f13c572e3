//! `bip-codegen`: Rust bindings for a model's GenoM layer, generated at build time as
//! prost-build and tonic-build do (docs/codegen.md). From `build.rs`:
//!
//! ```no_run
//! let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("rover.rs");
//! bip_codegen::write_rust_bindings("../robots/rover.ron", &out).unwrap();
//! ```
//!
//! and in the crate, `include!(concat!(env!("OUT_DIR"), "/rover.rs"));`. The generated
//! module has the model's records as structs and, per module of the model, a typed
//! request per service (its arguments' type in, a ticket that reads its typed end out),
//! per codel an enum of exactly its declared yields and exceptions (returning another
//! does not compile) and a typed context (what the model lets it read and write, of the
//! model's types), a trait with one method per codel, and a `bind` that gives an
//! implementation of the trait to an `EngineBuilder` as one module object (a missing
//! codel does not compile). The code depends on bip-engine alone.
//!
//! For a GenoM3 component whose codels are C, [`c`] writes the headers those codels
//! include (GenoM3's C mapping of its types, its events, ports and codel prototypes) and
//! the Rust glue that binds those codels to the engine by their C names:
//! `bip_codegen::c::write_c_bindings("loco.gen", &[], out_dir)`.

pub mod c;
mod context;
mod emit;
mod names;
mod requests;
mod signature;
mod types;

use std::path::{Path, PathBuf};

use bip_model::System;

pub use c::{c_headers, write_c_headers, write_c_headers_of};

/// What keeps bindings from being generated.
#[derive(Debug, thiserror::Error)]
pub enum CodegenError {
    #[error("{0:?}")]
    Load(bip_lang::LoadError),
    #[error("the model has no GenoM layer: no codel to bind")]
    NoGenomLayer,
    /// A type or a codel parameter that GenoM3's C mapping (or bip's headers) does not
    /// cover, with its place.
    #[error("no C mapping: {0}")]
    CMapping(String),
    /// Two names of the model give the same Rust (or C) name in one scope.
    #[error("{first} and {second} both become `{rust}` in the bindings; rename one")]
    Clash {
        first: String,
        second: String,
        rust: String,
    },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// The bindings of `system`'s GenoM layer, as the text of a Rust module, for bip-engine
/// with its `std` feature (the default): with typed requests from other threads too
/// (`request_go_to_from(&handle, ..)`, through a `bip_engine::Handle`).
pub fn rust_bindings(system: &System) -> Result<String, CodegenError> {
    let layer = system.genom.as_ref().ok_or(CodegenError::NoGenomLayer)?;
    emit::bindings(&system.name, layer, true)
}

/// The bindings for bip-engine without `std`: as [`rust_bindings`], without the requests
/// from other threads (there is no `Handle` without `std`).
pub fn rust_bindings_no_std(system: &System) -> Result<String, CodegenError> {
    let layer = system.genom.as_ref().ok_or(CodegenError::NoGenomLayer)?;
    emit::bindings(&system.name, layer, false)
}

/// Loads the model at `model`, writes its bindings to `out`, and tells cargo to run the
/// build script again when the model changes. Writes only if the text changed, so that
/// an unchanged model rebuilds nothing.
pub fn write_rust_bindings(
    model: impl AsRef<Path>,
    out: impl AsRef<Path>,
) -> Result<(), CodegenError> {
    let model = model.as_ref();
    println!("cargo:rerun-if-changed={}", model.display());
    let system = bip_lang::load_file(model).map_err(CodegenError::Load)?;
    write_bindings_of(&system, out)
}

/// Writes the bindings of `system` to `out`, formatted by rustfmt where it is installed
/// (`$RUSTFMT`, else `rustfmt` on the path; they compile as well unformatted), only if
/// the text changed: what [`write_rust_bindings`] does once the model is loaded, and
/// `bip codegen`.
pub fn write_bindings_of(system: &System, out: impl AsRef<Path>) -> Result<(), CodegenError> {
    let text = rust_bindings(system)?;
    let text = rustfmt(&text).unwrap_or(text);
    let out = out.as_ref();
    if std::fs::read_to_string(out).is_ok_and(|old| old == text) {
        return Ok(());
    }
    std::fs::write(out, text).map_err(|source| CodegenError::Write {
        path: out.to_path_buf(),
        source,
    })
}

/// `text` as rustfmt formats it, if rustfmt is installed (`$RUSTFMT`, else `rustfmt` on the
/// path) and formats it; the bindings compile as well unformatted.
pub(crate) fn rustfmt(text: &str) -> Option<String> {
    use std::io::Write as _;
    use std::process::{Command, Stdio};
    let tool = std::env::var_os("RUSTFMT").unwrap_or_else(|| "rustfmt".into());
    let mut child = Command::new(tool)
        .args(["--edition", "2021", "--emit", "stdout", "--quiet"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .ok()?;
    child.stdin.take()?.write_all(text.as_bytes()).ok()?;
    let done = child.wait_with_output().ok()?;
    let formatted = String::from_utf8(done.stdout).ok()?;
    (done.status.success() && !formatted.is_empty()).then_some(formatted)
}
