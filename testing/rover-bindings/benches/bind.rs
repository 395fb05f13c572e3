//! The generated bindings against closures, side by side, on robots/rover.ron
//! (docs/performance.md, "Generated bindings"): the engine benchmark's first part (every
//! codel returns its first yield at once, so the time is the engine's and the binding's),
//! once with every codel bound to a closure, once through the generated `bind`.
//!
//!     cargo bench -p bip-rover-bindings --bench bind
//!
//! For instructions instead of time, one binding at a time under callgrind, at two
//! lengths (the difference divided by the difference of steps is the cost of a step):
//!
//!     valgrind --tool=callgrind target/release/deps/bind-HASH --generated --steps 200000 --runs 1

use std::hint::black_box;
use std::time::{Duration, Instant};

use bip_engine::{Engine, EngineBuilder, Next, System, Until};
use bip_rover_bindings::*;

const WARM_UP: u64 = 20_000;

fn rover() -> System {
    let p = concat!(env!("CARGO_MANIFEST_DIR"), "/../../robots/rover.ron");
    bip_engine::load_file(p).unwrap_or_else(|e| panic!("{e:?}"))
}

/// Every codel bound to a closure that returns its first yield, as the engine's bench.
fn closures(system: &System) -> EngineBuilder {
    let mut b = Engine::builder(system.clone());
    let Some(map) = &system.genom else {
        panic!("the rover has a GenoM layer")
    };
    for m in &map.modules {
        for s in &m.services {
            for c in &s.codels {
                let first: &'static str = Box::leak(c.yields[0].target.clone().into_boxed_str());
                b = b.codel((&m.name, &s.name, &c.state), move |_| Next::Yield(first));
            }
        }
    }
    b
}

/// Every codel through the generated bindings, returning its first yield.
struct First;

impl rflex::Codels for First {
    fn track_speed_start(
        &mut self,
        _: rflex::TrackSpeedStartCtx<'_, '_>,
    ) -> rflex::TrackSpeedStart {
        rflex::TrackSpeedStart::ALL[0]
    }
    fn track_speed_track(
        &mut self,
        _: rflex::TrackSpeedTrackCtx<'_, '_>,
    ) -> rflex::TrackSpeedTrack {
        rflex::TrackSpeedTrack::ALL[0]
    }
}

impl sick::Codels for First {
    fn scan_start(&mut self, _: sick::ScanStartCtx<'_, '_>) -> sick::ScanStart {
        sick::ScanStart::ALL[0]
    }
    fn scan_scan(&mut self, _: sick::ScanScanCtx<'_, '_>) -> sick::ScanScan {
        sick::ScanScan::ALL[0]
    }
}

impl pom::Codels for First {
    fn track_start(&mut self, _: pom::TrackStartCtx<'_, '_>) -> pom::TrackStart {
        pom::TrackStart::ALL[0]
    }
    fn track_fuse(&mut self, _: pom::TrackFuseCtx<'_, '_>) -> pom::TrackFuse {
        pom::TrackFuse::ALL[0]
    }
}

impl ndd::Codels for First {
    fn go_to_start(&mut self, _: ndd::GoToStartCtx<'_, '_>) -> ndd::GoToStart {
        ndd::GoToStart::ALL[0]
    }
    fn go_to_move(&mut self, _: ndd::GoToMoveCtx<'_, '_>) -> ndd::GoToMove {
        ndd::GoToMove::ALL[0]
    }
    fn go_to_stop(&mut self, _: ndd::GoToStopCtx<'_, '_>) -> ndd::GoToStop {
        ndd::GoToStop::ALL[0]
    }
}

impl aspect::Codels for First {
    fn build_start(&mut self, _: aspect::BuildStartCtx<'_, '_>) -> aspect::BuildStart {
        aspect::BuildStart::ALL[0]
    }
    fn build_fuse(&mut self, _: aspect::BuildFuseCtx<'_, '_>) -> aspect::BuildFuse {
        aspect::BuildFuse::ALL[0]
    }
}

impl antenna::Codels for First {
    fn communicate_start(
        &mut self,
        _: antenna::CommunicateStartCtx<'_, '_>,
    ) -> antenna::CommunicateStart {
        antenna::CommunicateStart::ALL[0]
    }
    fn communicate_send(
        &mut self,
        _: antenna::CommunicateSendCtx<'_, '_>,
    ) -> antenna::CommunicateSend {
        antenna::CommunicateSend::ALL[0]
    }
}

impl heating::Codels for First {
    fn heat_start(&mut self, _: heating::HeatStartCtx<'_, '_>) -> heating::HeatStart {
        heating::HeatStart::ALL[0]
    }
    fn heat_heat(&mut self, _: heating::HeatHeatCtx<'_, '_>) -> heating::HeatHeat {
        heating::HeatHeat::ALL[0]
    }
}

impl camera::Codels for First {
    fn shoot_start(&mut self, _: camera::ShootStartCtx<'_, '_>) -> camera::ShootStart {
        camera::ShootStart::ALL[0]
    }
    fn shoot_expose(&mut self, _: camera::ShootExposeCtx<'_, '_>) -> camera::ShootExpose {
        camera::ShootExpose::ALL[0]
    }
}

fn generated(system: &System) -> EngineBuilder {
    let b = Engine::builder(system.clone());
    bind(b, First, First, First, First, First, First, First, First)
}

/// The engine's bench's six activities, warmed up.
fn running(builder: EngineBuilder) -> Engine {
    let mut e = builder.event_capacity(1024).build().expect("builds");
    for (m, s) in [
        ("rflex", "Init"),
        ("rflex", "TrackSpeed"),
        ("sick", "Scan"),
        ("pom", "Track"),
        ("aspect", "Build"),
        ("heating", "Heat"),
    ] {
        e.request(m, s, ()).expect("queued");
    }
    e.run_until(Until::Steps(WARM_UP)).expect("runs");
    let _ = e.events().count();
    e
}

fn timed(e: &mut Engine, steps: u64) -> Duration {
    let t = Instant::now();
    let mut left = steps;
    while left > 0 {
        let n = left.min(10_000);
        e.run_until(Until::Steps(n)).expect("runs");
        black_box(e.events().count());
        left -= n;
    }
    t.elapsed()
}

fn main() {
    let mut steps = 2_000_000u64;
    let mut runs = 5usize;
    let mut which: Vec<&str> = vec!["closures", "generated"];
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut number = |name: &str| -> u64 {
            match args.next().map(|v| v.parse()) {
                Some(Ok(n)) if n >= 1 => n,
                _ => {
                    eprintln!("{name} takes a positive number");
                    std::process::exit(2)
                }
            }
        };
        match a.as_str() {
            "--steps" => steps = number("--steps"),
            "--runs" => runs = number("--runs") as usize,
            "--closures" => which = vec!["closures"],
            "--generated" => which = vec!["generated"],
            _ => {}
        }
    }
    let system = rover();
    println!("rover.ron, one thread, virtual clock, first yields; median of {runs} runs");
    for w in which {
        let mut times: Vec<Duration> = (0..runs)
            .map(|_| {
                let builder = if w == "closures" {
                    closures(&system)
                } else {
                    generated(&system)
                };
                timed(&mut running(builder), steps)
            })
            .collect();
        times.sort();
        let t = times[times.len() / 2];
        println!(
            "{w}: {:.0} ns per step",
            t.as_secs_f64() * 1e9 / steps as f64
        );
    }
}
