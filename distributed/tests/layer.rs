//! `bip run`'s library: a layer started from its model and its deployment file alone,
//! its module process a program of its own (examples/counter_module.rs) started by the
//! command the file names, on loopback (a free port, a key prefix of the test's own); a
//! client's requests, checked against the model, and their replies.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use bip_zenoh::{run_layer, ClientRequest, Deployment, LayerOptions, ServiceReply};

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

#[test]
fn a_layer_runs_from_its_deployment_file_and_answers_typed_requests() {
    let system = bip_engine::load_file(model()).expect("the model");
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    let prefix = format!("bip/test/{}/layer", std::process::id());
    let dir = std::env::temp_dir().join(format!("bip-layer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a directory");
    let file = dir.join("deploy.ron");
    let text = format!(
        r#"(prefix: "{prefix}", listen: ["tcp/127.0.0.1:{port}"],
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
    assert!(
        matches!(replies.as_slice(), [ServiceReply::Accepted { .. }, ServiceReply::Started { .. }, ServiceReply::Done { outcome, .. }] if outcome == "ether"),
        "{replies:?}"
    );
    // malformed requests are refused before anything is sent, in the model's terms
    let bad = ClientRequest::parse(&system, "counter.Add", Some("\"fast\"")).expect_err("refused");
    assert!(bad.contains("not of its type Float"), "{bad}");
    let bad = ClientRequest::parse(&system, "counter.Reset", Some("1")).expect_err("refused");
    assert!(bad.contains("takes no arguments"), "{bad}");
    let bad = ClientRequest::parse(&system, "counter.Fly", None).expect_err("refused");
    assert!(bad.contains("has no service `Fly`"), "{bad}");

    stop.store(true, Ordering::Relaxed);
    let (stats, events) = layer.join().expect("the layer's thread");
    let stats = stats.expect("the layer ran");
    // Add's codels ran in the module process: start, then three times add
    assert_eq!((stats.codels, stats.faults), (4, 0), "{events:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
