//! Explicit-state verification: breadth-first exploration of the reachable states with the
//! step relation of `bip-model`, level by level, in parallel.
//!
//! Each level is cut into chunks of states in a fixed order (see [`Visited::chunks`]), and
//! chunks are handled in batches, each in two phases:
//!
//! 1. *expand* (chunks in parallel, the visited set read-only): check the properties on each
//!    state of the chunk, compute its steps, fire them, and keep the successors that are not
//!    stored yet as candidates, bucketed by shard;
//! 2. *insert* (shards in parallel): each shard takes its candidates, chunk by chunk in order,
//!    and stores the new ones with their parent.
//!
//! Every state of level `d` is checked before any of level `d + 1`, so the first state found
//! violating a property is at the smallest depth, and following parent links gives a
//! shortest counterexample. States are numbered and findings chosen in chunk order, which
//! does not depend on the number of workers: a run with one worker and a run with eight
//! store the same states under the same numbers and report the same traces.
//!
//! This module holds the driver (levels, batches, the two phases, the limits) and the
//! data it hands each batch; `expand` is phase 1 on one chunk, `targets` the properties a
//! run checks and how its findings become verdicts and traces, `graph` the state graph,
//! which phase 1 records as it goes when a question about paths needs it, `response`
//! the response properties and time progress, decided on it once the exploration is
//! complete, `worst` the timed tasks' worst responses, which phase 1 gathers too: one
//! pass computes each state's steps for every question. [`on_state_graph`] explores and
//! records the graph for questions asked elsewhere (the scheduling analysis's demands).

mod expand;
pub(crate) mod graph;
mod response;
pub(crate) mod scc;
mod targets;
#[cfg(test)]
mod tests;
mod trace;
mod worst;

use std::sync::atomic::{AtomicBool, AtomicU64};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use bip_model::{LivenessChecker, State, Steps, System};
use rayon::prelude::*;

use crate::error::VerifyError;
use crate::memory;
use crate::options::Options;
use crate::progress::Progress;
use crate::report::{Report, Stop};
use crate::visited::{Chunk, Refused, StateId, Visited};
use crate::watch::Watch;

use expand::{read_hash, read_parent, REC_HEADER};
use graph::{Graph, Keep, Recorder, Rows};
use targets::{asks_paths, range_errors, targets, watched, watching, Target};
use worst::{Seen, Tasks};

/// States per chunk: large enough to amortise scheduling, small enough to balance.
const CHUNK_STATES: u32 = 1024;
/// Chunks per worker in one batch; limits are checked between batches.
const CHUNKS_PER_WORKER: usize = 8;
/// Memory the liveness checker of one worker may use for its memory of states.
const LIVENESS_MEMO_BYTES: usize = 32 << 20;
/// Successors fired between two looks at the limits, within one state (a state of a wide
/// model has as many successors as components).
const SUCCESSORS_PER_LOOK: usize = 256;

/// What was found about a property in a state.
#[derive(Clone, Debug)]
struct Finding {
    state: StateId,
    what: Found,
}

#[derive(Clone, Debug)]
enum Found {
    Deadlock,
    Violation,
    Witness,
    RangeError(String),
}

/// Per-worker scratch, reused across chunks.
struct Scratch {
    state: State,
    next: State,
    steps: Steps,
    checker: LivenessChecker,
    packed: Vec<u8>,
}

/// The output of expanding one chunk.
struct ChunkOut<K: Keep> {
    /// Candidate records `[hash: 8][parent: 4][packed state]`, in the order found...
    raw: Vec<u8>,
    /// ... and grouped by shard: shard `s` holds records `offsets[s]..offsets[s + 1]`.
    sorted: Vec<u8>,
    offsets: Vec<u32>,
    transitions: u64,
    findings: Vec<Option<Finding>>,
    liveness_unknown: u64,
    /// The chunk stopped before its end because a limit was reached.
    cut: bool,
    /// The chunk's rows of the state graph, when the run records it.
    rows: Option<Rows<K::Edge, K::Notes>>,
    /// What the chunk's states show of the tasks whose worst responses the run gives,
    /// or the first state whose steps could not be computed.
    seen: Result<Vec<Seen>, String>,
}

