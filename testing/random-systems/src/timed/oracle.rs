//! The timed semantics of docs/model.md ("Timed semantics"), interpreted naively: the
//! state is exactly what the semantics stores, one unit of time passes per step, every
//! zero-time step of every task (a period boundary's release among them) is tried in
//! every order, and nothing is derived that is not in the definition. Written to be read
//! against the definition, not to be fast.

use std::collections::{BTreeSet, HashMap, VecDeque};

use super::{Policy, Preemption, TaskSet, Yield};

/// A task's job.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Stage {
    /// No job: nothing released, or its last job is done.
    Idle,
    /// Released, waiting for a core (or preempted: its running codel waits with it).
    Ready,
    /// Holding a core.
    Running,
}

/// Where a task machine is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Position {
    /// Waiting for the task's next period boundary to run this codel (the initial
    /// position is `Paused(0)`: `start` runs at the first boundary).
    Paused(usize),
    /// This codel may start in the current job.
    Runnable(usize),
    /// This codel has started and not finished: it runs while its task holds a core.
    Running(usize),
    /// The machine is done (a codel failed): the task never has work again.
    Ended,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TaskState {
    pub stage: Stage,
    pub position: Position,
    /// Units the running codel has held its core; 0 when no codel runs.
    pub x: u64,
    /// A period boundary passed while the job was ready or running (0 when idle).
    pub late: bool,
}

/// A state of the timed semantics: all it stores.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Projected {
    /// The time modulo the hyperperiod, in units.
    pub n: u64,
    /// The current instant is a period boundary of some tasks and their release has not
    /// happened yet: one zero-time step for all of them, in any order among the instant's
    /// other zero-time steps.
    pub due: bool,
    /// In the task set's order.
    pub tasks: Vec<TaskState>,
}

/// What the semantics answers for a task set.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Verdict {
    /// No reachable state has a job past its deadline.
    pub schedulable: bool,
    /// Per task, the largest elapsed time of a job when it is done, in units, None for a
    /// task none of whose jobs ever ends: its response time where it does not coalesce.
    pub worst_response: Vec<Option<u64>>,
    /// Per task, whether a reachable state releases its boundary while its job, already
    /// late, is ready or running: two late boundaries count as one, and its elapsed time
    /// (so its worst response) falls a period short from then on.
    pub coalesces: Vec<bool>,
    /// Per task, whether a reachable state has its job past its deadline.
    pub can_miss: Vec<bool>,
    /// The earliest time, in units from the start, at which a job can be past its
    /// deadline.
    pub earliest_miss: Option<u64>,
    /// Every reachable state.
    pub states: BTreeSet<Projected>,
}

/// A step of the semantics: what it leads to, whether it is the tick, and the response
/// time it ends (a job done: (task, elapsed)).
struct Successor {
    to: Projected,
    tick: bool,
    response: Option<(usize, u64)>,
}

struct Interp<'a> {
    set: &'a TaskSet,
    hyper: u64,
}

