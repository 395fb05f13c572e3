//! `bip simulate FILE --steps N --seed S [--trace OUT]`: runs the engine on a model with
//! default codels (random declared outcomes) and random requests, checking every
//! invariant (and deadlock freedom, if the model asks for it) at every step.

use std::path::PathBuf;

use bip_engine::{DefaultCodels, Engine, Policy, Stepped};
use bip_model::{Label, Liveness, LivenessChecker, PropertyKind, Role, Steps, System, Verdict};

use crate::{exit, report};

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

use bip_model::Rng;

/// Why a simulation stopped early.
enum Stop {
    Violation(String),
    Deadlock,
    RangeError(String),
    Stuck,
}

pub fn run(args: &Args) -> u8 {
    let system = match bip_model::load_file(&args.file) {
        Ok(s) => s,
        Err(e) => {
            report::load_error(&e);
            return exit::ERROR;
        }
    };
    let services: Vec<(&str, &str)> = system.requestable().collect();
    let mut engine = match Engine::builder(system.clone())
        .default_codels(DefaultCodels::Random(args.seed))
        .policy(Policy::Seeded(args.seed))
        .record(args.steps.min(1 << 20) as usize)
        .event_capacity(0)
        .build()
    {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: {e}");
            return exit::ERROR;
        }
    };
    let mut rng = Rng(args.seed ^ 0x5eed);
    let mut checker = LivenessChecker::default();
    let mut steps = Steps::new();
    let deadlock_free = system.properties.iter().find_map(|p| match &p.kind {
        PropertyKind::DeadlockFree { terminal } => Some(terminal.clone()),
        _ => None,
    });
    let mut requests = 0u64;
    let mut stop = check(
        &system,
        &engine,
        deadlock_free.as_ref(),
        &mut steps,
        &mut checker,
    );
    while stop.is_none() && engine.inspect().stats().steps < args.steps {
        // a request now and then, from the environment
        if rng.below(4) == 0 {
            if !services.is_empty() {
                let (m, s) = &services[rng.below(services.len())];
                if engine.request(m, s, ()).is_ok() {
                    requests += 1;
                }
            } else if let Some(step) = environment_step(&system, &engine, &mut rng) {
                if let Err(e) = engine.step_as(step.as_step()) {
                    stop = Some(Stop::RangeError(e.to_string()));
                    break;
                }
                stop = check(
                    &system,
                    &engine,
                    deadlock_free.as_ref(),
                    &mut steps,
                    &mut checker,
                );
                continue;
            }
        }
        let before = engine.inspect().stats().steps;
        match engine.step() {
            Err(e) => stop = Some(Stop::RangeError(e.to_string())),
            Ok(Stepped::Idle { next_tick_us }) => match next_tick_us {
                Some(t) => engine.wait_until(t),
                None if services.is_empty()
                    && environment_step(&system, &engine, &mut rng).is_none() =>
                {
                    stop = Some(Stop::Stuck)
                }
                None => {}
            },
            Ok(_) => {}
        }
        if stop.is_none() && engine.inspect().stats().steps != before {
            stop = check(
                &system,
                &engine,
                deadlock_free.as_ref(),
                &mut steps,
                &mut checker,
            );
        }
    }
    let stats = engine.inspect().stats();
    let (verdict, code) = match &stop {
        None | Some(Stop::Stuck) => (Verdict::None, exit::OK),
        Some(Stop::Violation(p)) => (Verdict::Violation(p.clone()), exit::FAILED),
        Some(Stop::Deadlock) => (Verdict::Deadlock, exit::FAILED),
        Some(Stop::RangeError(m)) => (Verdict::RangeError(m.clone()), exit::FAILED),
    };
    let mut trace = engine.record();
    trace.verdict = verdict;
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
        requests,
        stats.requests_accepted,
        stats.requests_refused
    );
    let invariants = system
        .properties
        .iter()
        .filter(|p| matches!(p.kind, PropertyKind::Invariant(_)))
        .count();
    match &stop {
        None => println!(
            "  {invariants} invariants{} held at every step",
            if deadlock_free.is_some() {
                " and deadlock freedom"
            } else {
                ""
            }
        ),
        Some(Stop::Stuck) => println!(
            "  stopped: no step is possible and nothing can arrive; {invariants} invariants held until then"
        ),
        Some(Stop::Violation(p)) => println!("  invariant `{p}` FAILS after step {}", stats.steps),
        Some(Stop::Deadlock) => println!("  DEADLOCK after step {}", stats.steps),
        Some(Stop::RangeError(m)) => println!("  RANGE ERROR after step {}: {m}", stats.steps),
    }
    if code != exit::OK {
        print!("{}", trace.display(Some(&system)));
    }
    if let Some(out) = &args.trace {
        if let Err(e) = std::fs::write(out, trace.to_ron()) {
            eprintln!("error: cannot write {}: {e}", out.display());
            return exit::ERROR;
        }
        println!("  trace saved in {}", out.display());
    }
    code
}

/// A random enabled environment step of a model without a GenoM layer.
fn environment_step(
    system: &System,
    engine: &Engine,
    rng: &mut Rng,
) -> Option<bip_model::OwnedStep> {
    let env: Vec<bip_model::OwnedStep> = engine
        .inspect()
        .enabled()
        .steps()
        .filter(|s| system.role(s.label) == Role::Environment)
        .filter(|s| matches!(s.label, Label::Interaction(_)))
        .map(|s| s.to_owned())
        .collect();
    (!env.is_empty()).then(|| env[rng.below(env.len())].clone())
}

/// Every invariant, and deadlock freedom if asked, in the engine's state.
fn check(
    system: &System,
    engine: &Engine,
    deadlock_free: Option<&Option<bip_model::eval::Expr>>,
    steps: &mut Steps,
    checker: &mut LivenessChecker,
) -> Option<Stop> {
    let state = engine.inspect().state();
    for p in &system.properties {
        if let PropertyKind::Invariant(e) = &p.kind {
            match system.holds(e, state, &p.name) {
                Ok(true) => {}
                Ok(false) => return Some(Stop::Violation(p.name.clone())),
                Err(e) => return Some(Stop::RangeError(e.to_string())),
            }
        }
    }
    let terminal = deadlock_free?;
    engine.inspect().enabled().copy_to(steps);
    match system.liveness(state, steps, checker) {
        Ok(Liveness::Deadlock) => {
            let excused = match terminal {
                Some(t) => system.holds(t, state, "terminal").unwrap_or(false),
                None => false,
            };
            (!excused).then_some(Stop::Deadlock)
        }
        Ok(_) => None,
        Err(e) => Some(Stop::RangeError(e.to_string())),
    }
}
