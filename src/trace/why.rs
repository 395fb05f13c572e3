//! Why a trace ends in a GenoM deadlock: the codels that are ready in its last state but
//! held back, and by what. The verify report, its JSON and JUnit forms, and the charts of
//! traces all say it in these words.

use std::fmt::Write;

use bip_model::System;

/// Under a GenoM deadlock: the codels that are ready but held back, and by what.
pub(crate) fn write_why_stuck(s: &mut String, system: &System, trace: &bip_model::Trace) {
    let Some(genom) = &system.genom else {
        return;
    };
    let last = match trace.replay(system) {
        Ok(path) => path
            .last()
            .map_or_else(|| system.initial_state(), |(_, st)| st.clone()),
        Err(_) => return,
    };
    match genom.stuck(system, &last) {
        Ok(stuck) if !stuck.is_empty() => {
            let _ = writeln!(s, "  why:");
            for st in stuck {
                let _ = writeln!(s, "    {st} but held by");
                for c in &st.held_by {
                    let _ = writeln!(s, "      {c}");
                }
            }
        }
        Ok(_) => {}
        Err(e) => {
            let _ = writeln!(s, "  why: cannot tell ({e})");
        }
    }
}
