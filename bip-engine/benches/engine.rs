//! The engine's speed on robots/rover.ron, by hand (docs/performance.md, "Engine"):
//!
//!     cargo bench -p bip-engine --bench engine
//!
//! 1. Gated steps per second on one core with empty codels: every codel returns its first
//!    yield at once, so the time is the engine's own (gating, choice, commit, ticks).
//! 2. The engine's overhead on a codel that computes for about 2 µs: the time of the run
//!    against the time the same computations take alone, called as many times.
//! 3. Without the state cache, and on a run that keeps meeting new states (random codel
//!    results, the requests again and again): what the cache spares, and what it costs
//!    when it seldom knows the step.
//!
//! The engine runs on a virtual clock, so ticks come as soon as nothing else is left to
//! do: the run measures the engine, not the rover's 100 ms period.
//!
//! For counting instructions instead of time (a noisy machine, or one without hardware
//! counters), run only the first part, shorter, under callgrind:
//!
//!     valgrind --tool=callgrind target/release/deps/engine-HASH --empty-only --steps 200000 --runs 1

use std::hint::black_box;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

use bip_engine::{
    CacheStats, DefaultCodels, Engine, EngineBuilder, Next, Until, DEFAULT_STATE_CACHE,
};
use bip_model::System;

const WARM_UP: u64 = 20_000;

fn rover() -> System {
    let p = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/rover.ron");
    match bip_lang::load_file(std::path::Path::new(p)) {
        Ok(s) => s,
        Err(e) => panic!("{}", e.summary()),
    }
}

/// Binds every codel of the rover to `body` followed by the codel's first yield.
fn bind_all(system: &System, body: fn()) -> EngineBuilder {
    let mut b = Engine::builder(system.clone()).event_capacity(1024);
    let Some(map) = &system.genom else {
        panic!("the rover has a GenoM layer")
    };
    for m in &map.modules {
        for s in &m.services {
            for c in &s.codels {
                let first: &'static str = Box::leak(c.yields[0].target.clone().into_boxed_str());
                b = b.codel((&m.name, &s.name, &c.state), move |_| {
                    body();
                    Next::Yield(first)
                });
            }
        }
    }
    b
}

const REQUESTS: [(&str, &str); 6] = [
    ("rflex", "Init"),
    ("rflex", "TrackSpeed"),
    ("sick", "Scan"),
    ("pom", "Track"),
    ("aspect", "Build"),
    ("heating", "Heat"),
];

/// The engine on the rover with six activities running (the battery's Guard holds the
/// motion now and then), warmed up; the state cache holds up to `cache` states.
fn running(system: &System, body: fn(), cache: usize) -> Engine {
    let mut e = bind_all(system, body)
        .state_cache(cache)
        .build()
        .expect("builds");
    for (m, s) in REQUESTS {
        e.request(m, s, ()).expect("queued");
    }
    e.run_until(Until::Steps(WARM_UP)).expect("runs");
    let _ = e.events().count();
    e
}

/// Runs `steps` steps (draining events as a controller would); the time and the codels
/// run.
fn timed(e: &mut Engine, steps: u64) -> (Duration, u64) {
    let codels0 = e.inspect().stats().codels;
    let t = Instant::now();
    let mut left = steps;
    while left > 0 {
        let n = left.min(10_000);
        e.run_until(Until::Steps(n)).expect("runs");
        black_box(e.events().count());
        left -= n;
    }
    (t.elapsed(), e.inspect().stats().codels - codels0)
}

fn empty() {}

fn hit_share(c: CacheStats) -> f64 {
    c.hits as f64 * 100.0 / (c.hits + c.misses).max(1) as f64
}

/// Steps per second on the rover with random codel results (yields, exceptions)
/// and the six requests again every 64 steps, and the cache's stats at the end.
fn varied(system: &System, cache: usize, steps: u64) -> (f64, CacheStats, usize) {
    let mut e = Engine::builder(system.clone())
        .default_codels(DefaultCodels::Random(7))
        .event_capacity(1024)
        .state_cache(cache)
        .build()
        .expect("builds");
    let t = Instant::now();
    let mut done = 0;
    while done < steps {
        for (m, s) in REQUESTS {
            e.request(m, s, ()).expect("queued");
        }
        e.run_until(Until::Steps(64)).expect("runs");
        black_box(e.events().count());
        done += 64;
    }
    let rate = done as f64 / t.elapsed().as_secs_f64();
    (rate, e.inspect().cache_stats(), e.inspect().cache_bytes())
}

/// Iterations of `work`'s loop: calibrated so that a call takes about 2 µs.
static ITERATIONS: AtomicU32 = AtomicU32::new(1000);

/// About 2 µs of arithmetic, that the compiler cannot skip.
fn work() {
    let mut x = black_box(0x9e37_79b9_7f4a_7c15u64);
    for _ in 0..ITERATIONS.load(Ordering::Relaxed) {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
    }
    black_box(x);
}

/// The time of `n` calls of `work` alone.
fn work_alone(n: u64) -> Duration {
    let t = Instant::now();
    for _ in 0..n {
        work();
    }
    t.elapsed()
}

