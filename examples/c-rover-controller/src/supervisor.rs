//! The supervisor: builds the engine with the three components' C codels bound, plays a
//! script of requests on the simulated world, prints what happens, and checks the
//! recording: it is a path of the model (bip-model's step relation accepts every step)
//! along which every invariant holds.

use std::sync::{Arc, Mutex};

use bip_engine::bip_model::PropertyKind;
use bip_engine::{Engine, Event, Reply, System, Ticket, Trace, Until};

use crate::rover_c::{loc, loco, nav, odo, rover};
use crate::world;
use crate::world::World;

/// rover.ron: robots/genom3's `.gen` files and odo.gen, with genom3-rover.ron's rules.
pub fn system() -> Result<System, String> {
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/rover.ron");
    bip_engine::load_file(model).map_err(|e| format!("{e:?}"))
}

/// An engine running the three components' C codels, recording its steps (with a seeded
/// choice among simultaneous steps); loc's module object is shared, for its estimate.
pub fn engine(system: &System, seed: u64) -> Result<(Engine, Arc<Mutex<loc::Component>>), String> {
    let builder = Engine::builder(system.clone())
        .policy(bip_engine::Policy::Seeded(seed))
        .record(100_000);
    let builder = loco::bind(builder);
    let (builder, loc) = loc::bind_shared(builder);
    let builder = nav::bind(builder);
    let builder = odo::bind(builder);
    Ok((builder.build().map_err(|e| e.to_string())?, loc))
}

/// What the run showed.
#[derive(Debug, Default)]
pub struct Report {
    /// Each reply: the service and the reply as the engine shows it.
    pub replies: Vec<(String, String)>,
    pub faults: u64,
    /// The world at the end, and loc's estimate of the rover's pose (x, y, heading).
    pub world: World,
    pub estimate: (f64, f64, f64),
    /// The recording's steps, each accepted by the model.
    pub steps: usize,
}

impl Report {
    fn note(&mut self, event: &Event, say: &mut dyn FnMut(String)) {
        match event {
            Event::Reply { service, reply, .. } => {
                let text = match reply {
                    Reply::Refused(_) => event.to_string(),
                    _ => reply.to_string(),
                };
                say(format!("  {service}: {text}"));
                self.replies.push((service.to_string(), text));
            }
            Event::Fault(f) => {
                say(format!("  fault: {f}"));
                self.faults += 1;
            }
            other => say(format!("  {other}")),
        }
    }

    /// The replies of `service`.
    pub fn of(&self, service: &str) -> Vec<&str> {
        self.replies
            .iter()
            .filter(|(s, _)| s == service)
            .map(|(_, t)| t.as_str())
            .collect()
    }
}

/// Plays the script; `say` receives the log, line by line.
pub fn run(say: &mut dyn FnMut(String)) -> Result<Report, String> {
    let _world = world::lock(World {
        obstacles: vec![(1.5, 2.0, 0.5)],
        ..World::default()
    });
    crate::hooks::set(crate::hooks::Outcomes::Own, 1);
    let system = system()?;
    let (mut engine, loc) = engine(&system, 1)?;
    let mut report = Report::default();
    let step = |engine: &mut Engine,
                report: &mut Report,
                ticks: u64,
                say: &mut dyn FnMut(String)|
     -> Result<(), String> {
        engine
            .run_until(Until::Ticks(ticks))
            .map_err(|e| e.to_string())?;
        for ev in engine.events() {
            report.note(&ev, say);
        }
        Ok(())
    };
    let request = |engine: &mut Engine,
                   module: &str,
                   service: &str,
                   args: &dyn Fn(&mut Engine) -> Result<Ticket, bip_engine::RequestError>,
                   say: &mut dyn FnMut(String)|
     -> Result<(), String> {
        say(format!("request {module}.{service}"));
        args(engine).map(|_| ()).map_err(|e| e.to_string())
    };
    let speed = rover::speed { v: 0.5, w: 0.0 };
    let goal = |x: f64, y: f64| nav::GoTo_input {
        goal: rover::pose {
            x,
            y,
            ..Default::default()
        },
        tolerance: 0.2,
    };

    say("localisation, and wheels before their Init (refused: after Init)".into());
    request(
        &mut engine,
        "loc",
        "Track",
        &|e| e.request("loc", "Track", ()),
        say,
    )?;
    request(
        &mut engine,
        "loco",
        "Move",
        &|e| e.request("loco", "Move", speed),
        say,
    )?;
    step(&mut engine, &mut report, 2, say)?;
    say("Init, then Move at 0.5 m/s".into());
    request(
        &mut engine,
        "loco",
        "Init",
        &|e| e.request("loco", "Init", ()),
        say,
    )?;
    step(&mut engine, &mut report, 1, say)?;
    request(
        &mut engine,
        "loco",
        "Move",
        &|e| e.request("loco", "Move", speed),
        say,
    )?;
    step(&mut engine, &mut report, 3, say)?;
    say("GoTo (1.5, 0): nav's codels follow the range sensor until within 0.2 m".into());
    request(
        &mut engine,
        "nav",
        "GoTo",
        &|e| e.request("nav", "GoTo", goal(1.5, 0.0)),
        say,
    )?;
    step(&mut engine, &mut report, 40, say)?;
    say("GoTo (1.5, 4): an obstacle on the way (e_blocked)".into());
    request(
        &mut engine,
        "nav",
        "GoTo",
        &|e| e.request("nav", "GoTo", goal(1.5, 4.0)),
        say,
    )?;
    // the async planner's outcome comes at the plan task's next cycle after it returns
    step(&mut engine, &mut report, 6, say)?;
    say("Stop the wheels".into());
    request(
        &mut engine,
        "loco",
        "Stop",
        &|e| e.request("loco", "Stop", ()),
        say,
    )?;
    step(&mut engine, &mut report, 3, say)?;

    report.world = world::now();
    if let Ok(loc) = loc.lock() {
        let e = loc.state.ids.estimate;
        report.estimate = (e.x, e.y, e.theta);
    }
    say(format!(
        "world: the rover at ({:.2}, {:.2}), heading {:.2}; loc's estimate ({:.2}, {:.2}), heading {:.2}",
        report.world.x, report.world.y, report.world.theta, report.estimate.0, report.estimate.1, report.estimate.2
    ));
    report.steps = check_recording(&system, &engine.record())?;
    say(format!(
        "recording: {} steps, each accepted by the model's step relation; every invariant holds in every state",
        report.steps
    ));
    Ok(report)
}

/// The recording is a path of the model, and every invariant holds along it; its length.
pub fn check_recording(system: &System, trace: &Trace) -> Result<usize, String> {
    let path = trace.replay(system).map_err(|e| e.to_string())?;
    for (_, state) in &path {
        for p in &system.properties {
            if let PropertyKind::Invariant(e) = &p.kind {
                if !system.holds(e, state, &p.name).map_err(|e| e.to_string())? {
                    return Err(format!("invariant {} fails in the recording", p.name));
                }
            }
        }
    }
    Ok(path.len())
}
