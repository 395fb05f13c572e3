//! No heap allocation per step in steady state: a counting global allocator counts the
//! allocations of this thread while the engine runs the rover with bound (empty) codels,
//! several activities running, ticks, held codels (the battery), requests being refused.

#[path = "suite/common/mod.rs"]
mod common;

use bip_counting_alloc::{allocations_during, installed, Counting};
use bip_engine::*;
use common::*;

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
fn steady_state_steps_allocate_nothing() {
    let system = load("rover.ron");
    let b = Engine::builder(system.clone()).event_capacity(256);
    let mut e = first_yields(b, &system).build().expect("builds");
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
    // warm up: every buffer grows to what the run needs
    e.run_until(Until::Steps(5_000)).expect("runs");
    let _ = e.events().count();
    let steps0 = e.inspect().stats().steps;
    let mut held = 0;
    assert!(installed());
    let n = allocations_during(|| {
        for _ in 0..20 {
            e.run_until(Until::Steps(1_000)).expect("runs");
            // drained as a controller would
            held += e
                .events()
                .filter(|ev| matches!(ev, Event::Held { .. }))
                .count();
        }
    });
    assert!(
        held > 100,
        "the battery holds the motion now and then ({held})"
    );
    let stats = e.inspect().stats();
    assert_eq!(stats.steps - steps0, 20_000);
    assert!(stats.codels > 5_000 && stats.ticks > 5_000, "{stats:?}");
    assert_eq!(n, 0, "{n} allocations in 20,000 steady-state steps");
    // the counter does count: a request allocates its arguments' box and queue slot
    let n = allocations_during(|| {
        e.request("camera", "Shoot", vec![1u8]).expect("queued");
    });
    assert!(n > 0);
}
