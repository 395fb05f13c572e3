//! The rover run through its generated bindings: each module's codels are a struct that
//! implements the module's `Codels` trait, each codel reads and writes through its typed
//! context and returns its own enum of outcomes, one `bind` registers them all, and typed
//! requests read their typed ends. The run is a path of the model.

use crate::{assert_clean_path, end_of};
use bip_engine::{Engine, Until};
use bip_rover_bindings::*;

/// The wheels: drive at the requested speed, publish the odometry.
#[derive(Default)]
struct Wheels {
    x: f64,
}

impl rflex::Codels for Wheels {
    fn track_speed_start(
        &mut self,
        _: rflex::TrackSpeedStartCtx<'_, '_>,
    ) -> rflex::TrackSpeedStart {
        rflex::TrackSpeedStart::PauseTrack
    }

    fn track_speed_track(
        &mut self,
        mut ctx: rflex::TrackSpeedTrackCtx<'_, '_>,
    ) -> rflex::TrackSpeedTrack {
        let speed = ctx.args().copied().unwrap_or(0.0);
        self.x += speed * 0.1;
        if let Some(odo) = ctx.port_odo_mut() {
            odo.x = self.x;
            odo.travelled += speed.abs() * 0.1;
        }
        rflex::TrackSpeedTrack::PauseTrack
    }
}

/// The laser: sees an obstacle this close, or none.
struct Laser {
    obstacle: Option<f64>,
}

impl sick::Codels for Laser {
    fn scan_start(&mut self, _: sick::ScanStartCtx<'_, '_>) -> sick::ScanStart {
        sick::ScanStart::PauseScan
    }
    fn scan_scan(&mut self, mut ctx: sick::ScanScanCtx<'_, '_>) -> sick::ScanScan {
        let ranges = self.obstacle.into_iter().collect();
        ctx.write_scan(Scan { ranges });
        sick::ScanScan::PauseScan
    }
}

/// The pose: the odometry's x.
struct Fuse;

impl pom::Codels for Fuse {
    fn track_start(&mut self, _: pom::TrackStartCtx<'_, '_>) -> pom::TrackStart {
        pom::TrackStart::PauseFuse
    }
    fn track_fuse(&mut self, mut ctx: pom::TrackFuseCtx<'_, '_>) -> pom::TrackFuse {
        let x = ctx.read_rflex_odo().map_or(0.0, |o| o.x);
        ctx.write_pose(Pose { x });
        pom::TrackFuse::PauseFuse
    }
}

/// Navigation: ends at the goal with where it stopped, blocked by a near obstacle.
struct Navigation;

impl ndd::Codels for Navigation {
    fn go_to_start(&mut self, _: ndd::GoToStartCtx<'_, '_>) -> ndd::GoToStart {
        ndd::GoToStart::PauseMove
    }
    fn go_to_move(&mut self, mut ctx: ndd::GoToMoveCtx<'_, '_>) -> ndd::GoToMove {
        let goal = ctx.args().copied().unwrap_or(0.0);
        let x = ctx.read_pom_pose().map_or(0.0, |p| p.x);
        let blocked = ctx
            .read_sick_scan()
            .is_some_and(|s| s.ranges.iter().any(|&r| r < 0.5));
        ctx.set_output(x);
        if blocked {
            ndd::GoToMove::EBlocked
        } else if x >= goal {
            ndd::GoToMove::Ether
        } else {
            ndd::GoToMove::PauseMove
        }
    }
    fn go_to_stop(&mut self, _: ndd::GoToStopCtx<'_, '_>) -> ndd::GoToStop {
        ndd::GoToStop::Ether
    }
}

/// Every other module: starts, and ends at its first chance.
struct Brief;

