//! The example controller's command: `cargo run --release -p bip-rover-controller [--
//! --real-time]` plays the script on the virtual clock (or the real one) and prints the
//! log; `RUST_LOG=bip_engine=debug` shows every step on stderr.
//!
//! Distributed (docs/distributed.md): `-- --deploy examples/rover-controller/deploy.ron`
//! starts the module processes the file names and the engine, which plays the script with
//! the codels there. Or one by one: `-- --module-process drive|perception|payload
//! --connect tcp/127.0.0.1:7447` runs one module process (its modules from the
//! deployment file, `deploy.ron` by default), and `-- --engine --listen
//! tcp/127.0.0.1:7447` the engine (`--prefix bip/rover` by default; `--until-stdin-closes`
//! ends a module process when its standard input closes, as its parent dies).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use bip_rover_controller::{distributed, supervisor};
use bip_zenoh::{Deployment, Network};

fn value(args: &[String], flag: &str) -> Option<String> {
    args.iter()
        .position(|a| a == flag)
        .and_then(|k| args.get(k + 1).cloned())
}

/// A client's request to a service of a layer (`--request module.Service [--args JSON]`),
/// its arguments read against the model: prints each reply as it comes.
fn request(
    model: &std::path::Path,
    network: &Network,
    target: &str,
    args: Option<String>,
    timeout_ms: Option<String>,
) -> Result<(), Box<dyn std::error::Error>> {
    let system = bip_engine::load_file(model)?;
    let request = bip_zenoh::ClientRequest::parse(&system, target, args.as_deref())?;
    let timeout_ms: u64 = match timeout_ms {
        Some(t) => t
            .parse()
            .map_err(|_| format!("--timeout-ms `{t}` is not a number"))?,
        None => 5_000,
    };
    let timeout = std::time::Duration::from_millis(timeout_ms);
    request.send(network, timeout, |r| println!("{r}"))?;
    Ok(())
}

/// The network the flags give (`--listen`, `--connect`, `--prefix`).
fn network_of(args: &[String], _engine: bool) -> Network {
    Network {
        listen: value(args, "--listen").into_iter().collect(),
        connect: value(args, "--connect").into_iter().collect(),
        prefix: value(args, "--prefix").unwrap_or_else(|| "bip/rover".into()),
        ..Network::default()
    }
}

/// The layer in one process, one of its module processes, its engine, or all of it from
/// a deployment file.
fn layer(
    args: &[String],
    model: &std::path::Path,
    real_time: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    let system = bip_engine::load_file(model)?;
    let deploy_file = value(args, "--deploy").map(std::path::PathBuf::from);
    let deployment = match &deploy_file {
        Some(f) => Some(Deployment::load(f, &system)?),
        None => None,
    };
    if let Some(process) = value(args, "--module-process") {
        let (network, d) = match &deployment {
            Some(d) => (d.module_network(), d.clone()),
            None => (
                network_of(args, false),
                Deployment::load(&distributed::default_deployment_file(), &system)?,
            ),
        };
        let modules = d.modules_of(&process).ok_or_else(|| {
            let names: Vec<&str> = d.processes.iter().map(|p| p.name.as_str()).collect();
            format!("no module process `{process}`; the deployment's are {names:?}")
        })?;
        let stop = Arc::new(AtomicBool::new(false));
        if args.iter().any(|a| a == "--until-stdin-closes") {
            let stop = Arc::clone(&stop);
            std::thread::spawn(move || {
                let _ = std::io::copy(&mut std::io::stdin(), &mut std::io::sink());
                stop.store(true, Ordering::Relaxed);
            });
        }
        return distributed::serve_process(model, &modules, &network, stop);
    }
    let say = &mut |line| println!("{line}");
    match (deployment, deploy_file) {
        (Some(d), Some(file)) => {
            // one command: the module processes (this binary, unless the file names
            // another), then the engine
            let me = std::env::current_exe()?;
            let launched = d.launch(&file, |p| {
                let mut c = std::process::Command::new(&me);
                c.args(["--module-process", &p.name, "--until-stdin-closes"])
                    .arg("--deploy")
                    .arg(&file);
                Some(c)
            })?;
            supervisor::run_on(model, real_time, Some(&d.engine_network()), say)?;
            drop(launched);
        }
        _ if args.iter().any(|a| a == "--engine") => {
            supervisor::run_on(model, real_time, Some(&network_of(args, true)), say)?;
        }
        _ => {
            supervisor::run_on(model, real_time, None, say)?;
        }
    }
    Ok(())
}

fn main() {
    bip_zenoh::tune_zenoh_runtime();
    let args: Vec<String> = std::env::args().collect();
    let real_time = args.iter().any(|a| a == "--real-time");
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/rover.ron");
    let _ = tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("off")),
        )
        .with_writer(std::io::stderr)
        .try_init();
    let result = if let Some(target) = value(&args, "--request") {
        let network = network_of(&args, false);
        request(
            &model,
            &network,
            &target,
            value(&args, "--args"),
            value(&args, "--timeout-ms"),
        )
    } else {
        layer(&args, &model, real_time)
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
