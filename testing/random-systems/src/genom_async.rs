//! Random GenoM layers with async codels (docs/genom.md, "Async codels"), written out as
//! model files, and the naive interpreter that says, word for word from the docs, what
//! their steps are: bip-lang's test of the expansion compares the step relation's graph
//! with it, and bip-engine's runs of the engine on these layers walk it along their
//! recordings.

use bip_model::{Label, State, System};

impl Layer {
    /// The layer of these draws, with a pause only where the task is periodic.
    pub fn new(
        period: i64,
        start_async: bool,
        start_pauses: bool,
        s1_loops: bool,
        stop: u8,
        self_interrupt: bool,
    ) -> Layer {
        Layer {
            period,
            start_async,
            start_pauses: start_pauses && period > 0,
            s1_loops: s1_loops && period > 0,
            stop: stop % 3,
            self_interrupt,
        }
    }
}

/// Activity `A` of task `t` (period `period`, aperiodic for 0) with codels `start` (maybe async), `s1`
/// (async) and maybe `stop` (maybe async), and activity `B` of the same task, whose
/// `start` ends at once. `A` may interrupt itself: its request while it runs takes it to
/// its stop path.
#[derive(Clone, Debug)]
pub struct Layer {
    /// 0: aperiodic, and then no codel pauses (no sleeper, so no wake-ups).
    pub period: i64,
    pub start_async: bool,
    /// `start` yields `s1` through a pause.
    pub start_pauses: bool,
    /// `s1` may pause back to itself (it always may end).
    pub s1_loops: bool,
    /// 0: no stop codel; 1: a synchronous one; 2: an async one.
    pub stop: u8,
    pub self_interrupt: bool,
}

pub fn model(l: &Layer) -> String {
    let asynchronous = |a: bool| if a { ", async: true" } else { "" };
    let start = if l.start_pauses { "pause::s1" } else { "s1" };
    let s1 = if l.s1_loops {
        r#""pause::s1", "ether""#
    } else {
        r#""ether""#
    };
    let stop = match l.stop {
        0 => String::new(),
        k => format!(
            r#", (state: "stop", yields: ["ether"]{})"#,
            asynchronous(k == 2)
        ),
    };
    let interrupts = if l.self_interrupt {
        r#"interrupts: ["A"], "#
    } else {
        ""
    };
    let task = match l.period {
        0 => r#"(name: "t")"#.to_string(),
        p => format!(r#"(name: "t", period: {p})"#),
    };
    format!(
        r#"System(name: "apart", modules: [(name: "m", tasks: [{task}],
            services: [
                (name: "A", kind: Activity, task: "t", {interrupts}codels: [
                    (state: "start", yields: ["{start}"]{}),
                    (state: "s1", yields: [{s1}], async: true){stop}]),
                (name: "B", kind: Activity, task: "t", codels: [(state: "start", yields: ["ether"])]),
            ])],
        properties: [DeadlockFree])"#,
        asynchronous(l.start_async),
    )
}

/// Where `A` is: `ether`, or at the state of one of its codels (0 `start`, 1 `s1`, 2
/// `stop`).
pub type Where = Option<u8>;

/// A's (where, req, paused, stopping, which async codel runs: 0 none or 1 + its codel,
/// returned), B's (req, paused), and the ticks modulo the period.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RefState {
    pub a: Where,
    pub req: bool,
    pub paused: bool,
    pub stopping: bool,
    pub busy: u8,
    pub returned: bool,
    pub b_req: bool,
    pub b_paused: bool,
    pub phase: i64,
}

pub const CODELS: [&str; 3] = ["start", "s1", "stop"];

fn is_async(l: &Layer, k: u8) -> bool {
    match k {
        0 => l.start_async,
        1 => true,
        _ => l.stop == 2,
    }
}

/// The yields of A's codel `k`: (to, pauses), with `None` for `ether`.
fn yields(l: &Layer, k: u8) -> Vec<(Where, bool)> {
    match k {
        0 => vec![(Some(1), l.start_pauses)],
        1 if l.s1_loops => vec![(Some(1), true), (None, false)],
        _ => vec![(None, false)],
    }
}

/// The number an async codel has in the activity's `busy`: 1 + its rank among the
/// activity's async codels.
fn number(l: &Layer, k: u8) -> u8 {
    1 + (0..k).filter(|&j| is_async(l, j)).count() as u8
}

