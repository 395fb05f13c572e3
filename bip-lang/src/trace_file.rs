//! The trace file format: a [`Trace`] as RON, the way `bip verify --trace-dir`,
//! `bip simulate --trace` and the engine's recorder write it and `bip replay` reads it.

use bip_model::Trace;

use crate::syntax::ron_options;

/// The trace as pretty RON: `Trace(` then its steps, each written
/// `(step: "...", state: {...})`.
pub fn to_ron(trace: &Trace) -> String {
    // ron names either every struct or none; the format names only the outer one
    let config = ron::ser::PrettyConfig::new()
        .struct_names(false)
        .depth_limit(2);
    match ron_options().to_string_pretty(trace, config) {
        Ok(body) => format!("Trace{body}\n"),
        Err(e) => format!("// could not write the trace: {e}\n"),
    }
}

/// Reads a trace written in RON; the error says where, as `line:column: what`.
pub fn from_ron(text: &str) -> Result<Trace, String> {
    ron_options()
        .from_str(text)
        .map_err(|e| format!("{}: {}", e.span.start, e.code))
}
