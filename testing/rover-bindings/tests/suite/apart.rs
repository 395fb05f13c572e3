//! `models/apart.ron`'s bindings: its async codel `Grab.grab` is given by the module
//! object once, runs on a thread of its own, and blocks there (on a channel the test
//! holds) while the same object runs `Tune` period after period; released, its start,
//! return and outcome come in order, and the recording replays.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::time::Duration;

use bip_engine::{Bounded, Engine, Event, Ticket};
use bip_rover_bindings::apart::{self, cam, drv};

/// Module `cam`'s codels: the grab's ends of the test's channels, and Tune's count.
struct Cam {
    grab: Option<(Sender<()>, Receiver<()>)>,
    tunes: Arc<AtomicU32>,
}

impl cam::Codels for Cam {
    fn grab_start(&mut self, _: cam::GrabStartCtx<'_, '_>) -> cam::GrabStart {
        cam::GrabStart::Grab
    }

    fn grab_grab(
        &mut self,
    ) -> impl FnMut(cam::GrabGrabCtx<'_, '_>) -> cam::GrabGrab + Send + 'static {
        let (started, release) = self.grab.take().expect("given once");
        move |mut ctx| {
            let _ = started.send(());
            if release.recv().is_err() {
                return cam::GrabGrab::EDriver;
            }
            ctx.set_ids_frames(Bounded::of::<2>());
            ctx.write_image(Bounded::of::<7>());
            cam::GrabGrab::Ether
        }
    }

    fn tune_start(&mut self, _: cam::TuneStartCtx<'_, '_>) -> cam::TuneStart {
        self.tunes.fetch_add(1, Ordering::SeqCst);
        cam::TuneStart::PauseStart
    }
}

/// Module `drv`, whose one codel is async.
struct Drv;

impl drv::Codels for Drv {
    fn wait_start(
        &mut self,
    ) -> impl FnMut(drv::WaitStartCtx<'_, '_>) -> drv::WaitStart + Send + 'static {
        |_| drv::WaitStart::Ether
    }
}

fn system() -> bip_engine::System {
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/models/apart.ron");
    bip_engine::load_file(model).unwrap_or_else(|e| panic!("{e:?}"))
}

/// Takes `steps` steps on another thread, and gives the engine back with its events: a
/// failure, not a hang, if a step waits for the async codel.
fn steps(mut engine: Engine, steps: usize) -> (Engine, Vec<Event>) {
    let (back, got) = channel();
    std::thread::spawn(move || {
        let mut events = Vec::new();
        for _ in 0..steps {
            engine.step().expect("steps");
            events.extend(engine.events());
        }
        let _ = back.send((engine, events));
    });
    got.recv_timeout(Duration::from_secs(30))
        .expect("the engine's steps waited for the async codel")
}

fn step_names(engine: &Engine) -> Vec<String> {
    engine.record().steps.into_iter().map(|s| s.step).collect()
}

/// Steps until the grab `ticket` ends, as its typed ticket reads it.
fn until_grab_ends(engine: &mut Engine, ticket: cam::GrabTicket) -> cam::GrabEnd {
    let t: Ticket = ticket.0;
    for _ in 0..20_000 {
        engine.step().expect("steps");
        let end = engine.events().find_map(|e| match e {
            Event::Reply {
                ticket: got, reply, ..
            } if got == t => ticket.end(got, &reply),
            _ => None,
        });
        if let Some(end) = end {
            return end;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("the grab never ended");
}

#[test]
fn the_async_codel_blocks_apart_while_its_module_object_runs_another_codel() {
    let system = system();
    let (started_tx, started) = channel();
    let (release, release_rx) = channel();
    let tunes = Arc::new(AtomicU32::new(0));
    let codels = Cam {
        grab: Some((started_tx, release_rx)),
        tunes: tunes.clone(),
    };
    let builder = Engine::builder(system.clone()).record(100_000);
    let mut engine = apart::bind(builder, codels, Drv).build().expect("builds");
    let grab = cam::request_grab(&mut engine).expect("queued");
    cam::request_tune(&mut engine).expect("queued");
    drv::request_wait(&mut engine).expect("queued");
    let (mut engine, events) = steps(engine, 300);
    started
        .recv_timeout(Duration::from_secs(10))
        .expect("the grab started");
    let during = tunes.load(Ordering::SeqCst);
    assert!(during >= 50, "Tune ran {during} times beside the grab");
    assert!(
        !events.iter().any(|e| matches!(e, Event::Held { .. })),
        "{events:?}"
    );
    assert_eq!(engine.inspect().ids("cam", "frames"), Some(0));
    let names = step_names(&engine);
    assert!(
        names.iter().any(|n| n == "cam_Grab_grab_start"),
        "{names:?}"
    );
    assert!(
        !names.iter().any(|n| n == "cam_Grab_grab_return"),
        "{names:?}"
    );

    release.send(()).expect("released");
    let end = until_grab_ends(&mut engine, grab);
    assert!(matches!(end, cam::GrabEnd::Done), "{end:?}");
    assert_eq!(engine.inspect().ids("cam", "frames"), Some(2));
    assert_eq!(engine.inspect().port::<i64>("cam", "image"), Some(&7));
    let names = step_names(&engine);
    let at = |name: &str| names.iter().position(|n| n == name);
    let (Some(start), Some(ret), Some(outcome)) = (
        at("cam_Grab_grab_start"),
        at("cam_Grab_grab_return"),
        at("cam_Grab_grab"),
    ) else {
        panic!("steps missing: {names:?}");
    };
    assert!(start < ret && ret < outcome, "{names:?}");
    let tuned = names[start..ret]
        .iter()
        .filter(|n| n.as_str() == "cam_Tune_start")
        .count();
    assert!(
        tuned >= 50,
        "Tune ran {tuned} times between start and return"
    );
    assert_eq!(engine.inspect().stats().faults, 0);

    // the recording is a path of the model, step by step, and the engine replays it
    let trace = engine.record();
    let path = trace.replay(&system).expect("a path of the model");
    assert_eq!(path.len(), trace.steps.len());
    let replay = bip_engine::replay::replay(system, &trace).expect("builds");
    assert!(
        replay.refused.is_none(),
        "{:?}",
        replay.refused.map(|r| r.step)
    );
    assert_eq!(replay.steps.len(), trace.steps.len());
}
