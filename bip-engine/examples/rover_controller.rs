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

use bip_engine::bip_model::PropertyKind;
use bip_engine::{
    CodelId, Engine, Event, Next, RealClock, Reply, RequestError, System, Ticket, Trace, Until,
    VirtualClock,
};

/// The arguments the supervisor sends with its requests, of the types rover.ron
/// declares (the engine refuses a request with another type).
#[derive(Clone, Copy, Debug)]
pub enum Arg {
    None,
    /// `rflex.TrackSpeed` (`Float`): the cruise speed (m/s), unless navigation gives a
    /// set point.
    Speed(f64),
    /// `ndd.GoTo` (`Float`): the goal on the x axis (m).
    Goal(f64),
    /// `antenna.Communicate` (`Int(1, 10)`): packets to send.
    Packets(i64),
}

impl Arg {
    fn request(self, engine: &mut Engine, m: &str, s: &str) -> Result<Ticket, RequestError> {
        match self {
            Arg::None => engine.request(m, s, ()),
            Arg::Speed(v) | Arg::Goal(v) => engine.request(m, s, v),
            Arg::Packets(n) => engine.request(m, s, n),
        }
    }
}

/// Port data (GenoM ports): written by one module's codels, read by others, of the types
/// rover.ron declares (`Odometry` and `Pose` are records there; the others Rust types).
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
    /// Where ndd.GoTo stopped, from each of its replies' output.
    pub stopped_at: Vec<f64>,
    pub overruns: usize,
    /// Codel runs past their WCET, and task periods past their deadline.
    pub over_budget: usize,
    pub faults: usize,
    /// Bounded response properties of the model that a tick found late.
    pub late_responses: Vec<String>,
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
    let system = bip_engine::load_file(model)?;
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
            let cruise = ctx.args::<f64>().copied().unwrap_or(0.0);
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
            let goal = ctx.args::<f64>().copied().unwrap_or(0.0);
            let x = ctx.port::<Pose>("pom", "pose").map_or(0.0, |p| p.x);
            let ahead = ctx.port::<Scan>("sick", "scan").map_or(0.0, |s| s.ahead);
            let mut w = w3.lock().unwrap_or_else(|p| p.into_inner());
            // GoTo's output (`Float`): where the rover stopped
            ctx.set_output(x);
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
            let want = ctx.args::<i64>().copied().unwrap_or(1);
            let mut w = w5.lock().unwrap_or_else(|p| p.into_inner());
            w.sent += 1;
            if i64::from(w.sent) >= want {
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
            verdict: bip_engine::bip_model::Verdict::None,
            steps: Vec::new(),
            loop_start: None,
        },
        replies: Vec::new(),
        held: Vec::new(),
        stopped_at: Vec::new(),
        overruns: 0,
        over_budget: 0,
        late_responses: Vec::new(),
        faults: 0,
    };
    let mut script = SCRIPT.iter().peekable();
    for tick in 0..TICKS {
        while let Some((_, m, s, arg)) = script.next_if(|r| r.0 <= tick) {
            let t = arg.request(&mut engine, m, s)?;
            say(format!(
                "[{:>5.1} s] supervisor: request #{} {m}.{s} {arg:?}",
                engine.inspect().now_us() as f64 / 1e6,
                t.0
            ));
        }
        engine.run_until(Until::Ticks(1))?;
        let now = engine.inspect().now_us() as f64 / 1e6;
        let mut battery_reported = false;
        // events name their codel or service: each prints as one line (`Display`)
        for event in engine.events() {
            let held_before = report.held.len();
            report.note(&event);
            // a codel held again for the same reasons is said once
            let repeated = report.held.len() > held_before
                && report.held[..held_before].contains(&report.held[held_before]);
            if !repeated {
                say(format!("[{now:>5.1} s] {event}"));
            }
            if let Event::Reply {
                service,
                reply: Reply::Done { .. },
                ..
            } = &event
            {
                battery_reported |=
                    (service.module.as_str(), service.name.as_str()) == ("battery", "Report");
            }
        }
        // the battery module's report: the charge the model's battery atom holds
        if battery_reported {
            say(format!(
                "[{now:>5.1} s] battery: charge {} of 3",
                system.value(engine.inspect().state(), pack, level)
            ));
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
        // runs by duration: bucket `b` holds the runs under 2^b µs
        let histogram: Vec<String> = t
            .histogram
            .iter()
            .enumerate()
            .filter(|(_, &n)| n > 0)
            .map(|(b, n)| format!("{n} under {} µs", 1u64 << b))
            .collect();
        say(format!(
            "codel {m}.{s}.{k}: {} runs, mean {:.0} µs, max {} µs, {} over its WCET ({})",
            t.runs,
            t.mean_us(),
            t.max_us,
            t.over_wcet,
            histogram.join(", ")
        ));
    }
    say(format!(
        "budgets: {} codel runs past their WCET, {} periods' work past their task's deadline",
        stats.wcet_exceeded, stats.deadlines_missed
    ));

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

impl Report {
    /// Notes what the test looks at: replies, held codels, overruns, budgets, faults.
    fn note(&mut self, event: &Event) {
        match event {
            Event::Reply {
                ticket,
                service,
                reply,
            } => {
                let text = match reply {
                    // the refused conditions are named by the event, from its service
                    Reply::Refused(_) => event.to_string(),
                    _ => reply.to_string(),
                };
                if let Reply::Done {
                    output: Some(out), ..
                } = reply
                {
                    self.stopped_at.extend(out.get::<f64>());
                }
                self.replies.push((service.to_string(), *ticket, text));
            }
            Event::Held { codel, reasons, .. } => {
                let why = reasons.iter().map(|k| codel.holds[k].clone()).collect();
                self.held.push((codel.to_string(), why));
            }
            Event::Fault(_) => self.faults += 1,
            Event::Overrun { .. } => self.overruns += 1,
            Event::WcetExceeded { .. } | Event::DeadlineMissed { .. } => self.over_budget += 1,
            Event::ResponseLate { .. } => self.late_responses.push(event.to_string()),
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
