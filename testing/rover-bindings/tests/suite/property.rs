//! Random runs of the rover through its generated bindings: every codel returns one of
//! its outcomes at random (its enum's `ALL`), reads and writes its typed ports, and
//! random typed requests arrive with random arguments. Every trace the engine records is
//! accepted step by step by the step relation, ends in the engine's state, keeps the
//! model's invariants, and no typed codel is ever found faulty.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use bip_engine::bip_model::{PropertyKind, Rng};
use bip_engine::{Engine, Event, Policy, Reply, RequestError, Ticket, Until};
use bip_rover_bindings::*;
use proptest::prelude::*;

use crate::rover::system;

/// Every codel of every module: a random outcome, drawn from one generator.
#[derive(Clone)]
struct Random(Arc<Mutex<Rng>>);

impl Random {
    fn pick<T: Copy>(&self, all: &[T]) -> T {
        let mut rng = self.0.lock().unwrap_or_else(|e| e.into_inner());
        all[rng.below(all.len())]
    }

    fn real(&self) -> f64 {
        let mut rng = self.0.lock().unwrap_or_else(|e| e.into_inner());
        rng.below(1000) as f64 / 100.0
    }
}

impl rflex::Codels for Random {
    fn track_speed_start(
        &mut self,
        _: rflex::TrackSpeedStartCtx<'_, '_>,
    ) -> rflex::TrackSpeedStart {
        self.pick(&rflex::TrackSpeedStart::ALL)
    }
    fn track_speed_track(
        &mut self,
        mut ctx: rflex::TrackSpeedTrackCtx<'_, '_>,
    ) -> rflex::TrackSpeedTrack {
        let speed = ctx.args().copied().unwrap_or(0.0);
        if let Some(odo) = ctx.port_odo_mut() {
            odo.x += speed;
        }
        self.pick(&rflex::TrackSpeedTrack::ALL)
    }
}

impl sick::Codels for Random {
    fn scan_start(&mut self, _: sick::ScanStartCtx<'_, '_>) -> sick::ScanStart {
        self.pick(&sick::ScanStart::ALL)
    }
    fn scan_scan(&mut self, mut ctx: sick::ScanScanCtx<'_, '_>) -> sick::ScanScan {
        ctx.write_scan(Scan {
            ranges: vec![self.real()],
        });
        self.pick(&sick::ScanScan::ALL)
    }
}

impl pom::Codels for Random {
    fn track_start(&mut self, _: pom::TrackStartCtx<'_, '_>) -> pom::TrackStart {
        self.pick(&pom::TrackStart::ALL)
    }
    fn track_fuse(&mut self, mut ctx: pom::TrackFuseCtx<'_, '_>) -> pom::TrackFuse {
        let x = ctx.read_rflex_odo().map_or(0.0, |o| o.x);
        ctx.write_pose(Pose { x });
        self.pick(&pom::TrackFuse::ALL)
    }
}

impl ndd::Codels for Random {
    fn go_to_start(&mut self, _: ndd::GoToStartCtx<'_, '_>) -> ndd::GoToStart {
        self.pick(&ndd::GoToStart::ALL)
    }
    fn go_to_move(&mut self, mut ctx: ndd::GoToMoveCtx<'_, '_>) -> ndd::GoToMove {
        let x = ctx.read_pom_pose().map_or(0.0, |p| p.x);
        ctx.set_output(x);
        self.pick(&ndd::GoToMove::ALL)
    }
    fn go_to_stop(&mut self, _: ndd::GoToStopCtx<'_, '_>) -> ndd::GoToStop {
        self.pick(&ndd::GoToStop::ALL)
    }
}

impl aspect::Codels for Random {
    fn build_start(&mut self, _: aspect::BuildStartCtx<'_, '_>) -> aspect::BuildStart {
        self.pick(&aspect::BuildStart::ALL)
    }
    fn build_fuse(&mut self, mut ctx: aspect::BuildFuseCtx<'_, '_>) -> aspect::BuildFuse {
        if let Some(dtm) = ctx.port_dtm_mut() {
            dtm.cells += 1;
        }
        self.pick(&aspect::BuildFuse::ALL)
    }
}

impl antenna::Codels for Random {
    fn communicate_start(
        &mut self,
        _: antenna::CommunicateStartCtx<'_, '_>,
    ) -> antenna::CommunicateStart {
        self.pick(&antenna::CommunicateStart::ALL)
    }
    fn communicate_send(
        &mut self,
        _: antenna::CommunicateSendCtx<'_, '_>,
    ) -> antenna::CommunicateSend {
        self.pick(&antenna::CommunicateSend::ALL)
    }
}

impl heating::Codels for Random {
    fn heat_start(&mut self, _: heating::HeatStartCtx<'_, '_>) -> heating::HeatStart {
        self.pick(&heating::HeatStart::ALL)
    }
    fn heat_heat(&mut self, _: heating::HeatHeatCtx<'_, '_>) -> heating::HeatHeat {
        self.pick(&heating::HeatHeat::ALL)
    }
}

