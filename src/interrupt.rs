//! Ctrl-C as a request to stop, not a kill: the first SIGINT raises a flag that the
//! running command's library polls (the verifier's methods, the simulation), which then
//! ends like a limit does, with its partial report; a second SIGINT exits at once.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// The flag the handler raises; set once, before the handler is installed, so that the
/// handler only ever reads an initialised cell.
static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// Exit status of a process ended by a second Ctrl-C (128 + SIGINT, as shells report it).
const SECOND_INTERRUPT: i32 = 130;

/// Installs the handler (once) and returns the flag it raises, for the library to poll.
#[allow(dead_code)] // until the verifier and the simulation take a stop flag
pub fn stop_flag() -> Arc<AtomicBool> {
    let flag = FLAG
        .get_or_init(|| Arc::new(AtomicBool::new(false)))
        .clone();
    install();
    flag
}

#[cfg(unix)]
fn install() {
    static INSTALLED: OnceLock<()> = OnceLock::new();
    INSTALLED.get_or_init(|| {
        // SAFETY: `on_sigint` is async-signal-safe (an atomic swap, write(2), _exit(2));
        // the sigaction struct is zeroed, then given a handler and an empty mask.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_sigint as *const () as usize;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(libc::SIGINT, &action, std::ptr::null_mut());
        }
    });
}

#[cfg(not(unix))]
fn install() {}

#[cfg(unix)]
extern "C" fn on_sigint(_signal: libc::c_int) {
    let Some(flag) = FLAG.get() else {
        // SAFETY: _exit is async-signal-safe.
        unsafe { libc::_exit(SECOND_INTERRUPT) }
    };
    let (message, again): (&[u8], bool) = if flag.swap(true, Ordering::SeqCst) {
        (b"\ninterrupted again: exiting now\n", true)
    } else {
        (
            b"\ninterrupted: finishing the report (Ctrl-C again to quit at once)\n",
            false,
        )
    };
    // SAFETY: write(2) and _exit(2) are async-signal-safe; the buffer outlives the call.
    unsafe {
        libc::write(libc::STDERR_FILENO, message.as_ptr().cast(), message.len());
        if again {
            libc::_exit(SECOND_INTERRUPT);
        }
    }
}
