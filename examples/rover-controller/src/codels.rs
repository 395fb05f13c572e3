//! The rover's codels: one implementation of each module's generated `Codels` trait. A
//! codel reads and writes through its typed context (only the ports it `writes` have a
//! writer) and returns its own enum of outcomes (only its declared yields and exceptions
//! exist).

use bip_engine::{Bounded, VirtualClock};

use crate::hardware::{Dtm, Hardware, Image, Scan};
use crate::rover::{antenna, aspect, camera, heating, ndd, pom, rflex, sick, Odometry, Pose};

/// rflex: the wheels follow navigation's set point, else the cruise speed.
pub struct Wheels {
    pub hw: Hardware,
    /// The length of a tick (s).
    pub tick_s: f64,
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
        let cruise = ctx.args().copied().unwrap_or(0.0);
        let x = {
            let mut w = self.hw.world();
            w.x += w.nav_speed.unwrap_or(cruise) * self.tick_s;
            w.x
        };
        if let Some(odo) = ctx.port_odo_mut() {
            *odo = Odometry {
                travelled: odo.travelled + (x - odo.x).abs(),
                x,
            };
        }
        rflex::TrackSpeedTrack::PauseTrack
    }
}

/// sick: the laser measures the distance to the rock.
pub struct Laser {
    pub hw: Hardware,
}

impl sick::Codels for Laser {
    fn scan_start(&mut self, _: sick::ScanStartCtx<'_, '_>) -> sick::ScanStart {
        sick::ScanStart::PauseScan
    }

    fn scan_scan(&mut self, mut ctx: sick::ScanScanCtx<'_, '_>) -> sick::ScanScan {
        let ahead = {
            let w = self.hw.world();
            (w.rock_x - w.x).max(0.0)
        };
        let tick = ctx.tick();
        ctx.write_scan(Scan { ahead, tick });
        sick::ScanScan::PauseScan
    }
}

/// pom: the pose is the odometry (no inertial unit in this simulation).
pub struct Localisation;

impl pom::Codels for Localisation {
    fn track_start(&mut self, _: pom::TrackStartCtx<'_, '_>) -> pom::TrackStart {
        pom::TrackStart::PauseFuse
    }

    fn track_fuse(&mut self, mut ctx: pom::TrackFuseCtx<'_, '_>) -> pom::TrackFuse {
        let x = ctx.read_rflex_odo().map_or(0.0, |o| o.x);
        ctx.write_pose(Pose { x });
        pom::TrackFuse::PauseFuse
    }
}

/// ndd: drive towards the goal, stop at it, give up before the rock.
pub struct Navigation {
    pub hw: Hardware,
}

impl ndd::Codels for Navigation {
    fn go_to_start(&mut self, _: ndd::GoToStartCtx<'_, '_>) -> ndd::GoToStart {
        ndd::GoToStart::PauseMove
    }

    fn go_to_move(&mut self, mut ctx: ndd::GoToMoveCtx<'_, '_>) -> ndd::GoToMove {
        let goal = ctx.args().copied().unwrap_or(0.0);
        let x = ctx.read_pom_pose().map_or(0.0, |p| p.x);
        let ahead = ctx.read_sick_scan().map_or(0.0, |s| s.ahead);
        // GoTo's output (`Float`): where the rover stopped
        ctx.set_output(x);
        let mut w = self.hw.world();
        if (goal - x).abs() < 0.05 {
            w.nav_speed = None;
            ndd::GoToMove::Ether
        } else if ahead < 0.3 && goal > x {
            w.nav_speed = None;
            ndd::GoToMove::EBlocked
        } else {
            // slow down near the goal: the pose lags the wheels by up to a period
            w.nav_speed = Some(((goal - x) * 5.0).clamp(-0.5, 0.5));
            ndd::GoToMove::PauseMove
        }
    }

    fn go_to_stop(&mut self, _: ndd::GoToStopCtx<'_, '_>) -> ndd::GoToStop {
        self.hw.world().nav_speed = None;
        ndd::GoToStop::Ether
    }
}

/// aspect: a terrain model from laser scans, done at five cells.
pub struct Mapping;

impl aspect::Codels for Mapping {
    fn build_start(&mut self, _: aspect::BuildStartCtx<'_, '_>) -> aspect::BuildStart {
        aspect::BuildStart::PauseFuse
    }

    fn build_fuse(&mut self, mut ctx: aspect::BuildFuseCtx<'_, '_>) -> aspect::BuildFuse {
        let seen = ctx.read_sick_scan().is_some();
        let cells = ctx.port_dtm_mut().map_or(0, |d: &mut Dtm| {
            d.cells += u32::from(seen);
            d.cells
        });
        if cells >= 5 {
            aspect::BuildFuse::Ether
        } else {
            aspect::BuildFuse::PauseFuse
        }
    }
}

/// antenna: send the packets, one per period.
pub struct Antenna {
    pub hw: Hardware,
}

impl antenna::Codels for Antenna {
    fn communicate_start(
        &mut self,
        _: antenna::CommunicateStartCtx<'_, '_>,
    ) -> antenna::CommunicateStart {
        antenna::CommunicateStart::PauseSend
    }

    fn communicate_send(
        &mut self,
        ctx: antenna::CommunicateSendCtx<'_, '_>,
    ) -> antenna::CommunicateSend {
        // an Int(1, 10): a Bounded, at least one packet
        let want = ctx.args().unwrap_or(Bounded::MIN);
        let mut w = self.hw.world();
        w.sent += 1;
        if i64::from(w.sent) >= want.get() {
            antenna::CommunicateSend::Ether
        } else {
            antenna::CommunicateSend::PauseSend
        }
    }
}

/// heating: three periods of heat.
#[derive(Default)]
pub struct Heater {
    periods: u32,
}

impl heating::Codels for Heater {
    fn heat_start(&mut self, _: heating::HeatStartCtx<'_, '_>) -> heating::HeatStart {
        heating::HeatStart::PauseHeat
    }

    fn heat_heat(&mut self, _: heating::HeatHeatCtx<'_, '_>) -> heating::HeatHeat {
        self.periods += 1;
        if self.periods >= 3 {
            heating::HeatHeat::Ether
        } else {
            heating::HeatHeat::PauseHeat
        }
    }
}

/// camera: the exposure takes 150 ms, longer than the task's period (an overrun): slept
/// on the real clock, added to the virtual one.
pub struct Camera {
    pub exposure: Option<VirtualClock>,
}

impl camera::Codels for Camera {
    fn shoot_start(&mut self, _: camera::ShootStartCtx<'_, '_>) -> camera::ShootStart {
        camera::ShootStart::PauseExpose
    }

    fn shoot_expose(&mut self, mut ctx: camera::ShootExposeCtx<'_, '_>) -> camera::ShootExpose {
        match &self.exposure {
            Some(clock) => clock.advance(150_000),
            None => std::thread::sleep(std::time::Duration::from_millis(150)),
        }
        if let Some(img) = ctx.port_image_mut() {
            *img = Image {
                frames: img.frames + 1,
            };
        }
        camera::ShootExpose::Ether
    }
}
