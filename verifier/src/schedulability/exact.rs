//! A task's exact demand per period: the most WCET of its codels that any run of the
//! model can pack between two ticks.
//!
//! The question is about paths, not states: the explicit exploration records the graph
//! of the reachable states as it explores them (`explore::on_state_graph`), keeping each
//! step's interaction. A task's period is a path of steps other than the tick, starting where a
//! tick (or the start) left the model; its cost is the sum of the WCETs of the task's
//! codel runs on it. The longest such path is found on the graph of non-tick steps
//! condensed into strongly connected components: a component with a costly step inside
//! it is a loop the task can run forever in one period (no bound), the others form a DAG,
//! costed from its sinks up in the order Tarjan's algorithm completes them, for several
//! tasks in one pass (the pass is a walk of the whole graph; a task more is a word more
//! per component).

use bip_model::{Label, State, Step, System};

use super::tasks::{TaskKind, TaskTable};
use crate::explore::graph::{Graph, Keep};
use crate::explore::scc::{self, Components};
use crate::explore::{on_state_graph, Unanswered};
use crate::options::Options;
use crate::report::Stop;
use crate::watch::Watch;

/// The exact demands, and the size of what was explored.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Exact {
    /// Per task of the table: its demand in microseconds, `None` if unbounded (a
    /// component's is its declared WCET).
    pub demands: Vec<Option<u64>>,
    pub states: u64,
    pub transitions: u64,
}

/// Components handled between two looks at the limits.
const COMPONENTS_PER_LOOK: u32 = 4096;

/// Tasks whose demands one pass over the graph finds: a component holds a row of as
/// many values while the pass runs (at most 64, the bits of a word).
const TASKS_PER_PASS: usize = 8;

/// Label of an internal transition in the graph (it belongs to no task, and is no tick).
const INTERNAL: u32 = u32::MAX;

/// What the demands keep of each step: its interaction, or [`INTERNAL`].
struct Labels;

impl Keep for Labels {
    type Edge = u32;
    type Notes = ();

    fn notes(&self) {}

    fn state(&self, _: &State, _: u32, _: &mut ()) -> u32 {
        0
    }

    fn edge(&self, _: &State, step: Step<'_>, _: &State, _: u32, _: &mut ()) -> u32 {
        match step.label {
            Label::Interaction(i) => i,
            Label::Internal { .. } => INTERNAL,
        }
    }

    fn merge(&self, _: &mut (), _: ()) {}
}

/// The explored graph, with each edge's label.
type Labelled = Graph<u32>;

/// Explores `system` and computes every task's demand, within the limits of `options`;
/// `Err` says why it could not (a limit, or a range error in the model).
pub fn exact_demands(
    system: &System,
    table: &TaskTable,
    options: &Options,
) -> Result<Exact, String> {
    let tick = table.tick.ok_or("no task runs codels")?;
    on_state_graph(system, options, &Labels, |graph, watch| {
        demands(graph, table, tick, watch)
    })
    .map_err(|why| match why {
        Unanswered::Stopped(stop) => stopped(&stop),
        Unanswered::RangeError(e) => format!("a range error ({e}); `bip verify` shows it"),
        Unanswered::Failed(e) => e.to_string(),
    })
}

/// The demands on the explored graph; `None` once `watch` says stop.
fn demands(mut graph: Labelled, table: &TaskTable, tick: u32, watch: &Watch) -> Option<Exact> {
    let states = graph.len() as u64;
    let transitions = graph.targets.len() as u64;
    let mut components = condense(&graph, tick, watch)?;
    let starts = period_starts(&graph, tick, &components.of);
    // from here on an edge leads to its target's component; what the passes do not read
    // is freed first
    for t in &mut graph.targets {
        *t = components.of[*t as usize];
    }
    components.of = Vec::new();
    graph.ids = Vec::new();
    graph.state_flags = Vec::new();
    let mut demands: Vec<Option<u64>> = table
        .tasks
        .iter()
        .map(|t| match t.kind {
            TaskKind::Component { wcet_us, .. } => Some(wcet_us),
            TaskKind::Genom { .. } => None,
        })
        .collect();
    let genom: Vec<usize> = (0..table.tasks.len())
        .filter(|&t| matches!(table.tasks[t].kind, TaskKind::Genom { .. }))
        .collect();
    for tasks in genom.chunks(TASKS_PER_PASS) {
        let pass = |narrow: bool| {
            let (g, c) = (&graph, &components);
            if narrow {
                longest_periods::<u32>(g, &starts, table, tick, tasks, c, watch)
            } else {
                longest_periods::<u64>(g, &starts, table, tick, tasks, c, watch)
            }
        };
        let found = match pass(true) {
            Pass::Found(found) => found,
            Pass::TooCostly => match pass(false) {
                Pass::Found(found) => found,
                Pass::TooCostly | Pass::Stopped => return None,
            },
            Pass::Stopped => return None,
        };
        for (&t, d) in tasks.iter().zip(found) {
            demands[t] = d;
        }
    }
    Some(Exact {
        demands,
        states,
        transitions,
    })
}

