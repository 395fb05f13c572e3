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

use std::borrow::Cow;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use bip_model::eval::{Env, Expr};
use bip_model::{
    Liveness, LivenessChecker, OwnedStep, Property, PropertyKind as ModelKind, State, Steps,
    System, Trace,
};
use rayon::prelude::*;

use crate::error::VerifyError;
use crate::memory;
use crate::options::Options;
use crate::progress::Progress;
use crate::properties::{checked_properties, default_terminal, error_step, RANGE_ERRORS};
use crate::report::{CheckKind, Method, PropertyResult, PropertyVerdict, Report, RunStats, Stop};
use crate::visited::{hash, shard_of, Chunk, ShardFull, StateId, Visited, SHARDS};
use crate::watch::Watch;

/// States per chunk: large enough to amortise scheduling, small enough to balance.
const CHUNK_STATES: u32 = 1024;
/// Chunks per worker in one batch; limits are checked between batches.
const CHUNKS_PER_WORKER: usize = 8;
/// Memory the liveness checker of one worker may use for its memory of states.
const LIVENESS_MEMO_BYTES: usize = 32 << 20;
/// Successors fired between two looks at the limits, within one state (a state of a wide
/// model has as many successors as components).
const SUCCESSORS_PER_LOOK: usize = 256;
/// Candidate records a chunk finds before it announces them (bytes, records).
const ANNOUNCED_BYTES: usize = 64 << 10;
const ANNOUNCED_RECORDS: usize = 256;
/// A candidate record is held three times before it is stored: found, sorted by shard,
/// and stored; announced to the watch at that cost.
const RECORD_COPIES: u64 = 3;

/// What one property checks, with its compiled expression.
enum Check<'a> {
    Deadlock { terminal: Option<&'a Expr> },
    Invariant(&'a Expr),
    Reachable(&'a Expr),
    RangeErrors,
}

struct Target<'a> {
    name: String,
    kind: CheckKind,
    expr: String,
    check: Check<'a>,
}

/// The properties a run checks: the model's (deadlock freedom if it has none), and range
/// errors, which are always checked.
fn targets(system: &System) -> Vec<Target<'_>> {
    let mut out: Vec<Target<'_>> = checked_properties(system)
        .into_iter()
        .map(|p| {
            let (kind, check) = match &p {
                Cow::Borrowed(Property { kind, .. }) => match kind {
                    ModelKind::DeadlockFree { terminal } => (
                        CheckKind::DeadlockFree,
                        Check::Deadlock {
                            terminal: terminal.as_ref(),
                        },
                    ),
                    ModelKind::Invariant(e) => (CheckKind::Invariant, Check::Invariant(e)),
                    ModelKind::Reachable(e) => (CheckKind::Reachable, Check::Reachable(e)),
                },
                // the default property, which borrows nothing from the system's list
                Cow::Owned(_) => (
                    CheckKind::DeadlockFree,
                    Check::Deadlock {
                        terminal: default_terminal(system),
                    },
                ),
            };
            Target {
                name: p.name.clone(),
                kind,
                expr: p.text.clone(),
                check,
            }
        })
        .collect();
    out.push(Target {
        name: RANGE_ERRORS.into(),
        kind: CheckKind::RangeErrors,
        expr: String::new(),
        check: Check::RangeErrors,
    });
    out
}

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
#[derive(Default)]
struct ChunkOut {
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
}

impl ChunkOut {
    fn reset(&mut self, targets: usize) {
        self.cut = false;
        self.raw.clear();
        self.sorted.clear();
        self.offsets.clear();
        self.transitions = 0;
        self.findings.clear();
        self.findings.resize(targets, None);
        self.liveness_unknown = 0;
    }

    fn allocated(&self) -> usize {
        self.raw.capacity() + self.sorted.capacity() + self.offsets.capacity() * 4
    }

