//! `bip`: verify a robot functional layer model, and run it.
//!
//! A thin layer over the libraries: argument parsing, output formatting, exit codes.
//! Exit codes: 0 all properties hold (or the command succeeded), 1 a property fails,
//! 2 the model or the command is wrong, 3 the result is inconclusive.

mod check;
mod expand;
mod export;
mod replay;
mod report;
mod simulate;
mod verify;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "bip",
    version,
    about = "A formally checked behaviour engine for robot functional layers"
)]
struct Cli {
    /// More log output (-v: info, -vv: debug, -vvv: trace); RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Load and validate model files and print a summary of each.
    Check {
        /// Model files (RON).
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// Print a model with its GenoM layer expanded into BIP core (RON that `bip check`
    /// reads back).
    Expand {
        /// Model file (RON).
        file: PathBuf,
    },
    /// Verify a model's properties (deadlock freedom, invariants, reachability, range
    /// errors) by exploring its states or by symbolic proofs. Exit code 0: all hold,
    /// 1: some property fails, 2: model or usage error, 3: inconclusive.
    Verify(verify::Args),
    /// Write the model in another tool's language (Promela, for SPIN).
    Export(export::Args),
    /// Run the model in the engine with default codels (random declared outcomes) and
    /// random requests, checking every invariant at every step. Exit code 0: they held,
    /// 1: one failed (the trace is printed), 2: model or usage error.
    Simulate(simulate::Args),
    /// Re-execute a trace (a counterexample, a witness, a recording) through the engine,
    /// step by step, and show where the property fails. Exit code 0: a recording replayed,
    /// 1: the trace's failure (or witness) is reached, 2: the trace does not fit the model.
    Replay(replay::Args),
}

/// Exit codes shared by every command.
pub mod exit {
    pub const OK: u8 = 0;
    pub const FAILED: u8 = 1;
    pub const ERROR: u8 = 2;
    pub const INCONCLUSIVE: u8 = 3;
}

fn main() -> ExitCode {
    restore_sigpipe();
    let cli = Cli::parse();
    init_logging(cli.verbose);
    let code = match cli.command {
        Command::Check { files } => check::run(&files),
        Command::Expand { file } => expand::run(&file),
        Command::Verify(args) => verify::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Replay(args) => replay::run(&args),
    };
    ExitCode::from(code)
}

/// Rust ignores SIGPIPE, so printing into a closed pipe (`bip replay ... | head`) would
/// panic; restore the default, and end quietly as `head`'s other writers do.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is a valid
    // disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn init_logging(verbose: u8) {
    use tracing_subscriber::EnvFilter;
    let default = match verbose {
        0 => "warn",
        1 => "info",
        2 => "debug",
        _ => "trace",
    };
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .try_init();
}
