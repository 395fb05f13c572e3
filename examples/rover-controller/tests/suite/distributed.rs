//! The rover split into the engine (this test's process) and its three module processes
//! over zenoh on loopback: the same replies, held codels and recording as in one process.
//! The processes are killed when the test ends, whatever its end; each test has its own
//! port and key prefix, so tests run side by side.

use std::net::TcpListener;
use std::process::{Child, Command, Stdio};

use bip_rover_controller::distributed::default_deployment_file;
use bip_zenoh::{Deployment, Network};

/// Module processes, killed (and reaped) when dropped; they also end when their standard
/// input closes, should this process die without dropping them.
pub struct Processes(pub Vec<Child>);

impl Drop for Processes {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

impl Processes {
    pub fn spawn_one(&mut self, process: &str, network: &Network) {
        self.spawn_connecting(process, network, &network.listen[0]);
    }

    /// Spawns module process `process` of `network`, connecting to `endpoint` (the
    /// engine's, or a relay's).
    pub fn spawn_connecting(&mut self, process: &str, network: &Network, endpoint: &str) {
        let child = Command::new(env!("CARGO_BIN_EXE_bip-rover-controller"))
            .args(["--module-process", process, "--until-stdin-closes"])
            .args(["--connect", endpoint])
            .args(["--prefix", &network.prefix])
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .spawn()
            .expect("the controller's binary runs");
        self.0.push(child);
    }

    /// Kills the `k`-th process spawned.
    pub fn kill(&mut self, k: usize) {
        let _ = self.0[k].kill();
        let _ = self.0[k].wait();
    }

    /// Sends signal `signal` (`STOP`, `CONT`) to the `k`-th process spawned.
    pub fn signal(&self, k: usize, signal: &str) {
        let status = Command::new("kill")
            .arg(format!("-{signal}"))
            .arg(self.0[k].id().to_string())
            .status()
            .expect("kill runs");
        assert!(status.success(), "kill -{signal}");
    }
}

/// A network of its own for test `name`: a free port on 127.0.0.1 for the engine to
/// listen on, and a key prefix no other test uses.
pub fn network(name: &str) -> Network {
    let port = TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    Network::loopback(
        &format!("bip/test/{}/{name}", std::process::id()),
        port,
        true,
    )
}

/// The module processes of the rover's deployment file, on `network`.
pub fn spawn_all(network: &Network) -> Processes {
    spawn_all_but(network, None)
}

/// The module processes of the rover's deployment file, on `network`, those of `skip`
/// left out.
pub fn spawn_all_but(network: &Network, skip: Option<&str>) -> Processes {
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/rover.ron");
    let system = bip_engine::load_file(&model).expect("the rover");
    let d = Deployment::load(&default_deployment_file(), &system).expect("deploy.ron");
    let mut p = Processes(Vec::new());
    for process in d.processes.iter().filter(|p| Some(p.name.as_str()) != skip) {
        p.spawn_one(&process.name, network);
    }
    p
}

#[test]
fn the_rover_split_over_three_module_processes_runs_as_in_one() {
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/rover.ron");
    let one = bip_rover_controller::run(&model, false, &mut |_| {}).expect("in one process");
    let network = network("split");
    let _processes = spawn_all(&network);
    let mut log = Vec::new();
    let split = bip_rover_controller::supervisor::run_on(&model, false, Some(&network), &mut |l| {
        log.push(l)
    })
    .unwrap_or_else(|e| panic!("distributed: {e}"));
    let log = log.join("\n");
    // the controller checked its recording against the model and every invariant
    assert!(
        log.contains("every invariant holds in every state"),
        "{log}"
    );
    // the codels ran in the module processes: the engine's own simulated hardware never
    // moved
    assert!(log.contains("rover at x = 0.00 m, 0 packets sent"), "{log}");
    assert_eq!(split.replies, one.replies, "{log}");
    assert_eq!(split.held, one.held, "{log}");
    assert_eq!(split.goto_ends, one.goto_ends);
    assert_eq!(split.stopped_at, one.stopped_at);
    assert_eq!(
        (split.overruns, split.over_budget, split.faults),
        (one.overruns, one.over_budget, one.faults)
    );
    // step for step the same run of the model
    assert!(one.trace.steps.len() > 300);
    assert_eq!(split.trace, one.trace);
}

/// Runs the controller's binary as a client: `--request target [--args args]`; its exit
/// status and its lines.
pub fn client(
    network: &Network,
    target: &str,
    args: Option<&str>,
    timeout_ms: u64,
) -> (bool, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_bip-rover-controller"));
    c.args(["--request", target])
        .args(["--connect", &network.listen[0]])
        .args(["--prefix", &network.prefix])
        .args(["--timeout-ms", &timeout_ms.to_string()]);
    if let Some(a) = args {
        c.args(["--args", a]);
    }
    let out = c.output().expect("the client runs");
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.success(), text)
}

