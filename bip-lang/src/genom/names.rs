//! The names the GenoM layer generates in the core (a stable interface, docs/genom.md).

/// The component and atom of the global clock.
pub const CLOCK: &str = "clock";
pub const CLOCK_ATOM: &str = "Clock";
/// The clock's phase variable (ticks modulo the least common multiple of the periods).
pub const PHASE: &str = "n";
/// The tick connector.
pub const TICK: &str = "tick";
/// A timed model's release at a period boundary: the connector, the clock's port, and
/// the clock's variable that says the current instant's release has not happened yet.
pub const RELEASE: &str = "release";
pub const DUE: &str = "due";
/// Variables of an activity atom.
pub const REQ: &str = "req";
pub const PAUSED: &str = "paused";
pub const STOPPING: &str = "stopping";
pub const DONE: &str = "done";
/// An activity's variable that records an event of its module (a transition other than
/// a pause) until the module's wake-up has delivered it, and the port of that wake-up.
pub const WOKE: &str = "woke";
pub const WAKE: &str = "wake";
/// An activity's variables for its async codels: which one runs apart from the task (0:
/// none, else its number from 1 in codel order), and whether the one at the activity's
/// state has returned, its outcome waiting for the task.
pub const BUSY: &str = "busy";
pub const RETURNED: &str = "returned";

/// The connector that wakes module `m`'s sleeping aperiodic activities.
pub fn wake_connector(m: &str) -> String {
    format!("{m}_wake")
}

/// The component of module `m` (its ids, port ages, function ports).
pub fn module_component(m: &str) -> String {
    m.to_string()
}

pub fn module_atom(m: &str) -> String {
    format!("Module_{m}")
}

/// The component of activity `s` of module `m`.
pub fn activity_component(m: &str, s: &str) -> String {
    format!("{m}_{s}")
}

pub fn activity_atom(m: &str, s: &str) -> String {
    format!("Activity_{m}_{s}")
}

/// The connector of requests for service `s` of module `m`.
pub fn request_connector(m: &str, s: &str) -> String {
    format!("{m}_{s}_request")
}

/// The connector by which a pending request of activity `m.s` interrupts again the
/// activities it interrupts that were requested since its own request (docs/genom.md,
/// "Interrupts"). No codel state may be named `interrupt`, so no codel connector of
/// `m.s` has this name.
pub fn interrupt_connector(m: &str, s: &str) -> String {
    format!("{m}_{s}_interrupt")
}

/// The connector that runs codel `state` of activity `m.s`.
pub fn codel_connector(m: &str, s: &str, state: &str) -> String {
    format!("{m}_{s}_{state}")
}

/// The port of module atom through which codel `state` of activity `s` writes ids.
pub fn ids_port(s: &str, state: &str) -> String {
    format!("write_{s}_{state}")
}

/// The port of the module atom by which codel `codel` that runs at a request of `s` (its
/// `validate`, or a function's codel) fails: the request refused, or the function's reply
/// an exception (its connector is [`fail_connector`]).
pub fn request_fail_port(s: &str, codel: &str) -> String {
    format!("fail_{s}_{codel}")
}

/// The connector of codel `state` ending with one of its exceptions.
pub fn fail_connector(m: &str, s: &str, state: &str) -> String {
    format!("{m}_{s}_{state}_fail")
}

/// The error port of codel `state` in its activity atom.
pub fn fail_port(state: &str) -> String {
    format!("{state}_fail")
}

/// The port of async codel `state` in its activity atom by which it starts apart from
/// its task (its connector is [`start_connector`]).
pub fn start_port(state: &str) -> String {
    format!("{state}_start")
}

/// The port of async codel `state` in its activity atom by which it returns.
pub fn return_port(state: &str) -> String {
    format!("{state}_return")
}

/// The connector by which async codel `state` of activity `m.s` returns (its outcome is
/// then applied by [`codel_connector`] or [`fail_connector`] at its task's next cycle).
pub fn return_connector(m: &str, s: &str, state: &str) -> String {
    format!("{m}_{s}_{state}_return")
}

/// The age variable of port `p` in its module's atom.
pub fn age_var(p: &str) -> String {
    format!("age_{p}")
}

/// The "has completed once" variable of function or attribute `f` in its module's atom.
pub fn done_var(f: &str) -> String {
    format!("done_{f}")
}

// A timed model's generated names (docs/genom.md, "Timed models").

/// Variables of a task atom: its job's stage ([`STAGE_IDLE`], [`STAGE_READY`],
/// [`STAGE_RUNNING`]), which of its codels holds the core (0: none, else its number from
/// 1 in the task's order), that codel's elapsed time units, and whether a period boundary
/// passed while its job was unfinished.
pub const STAGE: &str = "stage";
pub const RUNNING_CODEL: &str = "codel";
pub const ELAPSED: &str = "x";
pub const LATE: &str = "late";
pub const STAGE_IDLE: i64 = 0;
pub const STAGE_READY: i64 = 1;
pub const STAGE_RUNNING: i64 = 2;

/// The component of task `t` of module `m` (`m_t` is its machine's).
pub fn task_component(m: &str, t: &str) -> String {
    format!("{m}_{t}_task")
}

pub fn task_atom(m: &str, t: &str) -> String {
    format!("Task_{m}_{t}")
}

/// The connector by which task `m.t`'s ready job takes a core.
pub fn dispatch_connector(m: &str, t: &str) -> String {
    format!("{m}_{t}_dispatch")
}

/// The connector by which running task `m.t` gives its core, between two codels of its
/// job, to a more urgent ready task (`preemption: Codel`).
pub fn yield_connector(m: &str, t: &str) -> String {
    format!("{m}_{t}_yield")
}

/// The connector by which ready task `m.t` takes the core of running task `n.u`
/// (`preemption: Preemptive`).
pub fn preempt_connector(m: &str, t: &str, n: &str, u: &str) -> String {
    format!("{m}_{t}_preempts_{n}_{u}")
}

/// The connector by which task `m.t`'s job ends, freeing its core.
pub fn done_connector(m: &str, t: &str) -> String {
    format!("{m}_{t}_done")
}

/// The connector that starts codel `state` of activity `m.s`: on its task's core in a
/// timed model (its finish is [`codel_connector`]), apart from its task for an async
/// codel in an untimed one.
pub fn start_connector(m: &str, s: &str, state: &str) -> String {
    format!("{m}_{s}_{state}_start")
}

/// The connector by which codel `state` of activity `m.s` finishes after its activity
/// was interrupted or aborted while it ran: it frees the core, its outcome dropped.
pub fn dropped_connector(m: &str, s: &str, state: &str) -> String {
    format!("{m}_{s}_{state}_dropped")
}

/// The invariant that task `m.t` meets its deadline (`deadline` as the user reads it).
pub fn deadline_property(m: &str, t: &str, deadline: &str) -> String {
    format!("{m}.{t} meets its {deadline} deadline")
}
