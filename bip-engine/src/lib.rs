//! `bip-engine`: the runtime engine that runs the codels of a GenoM-style functional layer
//! and gates every step on the model `bip verify` checked.
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use bip_engine::{Engine, Next, RealClock, Until};
//! let system = bip_engine::load_file("robots/rover.ron")?;
//! let mut engine = Engine::builder(system)
//!     .codel(("rflex", "TrackSpeed", "track"), |ctx| {
//!         // drive the wheels...
//!         Next::Yield("pause::track")
//!     })
//!     .default_codels(bip_engine::DefaultCodels::FirstYield)
//!     .clock(RealClock::new())
//!     .build()?;
//! engine.request("rflex", "Init", ())?;
//! engine.request("rflex", "TrackSpeed", ())?;
//! engine.run_until(Until::Ticks(50))?;
//! for event in engine.events() {
//!     println!("{event}"); // "#2 rflex.TrackSpeed: started", in the model's names
//! }
//! # Ok(()) }
//! ```
//!
//! - The engine gates every step through a [`bip_model::Gate`]: the model's state and its
//!   enabled steps, kept up to date by bip-model's step relation; it commits only steps the
//!   gate lists, so its run is a path of the model ([`Engine::record`] writes it as a
//!   trace).
//! - A codel ([`Ctx`] → [`Next`]) returns a yield or an exception; a panic, an undeclared
//!   yield, an ids value out of range take the codel's error path (the model's `_fail`
//!   step) and are reported ([`Event::Fault`]).
//! - Requests are served when the functional layer is quiescent; the reply says whether
//!   the model accepted them and, later, how the activity ended.
//!
//! - [`Engine::inspect`] is the read-only view: state, names, counters, the state cache's
//!   figures, held codels. [`replay`] and [`simulate`] are `bip replay` and `bip simulate`.
//!
//! - bip-engine re-exports what an embedder needs: [`load_file`] and [`load_str`]
//!   (bip-lang's loader, with the `std` feature), and [`bip_model`] with [`System`],
//!   [`State`] and [`Trace`]: one dependency suffices.
//!
//! docs/engine.md is the user's guide (embedding, binding, time, threads, faults, replies,
//! recording, replay).
//!
//! # Features
//! `std` (default): task threads, [`RealClock`], catching codel panics, [`Handle`] for
//! requests from other threads. Without it the engine is `no_std` + `alloc`.

#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod prelude {
    #[allow(unused_imports)]
    pub(crate) use alloc::{
        borrow::ToOwned,
        boxed::Box,
        format,
        string::{String, ToString},
        vec,
        vec::Vec,
    };
}

mod bind;
mod bounded;
mod budgets;
mod chosen;
mod clock;
mod codel;
mod engine;
mod error;
mod event;
#[cfg(feature = "std")]
mod handle;
mod hosted;
mod per_state;
mod policy;
mod ports;
mod record;
pub mod replay;
mod signature;
pub mod simulate;
#[cfg(feature = "std")]
mod threads;
mod types;

/// Loading a model file into a [`System`] (bip-lang), with errors in the file's terms.
#[cfg(feature = "std")]
pub use bip_lang::{load_file, load_str, LoadError};
/// The compiled model and its step relation (bip-model), which the engine's API hands
/// out: an embedder depends on bip-engine alone.
pub use bip_model;
pub use bip_model::{CacheStats, State, System, Trace};
pub use bounded::{Bounded, OutOfRange};
pub use budgets::{CodelTime, CodelTimes, BUCKETS as CODEL_TIME_BUCKETS};
pub use clock::Clock;
#[cfg(feature = "std")]
pub use clock::RealClock;
#[cfg(target_has_atomic = "64")]
pub use clock::VirtualClock;
pub use codel::{Args, CodelFn, Ctx, DefaultCodels, ModuleFn, Next};
pub use engine::{Engine, EngineBuilder, Inspect, Stats, Stepped, Until, DEFAULT_STATE_CACHE};
pub use error::{BuildError, EngineError, RequestError};
pub use event::{
    Codel, CodelId, Event, EventFn, Fault, FaultKind, Outcome, Output, Reasons, Refusal, Reply,
    Service, ServiceId, Ticket,
};
#[cfg(feature = "std")]
pub use handle::{Handle, PendingReply};
pub use hosted::{HostedEnd, HostedModule, HostedRun};
pub use policy::Policy;
pub use record::Window;
pub use signature::{CodelSignature, ModuleTypes, ServiceTypes, Typed};
