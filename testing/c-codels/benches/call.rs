//! The engine's time per step with counter's C codels (bound by the generated glue)
//! against the same codels in Rust, bound alike (one module object each, owning its ids):
//! `Count(n)` with `n` past the run, so that its step codel runs every tick; and the C
//! codels bound with `bind_shared`, whose module object is behind a lock (docs/codegen.md, "Running C codels on the engine").
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
    engine.run_until(Until::Steps(steps())).expect("runs");
    let took = start.elapsed();
    black_box(engine.events().count());
    took
}

/// The least of `TRIES` runs, each variant's runs interleaved with the others': the
/// machine is shared, and the least time is the one the least disturbed.
const TRIES: usize = 5;

/// The steps measured: `CALL_STEPS`, else [`STEPS`].
fn steps() -> u64 {
    std::env::var("CALL_STEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(STEPS)
}

fn main() {
    let system = system();
    // `CALL_ONLY=c`, `rust` or `shared`: one run of that binding alone, for a counter of
    // the process's own instructions and cycles (`perf stat -e instructions:u,cycles:u`),
    // which other processes on the machine do not disturb
    if let Ok(only) = std::env::var("CALL_ONLY") {
        let bind: &dyn Fn(EngineBuilder) -> EngineBuilder = match only.as_str() {
            "c" => &counter::bind,
            "rust" => &rust,
            _ => &|b| counter::bind_shared(b).0,
        };
        black_box(run(&system, bind));
        return;
    }
    let ns = |d: Duration| d.as_nanos() as f64 / steps() as f64;
    for round in 0..3 {
        let mut best = [Duration::MAX; 3];
        for _ in 0..TRIES {
            let runs = [
                run(&system, &counter::bind),
                run(&system, &rust),
                run(&system, &|b| counter::bind_shared(b).0),
            ];
            for (b, r) in best.iter_mut().zip(runs) {
                *b = (*b).min(r);
            }
        }
        let [c, r, shared] = best.map(ns);
        println!(
            "round {round}: C codels {c:.1} ns per step, Rust codels {r:.1} ns per step ({:+.1}%); C codels shared behind a lock {shared:.1} ns",
            100.0 * (c - r) / r,
        );
    }
}
