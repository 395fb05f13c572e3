//! Task threads under load: every task's codels run on a thread of their own and do real
//! work, clients on other threads send requests through handles, the clock is real; the
//! recorded trace is a path of the model and keeps its invariants. Bounded in time (about
//! half a second).

#[path = "suite/common/mod.rs"]
mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use bip_engine::*;
use common::*;

fn spin(us: u64) {
    let t = Instant::now();
    while t.elapsed() < Duration::from_micros(us) {
        std::hint::spin_loop();
    }
}

#[test]
fn task_threads_under_load_record_a_valid_trace() {
    let system = load("rover.ron");
    let seen: Arc<Mutex<BTreeMap<String, BTreeSet<String>>>> = Arc::default();
    let mut b = Engine::builder(system.clone())
        .threads(true)
        .clock(RealClock::new())
        .tick_us(2_000)
        .record(100_000);
    let map = system.genom.clone().expect("a GenoM layer");
    let mut tasks = BTreeSet::new();
    for m in &map.modules {
        for s in &m.services {
            let Some(task) = s.task.map(|k| m.tasks[k].name.clone()) else {
                continue;
            };
            tasks.insert(format!("{}.{task}", m.name));
            for c in &s.codels {
                let key = format!("{}.{task}", m.name);
                let yields: Vec<&'static str> = c.yields.iter().map(|y| leak(&y.target)).collect();
                let seen = seen.clone();
                let mut k = 0usize;
                b = b.codel((&m.name, &s.name, &c.state), move |_| {
                    spin(150);
                    let me = std::thread::current().name().unwrap_or("?").to_string();
                    seen.lock()
                        .expect("lock")
                        .entry(key.clone())
                        .or_default()
                        .insert(me);
                    k += 1;
                    // mostly go on, sometimes end
                    Next::Yield(
                        yields[if k.is_multiple_of(7) {
                            yields.len() - 1
                        } else {
                            0
                        }],
                    )
                });
            }
        }
    }
    let mut engine = b.build().expect("builds");
    let start = Instant::now();
    let clients: Vec<_> = (0..3)
        .map(|n| {
            let h = engine.handle();
            let services: Vec<(String, String)> = map
                .modules
                .iter()
                .flat_map(|m| {
                    m.services
                        .iter()
                        .map(move |s| (m.name.clone(), s.name.clone()))
                })
                .collect();
            std::thread::spawn(move || {
                let mut accepted = 0;
                let mut k = n * 5;
                let mut pending = Vec::new();
                while start.elapsed() < Duration::from_millis(300) {
                    let (m, s) = &services[k % services.len()];
                    k += 1;
                    pending.push(h.request(m, s, ()).expect("a known service"));
                    std::thread::sleep(Duration::from_millis(3));
                    for p in &pending {
                        while let Some((_, r)) = p.try_next() {
                            if r == Reply::Accepted {
                                accepted += 1;
                            }
                        }
                    }
                }
                accepted
            })
        })
        .collect();
    engine.run_until(Until::TimeUs(400_000)).expect("runs");
    let accepted: usize = clients.into_iter().map(|c| c.join().expect("client")).sum();
    assert!(accepted > 10, "only {accepted} requests accepted");
    let stats = engine.inspect().stats();
    assert!(stats.codels > 50 && stats.ticks > 50, "{stats:?}");
    // each task's codels ran on that task's thread only
    let seen = seen.lock().expect("lock");
    assert!(seen.len() >= 5, "{seen:?}");
    for (task, threads) in seen.iter() {
        assert!(tasks.contains(task));
        assert_eq!(threads.iter().collect::<Vec<_>>(), [task], "{task}");
    }
    let trace = engine.record();
    let states = states_of(&system, &trace);
    assert_eq!(states.last(), Some(engine.inspect().state()));
    assert_invariants(&system, &states);
}
