//! The response properties (`Response`, `LeadsTo`, `Replies`, `Terminates`), decided on
//! the state graph once the exploration is complete (docs/verify.md, "Response and
//! liveness"): `watched` says what the stored graph (`explore::graph`) keeps for them,
//! `bounded` searches the product with a tick-counting
//! observer, `cycles` searches for runs on which the response never comes, `worst`
//! finds the longest wait for the response in a model with time, `run` holds the paths
//! they return. `timelock` decides time progress on the same graph: the
//! liveness verdicts assume that time diverges, and its timelocked states are where it
//! cannot. A truncated exploration decides none of them.

mod bounded;
mod cycles;
mod run;
mod timelock;
pub(super) mod watched;
mod worst;

use crate::properties::time_words;
use bip_model::{OwnedStep, State, Steps, System, Trace, Verdict};

use crate::error::VerifyError;
use crate::report::PropertyVerdict;
use crate::visited::Visited;
use crate::watch::Watch;

use cycles::Forever;
use run::Run;
use timelock::Timelocks;
use watched::{Flagged, MAX_WATCHED};
use worst::Worst;

/// A response property's verdict, with a note when its trigger never happens, and in a
/// model with time its worst response.
pub(super) struct Decided {
    pub(super) verdict: PropertyVerdict,
    pub(super) note: Option<String>,
    pub(super) worst: Option<WorstWait>,
}

/// A response property's worst response: the longest time a trigger waits for its
/// response (docs/verify.md, "Worst responses of services and properties").
pub(super) struct WorstWait {
    /// Holds with the run that waits longest, fails where the wait is unbounded.
    pub(super) verdict: PropertyVerdict,
    /// The figure in time units, when there is one.
    pub(super) units: Option<u64>,
    /// Why no figure, or what the figure is not.
    pub(super) note: Option<String>,
}

/// A response property to decide.
pub(super) struct Question<'a> {
    pub(super) name: &'a str,
    pub(super) within: Option<u64>,
}

