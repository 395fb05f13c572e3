//! A timed model through the API: the time and each task's job in the view, the time step
//! named by how far it goes, and the values they take as steps fire, checked against the
//! model (the deadline invariants, the steps' advances) along random walks.

use serde_json::{json, Value};

use super::api::handle;
use super::session::Session;

fn timed_session() -> Session {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/robots/tests/timed.ron");
    Session::new(bip_lang::load_file(std::path::Path::new(path)).expect("loads"))
}

fn call(s: &mut Session, method: &str, path: &str, body: Value) -> Value {
    let r = handle(s, method, path, body.to_string().as_bytes());
    assert_eq!(r.status, 200, "{method} {path} {body}: {}", r.body);
    serde_json::from_str(&r.body).expect("JSON")
}

fn fire(s: &mut Session, step: &str) -> Value {
    call(s, "POST", "/api/fire", json!({ "step": step }))
}

/// The enabled time step of `view`.
fn time_step(view: &Value) -> Value {
    let steps = view["enabled"].as_array().expect("enabled steps");
    let mut time = steps.iter().filter(|e| e["time"] == true);
    let step = time
        .next()
        .unwrap_or_else(|| panic!("no time step: {view}"));
    assert!(time.next().is_none(), "one time step: {view}");
    step.clone()
}

fn task<'v>(view: &'v Value, name: &str) -> &'v Value {
    view["timing"]["tasks"]
        .as_array()
        .expect("tasks")
        .iter()
        .find(|t| t["name"] == name)
        .unwrap_or_else(|| panic!("no task {name}: {view}"))
}

fn units(v: &Value) -> u64 {
    v["units"]
        .as_u64()
        .unwrap_or_else(|| panic!("not a duration: {v}"))
}

/// The enabled step of `view` whose label starts with `label`, if any.
fn enabled<'v>(view: &'v Value, label: &str) -> Option<&'v Value> {
    view["enabled"]
        .as_array()
        .expect("enabled steps")
        .iter()
        .find(|e| e["label"].as_str().is_some_and(|l| l.starts_with(label)))
}

#[test]
fn a_timed_model_shows_the_time_and_each_tasks_job_as_steps_fire() {
    let mut s = timed_session();
    let view = call(&mut s, "GET", "/api/state", json!({}));
    let timing = &view["timing"];
    assert_eq!(timing["unit"], "500 µs", "{timing}");
    assert_eq!(timing["now"], json!({"units": 0, "time": "0"}));
    // control every 4 ms, plan and log every 8 ms: the clock counts modulo 8 ms
    assert_eq!(timing["cycle"], json!({"units": 16, "time": "8 ms"}));
    let names: Vec<&str> = timing["tasks"]
        .as_array()
        .expect("tasks")
        .iter()
        .map(|t| t["name"].as_str().expect("a name"))
        .collect();
    assert_eq!(names, ["nav.control", "nav.plan", "nav.log"]);
    for name in names {
        let t = task(&view, name);
        assert_eq!(
            (&t["stage"], &t["codel"], &t["job"]),
            (&json!("idle"), &Value::Null, &Value::Null),
            "{t}"
        );
        assert_eq!(t["late"], false);
    }
    // the task atoms are shown as tasks, not as the expansion's components
    let groups: Vec<&Value> = view["state"].as_array().expect("groups").iter().collect();
    assert!(groups.iter().all(|g| g["name"] == "nav"), "{groups:?}");

    // time passes to the first instant at which something may happen
    let tick = time_step(&view);
    let advance = units(&tick["advance"]);
    assert!(advance >= 1, "{tick}");
    assert_eq!(
        tick["label"],
        format!(
            "time passes {}: 0 → {}",
            tick["advance"]["time"].as_str().unwrap(),
            tick["advance"]["time"].as_str().unwrap()
        )
    );
    assert_eq!(tick["interaction"], "tick");
    let view = call(&mut s, "POST", "/api/fire", json!({"index": tick["index"]}));
    assert_eq!(units(&view["timing"]["now"]), advance);
    assert_eq!(units(&view["timing"]["since_start"]), advance);
    assert_eq!(view["steps"][0], tick["label"]);

    // releases and time steps until control's job is released
    let mut view = view;
    for _ in 0..20 {
        if task(&view, "nav.control")["stage"] == "ready" {
            break;
        }
        view = if let Some(release) = enabled(&view, "release") {
            // named by the tasks whose period boundary it is
            let label = release["label"].as_str().unwrap();
            assert!(
                [
                    "release nav.control",
                    "release nav.plan",
                    "release nav.control, nav.log"
                ]
                .contains(&label),
                "{label}"
            );
            fire(&mut s, label)
        } else {
            fire(&mut s, time_step(&view)["label"].as_str().unwrap())
        };
    }
    let control = task(&view, "nav.control");
    assert_eq!(control["stage"], "ready", "{view}");
    assert_eq!(units(&control["job"]["elapsed"]), 0);
    assert_eq!(control["job"]["deadline"], "3 ms");

    // the dispatch gives it a core; its first codel starts and runs while time passes
    let view = fire(&mut s, "dispatch nav.control");
    let control = task(&view, "nav.control");
    assert_eq!(
        (&control["stage"], &control["codel"]),
        (&json!("running"), &Value::Null),
        "{control}"
    );
    let view = fire(&mut s, "nav.control: start starts");
    let control = task(&view, "nav.control").clone();
    assert_eq!(control["codel"]["name"], "control.start", "{control}");
    assert_eq!(units(&control["codel"]["elapsed"]), 0);
    assert_eq!(control["codel"]["wcet"], "1 ms");
    let (now, since_start) = (
        units(&view["timing"]["now"]),
        units(&view["timing"]["since_start"]),
    );
    let tick = time_step(&view);
    let advance = units(&tick["advance"]);
    let after = call(&mut s, "POST", "/api/fire", json!({"index": tick["index"]}));
    let ran = task(&after, "nav.control");
    assert_eq!(units(&ran["codel"]["elapsed"]), advance, "{ran}");
    assert_eq!(
        units(&ran["job"]["elapsed"]),
        units(&control["job"]["elapsed"]) + advance
    );
    assert_eq!(units(&after["timing"]["now"]), (now + advance) % 16);
    assert_eq!(
        units(&after["timing"]["since_start"]),
        since_start + advance
    );

    // back: the state before, its time and tasks as they were
    let back = call(&mut s, "POST", "/api/back", json!({}));
    assert_eq!(back["timing"], view["timing"]);
}

