//! Faults of module processes (docs/distributed.md, "Faults"): a process that dies, hangs
//! (SIGSTOP) or is cut off (a relay that stops passing bytes) while an activity of its
//! modules runs. Its activities take their error path, a step of the model, within the
//! run's deadline, as a fault of their own kind ([`FaultKind::Remote`]); requests to its
//! modules are refused with the reason; the other processes' modules go on; the process
//! back, its modules run again; and the whole recording replays against the model with
//! every invariant holding.

use std::time::{Duration, Instant};

use bip_engine::{Engine, Event, FaultKind, System, VirtualClock};
use bip_rover_controller::rover::{pom, rflex};
use bip_zenoh::{Network, RemoteModules, RemoteOptions, RequestServer};

use super::distributed::{client, network, spawn_all_but, Processes};
use super::relay::Relay;

/// The deadline of a run beyond its WCET.
const DEADLINE: Duration = Duration::from_millis(300);

/// The rover's engine in this process (on a virtual clock, with a request server), its
/// module processes on loopback; process `drive` (rflex, sick, ndd, antenna) is the
/// first, connected through `relay` if one is given.
struct Layer {
    system: System,
    network: Network,
    processes: Processes,
    remote: RemoteModules,
    engine: Engine,
    _server: RequestServer,
}

impl Layer {
    fn start(name: &str, relay: bool) -> (Layer, Option<Relay>) {
        let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/rover.ron");
        let system = bip_engine::load_file(&model).expect("the rover");
        let network = network(name);
        let engine_port: u16 = network.listen[0]
            .rsplit(':')
            .next()
            .and_then(|p| p.parse().ok())
            .expect("a port");
        let relay = relay.then(|| Relay::start(engine_port));
        let mut processes = Processes(Vec::new());
        let drive_endpoint = match &relay {
            Some(r) => format!("tcp/127.0.0.1:{}", r.port),
            None => network.listen[0].clone(),
        };
        processes.spawn_connecting("drive", &network, &drive_endpoint);
        processes
            .0
            .append(&mut spawn_all_but(&network, Some("drive")).0);
        let clock = VirtualClock::new();
        let options = RemoteOptions {
            deadline: DEADLINE,
            virtual_clock: Some(clock.clone()),
            ..RemoteOptions::default()
        };
        let types = || bip_rover_controller::distributed::types(&system);
        let remote = RemoteModules::new(&network, &system, types(), options).expect("a session");
        let builder = Engine::builder(system.clone()).record(10_000).clock(clock);
        let mut engine = bip_rover_controller::distributed::bind_remote(builder, &remote)
            .expect("every module process answers")
            .build()
            .expect("the engine");
        let server = RequestServer::start(
            remote.session(),
            &network.prefix,
            &system,
            types(),
            engine.handle(),
            Duration::from_secs(5),
            Some(remote.presence()),
        )
        .expect("the request server");
        let layer = Layer {
            system,
            network,
            processes,
            remote,
            engine,
            _server: server,
        };
        (layer, relay)
    }

    /// The events of `ticks` ticks.
    fn run_ticks(&mut self, ticks: u64) -> Vec<Event> {
        self.engine
            .run_until(bip_engine::Until::Ticks(ticks))
            .expect("the engine runs");
        self.engine.events().collect()
    }

    /// rflex.TrackSpeed (process `drive`) and pom.Track (process `perception`) running,
    /// without a fault: their tickets.
    fn drive_and_track(&mut self) -> (u64, u64) {
        rflex::request_init(&mut self.engine).expect("a request");
        let drive = rflex::request_track_speed(&mut self.engine, 0.5).expect("a request");
        let track = pom::request_track(&mut self.engine).expect("a request");
        let before = lines(&self.run_ticks(5));
        assert!(
            before
                .iter()
                .any(|e| e.contains("rflex.TrackSpeed: started")),
            "{before:?}"
        );
        assert!(before.iter().all(|e| !e.contains("fault")), "{before:?}");
        (drive.0 .0, track.0 .0)
    }

    /// Ticks until the process of `module` has a fault reported, at most `bound` (wall
    /// clock): the events, and how long it took.
    fn run_until_fault(&mut self, bound: Duration) -> (Vec<Event>, Duration) {
        let t0 = Instant::now();
        let mut events = Vec::new();
        while t0.elapsed() < bound && !events.iter().any(is_remote_fault) {
            events.extend(self.run_ticks(1));
        }
        (events, t0.elapsed())
    }

