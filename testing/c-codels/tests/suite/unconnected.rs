//! Reading an in port the model connects to nothing (camera.gen's `reference`): GenoM3's
//! failed read, the handle's `read` returning an exception (`genom_syserr`, errno
//! ENOTCONN, its detail kept by the context) for the codel to handle, where the engine's
//! own reading of such a port would be a fault.

use bip_engine::Outcome;

use crate::owned::{engine, reply, system};

#[test]
fn reading_an_in_port_connected_to_nothing_is_a_failed_read() {
    let system = system();
    let (mut engine, shared) = engine(&system);
    let ticket = engine.request("camera", "Compare", ()).expect("a request");
    let (outcome, _) = reply(&mut engine, ticket);
    // the codel saw genom_syserr with ENOTCONN, and threw its own exception with it
    assert_eq!(outcome, Outcome::Exception("e_noref".into()));
    assert_eq!(engine.inspect().stats().faults, 0);
    let (_, detail) = shared
        .lock()
        .expect("unpoisoned")
        .raised()
        .last()
        .expect("raised");
    let code = i32::from_ne_bytes(detail[..4].try_into().expect("a long"));
    let kind = std::io::Error::from_raw_os_error(code).kind();
    assert_eq!(kind, std::io::ErrorKind::NotConnected, "errno {code}");
    engine
        .record()
        .replay(&system)
        .expect("a path of the model");
}
