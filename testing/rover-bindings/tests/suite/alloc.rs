//! No heap allocation per step in steady state through the generated bindings: a
//! counting global allocator counts this thread's allocations while the rover runs its
//! codels through their typed contexts (ports written in place and replaced, arguments
//! read), each module an object the engine calls by index.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use bip_engine::{Engine, Until};

use crate::rover::{driving, system};

struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new: usize) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        unsafe { System.realloc(ptr, layout, new) }
    }
}

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
    COUNT.with(|c| c.set(0));
    COUNTING.with(|c| c.set(true));
    for _ in 0..20 {
        e.run_until(Until::Steps(1_000)).expect("runs");
        let _ = e.events().count();
    }
    COUNTING.with(|c| c.set(false));
    let n = COUNT.with(Cell::get);
    let stats = e.inspect().stats();
    assert_eq!(stats.steps - steps0, 20_000);
    assert!(stats.codels - codels0 > 5_000, "{stats:?}");
    assert_eq!(n, 0, "{n} allocations in 20,000 steps");
}
