//! The engine's time per step with counter's C codels against the same codels in Rust,
//! bound alike (one module object each): `Count(n)` with `n` past the run, so that its
//! step codel runs every tick (docs/codegen.md, "Running C codels on the engine").
//!
//!     cargo bench -p bip-c-codels --bench call

use std::hint::black_box;
use std::time::{Duration, Instant};

use bip_c_codels::counter::{self, ids as CounterIds, CODELS};
use bip_engine::{Engine, EngineBuilder, Next, System, Until};

const STEPS: u64 = 1_000_000;

fn system() -> System {
    let p = concat!(env!("CARGO_MANIFEST_DIR"), "/counter.ron");
    bip_engine::load_file(p).unwrap_or_else(|e| panic!("{e:?}"))
}

/// counter.c's codels written in Rust, bound as one module object as the C ones are.
fn rust(builder: EngineBuilder) -> EngineBuilder {
    let mut ids = CounterIds::default();
    builder.module("counter", CODELS, move |k, ctx| {
        let n = ctx.args::<i64>().map_or(0, |&n| n as i32);
        // the ids are memory the C would see: written for real
        let ids = black_box(&mut ids);
        match k {
            0 => {
                ids.count = 0;
                ids.gain = 0.25;
                Next::Declared(if n > 0 { 0 } else { 1 })
            }
            1 => {
                ids.count += 1;
                ids.gain *= 2.0;
                Next::Declared(if ids.count < n { 0 } else { 1 })
            }
            _ => Next::Declared(0),
        }
    })
}

fn run(system: &System, bind: &dyn Fn(EngineBuilder) -> EngineBuilder) -> Duration {
    let mut engine = bind(Engine::builder(system.clone()))
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
    engine
        .request("counter", "Count", i64::from(i32::MAX))
        .unwrap_or_else(|e| panic!("{e}"));
    engine.run_until(Until::Steps(10_000)).expect("runs");
    let start = Instant::now();
    engine.run_until(Until::Steps(STEPS)).expect("runs");
    let took = start.elapsed();
    black_box(engine.events().count());
    took
}

fn main() {
    let system = system();
    for round in 0..3 {
        let c = run(&system, &|b| counter::bind(b));
        let r = run(&system, &rust);
        println!(
            "round {round}: C codels {:.1} ns per step, Rust codels {:.1} ns per step",
            c.as_nanos() as f64 / STEPS as f64,
            r.as_nanos() as f64 / STEPS as f64
        );
    }
}
