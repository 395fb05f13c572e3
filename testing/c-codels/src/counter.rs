//! counter.gen's C codels bound to the engine: the `#[repr(C)]` mirror of its ids struct,
//! the `extern "C"` declarations of its codels and events (their C names, from the
//! header bip-codegen writes), and one module object that calls them.

use std::ffi::{c_char, c_int};
use std::ptr::addr_of;
use std::sync::{Arc, Mutex};

use bip_engine::{CodelSignature, Ctx, EngineBuilder, Next};

use crate::runtime::{Context, ContextIface, Events, GenomEvent, Raised};

/// `counter_ids`, generated: the layout gcc gives the header's struct (checked by the
/// tests).
pub use crate::counter_types::counter::ids as CounterIds;
/// `place`, generated: what `Go` takes, the engine's `Record(name: "place", ..)`.
pub use crate::counter_types::place as Place;

// an event's size is its name's with its NUL; only its address is used
extern "C" {
    static counter_ether: [c_char; 17];
    static counter_step: [c_char; 16];
    static counter_pause_step: [c_char; 23];
    static counter_e_limit_id: [c_char; 19];
    static counter_e_stray_id: [c_char; 19];

    fn counter_count_start(n: i32, ids: *mut CounterIds, this: *const ContextIface) -> GenomEvent;
    fn counter_count_step(n: i32, ids: *mut CounterIds, this: *const ContextIface) -> GenomEvent;
    fn counter_go(to: *const Place, at: *mut Place, this: *const ContextIface) -> GenomEvent;
    fn counter_idle_start(gain: f64, this: *const ContextIface) -> GenomEvent;

    /// The tests' choice of what `counter_count_step` returns (codels/counter.c).
    static mut counter_test_outcome: c_int;
    /// gcc's layout of `counter_ids`: 0 its size, 1 its alignment, 2.. its members'
    /// offsets.
    pub fn counter_ids_layout(what: c_int) -> usize;
}

/// The module's codels as the engine numbers them (services, then their codels), with
/// their outcomes as the model declares them: the engine checks them against the model.
pub const CODELS: &[CodelSignature] = &[
    CodelSignature {
        service: "Count",
        codel: "start",
        yields: &["step", "ether"],
        throws: &["e_limit"],
    },
    CodelSignature {
        service: "Count",
        codel: "step",
        yields: &["pause::step", "ether"],
        throws: &["e_limit"],
    },
    CodelSignature {
        service: "Go",
        codel: "start",
        yields: &["ether"],
        throws: &[],
    },
    CodelSignature {
        service: "Idle",
        codel: "start",
        yields: &["ether"],
        throws: &["e_stray"],
    },
];

fn events() -> Events {
    // only the statics' addresses are taken, which needs no `unsafe`
    Events {
        yields: vec![
            (addr_of!(counter_ether) as usize, "ether"),
            (addr_of!(counter_step) as usize, "step"),
            (addr_of!(counter_pause_step) as usize, "pause::step"),
        ],
        exceptions: vec![
            (addr_of!(counter_e_limit_id) as usize, "e_limit"),
            (addr_of!(counter_e_stray_id) as usize, "e_stray"),
        ],
    }
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

/// The module's state outside the engine: its ids and what its codels raised.
#[derive(Clone)]
pub struct Counter {
    pub ids: Arc<Mutex<CounterIds>>,
    pub raised: Arc<Raised>,
}

/// Binds module `counter`'s C codels to `builder`; returns what the test reads back.
pub fn bind(builder: EngineBuilder) -> (EngineBuilder, Counter) {
    let context = Context::default();
    let counter = Counter {
        ids: Arc::new(Mutex::new(CounterIds::default())),
        raised: context.raised(),
    };
    let ids = Arc::clone(&counter.ids);
    let events = events();
    let f = move |k: usize, ctx: &mut Ctx<'_>| -> Next {
        let Ok(mut ids) = ids.lock() else {
            return Next::Declared(u16::MAX);
        };
        let this = context.as_ptr();
        // the engine checked the argument against `Int(-2^31, 2^31 - 1)`
        let n = ctx.args::<i64>().map_or(0, |&n| n as i32);
        // SAFETY: the prototypes are the header's; `ids` and the context outlive the call
        let ev = unsafe {
            match k {
                0 => counter_count_start(n, &mut *ids, this),
                1 => counter_count_step(n, &mut *ids, this),
                2 => match ctx.args::<Place>() {
                    Some(to) => counter_go(to, &mut ids.at, this),
                    // a request always carries its place: the engine checked its type
                    None => return Next::Declared(u16::MAX),
                },
                3 => counter_idle_start(ids.gain, this),
                _ => return Next::Declared(u16::MAX),
            }
        };
        events.next(&CODELS[k], ev)
    };
    (builder.module("counter", CODELS, f), counter)
}
