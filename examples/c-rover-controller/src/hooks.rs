//! The test hook of codels/hook.c: which outcomes the codels return (their own, any they
//! declare, or now and then one they do not), and how many undeclared ones they returned.

use std::ffi::c_int;

extern "C" {
    static mut rover_hook_mode: c_int;
    static mut rover_hook_seed: u32;
    static mut rover_hook_undeclared: u64;
}

/// What the codels return.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcomes {
    /// Each codel's own.
    Own,
    /// One the codel declares, at random.
    Declared,
    /// As `Declared`, or one time in five an event the codel does not declare.
    Undeclared,
}

/// Sets the codels' outcomes from now on, with the hook's random seed; the count of
/// undeclared ones returned starts again at 0. Hold [`crate::world::lock`] around a run.
pub fn set(outcomes: Outcomes, seed: u32) {
    let mode = match outcomes {
        Outcomes::Own => 0,
        Outcomes::Declared => 1,
        Outcomes::Undeclared => 2,
    };
    // SAFETY: plain C variables the codels read in the engine's thread, set between runs
    // by whoever holds the world's lock
    unsafe {
        *std::ptr::addr_of_mut!(rover_hook_mode) = mode;
        *std::ptr::addr_of_mut!(rover_hook_seed) = seed.max(1);
        *std::ptr::addr_of_mut!(rover_hook_undeclared) = 0;
    }
}

/// How many undeclared events the codels returned since [`set`].
pub fn undeclared() -> u64 {
    // SAFETY: as in `set`
    unsafe { *std::ptr::addr_of!(rover_hook_undeclared) }
}
