//! apart.gen's C codels through the generated glue: the async `Grab.grab` waits (for a
//! flag the test holds) on a thread of its own while the same component runs `Tune`,
//! period after period; released, its start, return and outcome come in order, what it
//! wrote reaches the component's memory and the engine, and the recording replays.

use std::time::Duration;

use bip_c_codels::apart_glue::apart;
use bip_c_codels::hooks;
use bip_engine::{Engine, Event, Outcome, Reply};

fn system() -> bip_engine::System {
    bip_engine::load_file(concat!(env!("CARGO_MANIFEST_DIR"), "/apart.ron")).expect("loads")
}

/// Takes `steps` steps on another thread, and gives the engine back: a failure, not a
/// hang, if a step waits for the async codel.
fn steps(mut engine: Engine, steps: usize) -> Engine {
    let (back, got) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for _ in 0..steps {
            engine.step().expect("steps");
        }
        let _ = back.send(engine);
    });
    got.recv_timeout(Duration::from_secs(30))
        .expect("the engine's steps waited for the async codel")
}

fn step_names(engine: &Engine) -> Vec<String> {
    engine.record().steps.into_iter().map(|s| s.step).collect()
}

#[test]
fn the_async_c_codel_waits_apart_while_its_component_runs_another_codel() {
    let system = system();
    let builder = Engine::builder(system.clone()).record(100_000);
    let (builder, component) = apart::bind_shared(builder);
    let mut engine = builder.build().expect("builds");
    let grab = engine.request("apart", "Grab", ()).expect("queued");
    engine.request("apart", "Tune", ()).expect("queued");
    let mut engine = steps(engine, 300);
    for _ in 0..1000 {
        if hooks::apart_started() {
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(hooks::apart_started(), "the grab began");
    let tunes = component.lock().expect("lock").state.ids.tunes;
    assert!(tunes >= 50, "Tune ran {tunes} times beside the grab");
    assert_eq!(component.lock().expect("lock").state.ids.frames, 0);
    let names = step_names(&engine);
    assert!(
        names.iter().any(|n| n == "apart_Grab_grab_start"),
        "{names:?}"
    );
    assert!(
        !names.iter().any(|n| n == "apart_Grab_grab_return"),
        "{names:?}"
    );

    hooks::apart_release();
    let mut end = None;
    for _ in 0..20_000 {
        engine.step().expect("steps");
        end = engine.events().find_map(|e| match e {
            Event::Reply {
                ticket,
                reply: Reply::Done { outcome, .. },
                ..
            } if ticket == grab => Some(outcome),
            _ => None,
        });
        if end.is_some() {
            break;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    assert_eq!(end, Some(Outcome::Ether));
    assert_eq!(engine.inspect().stats().faults, 0);
    // the grab's writes: the local and the ids member, which `publish` read, and the port
    assert_eq!(hooks::apart_published(), 41 * 100 + 2);
    assert_eq!(component.lock().expect("lock").state.ids.frames, 2);
    assert!(component.lock().expect("lock").state.ids.tunes > tunes);
    assert_eq!(engine.inspect().port::<i64>("apart", "image"), Some(&7));
    let names = step_names(&engine);
    let at = |name: &str| names.iter().position(|n| n == name);
    let (Some(start), Some(ret), Some(outcome)) = (
        at("apart_Grab_grab_start"),
        at("apart_Grab_grab_return"),
        at("apart_Grab_grab"),
    ) else {
        panic!("steps missing: {names:?}");
    };
    assert!(start < ret && ret < outcome, "{names:?}");
    let tuned = names[start..ret]
        .iter()
        .filter(|n| n.as_str() == "apart_Tune_start")
        .count();
    assert!(
        tuned >= 50,
        "Tune ran {tuned} times between start and return"
    );

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