    /// Waits (at most 20 s) until the engine hears from `module`'s process again.
    fn wait_until_back(&self, module: &str) {
        let t0 = Instant::now();
        while self.remote.presence().absent(module).is_some() {
            assert!(
                t0.elapsed() < Duration::from_secs(20),
                "the process of {module} did not come back"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The checks common to every fault: `ticket`'s TrackSpeed ended on its error path
    /// within the bound with a remote fault, pom.Track (`track`, another process) went on
    /// without one, and a client's request to rflex is refused with the reason.
    fn check_fault(&mut self, (drive, track): (u64, u64), events: &[Event], took: Duration) {
        let lines = lines(events);
        // a run waits for its deadline (its WCET and DEADLINE) at most once; later runs of
        // the absent process's codels fail at once
        assert!(took < DEADLINE * 2 + Duration::from_secs(1), "{took:?}");
        let ended = format!("#{drive} rflex.TrackSpeed: done: fault: codel rflex.TrackSpeed.track was not run by its module's process");
        assert!(lines.iter().any(|e| e.starts_with(&ended)), "{lines:?}");
        let faults: Vec<&Event> = events
            .iter()
            .filter(|e| matches!(e, Event::Fault(_)))
            .collect();
        assert!(
            !faults.is_empty() && faults.iter().all(|e| is_remote_fault(e)),
            "{faults:?}"
        );
        assert!(
            lines.iter().all(|e| !e.contains(&format!("#{track} "))),
            "{lines:?}"
        );
        // a request to the absent process's module is refused with the reason, from
        // another process, without reaching the engine (which does not step meanwhile)
        let (ok, out) = client(&self.network, "rflex.TrackSpeed", Some("0.5"), 5_000);
        assert!(
            !ok && out.contains("refused: the process of module `rflex` is absent"),
            "{out}"
        );
    }

    /// The process of rflex back, TrackSpeed runs there again, without a new fault; the
    /// whole recording replays, every invariant holding.
    fn check_rejoined(&mut self) {
        self.wait_until_back("rflex");
        let faults = self.engine.inspect().stats().faults;
        rflex::request_track_speed(&mut self.engine, 0.2).expect("a request");
        let after = lines(&self.run_ticks(5));
        assert!(
            after
                .iter()
                .any(|e| e.contains("rflex.TrackSpeed: started")),
            "{after:?}"
        );
        assert_eq!(self.engine.inspect().stats().faults, faults, "{after:?}");
        check_recording(&self.system, &self.engine.record());
    }
}

fn is_remote_fault(e: &Event) -> bool {
    matches!(e, Event::Fault(f) if matches!(f.kind, FaultKind::Remote(_)))
}

fn lines(events: &[Event]) -> Vec<String> {
    events.iter().map(ToString::to_string).collect()
}

/// The recording is a path of the model along which every invariant holds.
fn check_recording(system: &System, trace: &bip_engine::Trace) {
    use bip_engine::bip_model::PropertyKind;
    let path = trace.replay(system).expect("the recording replays");
    for (_, state) in &path {
        for p in &system.properties {
            if let PropertyKind::Invariant(e) = &p.kind {
                assert!(
                    system.holds(e, state, &p.name).expect("evaluates"),
                    "invariant {} fails",
                    p.name
                );
            }
        }
    }
}

#[test]
fn a_killed_module_process_fails_its_activity_and_rejoins_when_restarted() {
    let (mut layer, _) = Layer::start("killed", false);
    let tickets = layer.drive_and_track();
    layer.processes.kill(0);
    let (events, took) = layer.run_until_fault(Duration::from_secs(10));
    layer.check_fault(tickets, &events, took);
    layer.processes.spawn_one("drive", &layer.network);
    layer.check_rejoined();
}

#[test]
fn a_hung_module_process_fails_its_activity_and_rejoins_when_it_resumes() {
    let (mut layer, _) = Layer::start("hung", false);
    let tickets = layer.drive_and_track();
    layer.processes.signal(0, "STOP");
    let (events, took) = layer.run_until_fault(Duration::from_secs(10));
    layer.check_fault(tickets, &events, took);
    // hung, it keeps its place on the network: the engine knows it from the missed
    // deadline
    let why = layer.remote.presence().absent("rflex").expect("absent");
    assert!(why.contains("no answer"), "{why}");
    layer.processes.signal(0, "CONT");
    layer.check_rejoined();
}

#[test]
fn a_module_process_cut_off_fails_its_activity_and_rejoins_when_the_link_is_back() {
    let (mut layer, relay) = Layer::start("cut", true);
    let relay = relay.expect("a relay");
    let tickets = layer.drive_and_track();
    relay.set_cut(true);
    let (events, took) = layer.run_until_fault(Duration::from_secs(10));
    layer.check_fault(tickets, &events, took);
    // a short cut: the link is back before zenoh's lease (10 s) ends the session
    std::thread::sleep(Duration::from_millis(500));
    relay.set_cut(false);
    layer.check_rejoined();
}