/// Verifies every property of `system` by explicit-state exploration.
///
/// `progress` is called from time to time (about four times a second) during long runs.
pub(crate) fn verify(
    system: &System,
    options: &Options,
    progress: &(dyn Fn(&Progress) + Sync),
) -> Result<Report, VerifyError> {
    let (pool, jobs) = workers(options)?;
    let watch = Watch::new(options, options.max_memory.or_else(memory::default_limit));
    let targets = targets(system);
    let watched = watched(&targets);
    let watching = watching(system, &targets, &watched);
    // the state graph is recorded only for a question about paths
    let keep = asks_paths(&targets).then_some(&watching);
    watch.around(
        || {},
        || {
            pool.install(|| {
                Explorer::new(system, options, jobs, &watch, targets, keep).run(progress)
            })
        },
    )
}

/// Why [`on_state_graph`] gave no answer.
#[derive(Debug)]
pub(crate) enum Unanswered {
    /// A limit of the run was reached: in the exploration, the storing or the answer.
    Stopped(Stop),
    /// A state has a range error: the first in the exploration's order.
    RangeError(String),
    Failed(VerifyError),
}

/// Explores every reachable state of `system`, checking range errors only, records the
/// graph of its steps with what `keep` keeps of them, and answers `question` on it: for
/// questions about paths rather than states. Every limit of `options` holds, in the
/// exploration, in the storing, and in `question`, which polls the watch it is given
/// and returns `None` once it says stop.
pub(crate) fn on_state_graph<K: Keep, R: Send>(
    system: &System,
    options: &Options,
    keep: &K,
    question: impl FnOnce(Graph<K::Edge, K::Notes>, &Watch) -> Option<R> + Send,
) -> Result<R, Unanswered> {
    // a range error leaves steps out of the graph: the first one ends the run
    let options = Options {
        stop_at_first: true,
        ..options.clone()
    };
    let (pool, jobs) = workers(&options).map_err(Unanswered::Failed)?;
    let watch = Watch::new(&options, options.max_memory.or_else(memory::default_limit));
    let stored = || {
        let targets = vec![range_errors()];
        let mut explorer = Explorer::new(system, &options, jobs, &watch, targets, Some(keep));
        let stopped = explorer
            .explore(&|_: &Progress| {})
            .map_err(Unanswered::Failed)?;
        if let Some(Finding {
            what: Found::RangeError(message),
            ..
        }) = &explorer.findings[0]
        {
            return Err(Unanswered::RangeError(message.clone()));
        }
        if let Some(stop) = stopped {
            return Err(Unanswered::Stopped(stop));
        }
        // the explorer's buffers are freed before the question is asked
        let Explorer {
            visited, recorder, ..
        } = explorer;
        watch.rebase();
        let stopped = |what: &str| match watch.stopped() {
            Some(stop) => Unanswered::Stopped(stop.clone()),
            None => Unanswered::Failed(VerifyError::Internal(what.into())),
        };
        let graph = recorder
            .and_then(|r| r.finish(&visited, &watch))
            .ok_or_else(|| stopped("a successor of an explored state is not recorded"))?;
        drop(visited);
        watch.rebase();
        question(graph, &watch).ok_or_else(|| stopped("the question on the graph failed"))
    };
    watch.around(|| {}, || pool.install(stored))
}

/// The pool of `options.jobs` workers (one per core for 0), and their number.
fn workers(options: &Options) -> Result<(rayon::ThreadPool, usize), VerifyError> {
    let jobs = if options.jobs == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        options.jobs
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .thread_name(|i| format!("bip-verify-{i}"))
        .build()
        .map_err(|e| VerifyError::Threads(e.to_string()))?;
    Ok((pool, jobs))
}

struct Explorer<'a, K: Keep> {
    system: &'a System,
    options: &'a Options,
    jobs: usize,
    targets: Vec<Target<'a>>,
    visited: Visited,
    scratch: Vec<Mutex<Scratch>>,
    outs: Vec<ChunkOut<K>>,
    /// The state graph recorded so far, when a question about paths needs it.
    recorder: Option<Recorder<'a, K>>,
    /// The graph may be dropped when it does not fit, to decide the other properties
    /// (else the run is for the graph, and stops)...
    may_drop_graph: bool,
    /// ... and it was.
    graph_dropped: bool,
    /// The tasks whose worst responses the run gives, and what the states expanded so
    /// far show of them (the first state whose steps could not be computed, if any).
    tasks: Tasks,
    seen: Result<Vec<Seen>, String>,
    findings: Vec<Option<Finding>>,
    liveness_unknown: u64,
    transitions: u64,
    depth: u32,
    watch: &'a Watch,
    started: Instant,
    /// Time spent in each phase, for `-v` logs and profiles.
    expand_time: Duration,
    insert_time: Duration,
    /// The run ended early because every verdict was final.
    stopped_decided: bool,
}

