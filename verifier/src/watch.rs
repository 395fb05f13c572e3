//! The limits of a run, watched while it runs: time, memory and the user's interrupt.
//!
//! A method polls [`Watch::stopped`] (one atomic load) as often as it likes: between
//! batches, inside them for every state or every few hundred successors, between solver
//! calls. A watchdog thread ([`Watch::watchdog`]) samples the clock, the interrupt flag
//! and the process's resident memory every few milliseconds and raises the stop; it can
//! also act at once (interrupt z3), so a method that is inside a long call stops too. Code
//! that knows it is about to allocate a lot adds the bytes with [`Watch::expect`], which
//! raises the memory stop before the watchdog would see the memory in use.
//!
//! The first limit reached is the one reported.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, OnceLock};
use std::time::{Duration, Instant};

use crate::memory;
use crate::options::Options;
use crate::report::Stop;

/// The payload of [`Watch::halt_if_stopped`]'s unwinding.
struct Halted;

/// How often the watchdog looks.
const TICK: Duration = Duration::from_millis(5);

/// A run's limits and the first one reached.
pub(crate) struct Watch {
    started: Instant,
    timeout: Option<Duration>,
    max_memory: Option<u64>,
    interrupt: Option<Arc<AtomicBool>>,
    raised: AtomicBool,
    stop: OnceLock<Stop>,
    /// Bytes announced by [`Watch::expect`] and not yet in the resident figure.
    expected: AtomicU64,
    /// Resident bytes when the expected bytes started to count.
    base: AtomicU64,
    /// The end of the solver call in progress, in microseconds from `started` (0: none).
    call_deadline: AtomicU64,
    call_timed_out: AtomicBool,
    done: Mutex<bool>,
    wake: Condvar,
}

impl Watch {
    /// The limits of `options`; `max_memory` is the memory limit the method settled on
    /// (the user's, or a default).
    pub fn new(options: &Options, max_memory: Option<u64>) -> Watch {
        let w = Watch {
            started: Instant::now(),
            timeout: options.timeout,
            max_memory,
            interrupt: options.interrupt.clone(),
            raised: AtomicBool::new(false),
            stop: OnceLock::new(),
            expected: AtomicU64::new(0),
            base: AtomicU64::new(0),
            call_deadline: AtomicU64::new(0),
            call_timed_out: AtomicBool::new(false),
            done: Mutex::new(false),
            wake: Condvar::new(),
        };
        w.rebase();
        w.look();
        w
    }

    pub fn started(&self) -> Instant {
        self.started
    }

    pub fn max_memory(&self) -> Option<u64> {
        self.max_memory
    }

    /// The limit reached, if any. Cheap: poll it anywhere.
    pub fn stopped(&self) -> Option<&Stop> {
        if self.raised.load(Ordering::Relaxed) {
            self.stop.get()
        } else {
            None
        }
    }

    /// Checks every limit now (the clock, the interrupt, the memory) and returns the one
    /// reached, if any; for places that want an answer without waiting for the watchdog.
    pub fn look(&self) -> Option<&Stop> {
        if let Some(flag) = &self.interrupt {
            if flag.load(Ordering::Relaxed) {
                self.raise(Stop::Interrupted);
            }
        }
        if let Some(t) = self.timeout {
            if self.started.elapsed() >= t {
                self.raise(Stop::Timeout {
                    seconds: t.as_secs_f64(),
                });
            }
        }
        if let Some(limit) = self.max_memory {
            let resident = memory::resident_bytes().unwrap_or(0);
            let expected =
                self.base.load(Ordering::Relaxed) + self.expected.load(Ordering::Relaxed);
            if resident.max(expected) > limit {
                self.raise(Stop::MaxMemory { limit });
            }
        }
        self.stopped()
    }

    /// Ends the computation in progress by unwinding (no panic message: not a panic) once
    /// the run must stop; for long work that has no early result to return (the symbolic
    /// encoding of a wide model), caught where the method turns the stop into inconclusive
    /// verdicts.
    pub fn halt_if_stopped(&self) {
        if self.stopped().is_some() {
            std::panic::resume_unwind(Box::new(Halted));
        }
    }

