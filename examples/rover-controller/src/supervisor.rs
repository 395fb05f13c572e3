//! The supervisor: a script of typed requests at given ticks, the run of the engine with
//! the simulated hardware behind the codels, what it says, and the check of its
//! recording against the model.

use std::error::Error;

use bip_engine::bip_model::{PropertyKind, Verdict};
use bip_engine::{
    Bounded, CodelId, Engine, Event, RealClock, Reply, RequestError, System, Ticket, Trace, Until,
    VirtualClock,
};

use bip_zenoh::{Network, RemoteModules, RemoteOptions};

use crate::distributed::{bind_codels, bind_remote, types};
use crate::hardware::Hardware;
use crate::rover::{antenna, aspect, battery, camera, heating, ndd, pom, rflex, sick};

/// A request of the script, with its arguments of the types rover.ron declares.
#[derive(Clone, Copy, Debug)]
pub enum Order {
    Init,
    /// The cruise speed (m/s), unless navigation gives a set point.
    TrackSpeed(f64),
    StopWheels,
    Scan,
    StopLaser,
    Track,
    StopPose,
    /// The goal on the x axis (m).
    GoTo(f64),
    Build,
    /// Packets to send (`Int(1, 10)`: a number out of range does not compile).
    Communicate(Bounded<1, 10>),
    Report,
    Heat,
    Shoot,
}

impl Order {
    /// Sends the request through its typed function.
    fn send(self, e: &mut Engine) -> Result<Ticket, RequestError> {
        Ok(match self {
            Order::Init => rflex::request_init(e)?.0,
            Order::TrackSpeed(v) => rflex::request_track_speed(e, v)?.0,
            Order::StopWheels => rflex::request_stop(e)?.0,
            Order::Scan => sick::request_scan(e)?.0,
            Order::StopLaser => sick::request_stop(e)?.0,
            Order::Track => pom::request_track(e)?.0,
            Order::StopPose => pom::request_stop(e)?.0,
            Order::GoTo(goal) => ndd::request_go_to(e, goal)?.0,
            Order::Build => aspect::request_build(e)?.0,
            Order::Communicate(n) => antenna::request_communicate(e, n)?.0,
            Order::Report => battery::request_report(e)?.0,
            Order::Heat => heating::request_heat(e)?.0,
            Order::Shoot => camera::request_shoot(e)?.0,
        })
    }
}

/// The script: at which tick to send which request (in order of ticks).
const SCRIPT: &[(u64, Order)] = &[
    (0, Order::TrackSpeed(0.5)), // refused: after rflex.Init
    (1, Order::Init),
    (2, Order::TrackSpeed(0.5)), // drives; the battery Guard holds it at times
    (5, Order::Communicate(Bounded::of::<3>())), // held: Exclusive with TrackSpeed
    (9, Order::StopWheels),      // interrupts TrackSpeed, frees the antenna
    (14, Order::GoTo(1.0)),      // no laser: aborted (the rover's rule)
    (16, Order::Scan),
    (16, Order::Track),
    (18, Order::TrackSpeed(0.0)),
    (20, Order::GoTo(1.0)), // navigates there: ether
    (24, Order::Heat),
    (26, Order::Build),
    (27, Order::Shoot), // held: AtMost 1 with heating
    (55, Order::Report),
    (56, Order::GoTo(3.0)), // the rock is in the way: e_blocked
    (95, Order::StopWheels),
    (95, Order::StopLaser),
    (95, Order::StopPose),
];

const TICKS: u64 = 100;

/// Where a run of the controller ended, for the caller (and the test).
pub struct Report {
    pub system: System,
    pub trace: Trace,
    /// Each reply: the service (`module.Service`), the ticket, and what it said.
    pub replies: Vec<(String, Ticket, String)>,
    /// Each held codel (`module.Service.codel`) with the conditions that hold it.
    pub held: Vec<(String, Vec<String>)>,
    /// How each ndd.GoTo ended, read through its typed ticket.
    pub goto_ends: Vec<ndd::GoToEnd>,
    /// Where ndd.GoTo stopped, from each of its typed ends' output (also given when a
    /// codel threw).
    pub stopped_at: Vec<f64>,
    pub overruns: usize,
    /// Codel runs past their WCET, and task periods past their deadline.
    pub over_budget: usize,
    pub faults: usize,
    /// Bounded response properties of the model that a tick found late.
    pub late_responses: Vec<String>,
}

