//! No heap allocation per step in steady state through the generated bindings: a
//! counting global allocator counts this thread's allocations while the rover runs its
//! codels through their typed contexts (ports written in place and replaced, arguments
//! read), each module an object the engine calls by index.

use bip_counting_alloc::{allocations_during, installed, Counting};
use bip_engine::{Engine, Until};

use crate::rover::{driving, system};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
fn steady_state_steps_through_the_bindings_allocate_nothing() {
    let system = system();
    // wheels, laser, pose and the rest bound; rflex, sick and pom running; not recorded
    // (a recording grows)
    let mut e = driving(Engine::builder(system.clone()).event_capacity(256), None);
    e.run_until(Until::Steps(5_000)).expect("runs");
    let _ = e.events().count();
    let steps0 = e.inspect().stats().steps;
    let codels0 = e.inspect().stats().codels;
    assert!(installed());
    let n = allocations_during(|| {
        for _ in 0..20 {
            e.run_until(Until::Steps(1_000)).expect("runs");
            let _ = e.events().count();
        }
    });
    let stats = e.inspect().stats();
    assert_eq!(stats.steps - steps0, 20_000);
    assert!(stats.codels - codels0 > 5_000, "{stats:?}");
    assert_eq!(n, 0, "{n} allocations in 20,000 steps");
}
