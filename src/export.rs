//! `bip export FILE --promela OUT`: the model in another tool's language.

use std::path::{Path, PathBuf};

use crate::{exit, load};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// Write a Promela model for SPIN to OUT (`-` for stdout): one process, one statement
    /// per interaction, so SPIN's reachable states and deadlocks are bip's; invariants are
    /// assertions, a reachability property `p` is checked with `spin -DREACH_p`.
    #[arg(long, value_name = "OUT", required = true)]
    pub promela: PathBuf,
}

pub fn run(args: &Args) -> u8 {
    let Some(system) = load::system(&args.file) else {
        return exit::ERROR;
    };
    let text = match bip_verifier::to_promela(&system) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    match write(&args.promela, &text) {
        Ok(()) => exit::OK,
        Err(e) => {
            eprintln!("error: cannot write {}: {e}", args.promela.display());
            exit::ERROR
        }
    }
}

fn write(path: &Path, text: &str) -> std::io::Result<()> {
    use std::io::Write;
    if path.as_os_str() == "-" {
        let mut out = std::io::stdout().lock();
        out.write_all(text.as_bytes())?;
        out.flush()
    } else {
        std::fs::write(path, text)
    }
}