#[test]
fn a_client_in_another_process_sends_typed_requests_and_reads_their_replies() {
    use bip_engine::{Engine, RealClock, Until};
    use bip_zenoh::{request_bytes, RequestServer, ServiceReply};
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    use std::time::Duration;

    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/rover.ron");
    let system = bip_engine::load_file(&model).expect("the rover");
    let network = network("requests");
    let session = network.open().expect("the engine's session");
    let hw = bip_rover_controller::hardware::Hardware::new();
    let builder = bip_rover_controller::distributed::bind_codels(
        Engine::builder(system.clone()),
        &hw,
        0.1,
        None,
    );
    let mut engine = builder.clock(RealClock::new()).build().expect("the engine");
    let types = bip_rover_controller::distributed::types(&system);
    let server = RequestServer::start(
        &session,
        &network.prefix,
        &system,
        types,
        engine.handle(),
        Duration::from_secs(10),
        None,
    )
    .expect("the server");
    let stop = Arc::new(AtomicBool::new(false));
    let running = {
        let stop = Arc::clone(&stop);
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                engine.run_until(Until::Ticks(1)).expect("the engine runs");
            }
        })
    };
    // stops the engine's thread however the test ends
    struct Stop(Arc<AtomicBool>);
    impl Drop for Stop {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Relaxed);
        }
    }
    let _stop = Stop(Arc::clone(&stop));

    // refused by the model, with its reason in the model's words
    let (ok, out) = client(&network, "rflex.TrackSpeed", Some("0.5"), 5_000);
    assert!(ok && out.contains("refused: after rflex.Init"), "{out}");
    let (ok, out) = client(&network, "rflex.Init", None, 5_000);
    assert!(
        ok && out.contains("accepted") && out.contains("done: ether"),
        "{out}"
    );
    // an activity: accepted and started; it runs until stopped
    let (ok, out) = client(&network, "rflex.TrackSpeed", Some("0.5"), 1_500);
    assert!(
        ok && out.contains("accepted") && out.contains("started"),
        "{out}"
    );
    let (ok, out) = client(&network, "rflex.Stop", None, 5_000);
    assert!(ok && out.contains("done: ether"), "{out}");
    // an end the model's rule gives: GoTo is aborted without the laser
    let (ok, out) = client(&network, "ndd.GoTo", Some("1.0"), 5_000);
    assert!(
        ok && out.contains("done: aborted by a rule of the model"),
        "{out}"
    );

    // malformed requests are refused with a message: by the client, against the model,
    // before anything is sent
    let (ok, out) = client(&network, "rflex.TrackSpeed", Some("\"fast\""), 5_000);
    assert!(
        !ok && out.contains(
            "error: the arguments of rflex.TrackSpeed (`\"fast\"`) are not of its type Float"
        ),
        "{out}"
    );
    let (ok, out) = client(&network, "rflex.Fly", None, 5_000);
    assert!(
        !ok && out.contains("module `rflex` has no service `Fly`"),
        "{out}"
    );
    let (ok, out) = client(&network, "rflex.Init", Some("3"), 5_000);
    assert!(!ok && out.contains("takes no arguments"), "{out}");
    // and by the engine's server, for clients that do not check (another language's)
    let raw = |service: &str, payload: &[u8]| {
        request_bytes(
            &session,
            &network.prefix,
            "rflex",
            service,
            payload.to_vec(),
            Duration::from_secs(5),
            |_| {},
        )
        .expect("an answer")
    };
    let refused = |replies: Vec<ServiceReply>, why: &str| {
        assert!(
            matches!(replies.as_slice(), [ServiceReply::Error { message }] if message.contains(why)),
            "{replies:?}"
        )
    };
    refused(
        raw("TrackSpeed", br#"{"args": "fast"}"#),
        "the arguments of rflex.TrackSpeed (\"fast\") are not of its type",
    );
    refused(raw("Fly", b""), "names no service of the layer");
    refused(raw("Init", br#"{"args": 3}"#), "takes no arguments");
    refused(
        raw("Init", b"{not json"),
        "is not `{\"args\": ...}` in JSON",
    );
    let (ok, out) = client(&network, "antenna.Communicate", Some("3"), 1_500);
    assert!(ok && out.contains("accepted"), "{out}");

    stop.store(true, Ordering::Relaxed);
    running.join().expect("the engine's thread ends well");
    drop(server);
}

#[test]
fn one_command_starts_the_layer_from_a_deployment_file() {
    let network = network("deploy");
    let text = std::fs::read_to_string(default_deployment_file())
        .expect("deploy.ron")
        .replace("bip/rover", &network.prefix)
        .replace("tcp/127.0.0.1:7447", &network.listen[0]);
    let dir = std::env::temp_dir().join(format!("bip-deploy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a directory");
    let file = dir.join("deploy.ron");
    std::fs::write(&file, &text).expect("written");
    let run = |file: &std::path::Path| {
        let out = Command::new(env!("CARGO_BIN_EXE_bip-rover-controller"))
            .arg("--deploy")
            .arg(file)
            .stdin(Stdio::null())
            .output()
            .expect("the controller runs");
        let text = String::from_utf8_lossy(&out.stdout).to_string()
            + &String::from_utf8_lossy(&out.stderr);
        (out.status.success(), text)
    };
    let (ok, out) = run(&file);
    assert!(ok, "{out}");
    assert!(
        out.contains("every invariant holds in every state"),
        "{out}"
    );
    // the codels ran in the module processes it started
    assert!(out.contains("rover at x = 0.00 m, 0 packets sent"), "{out}");
    // a module in no process, and a misspelt field, are errors with the file's words
    let missing = dir.join("missing.ron");
    std::fs::write(&missing, text.replace("\"pom\", ", "")).expect("written");
    let (ok, out) = run(&missing);
    assert!(
        !ok && out.contains("module `pom` runs in no process"),
        "{out}"
    );
    let misspelt = dir.join("misspelt.ron");
    std::fs::write(&misspelt, text.replace("modules:", "modulez:")).expect("written");
    let (ok, out) = run(&misspelt);
    assert!(
        !ok && out.contains("misspelt.ron:") && out.contains("Unexpected field named `modulez`"),
        "{out}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