    /// Groups the raw records by shard (a counting sort, stable: order within a shard is
    /// the order found).
    fn sort_by_shard(&mut self, rec: usize) {
        let n = self.raw.len() / rec;
        self.offsets.clear();
        self.offsets.resize(SHARDS + 1, 0);
        for r in self.raw.chunks_exact(rec) {
            self.offsets[shard_of(read_hash(r)) + 1] += 1;
        }
        for s in 0..SHARDS {
            self.offsets[s + 1] += self.offsets[s];
        }
        let mut next: Vec<u32> = self.offsets[..SHARDS].to_vec();
        self.sorted.clear();
        self.sorted.resize(n * rec, 0);
        for r in self.raw.chunks_exact(rec) {
            let s = shard_of(read_hash(r));
            let at = next[s] as usize * rec;
            self.sorted[at..at + rec].copy_from_slice(r);
            next[s] += 1;
        }
    }

    fn bucket(&self, shard: usize, rec: usize) -> &[u8] {
        if self.offsets.is_empty() {
            return &[];
        }
        &self.sorted[self.offsets[shard] as usize * rec..self.offsets[shard + 1] as usize * rec]
    }
}

fn read_hash(rec: &[u8]) -> u64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&rec[..8]);
    u64::from_le_bytes(b)
}

fn read_parent(rec: &[u8]) -> u32 {
    let mut b = [0u8; 4];
    b.copy_from_slice(&rec[8..12]);
    u32::from_le_bytes(b)
}

const REC_HEADER: usize = 12;

/// Verifies every property of `system` by explicit-state exploration.
///
/// `progress` is called from time to time (about four times a second) during long runs.
pub(crate) fn verify(
    system: &System,
    options: &Options,
    progress: &(dyn Fn(&Progress) + Sync),
) -> Result<Report, VerifyError> {
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
    let watch = Watch::new(options, options.max_memory.or_else(memory::default_limit));
    watch.around(
        || {},
        || pool.install(|| Explorer::new(system, options, jobs, &watch).run(progress)),
    )
}

struct Explorer<'a> {
    system: &'a System,
    options: &'a Options,
    jobs: usize,
    targets: Vec<Target<'a>>,
    visited: Visited,
    scratch: Vec<Mutex<Scratch>>,
    outs: Vec<ChunkOut>,
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