fn calibrate(target: Duration) {
    let n = 20_000;
    work_alone(n);
    let per_call = work_alone(n).as_secs_f64() / n as f64;
    let k = ITERATIONS.load(Ordering::Relaxed) as f64 * target.as_secs_f64() / per_call;
    ITERATIONS.store(k.round().max(1.0) as u32, Ordering::Relaxed);
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The command line: `--steps N` (timed steps with empty codels, default 2,000,000),
/// `--runs N` (default 5), `--empty-only` (skip the 2 µs codels and part 3), `--cache N`
/// (the state cache of parts 1 and 2, default `DEFAULT_STATE_CACHE`), `--varied-only N`
/// (only part 3's run with random codel results, `--steps` steps, a cache of N states).
struct Options {
    steps: u64,
    runs: usize,
    empty_only: bool,
    cache: usize,
    varied: Option<usize>,
}

fn options() -> Options {
    let mut o = Options {
        steps: 2_000_000,
        runs: 5,
        empty_only: false,
        cache: DEFAULT_STATE_CACHE,
        varied: None,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        // the number after `what`, at least `least`
        let mut number = |what: &str, least: u64| -> u64 {
            match args.next().map(|v| v.parse()) {
                Some(Ok(n)) if n >= least => n,
                _ => panic!("{what} needs a number of at least {least}"),
            }
        };
        match a.as_str() {
            "--steps" => o.steps = number("--steps", 1),
            "--runs" => o.runs = number("--runs", 1) as usize,
            "--empty-only" => o.empty_only = true,
            "--varied-only" => o.varied = Some(number("--varied-only", 0) as usize),
            "--cache" => o.cache = number("--cache", 0) as usize,
            // cargo bench passes `--bench`
            _ => {}
        }
    }
    o
}

fn main() {
    let o = options();
    let system = rover();
    if let Some(cache) = o.varied {
        let (rate, stats, _) = varied(&system, cache, o.steps);
        println!("{:.0} ns per step, {stats:?}", 1e9 / rate);
        return;
    }
    println!(
        "rover.ron, one thread, virtual clock; median of {} runs",
        o.runs
    );

    // 1. empty codels
    let steps = o.steps;
    let mut rates = Vec::new();
    let mut codel_share = 0.0;
    let mut cache = CacheStats::default();
    let mut bytes = 0;
    for _ in 0..o.runs {
        let mut e = running(&system, empty, o.cache);
        let (t, codels) = timed(&mut e, steps);
        rates.push(steps as f64 / t.as_secs_f64());
        codel_share = codels as f64 / steps as f64;
        (cache, bytes) = (e.inspect().cache_stats(), e.inspect().cache_bytes());
    }
    let rate = median(rates);
    println!(
        "empty codels: {:.2} M gated steps/s ({:.0} ns per step; {:.0}% of the steps are codels, the rest ticks and requests)",
        rate / 1e6,
        1e9 / rate,
        codel_share * 100.0
    );
    // what the engine costs per codel run, ticks included, with nothing else running
    let engine_ns = 1e9 / rate / codel_share;
    println!(
        "  the engine's own time per codel run: {engine_ns:.0} ns ({:.1}% of a 2 µs codel)",
        engine_ns / 20.0
    );
    println!(
        "  state cache: {} states, {} steps known, {:.2}% of the steps taken from it, {} KiB",
        cache.states,
        cache.edges,
        hit_share(cache),
        bytes / 1024
    );
    if o.empty_only {
        return;
    }

    // 3. without the cache; and a run that keeps meeting new states
    let mut rates = Vec::new();
    for _ in 0..o.runs {
        let mut e = running(&system, empty, 0);
        let (t, _) = timed(&mut e, steps);
        rates.push(steps as f64 / t.as_secs_f64());
    }
    let rate = median(rates);
    println!(
        "empty codels, no state cache: {:.2} M gated steps/s ({:.0} ns per step)",
        rate / 1e6,
        1e9 / rate
    );
    // (a cache of 16 states is soon full and seldom knows the step: what misses cost)
    for cache in [0, 16, DEFAULT_STATE_CACHE] {
        let mut rates = Vec::new();
        let (mut stats, mut bytes) = (CacheStats::default(), 0);
        for _ in 0..o.runs {
            let (rate, s, b) = varied(&system, cache, steps / 4);
            rates.push(rate);
            (stats, bytes) = (s, b);
        }
        let rate = median(rates);
        println!(
            "random codel results, requests every 64 steps, state cache of {cache}: {:.2} M gated steps/s ({:.0} ns per step; {} states, {} KiB, {:.1}% of the steps taken from the cache)",
            rate / 1e6,
            1e9 / rate,
            stats.states,
            bytes / 1024,
            hit_share(stats)
        );
    }

    // 2. codels of about 2 µs
    calibrate(Duration::from_micros(2));
    let steps = 200_000;
    let mut overheads = Vec::new();
    let mut per_codel = Vec::new();
    let mut work_us = 0.0;
    for _ in 0..o.runs {
        let mut e = running(&system, work, o.cache);
        // the codels' own time, measured just before and just after the run (the machine's
        // speed drifts; one measurement apart from the run moves the overhead by percents)
        // (about three steps in four are codels; the "before" time is scaled to the count)
        let guess = steps * 3 / 4;
        let before = work_alone(guess);
        let (t, codels) = timed(&mut e, steps);
        let after = work_alone(codels);
        let alone =
            (before.as_secs_f64() * codels as f64 / guess as f64 + after.as_secs_f64()) / 2.0;
        let alone = Duration::from_secs_f64(alone);
        work_us = alone.as_secs_f64() * 1e6 / codels as f64;
        let extra = t.as_secs_f64() - alone.as_secs_f64();
        overheads.push(extra / alone.as_secs_f64());
        per_codel.push(extra * 1e9 / codels as f64);
    }
    println!(
        "codels of {work_us:.2} µs: engine overhead {:.1}% of the codels' time ({:.0} ns per codel run, ticks included)",
        median(overheads) * 100.0,
        median(per_codel)
    );
}
