//! camera.gen's multiple ports through their C handles: instances of `levels` opened,
//! written, closed by name, the engine's port holding the instance written last; the
//! instance `a` of `gains` (which reads `levels`) opened by its first read; the failed
//! calls' errnos (ENOENT for an instance not open, EINVAL for no name). The codel checks
//! each step and throws the number of the first that fails.

use std::ffi::CStr;

use bip_engine::Outcome;

use crate::owned::{engine, reply, system};

#[test]
fn a_multiple_ports_instances_are_opened_written_read_and_closed_by_name() {
    let system = system();
    let (mut engine, shared) = engine(&system);
    let ticket = engine.request("camera", "Publish", 2.5).expect("a request");
    let (outcome, _) = reply(&mut engine, ticket);
    let failed = shared
        .lock()
        .expect("unpoisoned")
        .raised()
        .last()
        .map(|(_, d)| i32::from_ne_bytes(d[..4].try_into().expect("a long")));
    assert_eq!(outcome, Outcome::Ether, "step {failed:?} failed");
    assert_eq!(engine.inspect().port::<f64>("camera", "levels"), Some(&2.5));
    let module = shared.lock().expect("unpoisoned");
    let levels: Vec<(&CStr, f64)> = module
        .state
        .port_levels
        .iter()
        .map(|(n, v)| (n, *v))
        .collect();
    assert_eq!(levels, [(c"left", 2.5)]);
    let gains: Vec<(&CStr, f64)> = module
        .state
        .port_gains
        .iter()
        .map(|(n, v)| (n, *v))
        .collect();
    assert_eq!(gains, [(c"a", 2.5)]);
    drop(module);
    engine
        .record()
        .replay(&system)
        .expect("a path of the model");
}
