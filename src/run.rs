//! `bip run MODEL --deploy FILE [--for SECONDS]`: runs a layer on this machine from its
//! deployment file ([`bip_zenoh::run_layer`]): starts the module processes the file names
//! by their commands, gates their codels in this process on the real clock, serves
//! requests on the network (`bip request`), and prints the engine's events, until Ctrl-C
//! or the time given. Exit codes: 0 it ran (and stopped), 2 model, deployment or start-up
//! error.

use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Duration;

use bip_zenoh::{run_layer, Deployment, LayerOptions, Mode};

use crate::{exit, interrupt, load};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// The deployment file (RON): which module runs in which process, each process's
    /// command, the network (docs/distributed.md, "Deployment").
    #[arg(long, value_name = "FILE")]
    pub deploy: PathBuf,
    /// Stop after this many seconds (default: at Ctrl-C).
    #[arg(long = "for", value_name = "SECONDS")]
    pub run_for: Option<f64>,
    /// The deadline of a codel run in its process beyond its WCET, in milliseconds: past
    /// it, the codel's activity takes its error path.
    #[arg(long, value_name = "MS", default_value_t = 500)]
    pub deadline_ms: u64,
}

pub fn run(args: &Args) -> u8 {
    // before zenoh starts, and inherited by the module processes started
    bip_zenoh::tune_zenoh_runtime();
    let Some(system) = load::system(&args.file) else {
        return exit::ERROR;
    };
    let deployment = match Deployment::load(&args.deploy, &system) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    let run_for = match args.run_for {
        Some(s) if !(s.is_finite() && s >= 0.0) => {
            eprintln!("error: --for {s} is not a number of seconds");
            return exit::ERROR;
        }
        s => s.map(Duration::from_secs_f64),
    };
    let options = LayerOptions {
        run_for,
        deadline: Duration::from_millis(args.deadline_ms),
        ..LayerOptions::default()
    };
    let flag = interrupt::stop_flag();
    let stop = || flag.load(Ordering::Relaxed);
    let place = match deployment.mode {
        Mode::Peer => deployment.engine_listen().join(", "),
        Mode::Client => format!("the zenoh router at {}", deployment.connect.join(", ")),
    };
    eprintln!(
        "{}: layer `{}` on {place}, keys under `{}`",
        args.file.display(),
        system.name,
        deployment.prefix
    );
    match run_layer(
        &system,
        &deployment,
        &args.deploy,
        &options,
        &stop,
        &mut |e| println!("{e}"),
    ) {
        Ok(stats) => {
            println!(
                "stopped after {} steps: {} codels run, {} faults",
                stats.steps, stats.codels, stats.faults
            );
            exit::OK
        }
        Err(e) => {
            eprintln!("error: {e}");
            exit::ERROR
        }
    }
}
