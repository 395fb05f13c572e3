//! `bip`: verify a robot functional layer model, and run it.
//!
//! A thin layer over the libraries: argument parsing, output formatting, exit codes. This
//! file parses and dispatches to one module per command. Exit codes (`exit.rs`): 0 all
//! properties hold (or the command succeeded), 1 a property fails, 2 the model or the
//! command is wrong, 3 the result is inconclusive.

mod check;
mod codegen;
mod exit;
mod expand;
mod explore;
mod export;
mod graph;
mod import;
mod interrupt;
mod load;
mod memory_guard;
mod names;
mod replay;
mod report;
#[cfg(feature = "distributed")]
mod request;
#[cfg(feature = "distributed")]
mod run;
mod sched;
mod simulate;
mod startup;
mod trace;
mod verify;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[global_allocator]
static ALLOCATOR: memory_guard::Allocator = memory_guard::Allocator;

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
    /// Print the components of GenoM3 `.gen` files as the equivalent model (RON), checked
    /// as `bip check` would.
    Import {
        /// The `.gen` files, their components the model's modules in this order.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// A directory `#include` searches (after the including file's own).
        #[arg(short = 'I', value_name = "DIR")]
        include: Vec<PathBuf>,
        /// Wire an in port to an out port, as a deployment's `connect_port` does:
        /// `--connect flight.state=pom.frame` (the in port first).
        #[arg(long = "connect", value_name = "IN=OUT")]
        connect: Vec<String>,
    },
    /// Verify a model's properties (deadlock freedom, invariants, reachability, range
    /// errors) by exploring its states or by symbolic proofs. Exit code 0: all hold,
    /// 1: some property fails, 2: model or usage error, 3: inconclusive.
    Verify(verify::Args),
    /// Write the model in another tool's language (Promela, for SPIN).
    Export(export::Args),
    /// Run the model in the engine with default codels (random declared outcomes) and
    /// random requests, checking every invariant at every step, in constant memory. Exit
    /// code 0: they held, 1: one failed (the last steps are printed), 2: model or usage
    /// error, 3: interrupted (Ctrl-C; the report and the trace so far).
    Simulate(simulate::Args),
    /// Whether the GenoM layer's tasks meet their deadlines, from the codels' WCETs:
    /// each task's work per period, its worst response time by exact response-time
    /// analysis, per CPU; with `--exact`, also by exploring the model as a timed model.
    /// Exit code 0: schedulable, 1: a task misses its deadline, 2: model or usage error
    /// (or no WCETs), 3: `--exact` stopped by a limit before deciding.
    Sched(sched::Args),
    /// Re-execute a trace (a counterexample, a witness, a recording) through the engine,
    /// step by step, and show where the property fails. Exit code 0: a recording replayed,
    /// 1: the trace's failure (or witness) is reached, 2: the trace does not fit the model.
    Replay(replay::Args),
    /// Draw the model: its GenoM layer, its BIP core or one activity's codels, as SVG or DOT.
    Graph(graph::Args),
    /// Show a trace in the model's terms, as text and as a sequence chart (SVG).
    Trace(trace::Args),
    /// Write the Rust bindings of the model's GenoM layer (per codel an enum of its
    /// outcomes, per module a trait of its codels; docs/codegen.md) to a file, or with
    /// `--c` the C headers a GenoM3 component's codels include.
    Codegen(codegen::Args),
    /// Run a layer on this machine from its deployment file: start its module processes,
    /// gate their codels here, serve requests on the network (zenoh), print the events,
    /// until Ctrl-C or --for. Exit code 0: it ran, 2: model, deployment or start-up error.
    #[cfg(feature = "distributed")]
    Run(run::Args),
    /// Send a request to a service of a running layer and print its replies; its
    /// arguments are checked against the model first. Exit code 0: the request was made,
    /// 2: it was not (malformed, refused by the layer, no engine answered).
    #[cfg(feature = "distributed")]
    Request(request::Args),
    /// Explore the model's states in a web browser: fire steps, go back and forward,
    /// step through a counterexample (a local server on 127.0.0.1; Ctrl-C stops it).
    Explore(explore::Args),
}

fn main() -> ExitCode {
    startup::restore_sigpipe();
    let cli = Cli::parse();
    startup::init_logging(cli.verbose);
    memory_guard::start();
    let code = match cli.command {
        Command::Check { files } => check::run(&files),
        Command::Expand { file } => expand::run(&file),
        Command::Import {
            files,
            include,
            connect,
        } => import::run(&files, &include, &connect),
        Command::Verify(args) => verify::run(&args),
        Command::Export(args) => export::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Replay(args) => replay::run(&args),
        Command::Sched(args) => sched::run(&args),
        Command::Graph(args) => graph::run(&args),
        Command::Trace(args) => trace::run(&args),
        Command::Codegen(args) => codegen::run(&args),
        Command::Explore(args) => explore::run(&args),
        #[cfg(feature = "distributed")]
        Command::Run(args) => run::run(&args),
        #[cfg(feature = "distributed")]
        Command::Request(args) => request::run(&args),
    };
    ExitCode::from(code)
}
