//! `bip import FILE.gen [-I DIR]...`: print the GenoM3 components of a `.gen` file as the
//! equivalent RON model (docs/genom.md, "GenoM3 files").

use std::path::{Path, PathBuf};

use crate::{exit, report};

pub fn run(file: &Path, include: &[PathBuf]) -> u8 {
    let def = match bip_lang::import_gen_file(file, include) {
        Ok(def) => def,
        Err(e) => {
            report::load_error(&e);
            return exit::ERROR;
        }
    };
    // a codel per line
    match def.to_ron_nested(6) {
        Ok(text) => {
            println!(
                "// {} imported by `bip import` (docs/genom.md, \"GenoM3 files\")",
                file.display()
            );
            println!("{text}");
            exit::OK
        }
        Err(e) => {
            eprintln!("error: cannot write the imported model: {e}");
            exit::ERROR
        }
    }
}
