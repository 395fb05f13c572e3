//! The trace file format: a [`Trace`] as RON, the way `bip verify --trace-dir`,
//! `bip simulate --trace` and the engine's recorder write it and `bip replay` reads it:
//!
//! ```text
//! Trace(
//!     system: "philosophers",
//!     steps: [
//!         (step: "left[2]", state: {"phil[2]": "hungry", "fork[2]": "taken"}),
//!     ],
//!     verdict: Deadlock,
//! )
//! ```
//!
//! A run of a model's timed semantics says `timed: true` after the system's name. The
//! verdict comes last, so that a run is written as it goes ([`TraceWriter`]); a
//! lasso (a run that repeats a cycle forever) adds `loop_start: k` after it: the steps
//! after the first `k` repeat.

use std::io::{self, Write};

use bip_model::{Trace, TraceStep, Verdict};

use crate::syntax::ron_options;

/// The trace as RON, one line per step.
pub fn to_ron(trace: &Trace) -> String {
    let mut w = TraceWriter::new(Vec::new(), &trace.system, trace.timed).expect("writes to memory");
    w.steps(&trace.steps).expect("writes to memory");
    let bytes = w
        .finish_lasso(&trace.verdict, trace.loop_start)
        .expect("writes to memory");
    String::from_utf8(bytes).expect("RON is UTF-8")
}

/// Writes a trace step by step, as a run goes, into `W`.
pub struct TraceWriter<W: Write> {
    out: W,
}

impl<W: Write> TraceWriter<W> {
    /// Writes the head of the trace of system `system`, a run of its timed semantics if
    /// `timed` (`timed: true`, written only then).
    pub fn new(mut out: W, system: &str, timed: bool) -> io::Result<TraceWriter<W>> {
        writeln!(out, "Trace(\n    system: {},", value(&system)?)?;
        if timed {
            writeln!(out, "    timed: true,")?;
        }
        writeln!(out, "    steps: [")?;
        Ok(TraceWriter { out })
    }

    /// Writes the next steps.
    pub fn steps(&mut self, steps: &[TraceStep]) -> io::Result<()> {
        for s in steps {
            writeln!(self.out, "        {},", value(s)?)?;
        }
        Ok(())
    }

    /// Writes the verdict and the end of the trace, and returns the writer.
    pub fn finish(self, verdict: &Verdict) -> io::Result<W> {
        self.finish_lasso(verdict, None)
    }

    /// Like [`TraceWriter::finish`], for a lasso whose loop starts after `loop_start`
    /// steps (written after the verdict, and only for a lasso).
    pub fn finish_lasso(mut self, verdict: &Verdict, loop_start: Option<usize>) -> io::Result<W> {
        write!(self.out, "    ],\n    verdict: {},\n", value(verdict)?)?;
        if let Some(k) = loop_start {
            writeln!(self.out, "    loop_start: {k},")?;
        }
        writeln!(self.out, ")")?;
        self.out.flush()?;
        Ok(self.out)
    }
}

/// One value as compact RON, with a space after each separator.
fn value<T: serde::Serialize>(v: &T) -> io::Result<String> {
    let config = ron::ser::PrettyConfig::new()
        .struct_names(false)
        .depth_limit(0)
        .separator(" ");
    ron_options()
        .to_string_pretty(v, config)
        .map_err(io::Error::other)
}

/// Reads a trace written in RON (in this format, or with the verdict first and a
/// recording's verdict written `r#None`, as earlier versions wrote it); the error says
/// where, as `line:column: what`.
pub fn from_ron(text: &str) -> Result<Trace, String> {
    ron_options()
        .from_str(text)
        .map_err(|e| format!("{}: {}", e.span.start, e.code))
}
