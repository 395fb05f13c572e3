//! `bip codegen FILE --rust OUT`: write a model's Rust bindings to a file, what
//! `bip_codegen::write_rust_bindings` does from a build script; `bip codegen FILE.gen --c
//! DIR [-I DIR]...`: write the C headers of a GenoM3 component's codels and the Rust glue
//! that binds them to bip-engine (`DIR/{stem}_c.rs`), what
//! `bip_codegen::c::write_c_bindings` does (docs/codegen.md).

use std::path::PathBuf;

use crate::{exit, load, report};

#[derive(clap::Args)]
#[command(group = clap::ArgGroup::new("out").required(true).args(["rust", "c"]))]
pub struct Args {
    /// Model file (RON) for `--rust`; GenoM3 `.gen` file for `--c`.
    file: PathBuf,
    /// Where to write the Rust module.
    #[arg(long, value_name = "OUT")]
    rust: Option<PathBuf>,
    /// Folder where to write the C headers of the `.gen` file's components and their Rust
    /// glue (`{stem}_c.rs`).
    #[arg(long, value_name = "DIR")]
    c: Option<PathBuf>,
    /// With `--c`: folders searched by the `.gen` file's `#include`, after its own.
    #[arg(short = 'I', long = "include", value_name = "DIR")]
    include: Vec<PathBuf>,
}

pub fn run(args: &Args) -> u8 {
    let written = if let Some(dir) = &args.c {
        let spec = match bip_lang::read_gen_file(&args.file, &args.include) {
            Ok(spec) => spec,
            Err(e) => {
                report::load_error(&e);
                return exit::ERROR;
            }
        };
        let stem = args
            .file
            .file_stem()
            .map_or_else(|| "component".into(), |s| s.to_string_lossy().into_owned());
        let to = bip_codegen::c::CBindings {
            include: dir.clone(),
            rust: dir.join(format!("{stem}_c.rs")),
        };
        bip_codegen::c::write_c_bindings_of(&[&spec], &to)
    } else {
        let Some(system) = load::system(&args.file) else {
            return exit::ERROR;
        };
        let Some(out) = &args.rust else {
            return exit::ERROR;
        };
        bip_codegen::write_bindings_of(&system, out)
    };
    match written {
        Ok(()) => exit::OK,
        Err(e) => {
            eprintln!("error: {e}");
            exit::ERROR
        }
    }
}
