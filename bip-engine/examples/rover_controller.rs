//! An example controller: the engine embedded on `robots/rover.ron`, with simulated
//! hardware behind the codels (wheels, laser, position manager, navigation, mapping,
//! antenna, heating, camera) and a small supervisor script of requests.
//!
//!     cargo run --release -p bip-engine --example rover_controller [-- --real-time]
//!
//! The script shows what the model allows and what it does not: a request refused (its
//! `after` is not met), starts and codels held by the rover's constraints (each shown by
//! its name, its line and as written: `mast_still (line 140): Exclusive(…)`), activities
//! that end in `ether`, in an exception and interrupted, and an overrun. At the end the recorded run is checked with
//! bip-model's step relation (it is a path of the model) and against every invariant.
//!
//! On rover.ron every constraint applies to activities, which the model *holds* (the
//! request is accepted and the start waits); a constraint *refuses* a request only for a
//! function it names (docs/engine.md, "Requests"). bip-engine's tests cover that case.
//!
//! `run` holds the whole controller; bip-engine's test `tests/rover_controller.rs` runs it.

use std::error::Error;
use std::sync::{Arc, Mutex};

use bip_engine::{
    CodelId, Engine, Event, Next, Outcome, RealClock, Refusal, Reply, Ticket, Until, VirtualClock,
};
use bip_model::{PropertyKind, System, Trace};

/// The arguments the supervisor sends with its requests.
#[derive(Clone, Copy, Debug)]
pub enum Arg {
    None,
    /// `rflex.TrackSpeed`: the cruise speed (m/s), unless navigation gives a set point.
    Speed(f64),
    /// `ndd.GoTo`: the goal on the x axis (m).
    Goal(f64),
    /// `antenna.Communicate`: packets to send.
    Packets(u32),
}

