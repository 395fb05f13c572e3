//! The result of a verification, whatever method produced it: one verdict per property,
//! the statistics of the run and why it stopped early, if it did.

use bip_model::Trace;
use serde::Serialize;

/// A method of verification: the one [`verify`](crate::verify) is asked to run, and the one
/// that gave a report or a verdict (a verdict's is never `Auto`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Breadth-first exploration of the reachable states.
    Explicit,
    /// Proofs with z3: compositional deadlock freedom, k-induction, bounded model checking.
    Symbolic,
    /// Explicit exploration within a budget, then symbolic proofs for what it left open.
    Auto,
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Explicit => "explicit-state",
            Method::Symbolic => "symbolic",
            Method::Auto => "auto",
        })
    }
}

/// What a result checks: a kind of model property (`bip_model::PropertyKind`, without its
/// expression), or range errors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CheckKind {
    DeadlockFree,
    Invariant,
    Reachable,
    /// Bounded response: `Response`, `Replies(within)`.
    Response,
    /// Unbounded response: `LeadsTo`, `Replies`, `Terminates`.
    LeadsTo,
    /// In a model with `Time` connectors, time can always pass: no reachable state is a
    /// timelock (docs/model.md, "Time progress"); reported before range errors.
    TimeProgress,
    /// Range errors are always checked (docs/model.md, "Range errors"); reported as a property of their own.
    RangeErrors,
    /// With time budgets: every task's work of a period ends by its deadline
    /// (docs/sched.md); reported after range errors.
    Schedulable,
    /// In a timed model, a task's worst response time over every reachable job end
    /// (`note`), with the run that reaches it; in a model with time, a response
    /// property's worst response, the longest wait for its response, with the run that
    /// waits it (docs/verify.md).
    WorstResponse,
}

/// The verdict on one property.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "verdict", rename_all = "snake_case")]
pub enum PropertyVerdict {
    /// The property holds. For `Reachable`, `witness` leads to a state satisfying it.
    Holds {
        #[serde(skip_serializing_if = "Option::is_none")]
        witness: Option<Trace>,
    },
    /// The property fails: `reason` says how; `trace` is a counterexample when there is one
    /// (an unreachable `Reachable` has none).
    Fails {
        reason: String,
        trace: Option<Trace>,
    },
    /// Not decided (a limit was reached, the run stopped at the first failure, ...).
    Inconclusive { reason: String },
}

impl PropertyVerdict {
    pub fn holds(&self) -> bool {
        matches!(self, PropertyVerdict::Holds { .. })
    }

    pub fn fails(&self) -> bool {
        matches!(self, PropertyVerdict::Fails { .. })
    }

    /// The counterexample or witness, if any.
    pub fn trace(&self) -> Option<&Trace> {
        match self {
            PropertyVerdict::Holds { witness } => witness.as_ref(),
            PropertyVerdict::Fails { trace, .. } => trace.as_ref(),
            PropertyVerdict::Inconclusive { .. } => None,
        }
    }
}

/// One property and its verdict.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PropertyResult {
    pub name: String,
    pub kind: CheckKind,
    /// The expression as written (`terminal` for `DeadlockFree`), empty if none.
    pub expr: String,
    #[serde(flatten)]
    pub verdict: PropertyVerdict,
    /// The method that gave the verdict (with `--method auto`, either).
    pub method: Method,
    /// How the verdict was obtained, when there is more to say (`2-induction`, ...).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// For a range error made by firing a step: the step (an interaction, or
    /// `component.internal`), the one after the trace's last.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_step: Option<String>,
    /// For a worst response time: the figure in microseconds, exact when the verdict
    /// holds, a lower bound when it is inconclusive (none in a model without a timed
    /// GenoM layer, whose figure `note` gives in time units).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub worst_us: Option<u64>,
}

impl PropertyResult {
    /// The explicit method's row of the worst response of `of` (a task `m.t`, or a
    /// response property's name): `of worst response`.
    pub(crate) fn worst_response(
        of: &str,
        verdict: PropertyVerdict,
        note: Option<String>,
        worst_us: Option<u64>,
    ) -> PropertyResult {
        PropertyResult {
            name: format!("{of} worst response"),
            kind: CheckKind::WorstResponse,
            expr: String::new(),
            verdict,
            method: Method::Explicit,
            note,
            error_step: None,
            worst_us,
        }
    }
}

/// Why a run ended before it had looked at every reachable state.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum Stop {
    MaxStates {
        limit: u64,
    },
    MaxMemory {
        limit: u64,
    },
    Timeout {
        seconds: f64,
    },
    /// `--stop-at-first`: a property failed.
    FirstFailure,
    /// More states than the visited set can number.
    TooManyStates,
    /// The user interrupted the run (Ctrl-C).
    Interrupted,
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::MaxStates { limit } => write!(f, "the state limit ({limit} states) was reached"),
            Stop::MaxMemory { limit } => {
                write!(f, "the memory limit ({}) was reached", human_bytes(*limit))
            }
            Stop::Timeout { seconds } => write!(
                f,
                "the time limit ({} s) was reached",
                (seconds * 1000.0).round() / 1000.0
            ),
            Stop::FirstFailure => write!(f, "the run stopped at the first failure"),
            Stop::TooManyStates => write!(
                f,
                "the model has more states than the visited set can number"
            ),
            Stop::Interrupted => write!(f, "the run was interrupted"),
        }
    }
}

