//! Printing errors for people (model diagnostics with carets, other errors on one line),
//! and for programs (the same diagnostics as a JSON document).

use std::io::IsTerminal;
use std::path::Path;

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

/// A load error as a JSON document: `{"file", "outcome": "error", "errors": [{"file",
/// "line", "column", "message", "help"}]}`; line and column are null for an error with no
/// place in the file (an unreadable file, a problem of the whole model).
pub fn load_error_json(file: &Path, e: &LoadError) -> String {
    #[derive(serde::Serialize)]
    struct Entry<'a> {
        file: String,
        line: Option<usize>,
        column: Option<usize>,
        message: &'a str,
        help: Option<&'a str>,
    }
    let shown = file.display().to_string();
    let errors: Vec<Entry<'_>> = match e {
        LoadError::Io { .. } => Vec::new(),
        LoadError::Model(_) => e
            .errors()
            .iter()
            .zip(e.places())
            .map(|(err, (place, line, column))| Entry {
                // an error in a `.gen` module names its file
                file: if err.span.is_none() {
                    shown.clone()
                } else {
                    place.to_string()
                },
                line: (!err.span.is_none()).then_some(line),
                column: (!err.span.is_none()).then_some(column),
                message: &err.message,
                help: err.help.as_deref(),
            })
            .collect(),
    };
    let io = e.to_string();
    let errors = if errors.is_empty() {
        vec![Entry {
            file: shown.clone(),
            line: None,
            column: None,
            message: &io,
            help: None,
        }]
    } else {
        errors
    };
    let doc = serde_json::json!({ "file": shown, "outcome": "error", "errors": errors });
    serde_json::to_string_pretty(&doc).unwrap_or_else(|_| "{}".into())
}
