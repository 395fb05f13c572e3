//! The test hooks of codels/counter.c and codels/apart.c, which are no part of the
//! components: what `counter_count_step` returns, chosen by a test, and gcc's layout of
//! `counter_ids`; when apart.c's async codel begins, its release, and what followed it.

use std::ffi::c_int;
use std::sync::atomic::{AtomicI32, Ordering};
use std::sync::Mutex;

extern "C" {
    /// The tests' choice of what `counter_count_step` returns.
    static mut counter_test_outcome: c_int;
    /// gcc's layout of `counter_ids`: 0 its size, 1 its alignment, 2.. its members'
    /// offsets.
    pub fn counter_ids_layout(what: c_int) -> usize;
}

/// What `counter_count_step` returns (see codels/counter.c): 0 counts, 1 its declared
/// exception, 2 an undeclared one, 3 another codel's yield, 4 an address of no event,
/// 5 `genom_ok`. Shared by every engine of the process.
pub fn set_step_outcome(k: i32) {
    // SAFETY: a plain int the codel reads; the tests that set it hold `OUTCOME_LOCK`.
    unsafe { *std::ptr::addr_of_mut!(counter_test_outcome) = k };
}

/// Held by whoever sets [`set_step_outcome`] and runs the codels (tests run in threads).
pub static OUTCOME_LOCK: Mutex<()> = Mutex::new(());

extern "C" {
    /// codels/apart.c: set by the async `apart_grab_wait` when it begins.
    static apart_test_started: AtomicI32;
    /// Read by `apart_grab_wait`, which waits until it is set.
    static apart_test_release: AtomicI32;
    /// What `apart_grab_publish` saw: 100 × the local `got` + the ids' `frames`.
    static apart_test_published: AtomicI32;
}

/// Whether apart.c's async codel has begun.
pub fn apart_started() -> bool {
    // SAFETY: a C11 `atomic_int`, laid out as an `AtomicI32`, alive for the process
    unsafe { apart_test_started.load(Ordering::SeqCst) != 0 }
}

/// Lets apart.c's async codel return.
pub fn apart_release() {
    // SAFETY: as in `apart_started`
    unsafe { apart_test_release.store(1, Ordering::SeqCst) }
}

/// What apart.c's `publish` codel saw (0 before it ran).
pub fn apart_published() -> i32 {
    // SAFETY: as in `apart_started`
    unsafe { apart_test_published.load(Ordering::SeqCst) }
}