impl camera::Codels for Random {
    fn shoot_start(&mut self, _: camera::ShootStartCtx<'_, '_>) -> camera::ShootStart {
        self.pick(&camera::ShootStart::ALL)
    }
    fn shoot_expose(&mut self, mut ctx: camera::ShootExposeCtx<'_, '_>) -> camera::ShootExpose {
        ctx.write_image(Image { shots: 1 });
        self.pick(&camera::ShootExpose::ALL)
    }
}

type Request = fn(&mut Engine, &Random) -> Result<Ticket, RequestError>;

/// Every service of the rover, requested through its typed function.
const REQUESTS: &[(&str, &str, Request)] = &[
    ("rflex", "Init", |e, _| rflex::request_init(e).map(|t| t.0)),
    ("rflex", "TrackSpeed", |e, r| {
        rflex::request_track_speed(e, r.real()).map(|t| t.0)
    }),
    ("rflex", "Stop", |e, _| rflex::request_stop(e).map(|t| t.0)),
    ("sick", "Scan", |e, _| sick::request_scan(e).map(|t| t.0)),
    ("sick", "Stop", |e, _| sick::request_stop(e).map(|t| t.0)),
    ("pom", "Track", |e, _| pom::request_track(e).map(|t| t.0)),
    ("pom", "Stop", |e, _| pom::request_stop(e).map(|t| t.0)),
    ("ndd", "GoTo", |e, r| {
        ndd::request_go_to(e, r.real()).map(|t| t.0)
    }),
    ("ndd", "Stop", |e, _| ndd::request_stop(e).map(|t| t.0)),
    ("aspect", "Build", |e, _| {
        aspect::request_build(e).map(|t| t.0)
    }),
    ("antenna", "Communicate", |e, r| {
        let packets = bip_engine::Bounded::new(r.pick(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]))
            .expect("1..=10 is Int(1, 10)");
        antenna::request_communicate(e, packets).map(|t| t.0)
    }),
    ("battery", "Report", |e, _| {
        battery::request_report(e).map(|t| t.0)
    }),
    ("heating", "Heat", |e, _| {
        heating::request_heat(e).map(|t| t.0)
    }),
    ("camera", "Shoot", |e, _| {
        camera::request_shoot(e).map(|t| t.0)
    }),
];

/// A random run of 600 steps with seed `seed`.
fn run_case(seed: u64) -> Result<(), TestCaseError> {
    let system = system();
    let random = Random(Arc::new(Mutex::new(Rng(seed))));
    let builder = Engine::builder(system.clone())
        .policy(Policy::Seeded(seed))
        .record(2000);
    let r = random.clone();
    let mut engine = bind(
        builder,
        r.clone(),
        r.clone(),
        r.clone(),
        r.clone(),
        r.clone(),
        r.clone(),
        r.clone(),
        r,
    )
    .build()
    .map_err(|e| TestCaseError::fail(e.to_string()))?;
    let requestable: Vec<(&str, &str)> = system.requestable().collect();
    let requests: Vec<&Request> = REQUESTS
        .iter()
        .filter(|(m, s, _)| requestable.contains(&(*m, *s)))
        .map(|(_, _, f)| f)
        .collect();
    prop_assert_eq!(
        requests.len(),
        requestable.len(),
        "a requestable service without a typed request"
    );
    let mut ends: HashMap<Ticket, usize> = HashMap::new();
    while engine.inspect().stats().steps < 600 {
        if random.pick(&[true, false, false]) {
            let request = random.pick(&requests);
            request(&mut engine, &random).map_err(|e| TestCaseError::fail(e.to_string()))?;
        }
        let chunk = 1 + random.pick(&[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]);
        engine
            .run_until(Until::Steps(chunk))
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        for ev in engine.events() {
            if let Event::Reply {
                ticket,
                reply: Reply::Done { .. } | Reply::Refused(_),
                ..
            } = ev
            {
                *ends.entry(ticket).or_default() += 1;
            }
        }
    }
    prop_assert!(ends.values().all(|&n| n == 1), "a request ended twice");
    prop_assert_eq!(
        engine.inspect().stats().faults,
        0,
        "a typed codel was faulty"
    );
    let path = engine
        .record()
        .replay(&system)
        .map_err(|e| TestCaseError::fail(format!("not a path of the model: {e}")))?;
    prop_assert_eq!(path.last().map(|(_, s)| s), Some(engine.inspect().state()));
    for (k, (_, state)) in path.iter().enumerate() {
        for p in &system.properties {
            if let PropertyKind::Invariant(e) = &p.kind {
                prop_assert!(
                    system.holds(e, state, &p.name).expect("evaluates"),
                    "invariant {} fails after step {}",
                    p.name,
                    k
                );
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 60, ..ProptestConfig::default() })]

    #[test]
    fn random_runs_through_the_bindings_are_model_paths(seed in any::<u64>()) {
        run_case(seed)?;
    }
}