impl aspect::Codels for Brief {
    fn build_start(&mut self, _: aspect::BuildStartCtx<'_, '_>) -> aspect::BuildStart {
        aspect::BuildStart::PauseFuse
    }
    fn build_fuse(&mut self, mut ctx: aspect::BuildFuseCtx<'_, '_>) -> aspect::BuildFuse {
        ctx.write_dtm(Dtm { cells: 4 });
        aspect::BuildFuse::Ether
    }
}

impl antenna::Codels for Brief {
    fn communicate_start(
        &mut self,
        _: antenna::CommunicateStartCtx<'_, '_>,
    ) -> antenna::CommunicateStart {
        antenna::CommunicateStart::PauseSend
    }
    fn communicate_send(
        &mut self,
        _: antenna::CommunicateSendCtx<'_, '_>,
    ) -> antenna::CommunicateSend {
        antenna::CommunicateSend::Ether
    }
}

impl heating::Codels for Brief {
    fn heat_start(&mut self, _: heating::HeatStartCtx<'_, '_>) -> heating::HeatStart {
        heating::HeatStart::PauseHeat
    }
    fn heat_heat(&mut self, _: heating::HeatHeatCtx<'_, '_>) -> heating::HeatHeat {
        heating::HeatHeat::Ether
    }
}

impl camera::Codels for Brief {
    fn shoot_start(&mut self, _: camera::ShootStartCtx<'_, '_>) -> camera::ShootStart {
        camera::ShootStart::PauseExpose
    }
    fn shoot_expose(&mut self, mut ctx: camera::ShootExposeCtx<'_, '_>) -> camera::ShootExpose {
        ctx.write_image(Image { shots: 1 });
        camera::ShootExpose::Ether
    }
}

pub(crate) fn system() -> bip_engine::System {
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../../robots/rover.ron");
    bip_engine::load_file(model).unwrap_or_else(|e| panic!("{e:?}"))
}

/// The rover bound to its codels, the laser seeing `obstacle`, driving at 0.5 m/s; its
/// steps recorded.
fn rover(system: &bip_engine::System, obstacle: Option<f64>) -> Engine {
    driving(Engine::builder(system.clone()).record(10_000), obstacle)
}

/// The rover built from `builder` with its codels bound, the laser seeing `obstacle`,
/// driving at 0.5 m/s.
pub(crate) fn driving(builder: bip_engine::EngineBuilder, obstacle: Option<f64>) -> Engine {
    let laser = Laser { obstacle };
    let wheels = Wheels::default();
    let mut engine = bind(
        builder, wheels, laser, Fuse, Navigation, Brief, Brief, Brief, Brief,
    )
    .build()
    .expect("every codel is bound");
    rflex::request_init(&mut engine).expect("queued");
    sick::request_scan(&mut engine).expect("queued");
    pom::request_track(&mut engine).expect("queued");
    rflex::request_track_speed(&mut engine, 0.5).expect("queued");
    engine.run_until(Until::Ticks(4)).expect("runs");
    engine
}

#[test]
fn a_typed_request_ends_with_its_typed_output() {
    let system = system();
    let mut engine = rover(&system, None);
    let goto = ndd::request_go_to(&mut engine, 0.4).expect("queued");
    let Some(ndd::GoToEnd::Done(Some(x))) = end_of(&mut engine, 30, |t, r| goto.end(t, r)) else {
        panic!("GoTo did not reach its goal");
    };
    assert!(x >= 0.4, "stopped at {x}");
    let steps = assert_clean_path(&mut engine, &system);
    assert!(steps > 50, "{steps}");
}

