//! zenoh's threads in a layer's process. zenoh runs its network on tokio runtimes of its
//! own: by default a socket's readiness is polled by the runtime that opened it (the
//! acceptor's for a link accepted, the network's for a link connected), which then wakes
//! the receiving task on a third (two threads): some twelve thread switches per round
//! trip of a codel run where four do, and most of its time on loopback
//! (docs/performance.md, "Distributed"). Handing the acceptor's and the network's runtimes
//! over to the receiving one, with one thread, keeps a message's reception on one thread.
//!
//! zenoh reads this configuration from the environment variable `ZENOH_RUNTIME` (RON), once,
//! when its runtimes start; there is no other way to give it.

/// The variable zenoh reads.
pub const ZENOH_RUNTIME_ENV: &str = "ZENOH_RUNTIME";

/// A layer's zenoh runtimes: sockets polled by the runtime that receives from them, one
/// thread.
pub const LAYER_RUNTIME: &str =
    "(acc: (handover: rx), net: (handover: rx), rx: (worker_threads: 1))";

/// Sets `ZENOH_RUNTIME` to [`LAYER_RUNTIME`] unless it is set already (a user's own choice
/// stands); the processes this one starts inherit it. Call it first thing in `main`, before
/// any thread is started (the environment is not safely written beside other threads) and
/// before any zenoh session is opened (zenoh reads it once). Without it a layer runs the
/// same, its round trips slower.
pub fn tune_zenoh_runtime() {
    if std::env::var_os(ZENOH_RUNTIME_ENV).is_none() {
        std::env::set_var(ZENOH_RUNTIME_ENV, LAYER_RUNTIME);
    }
}