    /// Stops the run for `stop`, unless it has stopped already.
    pub fn raise(&self, stop: Stop) {
        let _ = self.stop.set(stop);
        self.raised.store(true, Ordering::Release);
    }

    /// Announces `bytes` about to be allocated; raises the memory stop if they would not
    /// fit. Returns true if the run may go on.
    pub fn expect(&self, bytes: u64) -> bool {
        let total = self.expected.fetch_add(bytes, Ordering::Relaxed) + bytes;
        if let Some(limit) = self.max_memory {
            if self.base.load(Ordering::Relaxed) + total > limit {
                self.raise(Stop::MaxMemory { limit });
            }
        }
        self.stopped().is_none()
    }

    /// Makes room in `v` for `additional` more elements, as pushing them would (doubling
    /// its capacity), once the growth is known to fit: false, with the memory stop raised,
    /// if the new allocation would pass the memory limit or the allocator refuses it, so
    /// that a big allocation ends the run as inconclusive instead of aborting it.
    pub fn reserve<T>(&self, v: &mut Vec<T>, additional: usize) -> bool {
        match self.grow_or_say_why(v, additional) {
            Ok(()) => true,
            Err(stop) => {
                self.raise(stop);
                false
            }
        }
    }

    /// [`Watch::reserve`] without stopping the run: false if the growth does not fit,
    /// for memory the run can do without.
    pub fn grow<T>(&self, v: &mut Vec<T>, additional: usize) -> bool {
        self.grow_or_say_why(v, additional).is_ok()
    }

    fn grow_or_say_why<T>(&self, v: &mut Vec<T>, additional: usize) -> Result<(), Stop> {
        if v.capacity() - v.len() >= additional {
            return Ok(());
        }
        let capacity = v.capacity().saturating_mul(2).max(v.len() + additional);
        let bytes = (capacity * std::mem::size_of::<T>()) as u64;
        if let Some(limit) = self.max_memory {
            let resident = memory::resident_bytes().unwrap_or(0);
            let expected =
                self.base.load(Ordering::Relaxed) + self.expected.load(Ordering::Relaxed);
            if resident.max(expected).saturating_add(bytes) > limit {
                return Err(Stop::MaxMemory { limit });
            }
        }
        if memory::fallibly(|| v.try_reserve_exact(capacity - v.len())).is_err() {
            let limit = self.max_memory.or_else(memory::resident_bytes).unwrap_or(0);
            return Err(Stop::MaxMemory { limit });
        }
        Ok(())
    }

    /// Stops the run because the allocator refused memory: at the memory limit, or, with
    /// none set, at the memory resident now.
    pub fn out_of_memory(&self) {
        let limit = self.max_memory.or_else(memory::resident_bytes).unwrap_or(0);
        self.raise(Stop::MaxMemory { limit });
    }

    /// Forgets the announced bytes (they are resident now, or freed) and takes the
    /// resident memory as the new base.
    pub fn rebase(&self) {
        self.expected.store(0, Ordering::Relaxed);
        self.base
            .store(memory::resident_bytes().unwrap_or(0), Ordering::Relaxed);
    }

    /// Marks the start of a solver call that may run for `limit` at most; the watchdog
    /// interrupts it past that.
    pub fn call_started(&self, limit: Option<Duration>) {
        self.call_timed_out.store(false, Ordering::Relaxed);
        let end = limit.map_or(0, |l| {
            (self.started.elapsed() + l)
                .as_micros()
                .min(u128::from(u64::MAX)) as u64
        });
        self.call_deadline
            .store(end.max(u64::from(limit.is_some())), Ordering::Release);
    }

    /// Marks the end of the solver call; true if the watchdog interrupted it for its own
    /// time limit (not for a limit of the run).
    pub fn call_ended(&self) -> bool {
        self.call_deadline.store(0, Ordering::Release);
        self.call_timed_out.load(Ordering::Acquire)
    }