impl Interp<'_> {
    /// Whether time `n` (modulo the hyperperiod) is a period boundary of task `t`.
    fn boundary(&self, n: u64, t: usize) -> bool {
        let (p, d) = (self.set.period(t), self.set.delay(t));
        n % p == d % p
    }

    /// The elapsed time of task `t`'s job: late·P + ((n − d) mod P), plus P while the
    /// boundary at n is due and not yet released.
    fn elapsed(&self, s: &Projected, t: usize) -> u64 {
        let (p, d) = (self.set.period(t), self.set.delay(t));
        let since = (s.n + p - d % p) % p;
        let due = s.due && self.boundary(s.n, t);
        u64::from(s.tasks[t].late) * p + u64::from(due) * p + since
    }

    fn misses(&self, s: &Projected, t: usize) -> bool {
        s.tasks[t].stage != Stage::Idle && self.elapsed(s, t) > self.set.deadline(t)
    }

    /// Whether a core is free for task `t`: its pinned core runs no task, or (global)
    /// fewer tasks of its CPU run than it has cores.
    fn core_free(&self, s: &Projected, t: usize) -> bool {
        let task = &self.set.tasks[t];
        let running = |u: usize| s.tasks[u].stage == Stage::Running;
        let sharing = |u: usize| {
            let other = &self.set.tasks[u];
            other.cpu == task.cpu && other.core == task.core
        };
        let busy = (0..s.tasks.len())
            .filter(|&u| sharing(u) && running(u))
            .count();
        match task.core {
            Some(_) => busy == 0,
            None => busy < self.set.cpus[task.cpu].cores,
        }
    }

    /// Whether ready task `u` comes before ready task `t` in the dispatch order of their
    /// CPU: a higher priority, or under EDF an earlier absolute deadline (release + D, the
    /// same as a smaller D − elapsed now), ties by declaration order.
    fn before(&self, s: &Projected, u: usize, t: usize) -> bool {
        match self.set.cpus[self.set.tasks[t].cpu].policy {
            Policy::FixedPriority => self.set.tasks[u].priority > self.set.tasks[t].priority,
            Policy::Edf => {
                let left = |v: usize| self.set.deadline(v) as i64 - self.elapsed(s, v) as i64;
                (left(u), u) < (left(t), t)
            }
        }
    }

    /// Tasks `t` and `u` compete for the same cores: the same CPU, pinned to the same core
    /// or both global.
    fn compete(&self, t: usize, u: usize) -> bool {
        let (a, b) = (&self.set.tasks[t], &self.set.tasks[u]);
        t != u && a.cpu == b.cpu && a.core == b.core
    }

    /// Ready task `t` comes first among the ready tasks competing with it.
    fn first_ready(&self, s: &Projected, t: usize) -> bool {
        s.tasks[t].stage == Stage::Ready
            && !(0..s.tasks.len()).any(|u| {
                self.compete(t, u) && s.tasks[u].stage == Stage::Ready && self.before(s, u, t)
            })
    }

    /// Ready task `t` takes a core: one is free, and no ready task that competes for it
    /// (same CPU, same pinned core or both global) comes before it.
    fn may_dispatch(&self, s: &Projected, t: usize) -> bool {
        self.first_ready(s, t) && self.core_free(s, t)
    }

    /// The preemption of the CPU of task `t`.
    fn preemption(&self, t: usize) -> Preemption {
        self.set.cpus[self.set.tasks[t].cpu].preemption
    }

    /// Task `t` is more urgent than task `u`, enough to take its core: a higher priority,
    /// or under EDF a strictly earlier absolute deadline.
    fn urgent(&self, s: &Projected, t: usize, u: usize) -> bool {
        match self.set.cpus[self.set.tasks[t].cpu].policy {
            Policy::FixedPriority => self.set.tasks[t].priority > self.set.tasks[u].priority,
            Policy::Edf => {
                let left = |v: usize| self.set.deadline(v) as i64 - self.elapsed(s, v) as i64;
                left(t) < left(u)
            }
        }
    }

    /// Running task `u`, between two codels of its job on a CPU with `preemption: Codel`,
    /// gives its core to a ready task: one competing with it is more urgent, and no core
    /// is free for it (any such running task gives its core at its first codel boundary,
    /// not only the least urgent one).
    fn yields(&self, s: &Projected, u: usize) -> bool {
        self.preemption(u) == Preemption::Codel
            && (0..s.tasks.len()).any(|t| {
                self.compete(t, u)
                    && s.tasks[t].stage == Stage::Ready
                    && self.urgent(s, t, u)
                    && !self.core_free(s, t)
            })
    }

    /// The running tasks that ready task `t` may preempt (`preemption: Preemptive`): it
    /// comes first among the ready, no core is free for it, and each comes last among the
    /// running tasks competing with it, is less urgent than `t`, has work left in its job
    /// (else its job ends first), and is not at the end of a codel's WCET (a codel that
    /// has run its WCET is done: it finishes first).
    fn victims(&self, s: &Projected, t: usize) -> Vec<usize> {
        if self.preemption(t) != Preemption::Preemptive
            || !self.first_ready(s, t)
            || self.core_free(s, t)
        {
            return Vec::new();
        }
        let running = |u: usize| self.compete(t, u) && s.tasks[u].stage == Stage::Running;
        (0..s.tasks.len())
            .filter(|&u| {
                running(u)
                    && matches!(
                        s.tasks[u].position,
                        Position::Runnable(_) | Position::Running(_)
                    )
                    && self.urgent(s, t, u)
                    && !self.at_wcet(s, u)
                    && !(0..s.tasks.len()).any(|v| v != u && running(v) && self.before(s, u, v))
            })
            .collect()
    }

    /// Task `t`'s running codel has held a core for its WCET.
    fn at_wcet(&self, s: &Projected, t: usize) -> bool {
        let ts = s.tasks[t];
        match ts.position {
            Position::Running(c) => ts.x == self.set.window(t, c).1,
            _ => false,
        }
    }

    /// Codel `c` of task `t` may take its locks: no other task's running codel holds one
    /// of them (a task runs one codel at a time, so its own never do).
    fn locks_free(&self, s: &Projected, t: usize, c: usize) -> bool {
        let locks = |task: usize, codel: usize| {
            let module = self.set.tasks[task].module;
            self.set.tasks[task].codels[codel]
                .uses
                .iter()
                .map(move |&name| super::lock(module, name))
        };
        (0..s.tasks.len()).all(|u| match s.tasks[u].position {
            Position::Running(k) if u != t => {
                !locks(u, k).any(|held| locks(t, c).any(|wanted| wanted == held))
            }
            _ => true,
        })
    }

    /// The task's work released: a paused codel becomes runnable and the task ready; an
    /// ended machine has none, and the task stays idle.
    fn release(task: &mut TaskState) {
        if let Position::Paused(c) = task.position {
            task.position = Position::Runnable(c);
            task.stage = Stage::Ready;
        }
    }

    /// The release at a period boundary: each task whose boundary it is has its work
    /// released if idle, or its job marked late.
    fn release_due(&self, s: &Projected) -> Projected {
        let mut to = s.clone();
        to.due = false;
        for (t, k) in to.tasks.iter_mut().enumerate() {
            if self.boundary(s.n, t) {
                match k.stage {
                    Stage::Idle => Self::release(k),
                    Stage::Ready | Stage::Running => k.late = true,
                }
            }
        }
        to
    }

    /// Every zero-time step, of every task.
    fn zero_time(&self, s: &Projected, out: &mut Vec<Successor>) {
        if s.due {
            out.push(Successor {
                to: self.release_due(s),
                tick: false,
                response: None,
            });
        }
        for t in 0..s.tasks.len() {
            let ts = s.tasks[t];
            let mut go = |f: &dyn Fn(&mut TaskState), response: Option<(usize, u64)>| {
                let mut to = s.clone();
                f(&mut to.tasks[t]);
                out.push(Successor {
                    to,
                    tick: false,
                    response,
                });
            };
            match (ts.stage, ts.position) {
                (Stage::Ready, _) if self.may_dispatch(s, t) => {
                    go(&|k| k.stage = Stage::Running, None)
                }
                (Stage::Ready, _) => {
                    for u in self.victims(s, t) {
                        let mut to = s.clone();
                        to.tasks[t].stage = Stage::Running;
                        to.tasks[u].stage = Stage::Ready;
                        out.push(Successor {
                            to,
                            tick: false,
                            response: None,
                        });
                    }
                }
                // between two codels, a more urgent ready task takes the core
                (Stage::Running, Position::Runnable(_)) if self.yields(s, t) => {
                    go(&|k| k.stage = Stage::Ready, None)
                }
                // a codel waiting for a lock keeps its task's core
                (Stage::Running, Position::Runnable(c)) if self.locks_free(s, t, c) => go(
                    &|k| {
                        k.position = Position::Running(c);
                        k.x = 0;
                    },
                    None,
                ),
                (Stage::Running, Position::Running(c)) => {
                    let (bcet, _) = self.set.window(t, c);
                    if ts.x >= bcet {
                        for y in &self.set.tasks[t].codels[c].yields {
                            let next = match *y {
                                Yield::Next(n) => Position::Runnable(n),
                                Yield::Pause(n) => Position::Paused(n),
                            };
                            go(
                                &|k| {
                                    k.position = next;
                                    k.x = 0;
                                },
                                None,
                            );
                        }
                        go(
                            &|k| {
                                k.position = Position::Ended;
                                k.x = 0;
                            },
                            None,
                        );
                    }
                }
                // nothing runnable in this job: it is done
                (Stage::Running, Position::Paused(_) | Position::Ended) => go(
                    &|k| {
                        k.stage = Stage::Idle;
                        if k.late {
                            k.late = false;
                            Self::release(k);
                        }
                    },
                    Some((t, self.elapsed(s, t))),
                ),
                _ => {}
            }
        }
    }

    /// Time may pass: no zero-time step is pending but finishes before the wcet.
    fn may_tick(&self, s: &Projected) -> bool {
        !s.due
            && (0..s.tasks.len()).all(|t| {
                let ts = s.tasks[t];
                let pending = match (ts.stage, ts.position) {
                    (Stage::Ready, _) => self.may_dispatch(s, t) || !self.victims(s, t).is_empty(),
                    (Stage::Running, Position::Running(_)) => self.at_wcet(s, t),
                    (Stage::Running, Position::Runnable(c)) => {
                        self.yields(s, t) || self.locks_free(s, t, c)
                    }
                    (Stage::Running, _) => true,
                    (Stage::Idle, _) => false,
                };
                !pending
            })
    }

    /// One unit passes; if the new time is a period boundary, its release is due.
    fn tick(&self, s: &Projected) -> Projected {
        let mut to = s.clone();
        to.n = (s.n + 1) % self.hyper;
        for k in to.tasks.iter_mut() {
            // a preempted codel waits
            if k.stage == Stage::Running && matches!(k.position, Position::Running(_)) {
                k.x += 1;
            }
        }
        to.due = (0..to.tasks.len()).any(|t| self.boundary(to.n, t));
        to
    }

    fn successors(&self, s: &Projected) -> Vec<Successor> {
        let mut out = Vec::new();
        self.zero_time(s, &mut out);
        if self.may_tick(s) {
            out.push(Successor {
                to: self.tick(s),
                tick: true,
                response: None,
            });
        }
        out
    }
}