/// Figures of an exploration (all zero when none ran; the symbolic method's figures are
/// [`SymbolicStats`], the whole run's are in [`Report`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RunStats {
    /// Distinct states stored.
    pub states: u64,
    /// True if every reachable state was stored and expanded: `states` is the number of
    /// reachable states. False if a limit stopped the run, or it stopped early because no
    /// further state could change a verdict.
    pub complete: bool,
    /// Steps fired (edges of the state graph explored, including those to known states).
    pub transitions: u64,
    /// Largest distance, in steps, of a stored state from the initial state.
    pub depth: u32,
    pub seconds: f64,
    pub states_per_second: f64,
    /// Bytes of the visited set in use per stored state (packed state, parent link, table).
    pub bytes_per_state: f64,
    /// Bytes of a packed state.
    pub state_bytes: usize,
    /// Bytes allocated by the visited set and the work buffers at the end.
    pub store_bytes: u64,
    /// Worker threads.
    pub jobs: usize,
}

/// The verdicts and figures of a verification.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    pub model: String,
    pub method: Method,
    pub properties: Vec<PropertyResult>,
    pub stats: RunStats,
    /// Why the run ended early, if it did.
    pub stopped: Option<Stop>,
    /// Figures of the symbolic method, when it ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub symbolic: Option<SymbolicStats>,
    /// Seconds of the whole run (with `--method auto`, both phases).
    pub seconds: f64,
    /// Peak resident memory of the process (z3's included), where the system reports it.
    pub peak_memory_bytes: Option<u64>,
}

/// Figures of a symbolic run.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SymbolicStats {
    pub components: usize,
    /// Components whose variables' values could not be enumerated (only their ranges and
    /// reachable locations are used).
    pub approximate_components: usize,
    /// Places (locations) and transition groups (interactions, internal moves) of the net.
    pub places: usize,
    pub net_groups: usize,
    /// Linear invariants (P-semiflows) found.
    pub semiflows: usize,
    /// Traps learned from candidates.
    pub traps: usize,
    pub solver_calls: u64,
    pub solver_seconds: f64,
    /// Seconds to compute the component invariants, the net and the semiflows.
    pub invariant_seconds: f64,
    pub seconds: f64,
}

/// The overall outcome, which decides the exit code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum VerifyOutcome {
    /// Every property holds.
    AllHold,
    /// Some property fails (whatever the others say: a failure is final).
    SomeFail,
    /// Nothing fails, but something is undecided.
    Inconclusive,
}

impl Report {
    pub fn outcome(&self) -> VerifyOutcome {
        if self.properties.iter().any(|p| p.verdict.fails()) {
            VerifyOutcome::SomeFail
        } else if self.properties.iter().all(|p| p.verdict.holds()) {
            VerifyOutcome::AllHold
        } else {
            VerifyOutcome::Inconclusive
        }
    }

    pub fn property(&self, name: &str) -> Option<&PropertyResult> {
        self.properties.iter().find(|p| p.name == name)
    }
}

/// `1.5 GiB`, `12.0 MiB`, `512 B`.
pub fn human_bytes(n: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = n as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{n} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn result(verdict: PropertyVerdict) -> PropertyResult {
        PropertyResult {
            name: "p".into(),
            kind: CheckKind::Invariant,
            expr: String::new(),
            verdict,
            method: Method::Explicit,
            note: None,
            error_step: None,
            worst_us: None,
        }
    }

    fn report(verdicts: Vec<PropertyVerdict>) -> Report {
        Report {
            model: "m".into(),
            method: Method::Explicit,
            properties: verdicts.into_iter().map(result).collect(),
            stats: RunStats::default(),
            stopped: None,
            symbolic: None,
            seconds: 0.0,
            peak_memory_bytes: None,
        }
    }

    #[test]
    fn a_failure_outranks_an_inconclusive_verdict() {
        let holds = PropertyVerdict::Holds { witness: None };
        let fails = PropertyVerdict::Fails {
            reason: "x".into(),
            trace: None,
        };
        let unknown = PropertyVerdict::Inconclusive { reason: "y".into() };
        assert_eq!(
            report(vec![holds.clone()]).outcome(),
            VerifyOutcome::AllHold
        );
        assert_eq!(
            report(vec![holds.clone(), unknown.clone()]).outcome(),
            VerifyOutcome::Inconclusive
        );
        assert_eq!(
            report(vec![unknown, fails, holds]).outcome(),
            VerifyOutcome::SomeFail
        );
    }

    #[test]
    fn bytes_read_well() {
        assert_eq!(human_bytes(512), "512 B");
        assert_eq!(human_bytes(3 << 20), "3.0 MiB");
    }
}