/// The verdicts of the response properties `questions`, in order, and of time progress
/// if `time_progress` asks for it, from a complete exploration stored in `visited`, on
/// its state graph `graph` (which watches the first [`MAX_WATCHED`] questions; `None`
/// if it could not be recorded).
pub(super) fn decide(
    system: &System,
    visited: &Visited,
    questions: &[Question<'_>],
    time_progress: bool,
    graph: Option<Flagged>,
    watch: &Watch,
) -> Result<(Vec<Decided>, Option<Decided>), VerifyError> {
    if questions.is_empty() && !time_progress {
        return Ok((Vec::new(), None));
    }
    // the graph watches the first questions; the others are left open
    let which: Vec<usize> = (0..questions.len().min(MAX_WATCHED)).collect();
    let mut out: Vec<Option<Decided>> = (0..questions.len())
        .map(|k| {
            (k >= MAX_WATCHED).then(|| inconclusive(format!(
                "one run checks at most {MAX_WATCHED} response properties; check this one in a run of its own"
            )))
        })
        .collect();
    let done = |out: Vec<Option<Decided>>| {
        out.into_iter()
            .map(|d| d.expect("every question is answered"))
            .collect()
    };
    let Some(g) = graph else {
        for &k in &which {
            out[k] = Some(stopped(watch));
        }
        return Ok((done(out), time_progress.then(|| stopped(watch))));
    };
    // the timelocked states, which the liveness searches need in a model with time
    let timelocks = if system.has_time() {
        watch.rebase();
        let Some(t) = timelock::locked(&g, watch) else {
            for &k in &which {
                out[k] = Some(stopped(watch));
            }
            return Ok((done(out), time_progress.then(|| stopped(watch))));
        };
        Some(t)
    } else {
        None
    };
    let progress = match (&timelocks, time_progress) {
        (Some(t), true) => {
            watch.rebase();
            Some(time_progress_verdict(system, visited, &g, t, watch)?)
        }
        _ => None,
    };
    let locked: Option<&[bool]> = timelocks.as_ref().map(|t| t.locked.as_slice());
    let any_locked = locked.is_some_and(|l| l.iter().any(|&x| x));
    for (p, &k) in which.iter().enumerate() {
        // what the last search announced is freed or resident now
        watch.rebase();
        let t = &questions[k];
        let within = t.within;
        if let Some(f) = &g.notes.failures[p] {
            let run = Run {
                states: vec![f.state],
                ..Run::default()
            };
            let mut trace = run_trace(system, visited, &g, &stem_to(&g, run))?;
            trace.verdict = Verdict::RangeError(f.message.clone());
            out[k] = Some(Decided {
                verdict: PropertyVerdict::Fails {
                    reason: format!("range error: {}", f.message),
                    trace: Some(trace),
                },
                note: None,
                worst: None,
            });
            continue;
        }
        let found = match within {
            Some(bound) => match bounded::search(&g, p, bound, watch) {
                // the observer sees ticks: a wait on a cycle of timelocked states, where
                // no tick ever comes, is for the cycle search
                bounded::Found::Holds { vacuous: false } if any_locked => {
                    let forever = Forever::Timelocked(locked.unwrap_or_default());
                    match cycles::search(&g, p, forever, watch) {
                        cycles::Found::Holds { vacuous } => Ok(vacuous),
                        cycles::Found::Fails(run) => Err(run),
                        cycles::Found::Stopped => {
                            out[k] = Some(stopped(watch));
                            continue;
                        }
                    }
                }
                bounded::Found::Holds { vacuous } => Ok(vacuous),
                bounded::Found::Fails(run) => Err(run),
                bounded::Found::TooLarge => {
                    out[k] = Some(inconclusive(format!(
                        "the observer's product ({} states times {} tick counts) does not fit",
                        g.len(),
                        bound.saturating_add(2)
                    )));
                    continue;
                }
                bounded::Found::Stopped => {
                    out[k] = Some(stopped(watch));
                    continue;
                }
            },
            None => match cycles::search(
                &g,
                p,
                locked.map_or(Forever::Any, Forever::Divergent),
                watch,
            ) {
                cycles::Found::Holds { vacuous } => Ok(vacuous),
                cycles::Found::Fails(run) => Err(run),
                cycles::Found::Stopped => {
                    out[k] = Some(stopped(watch));
                    continue;
                }
            },
        };
        out[k] = Some(match found {
            Ok(vacuous) => Decided {
                verdict: PropertyVerdict::Holds { witness: None },
                note: vacuous.then(|| "vacuous: its trigger never happens".to_string()),
                worst: None,
            },
            Err(run) => {
                let mut trace = run_trace(system, visited, &g, &run)?;
                trace.verdict = Verdict::Violation(t.name.to_string());
                let reason = reason(system, &g, &run, within, locked);
                Decided {
                    verdict: PropertyVerdict::Fails {
                        reason,
                        trace: Some(trace),
                    },
                    note: None,
                    worst: None,
                }
            }
        });
    }
    if let Some(t) = timelocks.as_ref().filter(|_| gives_worst_waits(system)) {
        for (p, &k) in which.iter().enumerate() {
            watch.rebase();
            let worst = worst_wait(system, visited, &g, p, questions[k].name, &t.locked, watch)?;
            if let Some(d) = out[k].as_mut() {
                d.worst = Some(worst);
            }
        }
    }
    Ok((done(out), progress))
}

/// Whether `system`'s response properties get their worst responses: in a timed model,
/// and in a model without a GenoM layer whose time steps say how much time they
/// `advance`. An untimed GenoM layer's bounds count ticks, which `within` already asks
/// about; the search would cost each of its runs a pass over the graph per property.
pub(super) fn gives_worst_waits(system: &System) -> bool {
    system.is_timed() || (system.genom.is_none() && system.has_advance())
}

/// The worst response of property `p` (named `name`), from the complete graph `g` of a
/// model with time whose timelocked states are `locked`.
fn worst_wait(
    system: &System,
    visited: &Visited,
    g: &Flagged,
    p: usize,
    name: &str,
    locked: &[bool],
    watch: &Watch,
) -> Result<WorstWait, VerifyError> {
    if g.notes.failures[p].is_some() {
        return Ok(WorstWait {
            verdict: PropertyVerdict::Inconclusive {
                reason: "not given: evaluating the property makes a range error".into(),
            },
            units: None,
            note: None,
        });
    }
    Ok(match worst::longest_wait(g, p, locked, watch) {
        Worst::NoWait => WorstWait {
            verdict: PropertyVerdict::Holds { witness: None },
            units: Some(0),
            note: Some("no trigger ever waits".into()),
        },
        Worst::Units(units, run) => {
            let mut trace = run_trace(system, visited, g, &run)?;
            trace.verdict = Verdict::Witness(format!("{name} worst response"));
            WorstWait {
                verdict: PropertyVerdict::Holds {
                    witness: Some(trace),
                },
                units: Some(units),
                note: None,
            }
        }
        Worst::Unbounded => WorstWait {
            verdict: PropertyVerdict::Fails {
                reason: "unbounded: a trigger can wait for ever, or longer than any bound (the property without a bound fails)".into(),
                trace: None,
            },
            units: None,
            note: None,
        },
        Worst::Stopped => WorstWait {
            verdict: stopped(watch).verdict,
            units: None,
            note: None,
        },
    })
}

/// The verdict of time progress: fails with a shortest trace to the first timelocked
/// state, on to where the run is stuck, and why time cannot pass there; else with a
/// shortest lasso to a busy loop, and why time cannot pass where it starts.
fn time_progress_verdict(
    system: &System,
    visited: &Visited,
    g: &Flagged,
    t: &Timelocks,
    watch: &Watch,
) -> Result<Decided, VerifyError> {
    let Some(run) = timelock::first_timelock(g, t) else {
        return busy_loop_verdict(system, visited, g, watch);
    };
    let mut trace = run_trace(system, visited, g, &run)?;
    trace.verdict = Verdict::Violation(crate::properties::TIME_PROGRESS.into());
    let first = run
        .states
        .iter()
        .position(|&s| t.locked[s as usize])
        .expect("the run reaches a timelocked state");
    // where the run is stuck for ever: the cycle's first state, or the last
    let stuck = run.loop_start.unwrap_or(run.edges.len());
    let mut state = system.initial_state();
    system
        .layout
        .decode(visited.state(g.ids[run.states[stuck] as usize]), &mut state);
    let steps = |n: usize| format!("{n} step{}", if n == 1 { "" } else { "s" });
    let how = match run.loop_start {
        Some(k) => format!(
            "a cycle of {} without a tick repeats forever",
            steps(run.edges.len() - k)
        ),
        None => "the run stops there".into(),
    };
    Ok(Decided {
        verdict: PropertyVerdict::Fails {
            reason: format!(
                "time stops after {}: no run from there lets time pass ({how}); {}",
                steps(first),
                timelock::why(system, &state)
            ),
            trace: Some(trace),
        },
        note: None,
        worst: None,
    })
}

/// Time progress where no state is timelocked: it holds unless a run can stay for ever
/// on a busy loop, a cycle on which no state lets time pass.
fn busy_loop_verdict(
    system: &System,
    visited: &Visited,
    g: &Flagged,
    watch: &Watch,
) -> Result<Decided, VerifyError> {
    let run = match timelock::first_busy_loop(g, watch) {
        None => return Ok(stopped(watch)),
        Some(None) => {
            return Ok(Decided {
                verdict: PropertyVerdict::Holds { witness: None },
                note: None,
                worst: None,
            })
        }
        Some(Some(run)) => run,
    };
    let mut trace = run_trace(system, visited, g, &run)?;
    trace.verdict = Verdict::Violation(crate::properties::TIME_PROGRESS.into());
    let start = run.loop_start.expect("a busy loop is a cycle");
    let mut state = system.initial_state();
    system
        .layout
        .decode(visited.state(g.ids[run.states[start] as usize]), &mut state);
    let steps = |n: usize| format!("{n} step{}", if n == 1 { "" } else { "s" });
    Ok(Decided {
        verdict: PropertyVerdict::Fails {
            reason: format!(
                "a busy loop: after {}, a cycle of {} can repeat forever without letting time pass (no state on it has a tick; the run may leave it, but need not); {}",
                steps(start),
                steps(run.edges.len() - start),
                timelock::why(system, &state)
            ),
            trace: Some(trace),
        },
        note: None,
        worst: None,
    })
}

/// Inconclusive: `watch` stopped the search of the graph, or the graph was not stored.
fn stopped(watch: &Watch) -> Decided {
    inconclusive(match watch.stopped() {
        Some(stop) => format!("{stop} while the state graph was searched"),
        None => "the state graph could not be stored".into(),
    })
}

fn inconclusive(reason: String) -> Decided {
    Decided {
        verdict: PropertyVerdict::Inconclusive { reason },
        note: None,
        worst: None,
    }
}

/// How the counterexample `run` fails (`locked`: the timelocked states).
fn reason(
    system: &System,
    g: &Flagged,
    run: &Run,
    within: Option<u64>,
    locked: Option<&[bool]>,
) -> String {
    let n = run.edges.len();
    let steps = |n: usize| format!("{n} step{}", if n == 1 { "" } else { "s" });
    match (run.loop_start, within) {
        (Some(k), _) if locked.is_some_and(|l| l[run.states[k] as usize]) => format!(
            "the response never comes: after {}, a cycle of {} repeats forever without it, and time cannot pass on it (a timelock: TimeProgress fails)",
            steps(k),
            steps(n - k)
        ),
        (Some(k), _) => format!(
            "the response never comes: after {}, a cycle of {} repeats forever without it",
            steps(k),
            steps(n - k)
        ),
        (None, Some(bound)) if g.edges(run.last()).is_empty() => format!(
            "the response never comes: the run stops after {} with the trigger unanswered (bound {})",
            steps(n),
            time_words(system, bound)
        ),
        (None, Some(bound)) => format!(
            "the response does not come within {}: the tick of step {n} passes the bound",
            time_words(system, bound)
        ),
        (None, None) => format!(
            "the response never comes: the run stops after {} with the trigger unanswered",
            steps(n)
        ),
    }
}

/// The run from the initial state to the first state of `run`, joined with it.
fn stem_to(g: &Flagged, run: Run) -> Run {
    let mut out = Run {
        states: vec![0],
        ..Run::default()
    };
    let first = run.states[0];
    let path =
        run::shortest_path(g, 0, |_| true, |t| t == first).expect("every stored state is reached");
    out.extend(g, &path);
    out.extend(g, &run.edges);
    out.loop_start = run.loop_start;
    out
}

/// The trace of `run` (which starts at the initial state): each edge is the step of its
/// state that the graph stored at that place, found again by firing the state's steps in
/// the same order.
fn run_trace(
    system: &System,
    visited: &Visited,
    g: &Flagged,
    run: &Run,
) -> Result<Trace, VerifyError> {
    let layout = &system.layout;
    let mut steps = Steps::new();
    let mut path: Vec<(OwnedStep, State)> = Vec::with_capacity(run.edges.len());
    let mut state = system.initial_state();
    let mut next = system.initial_state();
    for (k, &e) in run.edges.iter().enumerate() {
        let from = run.states[k];
        layout.decode(visited.state(g.ids[from as usize]), &mut state);
        let nth = e - g.edges(from).start;
        system.enabled_steps(&state, &mut steps).map_err(|e| {
            VerifyError::Internal(format!("a state on a trace has a range error: {e}"))
        })?;
        let step = steps
            .iter()
            .filter(|s| system.fire(&state, *s, &mut next).is_ok())
            .nth(nth)
            .ok_or_else(|| VerifyError::Internal("an edge of the graph has no step".into()))?;
        system
            .fire(&state, step, &mut next)
            .map_err(|e| VerifyError::Internal(format!("a step of a trace fails: {e}")))?;
        path.push((step.to_owned(), next.clone()));
    }
    let mut trace = Trace::from_path(system, Verdict::None, &path);
    trace.loop_start = run.loop_start;
    Ok(trace)
}
