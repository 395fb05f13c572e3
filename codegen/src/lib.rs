//! `bip-codegen`: Rust bindings for a model's GenoM layer, generated at build time as
//! prost-build and tonic-build do (docs/codegen.md). From `build.rs`:
//!
//! ```no_run
//! let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("rover.rs");
//! bip_codegen::write_rust_bindings("../robots/rover.ron", &out).unwrap();
//! ```
//!
//! and in the crate, `include!(concat!(env!("OUT_DIR"), "/rover.rs"));`. The generated
//! module has, per module of the model, an enum per codel of exactly its declared yields
//! and exceptions (returning another does not compile), a trait with one method per
//! codel, and a `bind` that registers an implementation of the trait with an
//! `EngineBuilder` (a missing codel does not compile). The code depends on bip-engine
//! alone.

mod emit;
mod names;

use std::path::{Path, PathBuf};

use bip_model::System;

/// What keeps bindings from being generated.
#[derive(Debug, thiserror::Error)]
pub enum CodegenError {
    #[error("{0:?}")]
    Load(bip_lang::LoadError),
    #[error("the model has no GenoM layer: no codel to bind")]
    NoGenomLayer,
    /// Two names of the model give the same Rust name in one scope.
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

/// The bindings of `system`'s GenoM layer, as the text of a Rust module.
pub fn rust_bindings(system: &System) -> Result<String, CodegenError> {
    let layer = system.genom.as_ref().ok_or(CodegenError::NoGenomLayer)?;
    emit::bindings(&system.name, layer)
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
    let text = rust_bindings(&system)?;
    let out = out.as_ref();
    if std::fs::read_to_string(out).is_ok_and(|old| old == text) {
        return Ok(());
    }
    std::fs::write(out, text).map_err(|source| CodegenError::Write {
        path: out.to_path_buf(),
        source,
    })
}
