//! A gated codel run across processes on loopback against one in the engine's process:
//! the rover with its drive and its localisation running, each codel run timed from the
//! engine's step to its commit (docs/performance.md, "Distributed").
//!
//! `cargo bench -p bip-rover-controller --bench round_trip [-- --codels N] [--spin-us N]`

use std::net::TcpListener;
use std::process::{Child, Command, Stdio};
use std::time::Instant;

use bip_engine::{Engine, EngineBuilder, Stepped, VirtualClock};
use bip_rover_controller::distributed::{bind_codels, bind_remote, types};
use bip_rover_controller::hardware::Hardware;
use bip_rover_controller::rover::{pom, rflex, sick};
use bip_zenoh::{Network, RemoteModules, RemoteOptions};

struct Processes(Vec<Child>);

impl Drop for Processes {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// Runs `codels` codel runs; the time of each, sorted, and the wall time of all.
fn measure(builder: EngineBuilder, clock: VirtualClock, codels: usize) -> (Vec<u64>, f64) {
    let mut engine = builder.clock(clock).build().expect("the engine");
    rflex::request_init(&mut engine).expect("a request");
    rflex::request_track_speed(&mut engine, 0.0).expect("a request");
    sick::request_scan(&mut engine).expect("a request");
    pom::request_track(&mut engine).expect("a request");
    let mut times = Vec::with_capacity(codels);
    let start = Instant::now();
    while times.len() < codels {
        let t0 = Instant::now();
        let stepped = engine.step().expect("a step");
        let took = t0.elapsed().as_nanos() as u64;
        if let Stepped::Codel { failed, .. } = stepped {
            assert!(!failed, "a codel failed");
            times.push(took);
        }
        let _ = engine.events().count();
    }
    let wall = start.elapsed().as_secs_f64();
    times.sort_unstable();
    (times, wall)
}

fn report(what: &str, times: &[u64], wall: f64) {
    let at = |q: f64| times[((times.len() - 1) as f64 * q) as usize] as f64 / 1000.0;
    println!(
        "{what}: {} codel runs, median {:.1} µs, p90 {:.1} µs, p99 {:.1} µs; {:.0} gated codel runs per second",
        times.len(),
        at(0.5),
        at(0.9),
        at(0.99),
        times.len() as f64 / wall
    );
}

fn main() {
    bip_zenoh::tune_zenoh_runtime();
    let args: Vec<String> = std::env::args().collect();
    let codels: usize = args
        .iter()
        .position(|a| a == "--codels")
        .and_then(|k| args.get(k + 1))
        .and_then(|n| n.parse().ok())
        .unwrap_or(20_000);
    let spin_us: u64 = args
        .iter()
        .position(|a| a == "--spin-us")
        .and_then(|k| args.get(k + 1))
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/rover.ron");
    let system = bip_engine::load_file(&model).expect("the rover");

    let clock = VirtualClock::new();
    let hw = Hardware::new();
    let builder = bind_codels(
        Engine::builder(system.clone()),
        &hw,
        0.1,
        Some(clock.clone()),
    );
    let (times, wall) = measure(builder, clock, codels);
    report("one process", &times, wall);

    let port = TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    let network = Network::loopback(&format!("bip/bench/{}", std::process::id()), port, true);
    let mut processes = Processes(Vec::new());
    for name in ["drive", "perception", "payload"] {
        let child = Command::new(env!("CARGO_BIN_EXE_bip-rover-controller"))
            .args(["--module-process", name, "--until-stdin-closes"])
            .args(["--connect", &network.listen[0], "--prefix", &network.prefix])
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .expect("the controller's binary runs");
        processes.0.push(child);
    }
    let clock = VirtualClock::new();
    let options = RemoteOptions {
        virtual_clock: Some(clock.clone()),
        spin: std::time::Duration::from_micros(spin_us),
        ..RemoteOptions::default()
    };
    let remote = RemoteModules::new(&network, &system, types(&system), options).expect("a session");
    let builder = bind_remote(Engine::builder(system.clone()), &remote).expect("the processes");
    let (times, wall) = measure(builder, clock, codels);
    report(
        &format!("module processes over zenoh (TCP, loopback, engine polls {spin_us} µs)"),
        &times,
        wall,
    );
}
