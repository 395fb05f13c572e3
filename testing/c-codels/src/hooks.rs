//! The test hooks of codels/counter.c, which are no part of the component: what
//! `counter_count_step` returns, chosen by a test, and gcc's layout of `counter_ids`.

use std::ffi::c_int;
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
