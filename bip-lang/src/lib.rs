//! `bip-lang`: bip's model language, from a file to a compiled [`bip_model::System`].
//!
//! The front end's pipeline runs one way: the text is parsed with positions ([`source`],
//! [`syntax`], [`expr`]), a GenoM layer is expanded into atoms and connectors ([`genom`]),
//! and the result is validated and compiled ([`compile()`]) into the plain data of a
//! [`bip_model::System`]. Every error on the way is a [`ModelError`] with a span in the
//! user's file, reported together as a [`LoadError`] ([`diag`]).
//!
//! Modules import down these layers only (`tests/suite/layering.rs` checks it), lowest first:
//! positions (`source`, `excerpt`, `diag`); the file format (`syntax`, `expr`, `genom::syntax`);
//! `compile`, which knows only BIP core; `genom`, whose expansion evaluates constants and
//! compiles its result through `compile`; files (`load`, which chooses between compiling a
//! core model and expanding a GenoM layer first, and `trace_file`).
//!
//! - [`load_file`] / [`load_str`] read and compile a model;
//! - [`parse_str`], [`expand_str`] and [`compile_def`] run the stages one at a time;
//! - [`trace_file`] reads and writes the trace format.

mod compile;
pub mod diag;
mod excerpt;
pub mod expr;
pub mod gen3;
pub mod genom;
mod load;
pub mod source;
pub mod source_map;
pub mod syntax;
pub mod trace_file;

pub use compile::Ty;
pub use diag::{LoadError, ModelError};
pub use genom::expand;
pub use load::{
    compile, compile_def, expand_file, expand_str, import_gen_file, import_gen_files, load_file,
    load_file_timed, load_str, parse_str, read_gen_file, read_model_file,
};
pub use syntax::ron_options;