impl<'a> Explorer<'a> {
    fn new(
        system: &'a System,
        options: &'a Options,
        jobs: usize,
        watch: &'a Watch,
    ) -> Explorer<'a> {
        let targets = targets(system);
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
        Explorer {
            system,
            options,
            jobs,
            targets,
            visited: Visited::new(system.layout.bytes()),
            scratch,
            outs: Vec::new(),
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

    fn run(mut self, progress: &(dyn Fn(&Progress) + Sync)) -> Result<Report, VerifyError> {
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
                let before = self.visited.allocated_bytes();
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
                if let Err(ShardFull) = inserted {
                    stopped = Some(Stop::TooManyStates);
                    break 'levels;
                }
                if let Some(stop) = self.watch.stopped() {
                    self.merge_findings(group.len());
                    stopped = Some(stop.clone());
                    break 'levels;
                }
                last_growth = self.visited.allocated_bytes().saturating_sub(before);
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
        self.report(stopped)
    }

    /// A limit that stops the run before the next batch, if any.
    fn limit_reached(&self, last_growth: u64) -> Option<Stop> {
        if let Some(limit) = self.options.max_states {
            if self.visited.len() >= limit {
                return Some(Stop::MaxStates { limit });
            }
        }
        if let Some(limit) = self.watch.max_memory() {
            // the next batch may grow the set by about as much as the last one; leave room
            // for twice that, and for what the process holds besides (read from /proc)
            let projected = self.store_bytes() + 2 * last_growth;
            let resident = memory::resident_bytes().unwrap_or(0) + 2 * last_growth;
            if projected.max(resident) > limit {
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

    fn store_bytes(&self) -> u64 {
        self.visited.allocated_bytes() + self.outs.iter().map(|o| o.allocated() as u64).sum::<u64>()
    }

    /// Phase 1: expands the chunks of a batch in parallel, until they end or a limit is
    /// reached (the run's, or `room` new states found).
    fn expand(&mut self, group: &[Chunk], room: u64) {
        let n = self.targets.len();
        if self.outs.len() < group.len() {
            self.outs.resize_with(group.len(), ChunkOut::default);
        }
        let open: Vec<bool> = self.findings.iter().map(Option::is_none).collect();
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
        };
        let scratch = &self.scratch;
        self.outs[..group.len()]
            .par_iter_mut()
            .zip(group.par_iter())
            .for_each(|(out, chunk)| {
                out.reset(n);
                let worker = rayon::current_thread_index().unwrap_or(0) % scratch.len();
                let mut s = scratch[worker].lock().unwrap_or_else(|p| p.into_inner());
                ctx.expand_chunk(*chunk, &mut s, out);
            });
        self.outs.truncate(group.len());
    }

    /// Phase 2: stores the new states, shards in parallel, chunks in order within a shard.
    /// A shard stops early if the run must stop (what it stored is consistent: states
    /// with their parents).
    fn insert(&mut self) -> Result<(), ShardFull> {
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
                        shard.insert(read_hash(r), &r[REC_HEADER..], parent)?;
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

    fn any_failure(&self) -> bool {
        self.findings
            .iter()
            .any(|f| matches!(f, Some(Finding { what, .. }) if !matches!(what, Found::Witness)))
    }

    /// True if no further state can change a verdict.
    fn all_decided(&self) -> bool {
        self.findings.iter().all(Option::is_some)
    }

    fn report(self, stopped: Option<Stop>) -> Result<Report, VerifyError> {
        let seconds = self.started.elapsed().as_secs_f64();
        let states = self.visited.len();
        // the deepest level with a stored state (the run may have stopped before expanding it)
        let depth = (0..self.visited.levels())
            .rev()
            .find(|&l| self.visited.level_len(l) > 0)
            .unwrap_or(0) as u32;
        let complete = stopped.is_none() && !self.stopped_decided;
        let stats = RunStats {
            states,
            complete,
            transitions: self.transitions,
            depth,
            seconds,
            states_per_second: if seconds > 0.0 {
                states as f64 / seconds
            } else {
                0.0
            },
            bytes_per_state: self.visited.used_bytes() as f64 / states.max(1) as f64,
            state_bytes: self.visited.width(),
            store_bytes: self.store_bytes(),
            jobs: self.jobs,
        };
        let mut properties = Vec::with_capacity(self.targets.len());
        for (t, f) in self.targets.iter().zip(&self.findings) {
            let verdict = match f {
                Some(f) => self.verdict_of(t, f)?,
                None => self.open_verdict(t, stopped.as_ref(), states),
            };
            let error_step = verdict.trace().and_then(|tr| error_step(self.system, tr));
            properties.push(PropertyResult {
                name: t.name.clone(),
                kind: t.kind,
                expr: t.expr.clone(),
                verdict,
                method: Method::Explicit,
                note: None,
                error_step,
            });
        }
        tracing::info!(
            states,
            transitions = self.transitions,
            depth,
            seconds,
            expand_seconds = self.expand_time.as_secs_f64(),
            insert_seconds = self.insert_time.as_secs_f64(),
            "explored"
        );
        Ok(Report {
            model: self.system.name.clone(),
            method: Method::Explicit,
            properties,
            stats,
            stopped,
            symbolic: None,
            seconds,
            peak_memory_bytes: None,
        })
    }

    fn verdict_of(&self, t: &Target<'_>, f: &Finding) -> Result<PropertyVerdict, VerifyError> {
        use bip_model::Verdict as TraceVerdict;
        let (trace_verdict, reason) = match &f.what {
            Found::Deadlock => (TraceVerdict::Deadlock, "deadlock".to_string()),
            Found::Violation => (
                TraceVerdict::Violation(t.name.clone()),
                "violated".to_string(),
            ),
            Found::Witness => (TraceVerdict::Witness(t.name.clone()), String::new()),
            Found::RangeError(m) => (
                TraceVerdict::RangeError(m.clone()),
                format!("range error: {m}"),
            ),
        };
        let trace = trace_to(self.system, &self.visited, f.state, trace_verdict)?;
        let n = trace.steps.len();
        let after = format!("after {n} step{}", if n == 1 { "" } else { "s" });
        Ok(match f.what {
            Found::Witness => PropertyVerdict::Holds {
                witness: Some(trace),
            },
            _ => PropertyVerdict::Fails {
                reason: format!("{reason} {after}"),
                trace: Some(trace),
            },
        })
    }

    /// The verdict of a property nothing was found about.
    fn open_verdict(&self, t: &Target<'_>, stopped: Option<&Stop>, states: u64) -> PropertyVerdict {
        if let Some(stop) = stopped {
            return PropertyVerdict::Inconclusive {
                reason: format!("{stop} after {states} states"),
            };
        }
        match t.check {
            Check::Reachable(_) => PropertyVerdict::Fails {
                reason: format!("no reachable state satisfies it ({states} states explored)"),
                trace: None,
            },
            Check::Deadlock { .. } if self.liveness_unknown > 0 => PropertyVerdict::Inconclusive {
                reason: format!(
                    "in {} states without a progress step, the states reached by time steps alone exceed the liveness check's bound",
                    self.liveness_unknown
                ),
            },
            _ => PropertyVerdict::Holds { witness: None },
        }
    }
}

/// What phase 1 reads.
struct Ctx<'a, 'b> {
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
}

impl Ctx<'_, '_> {
    fn expand_chunk(&self, chunk: Chunk, s: &mut Scratch, out: &mut ChunkOut) {
        let sys = self.system;
        let layout = &sys.layout;
        let width = self.visited.width();
        let rec = REC_HEADER + width;
        let range_target = self.targets.len() - 1;
        let mut announced = 0usize;
        for local in chunk.start..chunk.end {
            if self.must_stop(out, &mut announced, rec, false) {
                out.cut = true;
                break;
            }
            let id = self.visited.id(chunk.shard, local);
            let current = self.visited.state(id);
            layout.decode(current, &mut s.state);
            let found = |p: usize, what: Found, out: &mut ChunkOut| {
                if out.findings[p].is_none() {
                    out.findings[p] = Some(Finding { state: id, what });
                }
            };
            let mut deadlock_target = None;
            for (p, t) in self.targets.iter().enumerate() {
                if !self.open[p] || out.findings[p].is_some() {
                    continue;
                }
                let (e, wanted, what) = match &t.check {
                    Check::Invariant(e) => (*e, false, Found::Violation),
                    Check::Reachable(e) => (*e, true, Found::Witness),
                    Check::Deadlock { .. } => {
                        deadlock_target = Some(p);
                        continue;
                    }
                    Check::RangeErrors => continue,
                };
                // the context string is built only on an error: this runs for every state
                match e.holds(&mut Env::new(s.state.slots(), 0)) {
                    Ok(v) if v == wanted => found(p, what, out),
                    Ok(_) => {}
                    Err(err) => {
                        let err = sys.range_error(err, &format!("property {}", t.name));
                        found(p, Found::RangeError(err.to_string()), out);
                    }
                }
            }
            if let Err(err) = sys.enabled_steps(&s.state, &mut s.steps) {
                found(range_target, Found::RangeError(err.to_string()), out);
                continue;
            }
            if let Some(p) = deadlock_target {
                match sys.liveness(&s.state, &s.steps, &mut s.checker) {
                    Ok(Liveness::Deadlock) => {
                        let Check::Deadlock { terminal } = &self.targets[p].check else {
                            unreachable!("deadlock_target is a deadlock check")
                        };
                        match terminal
                            .map(|e| sys.holds(e, &s.state, "terminal condition of DeadlockFree"))
                        {
                            None | Some(Ok(false)) => found(p, Found::Deadlock, out),
                            Some(Ok(true)) => {}
                            Some(Err(err)) => found(p, Found::RangeError(err.to_string()), out),
                        }
                    }
                    Ok(Liveness::Unknown) | Err(_) => out.liveness_unknown += 1,
                    Ok(Liveness::Progress | Liveness::AfterTime { .. }) => {}
                }
            }
            let Scratch {
                state,
                next,
                steps,
                packed,
                ..
            } = s;
            for (k, step) in steps.iter().enumerate() {
                if k % SUCCESSORS_PER_LOOK == SUCCESSORS_PER_LOOK - 1
                    && self.must_stop(out, &mut announced, rec, false)
                {
                    // the state is only partly expanded: its chunk ends here
                    out.cut = true;
                    break;
                }
                if let Err(err) = sys.fire(state, step, next) {
                    found(range_target, Found::RangeError(err.to_string()), out);
                    continue;
                }
                out.transitions += 1;
                layout.encode_changed(state, current, next, packed);
                let h = hash(packed);
                if self.visited.find(h, packed).is_none() {
                    out.raw.extend_from_slice(&h.to_le_bytes());
                    out.raw.extend_from_slice(&id.to_bits().to_le_bytes());
                    out.raw.extend_from_slice(packed);
                }
            }
        }
        self.must_stop(out, &mut announced, rec, true);
        // a stopped run inserts nothing: sorting a wide batch's records would cost time
        if self.watch.stopped().is_none() {
            out.sort_by_shard(rec);
        }
    }

    /// Announces the records found since the last call, and says whether the chunk must
    /// stop: a limit of the run is reached, or the batch has found `room` new states.
    /// The records are announced in groups (or all, with `flush`), to keep the shared
    /// counters off the path of every state.
    fn must_stop(&self, out: &ChunkOut, announced: &mut usize, rec: usize, flush: bool) -> bool {
        let new = out.raw.len() - *announced;
        if new >= ANNOUNCED_BYTES || new >= ANNOUNCED_RECORDS * rec || (flush && new > 0) {
            *announced = out.raw.len();
            let records = (new / rec) as u64;
            let found = self.found.fetch_add(records, Ordering::Relaxed) + records;
            if found >= self.room {
                self.full.store(true, Ordering::Relaxed);
            }
            self.watch.expect(new as u64 * RECORD_COPIES);
        }
        self.watch.stopped().is_some() || self.full.load(Ordering::Relaxed)
    }
}

/// The trace from the initial state to stored state `id`. The steps are found again by
/// firing the enabled steps of each state on the path until one leads to the next state.
fn trace_to(
    system: &System,
    visited: &Visited,
    id: StateId,
    verdict: bip_model::Verdict,
) -> Result<Trace, VerifyError> {
    let layout = &system.layout;
    let path = visited.path_to(id);
    let mut steps = Steps::new();
    let mut next = system.initial_state();
    let mut packed = vec![0u8; layout.bytes()];
    let mut out: Vec<(OwnedStep, State)> = Vec::with_capacity(path.len());
    let mut state = layout.unpack(visited.state(path[0]));
    for &to in &path[1..] {
        let target = visited.state(to);
        system.enabled_steps(&state, &mut steps).map_err(|e| {
            VerifyError::Internal(format!("a state on a trace has a range error: {e}"))
        })?;
        let mut taken = None;
        for step in steps.iter() {
            if system.fire(&state, step, &mut next).is_ok() {
                layout.encode(&next, &mut packed);
                if packed == target {
                    taken = Some(step.to_owned());
                    break;
                }
            }
        }
        let step = taken.ok_or_else(|| {
            VerifyError::Internal("no step leads to the next state of a trace".into())
        })?;
        state = next.clone();
        out.push((step, next.clone()));
    }
    Ok(Trace::from_path(system, verdict, &out))
}
