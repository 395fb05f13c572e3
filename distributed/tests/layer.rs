//! `bip run`'s library: a layer started from its model and its deployment file alone,
//! its module process a program of its own (examples/counter_module.rs) started by the
//! command the file names, on loopback (a free port, a key prefix of the test's own); a
//! client's requests, checked against the model, and their replies.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use bip_zenoh::{run_layer, ClientRequest, Deployment, LayerOptions, ServiceReply};
use zenoh::Wait;

fn model() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/counter.ron")
}

/// The example program, built beside this test by `cargo test`.
fn module_program() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's path");
    let debug = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>");
    debug.join("examples/counter_module")
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

/// Runs the counter's layer from a deployment file whose network is `network` (RON
/// fields), its one process the counter's program; a client's `counter.Add 0.5` made
/// through the layer's network: the replies, and the engine's figures and events.
fn run_counter_layer(
    name: &str,
    network: &str,
) -> (Vec<ServiceReply>, bip_engine::Stats, Vec<String>) {
    let system = bip_engine::load_file(model()).expect("the model");
    let prefix = format!("bip/test/{}/{name}", std::process::id());
    let dir = std::env::temp_dir().join(format!("bip-layer-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a directory");
    let file = dir.join("deploy.ron");
    let text = format!(
        r#"(prefix: "{prefix}", {network}
            processes: [(name: "count", modules: ["counter"], command: [{:?}, {:?}])])"#,
        module_program().display().to_string(),
        model().display().to_string()
    );
    std::fs::write(&file, text).expect("written");
    let deployment = Deployment::load(&file, &system).expect("the deployment");

    let stop = Arc::new(AtomicBool::new(false));
    let layer = {
        let (system, deployment, file, stop) = (
            system.clone(),
            deployment.clone(),
            file.clone(),
            Arc::clone(&stop),
        );
        std::thread::spawn(move || {
            let options = LayerOptions {
                run_for: Some(Duration::from_secs(30)),
                ..LayerOptions::default()
            };
            let mut events = Vec::new();
            let stats = run_layer(
                &system,
                &deployment,
                &file,
                &options,
                &|| stop.load(Ordering::Relaxed),
                &mut |e| events.push(e.to_string()),
            );
            (stats, events)
        })
    };
    // the engine serves once every process answered: ask until it does
    let network = deployment.module_network();
    let add = ClientRequest::parse(&system, "counter.Add", Some("0.5")).expect("well typed");
    let mut replies = Vec::new();
    for _ in 0..100 {
        match add.send(&network, Duration::from_secs(5), |_| {}) {
            Ok(r) => {
                replies = r;
                break;
            }
            Err(_) => std::thread::sleep(Duration::from_millis(100)),
        }
    }
    stop.store(true, Ordering::Relaxed);
    let (stats, events) = layer.join().expect("the layer's thread");
    let _ = std::fs::remove_dir_all(&dir);
    (replies, stats.expect("the layer ran"), events)
}

/// The client's replies and the engine's figures of a layer that ran `counter.Add`:
/// accepted, started, done, its four codel runs in the module process without a fault.
fn assert_added(replies: &[ServiceReply], stats: &bip_engine::Stats, events: &[String]) {
    assert!(
        matches!(replies, [ServiceReply::Accepted { .. }, ServiceReply::Started { .. }, ServiceReply::Done { outcome, .. }] if outcome == "ether"),
        "{replies:?}"
    );
    // Add's codels ran in the module process: start, then three times add
    assert_eq!((stats.codels, stats.faults), (4, 0), "{events:?}");
}

#[test]
fn a_layer_runs_from_its_deployment_file_and_answers_typed_requests() {
    let network = format!(r#"listen: ["tcp/127.0.0.1:{}"],"#, free_port());
    let (replies, stats, events) = run_counter_layer("layer", &network);
    assert_added(&replies, &stats, &events);
    // malformed requests are refused before anything is sent, in the model's terms
    let system = bip_engine::load_file(model()).expect("the model");
    let bad = ClientRequest::parse(&system, "counter.Add", Some("\"fast\"")).expect_err("refused");
    assert!(bad.contains("not of its type Float"), "{bad}");
    let bad = ClientRequest::parse(&system, "counter.Reset", Some("1")).expect_err("refused");
    assert!(bad.contains("takes no arguments"), "{bad}");
    let bad = ClientRequest::parse(&system, "counter.Fly", None).expect_err("refused");
    assert!(bad.contains("has no service `Fly`"), "{bad}");
}

#[test]
fn a_layer_runs_through_a_zenoh_router_its_processes_clients_of() {
    // a zenoh router of the test's own, as `zenohd` would be on another computer
    let port = free_port();
    let mut config = zenoh::Config::default();
    for (key, value) in [
        ("mode", r#""router""#.to_string()),
        ("scouting/multicast/enabled", "false".into()),
        ("listen/endpoints", format!(r#"["tcp/127.0.0.1:{port}"]"#)),
    ] {
        config
            .insert_json5(key, &value)
            .expect("a router's configuration");
    }
    let router = zenoh::open(config).wait().expect("the router");
    // the engine, the module process and the client are clients of the router; none
    // listens, and none would find the others without it
    let network = format!(r#"mode: client, connect: ["tcp/127.0.0.1:{port}"],"#);
    let (replies, stats, events) = run_counter_layer("router", &network);
    assert_added(&replies, &stats, &events);
    router.close().wait().expect("closed");
}

#[test]
fn a_layer_runs_with_zenoh_s_usual_transport_and_a_configuration_file() {
    // the low-latency transport off, and a zenoh configuration file of the user's (its
    // path relative to the deployment file) for what the deployment does not set
    let dir = std::env::temp_dir().join(format!("bip-layer-{}-usual", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a directory");
    std::fs::write(
        dir.join("zenoh.json5"),
        "{ transport: { link: { tx: { lease: 4000 } } } }",
    )
    .expect("written");
    let network = format!(
        r#"listen: ["tcp/127.0.0.1:{}"], low_latency: false, zenoh_config: "zenoh.json5","#,
        free_port()
    );
    let (replies, stats, events) = run_counter_layer("usual", &network);
    assert_added(&replies, &stats, &events);
}