/// Why the exploration stopped, in the words of `bip sched`'s demand line.
fn stopped(stop: &Stop) -> String {
    match stop {
        Stop::MaxStates { limit } => format!("more than {limit} states"),
        Stop::MaxMemory { limit } => format!("more than {limit} bytes of graph"),
        Stop::Timeout { .. } => "the time limit".into(),
        Stop::Interrupted => "interrupted".into(),
        Stop::TooManyStates => "more states than the demand's graph can number".into(),
        Stop::FirstFailure => stop.to_string(),
    }
}

/// The components a period starts in: those of the initial state and of every tick's
/// target (`of` gives each state's component), in order.
fn period_starts(graph: &Labelled, tick: u32, of: &[u32]) -> Vec<u32> {
    let mut starts: Vec<u32> = graph
        .targets
        .iter()
        .zip(&graph.edge_data)
        .filter(|&(_, &label)| label == tick)
        .map(|(&t, _)| of[t as usize])
        .collect();
    // the initial state is the first explored
    starts.push(of[0]);
    starts.sort_unstable();
    starts.dedup();
    starts
}

/// Strongly connected components of the non-tick steps.
fn condense(graph: &Labelled, tick: u32, watch: &Watch) -> Option<Components> {
    scc::components(graph, |_| true, |e| graph.edge_data[e] != tick, watch)
}

/// What a pass found.
enum Pass {
    /// Per task, its costliest period; `None` if unbounded.
    Found(Vec<Option<u64>>),
    /// A path costs more than the rows' values hold.
    TooCostly,
    Stopped,
}

/// The costliest periods of `tasks` (at most 64), over every period start (a component,
/// as every edge's target now is). One pass over the components for all of them: each
/// component's costliest path per task, as a `V` (a `u32` halves the rows and holds any
/// period up to an hour), and the tasks it can loop costly for, as bits.
fn longest_periods<V: Copy + Default + Into<u64> + TryFrom<u64>>(
    graph: &Labelled,
    starts: &[u32],
    table: &TaskTable,
    tick: u32,
    tasks: &[usize],
    components: &Components,
    watch: &Watch,
) -> Pass {
    const NONE: usize = usize::MAX;
    let k = tasks.len();
    let row_bytes = k * std::mem::size_of::<V>() + 8;
    if !watch.expect((components.len() * row_bytes) as u64) {
        return Pass::Stopped;
    }
    // each task's place in a component's row
    let mut slot = vec![NONE; table.tasks.len()];
    for (i, &t) in tasks.iter().enumerate() {
        slot[t] = i;
    }
    // best[c * k + i]: the costliest path of task tasks[i] from any state of component c
    let mut best = vec![V::default(); components.len() * k];
    let mut unbounded = vec![0u64; components.len()];
    let mut here = vec![0u64; k];
    for c in 0..components.len() as u32 {
        if c.is_multiple_of(COMPONENTS_PER_LOOK) && watch.stopped().is_some() {
            return Pass::Stopped;
        }
        here.fill(0);
        let mut looping = 0u64;
        for &v in components.members(c) {
            for edge in graph.edges(v) {
                let label = graph.edge_data[edge];
                if label == tick {
                    continue;
                }
                let (i, w) = match table.cost.get(label as usize) {
                    Some(&Some((t, w))) => (slot[t], w),
                    _ => (NONE, 0),
                };
                let d = graph.targets[edge];
                if d == c {
                    if i != NONE && w > 0 {
                        looping |= 1 << i;
                    }
                    continue;
                }
                looping |= unbounded[d as usize];
                let row = &best[d as usize * k..(d as usize + 1) * k];
                for (h, &b) in here.iter_mut().zip(row) {
                    *h = (*h).max(b.into());
                }
                if i != NONE {
                    here[i] = here[i].max(row[i].into().saturating_add(w));
                }
            }
        }
        for (b, &h) in best[c as usize * k..(c as usize + 1) * k]
            .iter_mut()
            .zip(&here)
        {
            let Ok(h) = V::try_from(h) else {
                return Pass::TooCostly;
            };
            *b = h;
        }
        unbounded[c as usize] = looping;
    }
    Pass::Found(
        (0..k)
            .map(|i| {
                starts.iter().try_fold(0u64, |m, &s| {
                    (unbounded[s as usize] & (1 << i) == 0)
                        .then(|| m.max(best[s as usize * k + i].into()))
                })
            })
            .collect(),
    )
}
