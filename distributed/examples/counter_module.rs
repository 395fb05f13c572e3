//! A module process as `bip run` starts it (docs/distributed.md, "bip run"): a program of
//! the layer's own that binds its module's codels, here module `counter` of
//! `tests/counter.ron` (given as the first argument), and serves them on the network its
//! launcher gives it in its environment, until its standard input closes.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use bip_engine::{CodelSignature, Ctx, Engine, Next};
use bip_zenoh::{ModuleHost, Network, Types};

/// The module's codels as the model declares them: Add's `start`, then `add`.
static CODELS: &[CodelSignature] = &[
    CodelSignature {
        service: "Add",
        codel: "start",
        yields: &["pause::add"],
        throws: &[],
    },
    CodelSignature {
        service: "Add",
        codel: "add",
        yields: &["pause::add", "ether"],
        throws: &[],
    },
];

/// Adds the request's argument to port `total` on each of three runs.
struct Counter {
    runs: u32,
}

impl Counter {
    fn run(&mut self, k: usize, ctx: &mut Ctx<'_>) -> Next {
        if k == 0 {
            self.runs = 0;
            return Next::Declared(0);
        }
        let step = ctx.args::<f64>().copied().unwrap_or(0.0);
        let total = ctx.port::<f64>("counter", "total").copied().unwrap_or(0.0);
        ctx.write_port("total", total + step);
        self.runs += 1;
        Next::Declared(if self.runs < 3 { 0 } else { 1 })
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    bip_zenoh::tune_zenoh_runtime();
    let model = std::env::args()
        .nth(1)
        .ok_or("usage: counter_module MODEL")?;
    let network =
        Network::from_env().ok_or("not started by `bip run` (no BIP_LAYER_CONNECT)")??;
    let system = bip_engine::load_file(std::path::Path::new(&model))?;
    let mut counter = Counter { runs: 0 };
    let builder = Engine::builder(system.clone())
        .module("counter", CODELS, move |k, ctx| counter.run(k, ctx));
    let mut host = ModuleHost::new(&network, &system, Types::of(&system))?;
    for hosted in builder.hosted(&["counter"])? {
        host = host.module(hosted);
    }
    let stop = Arc::new(AtomicBool::new(false));
    let stopped = Arc::clone(&stop);
    std::thread::spawn(move || {
        let _ = std::io::copy(&mut std::io::stdin(), &mut std::io::sink());
        stopped.store(true, Ordering::Relaxed);
    });
    host.serve(stop)?;
    Ok(())
}