/// Every behaviour of the task set, explored state by state from time 0 (every task idle,
/// its machine paused before `start`). Each state is first reached at its earliest time
/// (ticks cost one unit, other steps none), which gives [`Verdict::earliest_miss`].
pub fn explore(set: &TaskSet) -> Verdict {
    let interp = Interp {
        set,
        hyper: set.hyperperiod(),
    };
    let initial = Projected {
        n: 0,
        due: false,
        tasks: vec![
            TaskState {
                stage: Stage::Idle,
                position: Position::Paused(0),
                x: 0,
                late: false,
            };
            set.tasks.len()
        ],
    };
    let count = set.tasks.len();
    let mut worst: Vec<Option<u64>> = vec![None; count];
    let mut can_miss = vec![false; count];
    let mut coalesces = vec![false; count];
    let mut earliest_miss: Option<u64> = None;
    // earliest time of each state; zero-time steps go to the front of the queue
    let mut time: HashMap<Projected, u64> = HashMap::new();
    let mut queue = VecDeque::from([(initial.clone(), 0u64)]);
    time.insert(initial, 0);
    while let Some((s, now)) = queue.pop_front() {
        if time[&s] < now {
            continue;
        }
        for (t, miss) in can_miss.iter_mut().enumerate() {
            if interp.misses(&s, t) {
                *miss = true;
                earliest_miss = Some(earliest_miss.map_or(now, |e| e.min(now)));
            }
        }
        for (t, k) in s.tasks.iter().enumerate() {
            if s.due && interp.boundary(s.n, t) && k.stage != Stage::Idle && k.late {
                coalesces[t] = true;
            }
        }
        for succ in interp.successors(&s) {
            if let Some((t, r)) = succ.response {
                worst[t] = Some(worst[t].map_or(r, |w| w.max(r)));
            }
            let at = now + u64::from(succ.tick);
            if time.get(&succ.to).is_some_and(|&known| known <= at) {
                continue;
            }
            time.insert(succ.to.clone(), at);
            if succ.tick {
                queue.push_back((succ.to, at));
            } else {
                queue.push_front((succ.to, at));
            }
        }
    }
    Verdict {
        schedulable: !can_miss.iter().any(|&m| m),
        worst_response: worst,
        coalesces,
        can_miss,
        earliest_miss,
        states: time.into_keys().collect(),
    }
}
