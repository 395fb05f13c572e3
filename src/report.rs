//! Printing errors for people: model diagnostics with carets, other errors on one line.

use std::io::IsTerminal;

use bip_lang::LoadError;
use miette::{GraphicalReportHandler, GraphicalTheme};

/// Prints a load error to stderr: file, line, column and a caret under the offending text.
pub fn load_error(e: &LoadError) {
    let diag = e.diagnostic();
    let theme = if std::io::stderr().is_terminal() {
        GraphicalTheme::unicode()
    } else {
        GraphicalTheme::unicode_nocolor()
    };
    let handler = GraphicalReportHandler::new_themed(theme).with_context_lines(1);
    let mut out = String::new();
    match handler.render_report(&mut out, &diag) {
        Ok(()) => eprint!("{out}"),
        Err(_) => eprintln!("error: {}", e.summary()),
    }
    if let LoadError::Model(m) = e {
        if m.errors.len() > 1 {
            eprintln!("{} errors in {}", m.errors.len(), m.name);
        }
    }
}
