//! `bip import FILE.gen... [-I DIR]... [--connect IN=OUT]...`: print the GenoM3 components
//! of `.gen` files as the equivalent RON model, wired as the `--connect` options say
//! (docs/genom.md, "GenoM3 files").

use std::path::{Path, PathBuf};

use crate::{exit, report};

pub fn run(files: &[PathBuf], include: &[PathBuf], connect: &[String]) -> u8 {
    let mut connections = Vec::new();
    for c in connect {
        match c.split_once('=') {
            Some((port, reads)) if !port.trim().is_empty() && !reads.trim().is_empty() => {
                connections.push((port.trim().to_string(), reads.trim().to_string()));
            }
            _ => {
                eprintln!(
                    "error: `--connect {c}`: expected `module.in_port=module.out_port`, \
                     the in port first (`--connect flight.state=pom.frame`)"
                );
                return exit::ERROR;
            }
        }
    }
    let paths: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let def = match bip_lang::import_gen_files(&paths, include, &connections) {
        Ok(def) => def,
        Err(e) => {
            report::load_error(&e);
            return exit::ERROR;
        }
    };
    // a codel per line
    match def.to_ron_nested(6) {
        Ok(text) => {
            let shown: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
            println!(
                "// {} imported by `bip import` (docs/genom.md, \"GenoM3 files\")",
                shown.join(", ")
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
