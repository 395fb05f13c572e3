//! Each step is a `tracing` event. Alone in its test binary: tracing caches each
//! callsite's interest process-wide, so a test running the engine on another thread
//! without a subscriber could make these events look disabled to this test's
//! thread-local subscriber.

#[path = "suite/common/mod.rs"]
mod common;

use bip_engine::*;
use common::*;

fn rover() -> EngineBuilder {
    Engine::builder(load("rover.ron"))
        .default_codels(DefaultCodels::FirstYield)
        .record(10_000)
}

#[test]
fn each_step_is_a_tracing_event() {
    use std::io::Write;
    use std::sync::{Arc, Mutex};
    #[derive(Clone)]
    struct Buf(Arc<Mutex<Vec<u8>>>);
    impl Write for Buf {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.0.lock().expect("lock").extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }
    let buf = Buf(Arc::new(Mutex::new(Vec::new())));
    let writer = buf.clone();
    let subscriber = tracing_subscriber::fmt()
        .with_max_level(tracing::Level::DEBUG)
        .with_ansi(false)
        .with_writer(move || writer.clone())
        .finish();
    tracing::subscriber::with_default(subscriber, || {
        let mut e = rover().build().expect("builds");
        e.request("rflex", "Init", ()).expect("queued");
        e.request("rflex", "TrackSpeed", ()).expect("queued");
        e.run_until(Until::Ticks(3)).expect("runs");
    });
    let text = String::from_utf8(buf.0.lock().expect("lock").clone()).expect("utf-8");
    let codel_line = text
        .lines()
        .find(|l| l.contains("rflex_TrackSpeed_track"))
        .unwrap_or_else(|| panic!("{text}"));
    for field in [
        "module=\"rflex\"",
        "service=\"TrackSpeed\"",
        "codel=\"track\"",
        "yield=\"pause::track\"",
        "time_us=",
    ] {
        assert!(codel_line.contains(field), "{field} in {codel_line}");
    }
    assert!(text.lines().any(|l| l.contains("step=\"tick\"")), "{text}");
}
