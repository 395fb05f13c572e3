//! The rover run through its generated bindings: each module's codels are a struct that
//! implements the module's `Codels` trait, each codel returns its own enum of outcomes,
//! and one `bind` registers them all. The run is a path of the model, and its replies are
//! those of the codels' outcomes.

use bip_engine::{Ctx, Engine, Event, Outcome, Reply, Until};
use bip_rover_bindings::*;

/// The wheels: drive at the requested speed until asked to stop.
#[derive(Default)]
struct Wheels {
    x: f64,
}

impl rflex::Codels for Wheels {
    fn track_speed_start(&mut self, _: &mut Ctx<'_>) -> rflex::TrackSpeedStart {
        rflex::TrackSpeedStart::PauseTrack
    }

    fn track_speed_track(&mut self, ctx: &mut Ctx<'_>) -> rflex::TrackSpeedTrack {
        self.x += ctx.args::<f64>().copied().unwrap_or(0.0) * 0.1;
        rflex::TrackSpeedTrack::PauseTrack
    }
}

/// Every other module: starts, and ends at its first chance.
struct Brief;

impl sick::Codels for Brief {
    fn scan_start(&mut self, _: &mut Ctx<'_>) -> sick::ScanStart {
        sick::ScanStart::PauseScan
    }
    fn scan_scan(&mut self, _: &mut Ctx<'_>) -> sick::ScanScan {
        sick::ScanScan::PauseScan
    }
}

impl pom::Codels for Brief {
    fn track_start(&mut self, _: &mut Ctx<'_>) -> pom::TrackStart {
        pom::TrackStart::PauseFuse
    }
    fn track_fuse(&mut self, _: &mut Ctx<'_>) -> pom::TrackFuse {
        pom::TrackFuse::PauseFuse
    }
}

impl ndd::Codels for Brief {
    fn go_to_start(&mut self, _: &mut Ctx<'_>) -> ndd::GoToStart {
        ndd::GoToStart::PauseMove
    }
    fn go_to_move(&mut self, _: &mut Ctx<'_>) -> ndd::GoToMove {
        // blocked at once: the exception is a variant like the yields
        ndd::GoToMove::EBlocked
    }
    fn go_to_stop(&mut self, _: &mut Ctx<'_>) -> ndd::GoToStop {
        ndd::GoToStop::Ether
    }
}

impl aspect::Codels for Brief {
    fn build_start(&mut self, _: &mut Ctx<'_>) -> aspect::BuildStart {
        aspect::BuildStart::PauseFuse
    }
    fn build_fuse(&mut self, _: &mut Ctx<'_>) -> aspect::BuildFuse {
        aspect::BuildFuse::Ether
    }
}

impl antenna::Codels for Brief {
    fn communicate_start(&mut self, _: &mut Ctx<'_>) -> antenna::CommunicateStart {
        antenna::CommunicateStart::PauseSend
    }
    fn communicate_send(&mut self, _: &mut Ctx<'_>) -> antenna::CommunicateSend {
        antenna::CommunicateSend::Ether
    }
}

impl heating::Codels for Brief {
    fn heat_start(&mut self, _: &mut Ctx<'_>) -> heating::HeatStart {
        heating::HeatStart::PauseHeat
    }
    fn heat_heat(&mut self, _: &mut Ctx<'_>) -> heating::HeatHeat {
        heating::HeatHeat::Ether
    }
}

impl camera::Codels for Brief {
    fn shoot_start(&mut self, _: &mut Ctx<'_>) -> camera::ShootStart {
        camera::ShootStart::PauseExpose
    }
    fn shoot_expose(&mut self, _: &mut Ctx<'_>) -> camera::ShootExpose {
        camera::ShootExpose::Ether
    }
}

#[test]
fn the_rover_runs_on_its_generated_bindings() {
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../../robots/rover.ron");
    let system = bip_engine::load_file(model).unwrap_or_else(|e| panic!("{e:?}"));
    let builder = Engine::builder(system.clone()).record(10_000);
    let mut engine = bind(
        builder,
        Wheels::default(),
        Brief,
        Brief,
        Brief,
        Brief,
        Brief,
        Brief,
        Brief,
    )
    .build()
    .expect("every codel is bound");
    for (m, s) in [("rflex", "Init"), ("sick", "Scan"), ("pom", "Track")] {
        engine.request(m, s, ()).expect("queued");
    }
    engine.request("rflex", "TrackSpeed", 0.5).expect("queued");
    engine.run_until(Until::Ticks(6)).expect("runs");
    let goto = engine.request("ndd", "GoTo", 1.0).expect("queued");
    let build = engine.request("aspect", "Build", ()).expect("queued");
    engine.run_until(Until::Ticks(10)).expect("runs");
    let done: Vec<_> = engine
        .events()
        .filter_map(|ev| match ev {
            Event::Reply {
                ticket,
                reply: Reply::Done { outcome, .. },
                ..
            } => Some((ticket, outcome)),
            _ => None,
        })
        .collect();
    assert!(
        done.contains(&(goto, Outcome::Exception("e_blocked".into()))),
        "{done:?}"
    );
    assert!(done.contains(&(build, Outcome::Ether)), "{done:?}");
    assert_eq!(engine.inspect().stats().faults, 0);
    let steps = engine
        .record()
        .replay(&system)
        .expect("a path of the model");
    assert!(steps.len() > 50, "{}", steps.len());
}
