//! Time: the engine fires the model's tick every `tick_ms` of its clock's time.

#[allow(unused_imports)]
use crate::prelude::*;

/// A source of time for the engine, in microseconds since the engine started.
pub trait Clock: Send {
    fn now_us(&self) -> u64;
    /// Waits until `t_us` (a real clock sleeps; a virtual clock jumps there at once).
    fn sleep_until(&self, t_us: u64);
    /// Whether time passes only when told (a virtual clock). The engine then moves it to
    /// the next tick whenever nothing else can happen, in `Engine::step` as in
    /// `Engine::run_until`: time passes as a real clock's would by itself. Default false.
    fn is_virtual(&self) -> bool {
        false
    }
}

/// Time that passes only when told: tests and simulations run as fast as the machine
/// goes, and deterministically. The engine jumps it to the next tick when nothing else is
/// left to do; a codel may hold a clone and [`VirtualClock::advance`] it to act out a
/// slow computation (an overrun).
#[cfg(target_has_atomic = "64")]
#[derive(Clone, Debug, Default)]
pub struct VirtualClock {
    now: alloc::sync::Arc<core::sync::atomic::AtomicU64>,
}

#[cfg(target_has_atomic = "64")]
impl VirtualClock {
    pub fn new() -> VirtualClock {
        VirtualClock::default()
    }

    /// Moves time forward by `us`.
    pub fn advance(&self, us: u64) {
        self.now.fetch_add(us, core::sync::atomic::Ordering::SeqCst);
    }
}

#[cfg(target_has_atomic = "64")]
impl Clock for VirtualClock {
    fn now_us(&self) -> u64 {
        self.now.load(core::sync::atomic::Ordering::SeqCst)
    }

    fn sleep_until(&self, t_us: u64) {
        self.now
            .fetch_max(t_us, core::sync::atomic::Ordering::SeqCst);
    }

    fn is_virtual(&self) -> bool {
        true
    }
}

/// Wall-clock time (`std::time::Instant`).
#[cfg(feature = "std")]
#[derive(Clone, Copy, Debug)]
pub struct RealClock {
    start: std::time::Instant,
}

#[cfg(feature = "std")]
impl RealClock {
    pub fn new() -> RealClock {
        RealClock {
            start: std::time::Instant::now(),
        }
    }
}

#[cfg(feature = "std")]
impl Default for RealClock {
    fn default() -> Self {
        RealClock::new()
    }
}

#[cfg(feature = "std")]
impl Clock for RealClock {
    fn now_us(&self) -> u64 {
        self.start.elapsed().as_micros() as u64
    }

    fn sleep_until(&self, t_us: u64) {
        let now = self.now_us();
        if t_us > now {
            std::thread::sleep(std::time::Duration::from_micros(t_us - now));
        }
    }
}