#[test]
fn a_typed_request_from_another_thread_reads_its_typed_end() {
    let system = system();
    let mut engine = rover(&system, None);
    let handle = engine.handle();
    let client = std::thread::spawn(move || {
        let pending = ndd::request_go_to_from(&handle, 0.4).expect("queued");
        pending.end(std::time::Duration::from_secs(60))
    });
    // the engine serves the other thread's request as it runs
    while !client.is_finished() {
        engine.run_until(Until::Ticks(1)).expect("runs");
        std::thread::yield_now();
    }
    let Some(ndd::GoToEnd::Done(Some(x))) = client.join().expect("the client") else {
        panic!("GoTo did not reach its goal");
    };
    assert!(x >= 0.4, "stopped at {x}");
    // arguments of the wrong type are refused at the request, from a thread too
    let handle = engine.handle();
    assert!(matches!(
        handle.request("ndd", "GoTo", 0.4f32),
        Err(bip_engine::RequestError::WrongArguments { .. })
    ));
}

#[test]
fn a_thrown_exception_is_the_services_exception_variant() {
    let system = system();
    let mut engine = rover(&system, Some(0.2));
    let goto = ndd::request_go_to(&mut engine, 5.0).expect("queued");
    // the exception keeps the output the codel gave before it threw: where it stopped
    match end_of(&mut engine, 10, |t, r| goto.end(t, r)) {
        Some(ndd::GoToEnd::Exception(ndd::GoToException::EBlocked, Some(x))) => {
            assert!((0.0..5.0).contains(&x), "stopped at {x}")
        }
        other => panic!("{other:?}"),
    }
    assert_clean_path(&mut engine, &system);
}

#[test]
fn an_int_argument_is_made_in_range_or_not_at_all() {
    let system = system();
    let mut engine = rover(&system, None);
    // Communicate takes an Int(1, 10): 11 is no `Bounded<1, 10>`
    let err = bip_engine::Bounded::<1, 10>::try_from(11).expect_err("out of Int(1, 10)");
    assert_eq!(
        err.to_string(),
        "11 is out of the range 1..=10 (Int(1, 10))"
    );
    // untyped, the engine refuses it at the request
    let err = engine
        .request("antenna", "Communicate", 11i64)
        .expect_err("out of Int(1, 10)");
    assert!(err.to_string().contains("Int(1, 10)"), "{err}");
    antenna::request_communicate(&mut engine, bip_engine::Bounded::of::<3>()).expect("in range");
}

/// Bindings generated from one version of the model, bound to an engine built for
/// another (`rflex.TrackSpeed.track` yields `ether` first; `antenna.Communicate` takes up
/// to 20 packets): the build fails and says what differs, where the codels' outcomes
/// would otherwise be taken by the wrong number, or typed data refused at run time.
#[test]
fn bindings_of_another_version_of_the_model_are_refused() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../robots/rover.ron");
    let text = std::fs::read_to_string(path).expect("the rover");
    let edits = [
        (
            r#"(state: "track", yields: ["pause::track", "ether"]"#,
            r#"(state: "track", yields: ["ether", "pause::track"]"#,
            "module `rflex` was bound for another model: codel `TrackSpeed.track` yields \
             [\"pause::track\", \"ether\"] in them, [\"ether\", \"pause::track\"] in the model; \
             regenerate its bindings from this model",
        ),
        (
            r#"(name: "Communicate", kind: Activity, task: "comm", args: Int(1, 10)"#,
            r#"(name: "Communicate", kind: Activity, task: "comm", args: Int(1, 20)"#,
            "module `antenna` was bound for another model: service `Communicate` is \
             Int(1, 10) in them, Int(1, 20) in the model (arguments); regenerate its \
             bindings from this model",
        ),
    ];
    for (from, to, refused) in edits {
        assert!(text.contains(from), "the rover has {from}");
        let edited = text.replace(from, to);
        let system = bip_engine::load_str("rover.ron", &edited).unwrap_or_else(|e| panic!("{e:?}"));
        let err = bind(
            Engine::builder(system),
            Wheels::default(),
            Laser { obstacle: None },
            Fuse,
            Navigation,
            Brief,
            Brief,
            Brief,
            Brief,
        )
        .build()
        .err()
        .map(|e| e.to_string());
        assert_eq!(err.as_deref(), Some(refused));
    }
}