#[test]
fn an_untimed_model_shows_no_timing() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/robots/served.ron");
    let mut s = Session::new(bip_lang::load_file(std::path::Path::new(path)).expect("loads"));
    let view = call(&mut s, "GET", "/api/state", json!({}));
    assert_eq!(view["timing"], Value::Null);
    let tick = time_step(&view);
    assert_eq!(tick["label"], "tick");
    assert!(tick.get("advance").is_none(), "{tick}");
    let view = fire(&mut s, "tick");
    assert_eq!(view["steps"], json!(["tick"]));
    assert_eq!(view["timing"], Value::Null);
}

/// A model that misses deadlines: `hi` holds the only core 3 ms of every 4 ms, so `lo`,
/// which needs 4 ms every 8 ms, finishes past its deadline and past its period's
/// boundary (or, once it holds the core, makes `hi` miss). `Preemptive`: `hi` takes the
/// core from `lo`'s codel when it is released.
fn missing(preemption: &str) -> Session {
    let text = format!(
        r#"System(name: "missing", tick_ms: 2, time: Exact,
    cpus: [(name: "main", preemption: {preemption})],
    modules: [(name: "m", tasks: [
        (name: "hi", period: 2, priority: 2, codels: [
            (state: "start", yields: ["pause::start"], bcet: "3ms", wcet: "3ms")]),
        (name: "lo", period: 4, priority: 1, deadline: "6ms", codels: [
            (state: "start", yields: ["pause::start"], bcet: "4ms", wcet: "4ms")])])])"#
    );
    Session::new(bip_lang::load_str("missing.ron", &text).expect("loads"))
}

/// What a walk saw: each task's stages, a late job, a deadline passed.
#[derive(Default)]
struct Seen {
    stages: std::collections::BTreeSet<String>,
    late: bool,
    past_deadline: bool,
    starts: usize,
}

