//! The example controller's command: `cargo run --release -p bip-rover-controller [--
//! --real-time]` plays the script on the virtual clock (or the real one) and prints the
//! log; `RUST_LOG=bip_engine=debug` shows every step on stderr.
//!
//! Distributed (docs/distributed.md): `-- --module-process drive|perception|payload
//! --connect tcp/127.0.0.1:7447` runs one module process, and `-- --engine --listen
//! tcp/127.0.0.1:7447` the engine that plays the script with the codels there
//! (`--prefix bip/rover` by default; `--until-stdin-closes` ends a module process when
//! its standard input closes, as its parent dies).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use bip_zenoh::Network;

fn value(args: &[String], flag: &str) -> Option<String> {
    args.iter()
        .position(|a| a == flag)
        .and_then(|k| args.get(k + 1).cloned())
}

/// A client's request to a service of a layer (`--request module.Service [--args JSON]`):
/// prints each reply as it comes.
fn request(
    network: &Network,
    target: &str,
    args: Option<String>,
    timeout_ms: Option<String>,
) -> Result<(), Box<dyn std::error::Error>> {
    let (module, service) = target
        .split_once('.')
        .ok_or_else(|| format!("`{target}` is not `module.Service`"))?;
    let args = match args {
        Some(a) => {
            Some(serde_json::from_str(&a).map_err(|e| format!("--args `{a}` is not JSON: {e}"))?)
        }
        None => None,
    };
    let timeout_ms: u64 = match timeout_ms {
        Some(t) => t
            .parse()
            .map_err(|_| format!("--timeout-ms `{t}` is not a number"))?,
        None => 5_000,
    };
    let session = network.open()?;
    let timeout = std::time::Duration::from_millis(timeout_ms);
    let replies = bip_zenoh::request(
        &session,
        &network.prefix,
        module,
        service,
        args,
        timeout,
        |r| println!("{r}"),
    )?;
    match replies.last() {
        Some(bip_zenoh::ServiceReply::Error { .. }) => Err("the request was not made".into()),
        _ => Ok(()),
    }
}

fn main() {
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
    let network = Network {
        listen: value(&args, "--listen").into_iter().collect(),
        connect: value(&args, "--connect").into_iter().collect(),
        prefix: value(&args, "--prefix").unwrap_or_else(|| "bip/rover".into()),
    };
    let result = if let Some(target) = value(&args, "--request") {
        request(
            &network,
            &target,
            value(&args, "--args"),
            value(&args, "--timeout-ms"),
        )
    } else if let Some(process) = value(&args, "--module-process") {
        let stop = Arc::new(AtomicBool::new(false));
        if args.iter().any(|a| a == "--until-stdin-closes") {
            let stop = Arc::clone(&stop);
            std::thread::spawn(move || {
                let _ = std::io::copy(&mut std::io::stdin(), &mut std::io::sink());
                stop.store(true, Ordering::Relaxed);
            });
        }
        bip_rover_controller::distributed::serve_process(&model, &process, &network, stop)
    } else {
        let network = args.iter().any(|a| a == "--engine").then_some(&network);
        bip_rover_controller::supervisor::run_on(&model, real_time, network, &mut |line| {
            println!("{line}")
        })
        .map(|_| ())
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