/// Builds the engine with the simulated hardware behind the codels, plays the script,
/// and checks the recording. `say` receives the log, line by line.
pub fn run(
    model: &std::path::Path,
    real_time: bool,
    say: &mut dyn FnMut(String),
) -> Result<Report, Box<dyn Error>> {
    run_on(model, real_time, None, say)
}

/// [`run`], with the codels in this process or, given a network, in the rover's module
/// processes ([`crate::distributed`]), which must be running.
pub fn run_on(
    model: &std::path::Path,
    real_time: bool,
    network: Option<&Network>,
    say: &mut dyn FnMut(String),
) -> Result<Report, Box<dyn Error>> {
    let system = bip_engine::load_file(model)?;
    let hw = Hardware::new();
    let tick_s = system.tick_ms.unwrap_or(100) as f64 / 1000.0;
    let virtual_clock = VirtualClock::new();
    let builder = Engine::builder(system.clone()).record(10_000);
    let builder = match network {
        None => bind_codels(
            builder,
            &hw,
            tick_s,
            (!real_time).then(|| virtual_clock.clone()),
        ),
        Some(network) => {
            let options = RemoteOptions {
                virtual_clock: (!real_time).then(|| virtual_clock.clone()),
                ..RemoteOptions::default()
            };
            let remote = RemoteModules::new(network, &system, types(&system), options)?;
            bind_remote(builder, &remote)?
        }
    };
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
        trace: Trace::new(&system, Verdict::None, Vec::new()),
        replies: Vec::new(),
        held: Vec::new(),
        goto_ends: Vec::new(),
        stopped_at: Vec::new(),
        overruns: 0,
        over_budget: 0,
        faults: 0,
        late_responses: Vec::new(),
    };
    let mut gotos: Vec<ndd::GoToTicket> = Vec::new();
    let mut script = SCRIPT.iter().peekable();
    for tick in 0..TICKS {
        while let Some((_, order)) = script.next_if(|r| r.0 <= tick) {
            let t = order.send(&mut engine)?;
            if let Order::GoTo(_) = order {
                gotos.push(ndd::GoToTicket(t));
            }
            say(format!(
                "[{:>5.1} s] supervisor: request #{} {order:?}",
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
            report.note(&event, &gotos);
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
        let w = hw.world();
        (w.x, w.sent)
    };
    say(format!(
        "end: {} steps ({} ticks, {} codels, {} exceptions, {} faults, {} overruns); rover at x = {x:.2} m, {sent} packets sent",
        stats.steps, stats.ticks, stats.codels, stats.exceptions, stats.faults, stats.overruns
    ));
    say_codel_times(&engine, say);
    report.trace = engine.record();
    check_recording(&system, &report.trace, say)?;
    Ok(report)
}

/// Each codel's run times against its WCET, the slowest first.
fn say_codel_times(engine: &Engine, say: &mut dyn FnMut(String)) {
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
    let stats = inspect.stats();
    say(format!(
        "budgets: {} codel runs past their WCET, {} periods' work past their task's deadline",
        stats.wcet_exceeded, stats.deadlines_missed
    ));
}

/// The recording is a path of the model, and every invariant holds along it.
fn check_recording(
    system: &System,
    trace: &Trace,
    say: &mut dyn FnMut(String),
) -> Result<(), Box<dyn Error>> {
    let path = trace.replay(system)?;
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
    Ok(())
}

impl Report {
    /// Notes what the test looks at: replies (GoTo's typed), held codels, overruns,
    /// budgets, faults.
    fn note(&mut self, event: &Event, gotos: &[ndd::GoToTicket]) {
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
                if let Some(end) = gotos.iter().find_map(|g| g.end(*ticket, reply)) {
                    if let ndd::GoToEnd::Done(Some(x)) | ndd::GoToEnd::Exception(_, Some(x)) = end {
                        self.stopped_at.push(x);
                    }
                    self.goto_ends.push(end);
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