/// The naive interpreter, as docs/genom.md says: codels are urgent and `A`'s run before
/// `B`'s; a synchronous codel runs where its activity is, unpaused, with no async codel of
/// the activity running; an async codel starts there (the activity stays) and returns
/// whenever the world lets it (with requests and ticks, below every codel); where the
/// activity still waits for it, its outcome waits for the task's next period boundary
/// and is then the codel's normal outcome or error path; elsewhere it is dropped. A
/// request of a self-interrupting `A` while it runs takes it to `stop` (or `ether`),
/// dropping an outcome that waits, never the running codel. An aperiodic task has no
/// boundaries: what a periodic one leaves for its next boundary (a start, a queued
/// restart, a stop path, an outcome) is ready at once.
pub fn reference_successors(l: &Layer, s: &RefState) -> Vec<(String, RefState)> {
    let periodic = l.period > 0;
    let mut codels = Vec::new();
    let outcome = |codels: &mut Vec<(String, RefState)>, label: String, k: u8, base: RefState| {
        for (to, pauses) in yields(l, k) {
            let mut n = base;
            match to {
                Some(t) => {
                    n.a = Some(t);
                    n.paused = pauses;
                }
                None => {
                    n.a = None;
                    n.stopping = false;
                    n.paused = n.req && periodic;
                }
            }
            codels.push((label.clone(), n));
        }
        let mut n = base;
        n.a = None;
        n.stopping = false;
        n.paused = n.req && periodic;
        codels.push((format!("{label}_fail"), n));
    };
    // A's codel at `k`, from `ether` (its start) or its location
    let runs_from = match s.a {
        None if s.req && !s.paused && s.busy == 0 => Some((0, true)),
        Some(k) if !s.paused && (s.busy == 0 || s.returned) => Some((k, false)),
        _ => None,
    };
    if let Some((k, from_ether)) = runs_from {
        let name = format!("A_{}", CODELS[k as usize]);
        let mut base = *s;
        if from_ether {
            base.req = false;
        }
        if !is_async(l, k) {
            outcome(&mut codels, name, k, base);
        } else if s.returned {
            base.returned = false;
            outcome(&mut codels, name, k, base);
        } else {
            base.a = Some(k);
            base.busy = number(l, k);
            codels.push((format!("{name}_start"), base));
        }
    }
    if codels.is_empty() && s.b_req && !s.b_paused {
        for label in ["B_start", "B_start_fail"] {
            let n = RefState {
                b_req: false,
                b_paused: false,
                ..*s
            };
            codels.push((label.to_string(), n));
        }
    }
    if !codels.is_empty() {
        return codels;
    }
    let mut out = Vec::new();
    let phase = (s.phase + 1) % l.period.max(1);
    out.push((
        "tick".to_string(),
        RefState {
            paused: s.paused && phase != 0,
            b_paused: s.b_paused && phase != 0,
            phase,
            ..*s
        },
    ));
    if !s.b_req {
        out.push((
            "B_request".into(),
            RefState {
                b_req: true,
                b_paused: periodic,
                ..*s
            },
        ));
    }
    match s.a {
        None if !s.req => out.push((
            "A_request".into(),
            RefState {
                req: true,
                paused: periodic,
                ..*s
            },
        )),
        None if l.self_interrupt => out.push(("A_request".into(), *s)),
        Some(_) if l.self_interrupt => {
            let mut n = RefState { req: true, ..*s };
            if l.stop == 0 {
                n.a = None;
                n.paused = periodic;
                n.returned = false;
            } else {
                if !s.stopping {
                    n.a = Some(2);
                    n.stopping = true;
                    n.returned = false;
                }
                n.paused &= periodic;
            }
            out.push(("A_request".into(), n));
        }
        _ => {}
    }
    if s.busy != 0 {
        let k = (0..3u8)
            .find(|&k| is_async(l, k) && number(l, k) == s.busy)
            .expect("a running codel");
        let mut n = RefState { busy: 0, ..*s };
        if s.a == Some(k) {
            n.returned = true;
            n.paused = periodic;
        }
        out.push((format!("A_{}_return", CODELS[k as usize]), n));
    }
    out
}

impl RefState {
    /// Where every layer starts.
    pub const FIRST: RefState = RefState {
        a: None,
        req: false,
        paused: false,
        stopping: false,
        busy: 0,
        returned: false,
        b_req: false,
        b_paused: false,
        phase: 0,
    };

    /// State `s` of a layer's expanded system, in the interpreter's terms.
    pub fn of(sys: &System, s: &State) -> RefState {
        let component = |name: &str| sys.component_index(name).expect("a layer's component");
        let (a, b, clock) = (component("m_A"), component("m_B"), component("clock"));
        let value = |comp: u32, name: &str| {
            sys.atom_of(comp)
                .var_index(name)
                .map_or(0, |v| sys.value(s, comp, v))
        };
        RefState {
            a: match sys.location_name(s, a) {
                "ether" => None,
                l => Some(CODELS.iter().position(|c| *c == l).expect("a codel state") as u8),
            },
            req: value(a, "req") != 0,
            paused: value(a, "paused") != 0,
            stopping: value(a, "stopping") != 0,
            busy: value(a, "busy") as u8,
            returned: value(a, "returned") != 0,
            b_req: value(b, "req") != 0,
            b_paused: value(b, "paused") != 0,
            phase: value(clock, "n"),
        }
    }
}

/// A step of a layer's expanded system by the interpreter's name for it (`A_s1_start`).
pub fn step_name(sys: &System, label: Label) -> String {
    let Label::Interaction(i) = label else {
        panic!("a GenoM layer has no internal steps")
    };
    let name = &sys.interactions[i as usize].name;
    name.strip_prefix("m_").unwrap_or(name).to_string()
}
