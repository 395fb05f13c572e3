//! Connected ports (docs/model.md, "Connections"): a codel reads an in port and gets the
//! data the out port connected to it holds, which the model's freshness of that in port
//! follows.

use std::sync::{Arc, Mutex};

use crate::common;

use bip_engine::{DefaultCodels, Engine, Event, Next, Until};
use common::*;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Frame {
    x: f64,
    v: f64,
}

#[test]
fn an_in_port_reads_the_data_of_the_out_port_it_is_connected_to() {
    let written = Arc::new(Mutex::new(Vec::new()));
    let read = Arc::new(Mutex::new(Vec::new()));
    let (w, r) = (written.clone(), read.clone());
    let mut e = Engine::builder(load("tests/connections.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .codel(("estimator", "filter", "predict"), move |ctx| {
            let tick = ctx.tick() as f64;
            ctx.write_port("frame", Frame { x: tick, v: 1.0 });
            w.lock().expect("lock").push(tick);
            Next::Yield("pause::predict")
        })
        .codel(("controller", "Servo", "control"), move |ctx| {
            let seen = ctx.port::<Frame>("controller", "state").copied();
            r.lock().expect("lock").push(seen);
            Next::Yield("pause::control")
        })
        .build()
        .expect("builds");
    e.request("controller", "Servo", ()).expect("queued");
    e.run_until(Until::Ticks(20)).expect("runs");
    let faults: Vec<String> = e
        .events()
        .filter_map(|ev| match ev {
            Event::Fault(f) => Some(f.to_string()),
            _ => None,
        })
        .collect();
    assert_eq!(faults, Vec::<String>::new());
    let written = written.lock().expect("lock").clone();
    let read = read.lock().expect("lock").clone();
    assert!(read.len() >= 5, "the controller ran: {read:?}");
    // every run saw a frame, the estimator's last one: the controller's codels are held
    // until the first frame (its `Fresh` constraint names the in port)
    for seen in &read {
        let frame = seen.expect("a frame under the in port's name");
        assert!(written.contains(&frame.x), "{frame:?} not in {written:?}");
        assert_eq!(frame.v, 1.0);
    }
    assert!(
        read.windows(2)
            .all(|p| p[0].map(|f| f.x) <= p[1].map(|f| f.x)),
        "{read:?}"
    );
    // and reading the in port from outside is reading the out port
    assert_eq!(
        e.inspect().port::<Frame>("controller", "state"),
        e.inspect().port::<Frame>("estimator", "frame")
    );
    assert!(e.inspect().port::<Frame>("controller", "state").is_some());
}
