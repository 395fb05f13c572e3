//! The simulated rover: where it is, the speeds its wheels are driven at, the obstacles
//! around it; and the hardware functions its C codels call (codels/sim.h), which a real
//! rover's drivers would give. One world per process, as the drivers are: [`lock`] it
//! for a run.

use std::ffi::c_int;
use std::sync::{Mutex, MutexGuard};

/// The filter's period (loc's task), in seconds: the world moves by one at each reading of
/// the encoders.
const DT: f64 = 0.1;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct World {
    /// Where the rover is: x and y in metres, heading in radians.
    pub x: f64,
    pub y: f64,
    pub theta: f64,
    /// The speeds the wheels are driven at.
    pub v: f64,
    pub w: f64,
    /// Obstacles: centre and radius, in metres.
    pub obstacles: Vec<(f64, f64, f64)>,
}

static WORLD: Mutex<World> = Mutex::new(World {
    x: 0.0,
    y: 0.0,
    theta: 0.0,
    v: 0.0,
    w: 0.0,
    obstacles: Vec::new(),
});

static RUN: Mutex<()> = Mutex::new(());

fn world() -> MutexGuard<'static, World> {
    WORLD.lock().unwrap_or_else(|e| e.into_inner())
}

/// Holds the world for one run (tests run in threads) and resets it to `start`.
pub fn lock(start: World) -> MutexGuard<'static, ()> {
    let guard = RUN.lock().unwrap_or_else(|e| e.into_inner());
    *world() = start;
    guard
}

/// The world as it is.
pub fn now() -> World {
    world().clone()
}

#[no_mangle]
pub extern "C" fn rover_sim_wheels(v: f64, w: f64) {
    let mut s = world();
    s.v = v;
    s.w = w;
}

/// # Safety
/// `v` and `w` are null or point to doubles.
#[no_mangle]
pub unsafe extern "C" fn rover_sim_encoders(v: *mut f64, w: *mut f64) {
    let mut s = world();
    s.theta += s.w * DT;
    s.x += s.v * DT * s.theta.cos();
    s.y += s.v * DT * s.theta.sin();
    // SAFETY: the codel passes its own doubles
    unsafe {
        if let Some(v) = v.as_mut() {
            *v = s.v;
        }
        if let Some(w) = w.as_mut() {
            *w = s.w;
        }
    }
}

#[no_mangle]
pub extern "C" fn rover_sim_blocked(x: f64, y: f64) -> c_int {
    let s = world();
    let hit = s
        .obstacles
        .iter()
        .any(|&(ox, oy, r)| segment_distance((s.x, s.y), (x, y), (ox, oy)) <= r);
    c_int::from(hit)
}

#[no_mangle]
pub extern "C" fn rover_sim_distance(x: f64, y: f64) -> f64 {
    let s = world();
    (x - s.x).hypot(y - s.y)
}

/// The distance from `p` to the segment from `a` to `b`.
fn segment_distance(a: (f64, f64), b: (f64, f64), p: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len = dx * dx + dy * dy;
    let t = if len == 0.0 {
        0.0
    } else {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len).clamp(0.0, 1.0)
    };
    (a.0 + t * dx - p.0).hypot(a.1 + t * dy - p.1)
}
