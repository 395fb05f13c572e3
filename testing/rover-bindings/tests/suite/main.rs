//! robots/rover.ron's generated bindings from the outside: the rover run through them,
//! random codels and requests through them under the step relation, and what must not
//! compile; and `models/typed.ron`'s, for the types the rover does not use.

mod alloc;
mod apart;
mod compile_fail;
mod property;
mod rover;
mod typed;

use bip_engine::{Engine, Event, Reply, System, Ticket, Until};

/// How a request ended, once the engine ran `ticks` more: the first reply its typed
/// ticket reads as its end (`|t, r| ticket.end(t, r)`).
pub(crate) fn end_of<E>(
    engine: &mut Engine,
    ticks: u64,
    end: impl Fn(Ticket, &Reply) -> Option<E>,
) -> Option<E> {
    engine.run_until(Until::Ticks(ticks)).expect("runs");
    engine.events().find_map(|ev| match ev {
        Event::Reply { ticket, reply, .. } => end(ticket, &reply),
        _ => None,
    })
}

/// No codel was faulty, and the recorded run is a path of `system`: its steps, replayed.
pub(crate) fn assert_clean_path(engine: &mut Engine, system: &System) -> usize {
    assert_eq!(engine.inspect().stats().faults, 0);
    let steps = engine.record().replay(system).expect("a path of the model");
    steps.len()
}
