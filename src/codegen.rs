//! `bip codegen FILE --rust OUT`: write a model's Rust bindings to a file, what
//! `bip_codegen::write_rust_bindings` does from a build script (docs/codegen.md).

use std::path::PathBuf;

use crate::{exit, load};

#[derive(clap::Args)]
pub struct Args {
    /// Model file (RON).
    file: PathBuf,
    /// Where to write the Rust module.
    #[arg(long, value_name = "OUT")]
    rust: PathBuf,
}

pub fn run(args: &Args) -> u8 {
    let Some(system) = load::system(&args.file) else {
        return exit::ERROR;
    };
    match bip_codegen::write_bindings_of(&system, &args.rust) {
        Ok(()) => exit::OK,
        Err(e) => {
            eprintln!("error: {e}");
            exit::ERROR
        }
    }
}