    /// Runs the watchdog until [`Watch::finish`]: it checks the limits every few
    /// milliseconds and calls `on_stop` once when the run must stop, or when a solver call
    /// overruns its own limit.
    pub fn watchdog(&self, on_stop: impl Fn()) {
        let mut done = self.done.lock().unwrap_or_else(|e| e.into_inner());
        let mut told = false;
        while !*done {
            if self.look().is_some() && !told {
                told = true;
                on_stop();
            }
            let deadline = self.call_deadline.load(Ordering::Acquire);
            if deadline > 0 && self.started.elapsed().as_micros() >= u128::from(deadline) {
                self.call_deadline.store(0, Ordering::Release);
                self.call_timed_out.store(true, Ordering::Release);
                on_stop();
            }
            done = self
                .wake
                .wait_timeout(done, TICK)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
    }

    /// Ends the watchdog.
    pub fn finish(&self) {
        *self.done.lock().unwrap_or_else(|e| e.into_inner()) = true;
        self.wake.notify_all();
    }

    /// Runs `work` with a watchdog beside it (which calls `on_stop` as
    /// [`Watch::watchdog`] says), and ends the watchdog when `work` returns.
    pub fn around<T>(&self, on_stop: impl Fn() + Send, work: impl FnOnce() -> T) -> T {
        std::thread::scope(|scope| {
            let dog = std::thread::Builder::new()
                .name("bip-watchdog".into())
                .spawn_scoped(scope, || self.watchdog(on_stop));
            let out = work();
            self.finish();
            if let Ok(dog) = dog {
                let _ = dog.join();
            }
            out
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_limit_reached_is_the_one_reported() {
        let flag = Arc::new(AtomicBool::new(false));
        let options = Options {
            interrupt: Some(flag.clone()),
            timeout: Some(Duration::from_secs(3600)),
            ..Options::default()
        };
        let w = Watch::new(&options, Some(u64::MAX / 4));
        assert_eq!(w.stopped(), None);
        flag.store(true, Ordering::Relaxed);
        assert_eq!(w.stopped(), None, "the flag is seen by a look");
        assert_eq!(w.look(), Some(&Stop::Interrupted));
        w.raise(Stop::MaxStates { limit: 3 });
        assert_eq!(w.stopped(), Some(&Stop::Interrupted));
    }

    #[test]
    fn announced_bytes_count_against_the_memory_limit() {
        let w = Watch::new(&Options::default(), Some(u64::MAX / 2));
        assert!(w.expect(1 << 20));
        assert!(!w.expect(u64::MAX / 2));
        assert!(matches!(w.stopped(), Some(Stop::MaxMemory { .. })));
    }

    #[test]
    fn a_growth_past_the_memory_limit_is_refused_before_it_is_made() {
        let resident = memory::resident_bytes().unwrap_or(0);
        let w = Watch::new(&Options::default(), Some(resident + (64 << 20)));
        let mut v: Vec<u8> = Vec::new();
        assert!(w.reserve(&mut v, 1 << 10));
        assert!(v.capacity() >= 1 << 10);
        assert_eq!(w.stopped(), None);
        assert!(!w.reserve(&mut v, 128 << 20));
        assert!(v.capacity() < 128 << 20, "nothing was allocated");
        assert!(matches!(w.stopped(), Some(Stop::MaxMemory { .. })));
    }

    #[test]
    fn the_watchdog_stops_a_run_at_its_time_limit() {
        let options = Options {
            timeout: Some(Duration::from_millis(50)),
            ..Options::default()
        };
        let w = Watch::new(&options, None);
        let calls = AtomicU64::new(0);
        let stop = w.around(
            || {
                calls.fetch_add(1, Ordering::Relaxed);
            },
            || loop {
                if let Some(s) = w.stopped() {
                    break s.clone();
                }
                std::thread::sleep(Duration::from_millis(1));
            },
        );
        assert!(matches!(stop, Stop::Timeout { .. }));
        assert_eq!(calls.load(Ordering::Relaxed), 1);
    }
}