/// Random walks from the initial state (a fixed seed), checking every view against the
/// model: a job past its deadline exactly where its deadline invariant fails; a time step
/// moves the clock, every job's elapsed time and every running codel's by its advance;
/// a codel's start shows that codel running.
fn walk(s: &mut Session, seen: &mut Seen) {
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut random = move |n: usize| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % n as u64) as usize
    };
    for _ in 0..12 {
        let mut view = call(s, "POST", "/api/replay", json!({"history": []}));
        for _ in 0..30 {
            check_deadlines(&view, seen);
            let steps = view["enabled"].as_array().expect("enabled steps").clone();
            if steps.is_empty() {
                break;
            }
            let step = &steps[random(steps.len())];
            let after = call(s, "POST", "/api/fire", json!({"index": step["index"]}));
            check_step(&view, step, &after, seen);
            view = after;
        }
    }
}

fn check_deadlines(view: &Value, seen: &mut Seen) {
    for t in view["timing"]["tasks"].as_array().expect("tasks") {
        let name = t["name"].as_str().expect("a name");
        let invariant = view["properties"]
            .as_array()
            .expect("properties")
            .iter()
            .find(|p| {
                p["name"]
                    .as_str()
                    .is_some_and(|n| n.starts_with(&format!("{name} meets its ")))
            })
            .unwrap_or_else(|| panic!("no deadline invariant of {name}"));
        let past = t["job"]["past_deadline"] == true;
        assert_eq!(past, invariant["status"] == "fails", "{t} {invariant}");
        assert_eq!(t["job"].is_null(), t["stage"] == "idle", "{t}");
        seen.stages
            .insert(format!("{name} {}", t["stage"].as_str().expect("a stage")));
        seen.late |= t["late"] == true;
        seen.past_deadline |= past;
    }
}

fn check_step(before: &Value, step: &Value, after: &Value, seen: &mut Seen) {
    let tasks = |v: &Value| v["timing"]["tasks"].as_array().expect("tasks").clone();
    if step["time"] == true {
        let advance = units(&step["advance"]);
        let cycle = units(&before["timing"]["cycle"]);
        assert_eq!(
            units(&after["timing"]["now"]),
            (units(&before["timing"]["now"]) + advance) % cycle
        );
        assert_eq!(
            units(&after["timing"]["since_start"]),
            units(&before["timing"]["since_start"]) + advance
        );
        for (b, a) in tasks(before).iter().zip(&tasks(after)) {
            assert_eq!(a["stage"], b["stage"], "time changes no stage: {b} {a}");
            if !b["job"].is_null() {
                assert_eq!(
                    units(&a["job"]["elapsed"]),
                    units(&b["job"]["elapsed"]) + advance,
                    "{b} {a}"
                );
            }
            if !b["codel"].is_null() {
                // a preempted codel waits
                let grows = if b["stage"] == "running" { advance } else { 0 };
                assert_eq!(
                    units(&a["codel"]["elapsed"]),
                    units(&b["codel"]["elapsed"]) + grows,
                    "{b} {a}"
                );
            }
        }
    }
    // a codel that starts is the one its start step names: `m_S_s_start` starts codel
    // `S.s` of module `m`
    let interaction = step["interaction"].as_str().expect("an interaction");
    for (b, a) in tasks(before).iter().zip(&tasks(after)) {
        if !b["codel"].is_null() || a["codel"].is_null() {
            continue;
        }
        let module = a["name"].as_str().unwrap().split('.').next().unwrap();
        let codel = a["codel"]["name"].as_str().unwrap().replace('.', "_");
        assert_eq!(interaction, format!("{module}_{codel}_start"), "{a}");
        assert_eq!(units(&a["codel"]["elapsed"]), 0);
        seen.starts += 1;
    }
}

#[test]
fn timing_follows_the_model_along_random_walks() {
    let mut seen = Seen::default();
    walk(&mut timed_session(), &mut seen);
    for stage in ["nav.control running", "nav.plan running", "nav.log ready"] {
        assert!(seen.stages.contains(stage), "{:?}", seen.stages);
    }
    assert!(seen.starts >= 10, "{} codels started", seen.starts);
    for preemption in ["Job", "Preemptive"] {
        let mut seen = Seen::default();
        walk(&mut missing(preemption), &mut seen);
        assert!(
            seen.late && seen.past_deadline,
            "{preemption}: {:?}",
            seen.stages
        );
        if preemption == "Preemptive" {
            assert!(seen.stages.contains("m.lo preempted"), "{:?}", seen.stages);
        }
    }
}
