//! counter.gen's C codels on the engine: each outcome a codel returns, declared or not;
//! the ids' layout on both sides; random outcomes whose recordings replay.

mod apart;
mod at_request;
mod compiles;
mod layout;
mod missing;
mod multiple;
mod outcomes;
mod owned;
mod property;
mod tools;
mod unconnected;

use std::sync::{Arc, Mutex};

use bip_c_codels::counter::{self, Component};
use bip_engine::{Engine, Policy, System};

pub(crate) fn system() -> System {
    bip_engine::load_file(concat!(env!("CARGO_MANIFEST_DIR"), "/counter.ron")).expect("loads")
}

/// An engine running counter's C codels, recording its steps.
/// The module object, shared with the test.
pub(crate) type Counter = Arc<Mutex<Component>>;

pub(crate) fn engine(system: &System, seed: u64) -> (Engine, Counter) {
    let builder = Engine::builder(system.clone())
        .policy(Policy::Seeded(seed))
        .record(4096);
    let (builder, counter) = counter::bind_shared(builder);
    (builder.build().expect("builds"), counter)
}
