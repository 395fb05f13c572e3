//! `bip expand FILE`: print a model with its GenoM layer expanded into BIP core, as RON
//! that `bip check` reads back (docs/genom.md).

use std::path::Path;

use crate::{exit, load};

pub fn run(file: &Path) -> u8 {
    let Some(def) = load::expanded(file) else {
        return exit::ERROR;
    };
    match def.to_ron() {
        Ok(text) => {
            println!(
                "// {} expanded into BIP core by `bip expand` (docs/genom.md)",
                file.display()
            );
            println!("{text}");
            exit::OK
        }
        Err(e) => {
            eprintln!("error: cannot write the expanded model: {e}");
            exit::ERROR
        }
    }
}
