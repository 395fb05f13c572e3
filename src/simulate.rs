//! `bip simulate FILE --steps N --seed S [--trace OUT]`: prints a simulation of the model
//! ([`bip_engine::simulate`]: the engine with default codels and random requests,
//! checking every invariant, and deadlock freedom if the model asks for it, at every
//! step) and saves its trace.

use std::path::PathBuf;

use bip_engine::simulate::{simulate, SimulationEnd, SimulationOptions};

use crate::{exit, load};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// Steps to take (ticks, codels, requests, other steps).
    #[arg(long, default_value_t = 1000)]
    pub steps: u64,
    /// Seed of the random requests and codel outcomes (the run is the same for a seed).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Save the run as a trace (RON) in OUT.
    #[arg(long, value_name = "OUT")]
    pub trace: Option<PathBuf>,
}

pub fn run(args: &Args) -> u8 {
    let Some(system) = load::system(&args.file) else {
        return exit::ERROR;
    };
    let options = SimulationOptions {
        steps: args.steps,
        seed: args.seed,
    };
    let sim = match simulate(system.clone(), options) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    let stats = sim.stats;
    let code = if sim.end.fails() {
        exit::FAILED
    } else {
        exit::OK
    };
    println!(
        "{}: system `{}`, simulation with seed {}",
        args.file.display(),
        system.name,
        args.seed
    );
    println!(
        "  {} steps: {} ticks, {} codels ({} exceptions, {} faults), {} requests sent ({} accepted, {} refused)",
        stats.steps,
        stats.ticks,
        stats.codels,
        stats.exceptions,
        stats.faults,
        sim.requests_sent,
        stats.requests_accepted,
        stats.requests_refused
    );
    let invariants = sim.invariants;
    match &sim.end {
        SimulationEnd::Completed => println!(
            "  {invariants} invariants{} held at every step",
            if sim.deadlock_checked {
                " and deadlock freedom"
            } else {
                ""
            }
        ),
        SimulationEnd::Stuck => println!(
            "  stopped: no step is possible and nothing can arrive; {invariants} invariants held until then"
        ),
        SimulationEnd::Violation(p) => {
            println!("  invariant `{p}` FAILS after step {}", stats.steps)
        }
        SimulationEnd::Deadlock => println!("  DEADLOCK after step {}", stats.steps),
        SimulationEnd::RangeError(m) => {
            println!("  RANGE ERROR after step {}: {m}", stats.steps)
        }
    }
    if code != exit::OK {
        print!("{}", sim.trace.display(Some(&system)));
    }
    if let Some(out) = &args.trace {
        if let Err(e) = std::fs::write(out, bip_lang::trace_file::to_ron(&sim.trace)) {
            eprintln!("error: cannot write {}: {e}", out.display());
            return exit::ERROR;
        }
        println!("  trace saved in {}", out.display());
    }
    code
}
