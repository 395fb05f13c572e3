//! The simulated hardware: a rover on a straight track with a rock on it, and the Rust
//! types rover.ron names for its ports' data (`Odometry` and `Pose` are records there,
//! generated into [`crate::rover`]).

use std::sync::{Arc, Mutex, MutexGuard};

/// The laser's range straight ahead (m), and when it was taken (port `sick.scan`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Scan {
    pub ahead: f64,
    pub tick: u64,
}

/// The terrain model (port `aspect.dtm`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dtm {
    pub cells: u32,
}

/// The camera's pictures (port `camera.image`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Image {
    pub frames: u32,
}

/// What the hardware is and senses, shared by the codels that drive it.
#[derive(Debug)]
pub struct World {
    /// Where the rover is (m, on a straight track).
    pub x: f64,
    /// A rock on the track.
    pub rock_x: f64,
    /// The wheels' set point from navigation (m/s), if it drives.
    pub nav_speed: Option<f64>,
    /// Packets that reached the orbiter.
    pub sent: u32,
}

/// The world, shared: each codel locks it for the little it does (the engine runs one
/// codel at a time, so the lock is never contended).
#[derive(Clone, Debug)]
pub struct Hardware(Arc<Mutex<World>>);

impl Hardware {
    /// The rover at 0 m, the rock at 2 m.
    pub fn new() -> Hardware {
        Hardware(Arc::new(Mutex::new(World {
            x: 0.0,
            rock_x: 2.0,
            nav_speed: None,
            sent: 0,
        })))
    }

    pub fn world(&self) -> MutexGuard<'_, World> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl Default for Hardware {
    fn default() -> Hardware {
        Hardware::new()
    }
}
