//! A global allocator that counts the allocations (and reallocations) of the thread that
//! asks, for the tests that the engine allocates nothing per step in steady state. A test
//! binary installs it:
//!
//! ```ignore
//! #[global_allocator]
//! static ALLOCATOR: bip_counting_alloc::Counting = bip_counting_alloc::Counting;
//! ```
//!
//! and measures with [`allocations_during`]. Other threads (the test harness's) are not
//! counted, so tests running beside each other do not disturb the count.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// The system allocator, counting.
pub struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    if COUNTING.with(Cell::get) {
        COUNT.with(|c| c.set(c.get() + 1));
    }
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new) }
    }
}

/// How many times this thread allocated or reallocated while `f` ran. Meaningful only
/// in a binary whose global allocator is [`Counting`] (else 0, which the tests would
/// take for success: [`installed`] says which).
pub fn allocations_during(f: impl FnOnce()) -> u64 {
    COUNT.with(|c| c.set(0));
    COUNTING.with(|c| c.set(true));
    f();
    COUNTING.with(|c| c.set(false));
    COUNT.with(Cell::get)
}

/// Whether [`Counting`] is this binary's global allocator: an allocation is counted.
pub fn installed() -> bool {
    allocations_during(|| drop(std::hint::black_box(Box::new(1u8)))) == 1
}