impl<'a, K: Keep> Explorer<'a, K> {
    fn new(
        system: &'a System,
        options: &'a Options,
        jobs: usize,
        watch: &'a Watch,
        targets: Vec<Target<'a>>,
        keep: Option<&'a K>,
    ) -> Explorer<'a, K> {
        let slots = system.slot_count();
        let memo = (LIVENESS_MEMO_BYTES / (slots * 8 + 64)).clamp(1_000, 1_000_000);
        let scratch = (0..jobs)
            .map(|_| {
                let mut checker = LivenessChecker::default();
                checker.max_memo = memo;
                if options.liveness_bound > 0 {
                    checker.max_time_states = options.liveness_bound;
                }
                Mutex::new(Scratch {
                    state: system.initial_state(),
                    next: system.initial_state(),
                    steps: Steps::new(),
                    checker,
                    packed: vec![0; system.layout.bytes()],
                })
            })
            .collect();
        let n = targets.len();
        let tasks = Tasks::of(system);
        Explorer {
            system,
            options,
            jobs,
            targets,
            visited: Visited::new(system.layout.bytes()),
            scratch,
            outs: Vec::new(),
            recorder: keep.map(Recorder::new),
            // a run that checks range errors alone is for the graph (`on_state_graph`)
            may_drop_graph: n > 1,
            graph_dropped: false,
            seen: Ok(tasks.unseen()),
            tasks,
            findings: vec![None; n],
            liveness_unknown: 0,
            transitions: 0,
            depth: 0,
            watch,
            started: watch.started(),
            expand_time: Duration::ZERO,
            insert_time: Duration::ZERO,
            stopped_decided: false,
        }
    }

    /// Explores level by level until every state is, or the run must stop (why, then).
    fn explore(
        &mut self,
        progress: &(dyn Fn(&Progress) + Sync),
    ) -> Result<Option<Stop>, VerifyError> {
        let initial = self.system.layout.pack(&self.system.initial_state());
        self.visited.start_level();
        if self.visited.insert(&initial, StateId::NONE).is_err() {
            return Err(VerifyError::Internal(
                "cannot store the initial state".into(),
            ));
        }
        let batch = self.jobs * CHUNKS_PER_WORKER;
        let mut last_progress = Instant::now();
        let mut last_growth = 0u64;
        let mut stopped = None;
        let mut level = 0usize;
        'levels: loop {
            let chunks = self.visited.chunks(level, CHUNK_STATES);
            if chunks.is_empty() {
                break;
            }
            self.depth = level as u32;
            let level_states = self.visited.level_len(level);
            let mut level_done = 0u64;
            self.visited.start_level();
            let mut groups = chunks.chunks(batch);
            let mut next_group = groups.next();
            while let Some(group) = next_group {
                if let Some(stop) = self.limit_reached(last_growth) {
                    stopped = Some(stop);
                    break 'levels;
                }
                let before = self.kept_bytes();
                let t0 = Instant::now();
                let room = self.room();
                self.expand(group, room);
                let t1 = Instant::now();
                self.expand_time += t1 - t0;
                let cut = self.outs.iter().any(|o| o.cut);
                if let Some(stop) = self.watch.stopped() {
                    // the states expanded so far were checked: keep what was found
                    self.merge_findings(group.len());
                    stopped = Some(stop.clone());
                    break 'levels;
                }
                let inserted = self.insert();
                self.insert_time += t1.elapsed();
                if let Err(Refused::ShardFull) = inserted {
                    stopped = Some(Stop::TooManyStates);
                    break 'levels;
                }
                if let Some(stop) = self.watch.stopped() {
                    self.merge_findings(group.len());
                    stopped = Some(stop.clone());
                    break 'levels;
                }
                last_growth = self.kept_bytes().saturating_sub(before);
                if cut {
                    // the batch stopped at the state limit; if the states it found were
                    // fewer (duplicates), expand it again: the stored ones are known now
                    if let Some(stop) = self.limit_reached(0) {
                        self.merge_findings(group.len());
                        stopped = Some(stop);
                        break 'levels;
                    }
                    continue;
                }
                next_group = groups.next();
                self.merge_findings(group.len());
                if !self.record(group)? {
                    stopped = self.watch.stopped().cloned();
                    break 'levels;
                }
                level_done += group
                    .iter()
                    .map(|c| u64::from(c.end - c.start))
                    .sum::<u64>();
                if self.options.stop_at_first && self.any_failure() {
                    stopped = Some(Stop::FirstFailure);
                    break 'levels;
                }
                // finish the level first: where a batch ends depends on the worker count,
                // and the states stored must not
                if self.all_decided() {
                    self.stopped_decided = true;
                }
                if last_progress.elapsed() >= Duration::from_millis(250) {
                    last_progress = Instant::now();
                    progress(&Progress::Exploring {
                        states: self.visited.len(),
                        transitions: self.transitions,
                        depth: self.depth,
                        level_states,
                        level_done,
                        elapsed: self.started.elapsed(),
                        store_bytes: self.store_bytes(),
                    });
                }
            }
            if self.stopped_decided {
                break;
            }
            level += 1;
        }
        Ok(stopped)
    }

    /// A limit that stops the run before the next batch, if any. In a run that decides
    /// other properties besides those the graph answers, a graph that would pass the
    /// memory limit is dropped first (those properties stay open: see `report`).
    fn limit_reached(&mut self, last_growth: u64) -> Option<Stop> {
        if let Some(limit) = self.options.max_states {
            if self.visited.len() >= limit {
                return Some(Stop::MaxStates { limit });
            }
        }
        if let Some(limit) = self.watch.max_memory() {
            // the next batch may grow the set by about as much as the last one; leave room
            // for twice that, and for what the process holds besides (read from /proc)
            let over = |me: &Self| {
                let projected = me.store_bytes() + me.graph_bytes() + 2 * last_growth;
                let resident = memory::resident_bytes().unwrap_or(0) + 2 * last_growth;
                projected.max(resident) > limit
            };
            if over(self) && self.may_drop_graph && self.recorder.is_some() {
                self.drop_graph();
            }
            if over(self) {
                self.watch.raise(Stop::MaxMemory { limit });
            }
        }
        self.watch.look().cloned()
    }

    /// New states a batch may find before it stops at the state limit: what remains below
    /// the limit, and a margin, so that a batch whose finds are partly duplicates still
    /// reaches the limit.
    fn room(&self) -> u64 {
        self.options.max_states.map_or(u64::MAX, |limit| {
            let left = limit.saturating_sub(self.visited.len());
            left.saturating_add(limit / 16).max(1)
        })
    }

    /// The store of states: the visited set and the buffers of a batch (the figure the
    /// run reports).
    fn store_bytes(&self) -> u64 {
        self.visited.allocated_bytes() + self.outs.iter().map(|o| o.allocated() as u64).sum::<u64>()
    }

    /// The recorded graph's arrays.
    fn graph_bytes(&self) -> u64 {
        self.recorder.as_ref().map_or(0, |r| r.allocated() as u64)
    }

    /// What the run keeps for good: the states and the recorded graph.
    fn kept_bytes(&self) -> u64 {
        self.visited.allocated_bytes() + self.graph_bytes()
    }

    /// Phase 1: expands the chunks of a batch in parallel, until they end or a limit is
    /// reached (the run's, or `room` new states found).
    fn expand(&mut self, group: &[Chunk], room: u64) {
        let n = self.targets.len();
        let keep = self.recorder.as_ref().map(Recorder::keep);
        if self.outs.len() < group.len() {
            self.outs
                .resize_with(group.len(), || ChunkOut::new(keep, &self.tasks));
        }
        let open: Vec<bool> = self.findings.iter().map(Option::is_none).collect();
        // the number of each chunk's first state, in the graph's order
        let mut first = self.recorder.as_ref().map_or(0, Recorder::states);
        let firsts: Vec<u32> = group
            .iter()
            .map(|c| {
                first += c.end - c.start;
                first - (c.end - c.start)
            })
            .collect();
        self.watch.rebase();
        let ctx = Ctx {
            system: self.system,
            targets: &self.targets,
            visited: &self.visited,
            open: &open,
            watch: self.watch,
            room,
            found: AtomicU64::new(0),
            full: AtomicBool::new(false),
            keep,
            tasks: &self.tasks,
        };
        let scratch = &self.scratch;
        self.outs[..group.len()]
            .par_iter_mut()
            .zip(group.par_iter().zip(firsts.par_iter()))
            .for_each(|(out, (chunk, &first))| {
                out.reset(n, keep, ctx.tasks);
                let worker = rayon::current_thread_index().unwrap_or(0) % scratch.len();
                let mut s = scratch[worker].lock().unwrap_or_else(|p| p.into_inner());
                ctx.expand_chunk(*chunk, first, &mut s, out);
            });
        self.outs.truncate(group.len());
    }

    /// Phase 2: stores the new states, shards in parallel, chunks in order within a shard.
    /// A shard stops early if the run must stop (what it stored is consistent: states
    /// with their parents).
    fn insert(&mut self) -> Result<(), Refused> {
        let rec = REC_HEADER + self.visited.width();
        let outs = &self.outs;
        let watch = self.watch;
        let visited = &mut self.visited;
        visited
            .shards_mut()
            .par_iter_mut()
            .enumerate()
            .try_for_each(|(s, shard)| {
                for out in outs {
                    for (k, r) in out.bucket(s, rec).chunks_exact(rec).enumerate() {
                        if k % SUCCESSORS_PER_LOOK == 0 && watch.stopped().is_some() {
                            return Ok(());
                        }
                        let parent = StateId::from_bits(read_parent(r));
                        match shard.insert(read_hash(r), &r[REC_HEADER..], parent) {
                            Err(Refused::NoMemory) => {
                                watch.out_of_memory();
                                return Ok(());
                            }
                            stored => stored?,
                        };
                    }
                }
                Ok(())
            })
    }

    /// Takes, for each open property, the first finding in chunk order.
    fn merge_findings(&mut self, chunks: usize) {
        for out in &self.outs[..chunks] {
            self.transitions += out.transitions;
            self.liveness_unknown += out.liveness_unknown;
            for (mine, theirs) in self.findings.iter_mut().zip(&out.findings) {
                if mine.is_none() {
                    mine.clone_from(theirs);
                }
            }
        }
    }

    /// Gives up the graph, which does not fit, to go on deciding the other properties.
    fn drop_graph(&mut self) {
        tracing::info!(
            graph_bytes = self.graph_bytes(),
            "the state graph does not fit in the memory limit: dropped"
        );
        self.recorder = None;
        for out in &mut self.outs {
            out.rows = None;
        }
        self.graph_dropped = true;
    }

    /// Adds the rows of a stored batch to the graph, and what its states show of the
    /// tasks; false if the run must stop (the graph does not fit, and the run is for it).
    fn record(&mut self, group: &[Chunk]) -> Result<bool, VerifyError> {
        for out in &mut self.outs[..group.len()] {
            if let Ok(seen) = &mut self.seen {
                match &mut out.seen {
                    Ok(later) => worst::merge(seen, later),
                    Err(e) => self.seen = Err(e.clone()),
                }
            }
        }
        let Some(recorder) = &mut self.recorder else {
            return Ok(true);
        };
        let rec = REC_HEADER + self.visited.width();
        let visited = &self.visited;
        let resolved = self.outs[..group.len()]
            .par_iter_mut()
            .all(|out| match &mut out.rows {
                Some(rows) => rows.resolve(visited, &out.raw, rec, REC_HEADER),
                None => false,
            });
        if !resolved {
            return Err(VerifyError::Internal(
                "a successor of a stored batch is not stored".into(),
            ));
        }
        for (out, chunk) in self.outs.iter_mut().zip(group) {
            let Some(rows) = out.rows.as_mut() else {
                continue;
            };
            if !recorder.append(*chunk, visited, rows, self.watch) {
                if !self.may_drop_graph {
                    self.watch.out_of_memory();
                    return Ok(false);
                }
                self.drop_graph();
                return Ok(true);
            }
        }
        Ok(true)
    }

    fn any_failure(&self) -> bool {
        self.findings
            .iter()
            .any(|f| matches!(f, Some(Finding { what, .. }) if !matches!(what, Found::Witness)))
    }

    /// True if no further state can change a verdict.
    fn all_decided(&self) -> bool {
        self.findings.iter().all(Option::is_some)
    }
}

/// What phase 1 reads.
struct Ctx<'a, 'b, K: Keep> {
    system: &'a System,
    targets: &'b [Target<'a>],
    visited: &'b Visited,
    /// The properties still undecided when the batch started.
    open: &'b [bool],
    watch: &'b Watch,
    /// New states the batch may find; `found` counts them (duplicates too) and `full` is
    /// raised once they reach `room`.
    room: u64,
    found: AtomicU64,
    full: AtomicBool,
    /// What the recorded graph keeps, when the run records it.
    keep: Option<&'b K>,
    tasks: &'b Tasks,
}
