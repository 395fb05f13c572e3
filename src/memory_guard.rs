//! The memory limit of every command outside a verification's own limits: loading a model
//! (the expansion of families and `forall` connectors, the system's tables), drawing it,
//! checking it. A watchdog thread samples the process's resident memory every few
//! milliseconds and, past the limit, ends the process with a message that says what it was
//! doing and the limit, instead of letting the operating system kill it. `bip verify` and
//! `bip sched` guard their loading with the user's `--max-memory` and hand over to the
//! verifier's own watch (which ends the run as inconclusive with a report) once the model
//! is loaded.
//!
//! An allocation the allocator refuses (the address-space limit, `ulimit -v`, reached by
//! one big request before the watchdog sees it) ends the process the same way, through
//! [`Allocator`], instead of Rust's abort.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::sync::atomic::{AtomicU64, AtomicU8, Ordering};
use std::sync::Mutex;
use std::time::Duration;

use crate::exit;

/// How often the watchdog looks.
const TICK: Duration = Duration::from_millis(5);

/// The limit in bytes; 0: not guarded (a verification watches itself).
static LIMIT: AtomicU64 = AtomicU64::new(0);
/// The exit code past the limit.
static CODE: AtomicU8 = AtomicU8::new(exit::ERROR);
/// What the command is doing, for the message.
static DOING: Mutex<&str> = Mutex::new("running the command");

/// Starts the watchdog with the default limit (bip_verifier's `default_limit`: what the
/// system, the cgroup and the address-space limit leave, with a margin).
pub fn start() {
    if let Some(limit) = bip_verifier::default_memory_limit() {
        LIMIT.store(limit, Ordering::Relaxed);
    }
    let _ = std::thread::Builder::new()
        .name("bip-memory-guard".into())
        .spawn(|| loop {
            std::thread::sleep(TICK);
            let limit = LIMIT.load(Ordering::Relaxed);
            if limit == 0 {
                continue;
            }
            if bip_verifier::resident_bytes().is_some_and(|r| r > limit) {
                let doing = *DOING.lock().unwrap_or_else(|e| e.into_inner());
                let _ = writeln!(
                    std::io::stderr().lock(),
                    "error: the memory limit ({}) was reached while {doing}\n  help: the model is too big for this limit: give a larger `--max-memory` (bip verify, bip sched) or more memory, or make the families and `forall` connectors smaller",
                    bip_verifier::human_bytes(limit)
                );
                std::process::exit(i32::from(CODE.load(Ordering::Relaxed)));
            }
        });
}

/// Guards what follows with `limit` (the user's `--max-memory`; `None` keeps the default),
/// saying `doing` past it and ending with `code`.
pub fn guard(limit: Option<u64>, doing: &'static str, code: u8) {
    if let Some(l) = limit.or_else(bip_verifier::default_memory_limit) {
        LIMIT.store(l, Ordering::Relaxed);
    }
    CODE.store(code, Ordering::Relaxed);
    *DOING.lock().unwrap_or_else(|e| e.into_inner()) = doing;
}

/// Hands over to a method that watches its own memory.
pub fn release() {
    LIMIT.store(0, Ordering::Relaxed);
}

/// The system allocator, ending the process with a message when it refuses an allocation
/// (Rust would abort with SIGABRT and no report).
pub struct Allocator;

// SAFETY: every call is forwarded to `System`, which upholds GlobalAlloc's contract; a
// refused allocation never returns (the process ends).
unsafe impl GlobalAlloc for Allocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded with the caller's layout
        refused(unsafe { System.alloc(layout) }, layout.size())
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded with the caller's layout
        refused(unsafe { System.alloc_zeroed(layout) }, layout.size())
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded; `ptr` came from `System` with this layout
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded; `ptr` came from `System` with this layout
        refused(unsafe { System.realloc(ptr, layout, new_size) }, new_size)
    }
}

/// `ptr`, unless it is null: then the process ends with a message (written with no
/// allocation: the allocator is what failed).
fn refused(ptr: *mut u8, size: usize) -> *mut u8 {
    if ptr.is_null() && !bip_verifier::allocation_may_fail() {
        let mut digits = [0u8; 20];
        let mut n = size;
        let mut at = digits.len();
        loop {
            at -= 1;
            digits[at] = b'0' + (n % 10) as u8;
            n /= 10;
            if n == 0 {
                break;
            }
        }
        let mut err = std::io::stderr();
        let _ = err.write_all(b"error: out of memory: an allocation of ");
        let _ = err.write_all(&digits[at..]);
        let _ = err.write_all(
            b" bytes was refused (the address-space limit, ulimit -v, or the system's memory)\n  help: give a `--max-memory` below the limit, or more memory\n",
        );
        // SAFETY: _exit ends the process at once, running nothing that could allocate
        unsafe { libc::_exit(i32::from(CODE.load(Ordering::Relaxed))) }
    }
    ptr
}