/// Port data (GenoM ports): written by one module's codels, read by others.
#[derive(Clone, Copy, Debug, Default)]
pub struct Odometry {
    pub x: f64,
    pub travelled: f64,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct Pose {
    pub x: f64,
}

/// The laser's range straight ahead (m), and when it was taken.
#[derive(Clone, Copy, Debug, Default)]
pub struct Scan {
    pub ahead: f64,
    pub tick: u64,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct Dtm {
    pub cells: u32,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct Image {
    pub frames: u32,
}

/// The simulated world and hardware the codels drive and sense.
#[derive(Debug)]
struct World {
    /// Where the rover is (m, on a straight track).
    x: f64,
    /// A rock on the track.
    rock_x: f64,
    /// The wheels' set point from navigation (m/s), if it drives.
    nav_speed: Option<f64>,
    /// Packets that reached the orbiter.
    sent: u32,
}

/// Where a run of the controller ended, for the caller (and the test).
pub struct Report {
    pub system: System,
    pub trace: Trace,
    /// Each reply: the service (`module.Service`), the ticket, and what it said.
    pub replies: Vec<(String, Ticket, String)>,
    /// Each held codel (`module.Service.codel`) with the conditions that hold it.
    pub held: Vec<(String, Vec<String>)>,
    pub overruns: usize,
    /// Codel runs past their WCET, and task periods past their deadline.
    pub over_budget: usize,
    pub faults: usize,
}

/// The supervisor script: at which tick to send which request (in order of ticks).
const SCRIPT: &[(u64, &str, &str, Arg)] = &[
    (0, "rflex", "TrackSpeed", Arg::Speed(0.5)), // refused: after rflex.Init
    (1, "rflex", "Init", Arg::None),
    (2, "rflex", "TrackSpeed", Arg::Speed(0.5)), // drives; the battery Guard holds it at times
    (5, "antenna", "Communicate", Arg::Packets(3)), // held: Exclusive with TrackSpeed
    (9, "rflex", "Stop", Arg::None),             // interrupts TrackSpeed, frees the antenna
    (14, "ndd", "GoTo", Arg::Goal(1.0)),         // no laser: aborted (the rover's rule)
    (16, "sick", "Scan", Arg::None),
    (16, "pom", "Track", Arg::None),
    (18, "rflex", "TrackSpeed", Arg::Speed(0.0)),
    (20, "ndd", "GoTo", Arg::Goal(1.0)), // navigates there: ether
    (24, "heating", "Heat", Arg::None),
    (26, "aspect", "Build", Arg::None),
    (27, "camera", "Shoot", Arg::None), // held: AtMost 1 with heating
    (55, "battery", "Report", Arg::None),
    (56, "ndd", "GoTo", Arg::Goal(3.0)), // the rock is in the way: e_blocked
    (95, "rflex", "Stop", Arg::None),
    (95, "sick", "Stop", Arg::None),
    (95, "pom", "Stop", Arg::None),
];

const TICKS: u64 = 100;

/// Builds the engine with the simulated hardware, plays the script, and checks the
/// recording. `say` receives the log, line by line.
pub fn run(
    model: &std::path::Path,
    real_time: bool,
    say: &mut dyn FnMut(String),
) -> Result<Report, Box<dyn Error>> {
    let system = bip_lang::load_file(model).map_err(|e| e.summary())?;
    let world = Arc::new(Mutex::new(World {
        x: 0.0,
        rock_x: 2.0,
        nav_speed: None,
        sent: 0,
    }));
    let tick_s = system.tick_ms.unwrap_or(100) as f64 / 1000.0;
    let virtual_clock = VirtualClock::new();
    let (w1, w2, w3, w4, w5) = (
        world.clone(),
        world.clone(),
        world.clone(),
        world.clone(),
        world.clone(),
    );
    let exposure = virtual_clock.clone();
    let builder = Engine::builder(system.clone())
        // rflex: the wheels follow navigation's set point, else the cruise speed
        .codel(("rflex", "TrackSpeed", "start"), |_| {
            Next::Yield("pause::track")
        })
        .codel(("rflex", "TrackSpeed", "track"), move |ctx| {
            let cruise = match ctx.args::<Arg>() {
                Some(Arg::Speed(v)) => *v,
                _ => 0.0,
            };
            let mut w = w1.lock().unwrap_or_else(|p| p.into_inner());
            let v = w.nav_speed.unwrap_or(cruise);
            w.x += v * tick_s;
            let x = w.x;
            drop(w);
            if let Some(odo) = ctx.port_mut::<Odometry>("odo") {
                odo.travelled += (x - odo.x).abs();
                odo.x = x;
            }
            Next::Yield("pause::track")
        })
        // sick: the laser measures the distance to the rock
        .codel(("sick", "Scan", "start"), |_| Next::Yield("pause::scan"))
        .codel(("sick", "Scan", "scan"), move |ctx| {
            let w = w2.lock().unwrap_or_else(|p| p.into_inner());
            let ahead = (w.rock_x - w.x).max(0.0);
            drop(w);
            let tick = ctx.tick();
            ctx.write_port("scan", Scan { ahead, tick });
            Next::Yield("pause::scan")
        })
        // pom: the pose is the odometry (no inertial unit in this simulation)
        .codel(("pom", "Track", "start"), |_| Next::Yield("pause::fuse"))
        .codel(("pom", "Track", "fuse"), |ctx| {
            let x = ctx.port::<Odometry>("rflex", "odo").map_or(0.0, |o| o.x);
            ctx.write_port("pose", Pose { x });
            Next::Yield("pause::fuse")
        })
        // ndd: drive towards the goal, stop at it, give up before the rock
        .codel(("ndd", "GoTo", "start"), |_| Next::Yield("pause::move"))
        .codel(("ndd", "GoTo", "move"), move |ctx| {
            let goal = match ctx.args::<Arg>() {
                Some(Arg::Goal(x)) => *x,
                _ => 0.0,
            };
            let x = ctx.port::<Pose>("pom", "pose").map_or(0.0, |p| p.x);
            let ahead = ctx.port::<Scan>("sick", "scan").map_or(0.0, |s| s.ahead);
            let mut w = w3.lock().unwrap_or_else(|p| p.into_inner());
            if (goal - x).abs() < 0.05 {
                w.nav_speed = None;
                Next::ETHER
            } else if ahead < 0.3 && goal > x {
                w.nav_speed = None;
                Next::Throw("e_blocked")
            } else {
                // slow down near the goal: the pose lags the wheels by up to a period
                w.nav_speed = Some(((goal - x) * 5.0).clamp(-0.5, 0.5));
                Next::Yield("pause::move")
            }
        })
        .codel(("ndd", "GoTo", "stop"), move |_| {
            w4.lock().unwrap_or_else(|p| p.into_inner()).nav_speed = None;
            Next::ETHER
        })
        // aspect: a terrain model from laser scans
        .codel(("aspect", "Build", "start"), |_| Next::Yield("pause::fuse"))
        .codel(("aspect", "Build", "fuse"), |ctx| {
            let seen = ctx.port::<Scan>("sick", "scan").is_some();
            let cells = ctx.port_mut::<Dtm>("dtm").map_or(0, |d| {
                d.cells += u32::from(seen);
                d.cells
            });
            if cells >= 5 {
                Next::ETHER
            } else {
                Next::Yield("pause::fuse")
            }
        })
        // antenna: send the packets, one per period
        .codel(("antenna", "Communicate", "start"), |_| {
            Next::Yield("pause::send")
        })
        .codel(("antenna", "Communicate", "send"), move |ctx| {
            let want = match ctx.args::<Arg>() {
                Some(Arg::Packets(n)) => *n,
                _ => 1,
            };
            let mut w = w5.lock().unwrap_or_else(|p| p.into_inner());
            w.sent += 1;
            if w.sent >= want {
                Next::ETHER
            } else {
                Next::Yield("pause::send")
            }
        })
        .codel(("heating", "Heat", "start"), |_| Next::Yield("pause::heat"))
        .codel(("heating", "Heat", "heat"), {
            let mut periods = 0;
            move |_| {
                periods += 1;
                if periods >= 3 {
                    Next::ETHER
                } else {
                    Next::Yield("pause::heat")
                }
            }
        })
        // camera: the exposure takes 150 ms, longer than the task's period (an overrun)
        .codel(("camera", "Shoot", "start"), |_| {
            Next::Yield("pause::expose")
        })
        .codel(("camera", "Shoot", "expose"), move |ctx| {
            if real_time {
                std::thread::sleep(std::time::Duration::from_millis(150));
            } else {
                exposure.advance(150_000);
            }
            if let Some(img) = ctx.port_mut::<Image>("image") {
                img.frames += 1;
            }
            Next::ETHER
        })
        .record(10_000);
    let mut engine = if real_time {
        builder.clock(RealClock::new()).build()?
    } else {
        builder.clock(virtual_clock).build()?
    };
    let pack = system
        .component_index("pack")
        .ok_or("rover.ron has no `pack`")?;
    let level = system
        .atom_of(pack)
        .var_index("level")
        .ok_or("`pack` has no `level`")?;

    let mut report = Report {
        system: system.clone(),
        trace: Trace {
            system: system.name.clone(),
            verdict: bip_model::Verdict::None,
            steps: Vec::new(),
            loop_start: None,
        },
        replies: Vec::new(),
        held: Vec::new(),
        overruns: 0,
        over_budget: 0,
        faults: 0,
    };
    let mut script = SCRIPT.iter().peekable();
    for tick in 0..TICKS {
        while let Some((_, m, s, arg)) = script.next_if(|r| r.0 <= tick) {
            let t = engine.request(m, s, *arg)?;
            say(format!(
                "[{:>5.1} s] supervisor: request #{} {m}.{s} {arg:?}",
                engine.inspect().now_us() as f64 / 1e6,
                t.0
            ));
        }
        engine.run_until(Until::Ticks(1))?;
        let now = engine.inspect().now_us() as f64 / 1e6;
        let events: Vec<Event> = engine.events().collect();
        for event in events {
            let held_before = report.held.len();
            let line = describe(&engine, &event, &mut report);
            // a codel held again for the same reasons is said once
            let repeated = report.held.len() > held_before
                && report.held[..held_before].contains(&report.held[held_before]);
            if !repeated {
                say(format!("[{now:>5.1} s] {line}"));
            }
            // the battery module's report: the charge the model's battery atom holds
            if let Event::Reply {
                service,
                reply: Reply::Done(_),
                ..
            } = event
            {
                if engine.inspect().service_name(service) == ("battery", "Report") {
                    say(format!(
                        "[{now:>5.1} s] battery: charge {} of 3",
                        system.value(engine.inspect().state(), pack, level)
                    ));
                }
            }
        }
    }
    let stats = engine.inspect().stats();
    let (x, sent) = {
        let w = world.lock().unwrap_or_else(|p| p.into_inner());
        (w.x, w.sent)
    };
    say(format!(
        "end: {} steps ({} ticks, {} codels, {} exceptions, {} faults, {} overruns); rover at x = {x:.2} m, {sent} packets sent",
        stats.steps, stats.ticks, stats.codels, stats.exceptions, stats.faults, stats.overruns
    ));
    // each codel's run times against its WCET, the slowest first
    let inspect = engine.inspect();
    let mut timed: Vec<_> = (0..inspect.codel_count() as u32)
        .map(CodelId)
        .map(|c| (c, inspect.codel_times(c)))
        .filter(|(_, t)| t.runs > 0)
        .collect();
    timed.sort_by_key(|(_, t)| std::cmp::Reverse(t.max_us));
    for (c, t) in timed.iter().take(5) {
        let (m, s, k) = inspect.codel_name(*c);
        say(format!(
            "codel {m}.{s}.{k}: {} runs, mean {:.0} µs, max {} µs, {} over its WCET",
            t.runs,
            t.mean_us(),
            t.max_us,
            t.over_wcet
        ));
    }

    // the recording is a path of the model, and every invariant holds along it
    report.trace = engine.record();
    let path = report.trace.replay(&system)?;
    for (_, state) in &path {
        for p in &system.properties {
            if let PropertyKind::Invariant(e) = &p.kind {
                if !system.holds(e, state, &p.name)? {
                    return Err(format!("invariant {} fails in the recording", p.name).into());
                }
            }
        }
    }
    say(format!(
        "recording: {} steps, each accepted by the model's step relation; every invariant holds in every state",
        path.len()
    ));
    Ok(report)
}

/// One line for an event, noted in the report.
fn describe(engine: &Engine, event: &Event, report: &mut Report) -> String {
    match event {
        Event::Reply {
            ticket,
            service,
            reply,
        } => {
            let (m, s) = engine.inspect().service_name(*service);
            let text = match reply {
                Reply::Accepted => "accepted".to_string(),
                Reply::Refused(Refusal::Conditions(r)) => format!(
                    "REFUSED: {}",
                    engine
                        .inspect()
                        .refusal_texts(*service, *r)
                        .collect::<Vec<_>>()
                        .join("; ")
                ),
                Reply::Refused(Refusal::NotEnabled) => "REFUSED: not enabled now".to_string(),
                Reply::Done(Outcome::Ether) => "done: ether".to_string(),
                Reply::Done(o) => format!("done: {o}"),
            };
            report
                .replies
                .push((format!("{m}.{s}"), *ticket, text.clone()));
            format!("reply to #{} {m}.{s}: {text}", ticket.0)
        }
        Event::Held { codel, reasons, .. } => {
            let (m, s, c) = engine.inspect().codel_name(*codel);
            let why: Vec<String> = engine.inspect().hold_texts(*codel, *reasons).collect();
            let line = format!("held: {m}.{s} codel `{c}` waits for {}", why.join("; "));
            report.held.push((format!("{m}.{s}.{c}"), why));
            line
        }
        Event::Fault(f) => {
            report.faults += 1;
            let (m, s, c) = engine.inspect().codel_name(f.codel);
            format!("FAULT: {m}.{s}.{c} {}", f.kind)
        }
        Event::Overrun {
            codel,
            took_us,
            period_us,
        } => {
            report.overruns += 1;
            let (m, s, c) = engine.inspect().codel_name(*codel);
            format!(
                "overrun: {m}.{s}.{c} took {} ms, its period is {} ms",
                took_us / 1000,
                period_us / 1000
            )
        }
        Event::WcetExceeded {
            codel,
            took_us,
            wcet_us,
        } => {
            report.over_budget += 1;
            let (m, s, c) = engine.inspect().codel_name(*codel);
            format!("over budget: {m}.{s}.{c} took {took_us} µs, its WCET is {wcet_us} µs")
        }
        Event::DeadlineMissed {
            codel,
            elapsed_us,
            deadline_us,
        } => {
            report.over_budget += 1;
            let (m, s, _) = engine.inspect().codel_name(*codel);
            format!(
                "deadline missed: {m}.{s}'s task ended its period's work {elapsed_us} µs after its release, past {deadline_us} µs"
            )
        }
    }
}

#[allow(dead_code)] // the test includes this file for `run`
fn main() {
    let real_time = std::env::args().any(|a| a == "--real-time");
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/rover.ron");
    let _ = tracing_subscriber_init();
    match run(&model, real_time, &mut |line| println!("{line}")) {
        Ok(_) => {}
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}

/// Logs the engine's warnings (faults, overruns) on stderr; `RUST_LOG=bip_engine=debug`
/// shows every step.
fn tracing_subscriber_init() -> Result<(), Box<dyn Error + Send + Sync>> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("off")),
        )
        .with_writer(std::io::stderr)
        .try_init()
}
