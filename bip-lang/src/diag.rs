//! Load errors: what went wrong in a model file, where, and how to fix it.
//!
//! Every error found while reading and compiling a file is collected (not only the first),
//! each with the byte span it concerns. [`LoadError`] implements `miette::Diagnostic`, so the
//! command line prints the file name, line, column and a caret under the offending text.

use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

use miette::{Diagnostic, LabeledSpan, SourceCode};

use crate::excerpt::Excerpt;
use crate::source::{line_col, Span};
use crate::source_map::SourceMap;

/// One problem in a model file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModelError {
    pub message: String,
    /// Where in the file; `Span::NONE` when the problem has no single place.
    pub span: Span,
    /// Text shown under the caret.
    pub label: Option<String>,
    pub help: Option<String>,
    /// Further places that explain the error (the other members of a priority cycle, the
    /// first definition of a duplicate name).
    pub notes: Vec<(Span, String)>,
}

impl ModelError {
    pub fn new(message: impl Into<String>, span: Span) -> ModelError {
        ModelError {
            message: message.into(),
            span,
            label: None,
            help: None,
            notes: Vec::new(),
        }
    }

    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = Some(label.into());
        self
    }

    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    pub fn with_note(mut self, span: Span, note: impl Into<String>) -> Self {
        self.notes.push((span, note.into()));
        self
    }
}

/// Collects the errors of one file.
#[derive(Debug, Default)]
pub struct Errors {
    pub list: Vec<ModelError>,
}

/// Enough errors for any user to act on; more is noise (and a huge broken file must not
/// produce a huge report).
const MAX_ERRORS: usize = 50;

impl Errors {
    pub fn push(&mut self, e: ModelError) {
        if self.list.len() < MAX_ERRORS && !self.list.contains(&e) {
            self.list.push(e);
        }
    }

    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Moves `other`'s errors here; true if it had any.
    pub fn absorb(&mut self, other: Errors) -> bool {
        let any = !other.is_empty();
        for e in other.list {
            self.push(e);
        }
        any
    }
}

/// A model file that could not be loaded. Its `Debug` is [`LoadError::summary`] (one line
/// per error, `file:line:col: message`), so that `main` returning it with `?` prints the
/// errors, not the model's text.
pub enum LoadError {
    /// The file could not be read.
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The file was read but is not a valid model.
    Model(ModelErrors),
}

/// The errors of one file with the file's text, for rendering.
#[derive(Debug)]
pub struct ModelErrors {
    pub name: String,
    pub text: Arc<String>,
    pub errors: Vec<ModelError>,
    /// The other files the errors may lie in (`.gen` modules).
    pub files: SourceMap,
}

impl ModelErrors {
    /// The file a span lies in (its name and text) and the span in that file.
    fn place(&self, span: Span) -> (&str, &Arc<String>, Span) {
        match self.files.locate(span) {
            Some((f, local)) => (&f.name, &f.text, local),
            None => (&self.name, &self.text, span),
        }
    }

    /// `(file, line, column)` of a span's start.
    fn position(&self, span: Span) -> (&str, usize, usize) {
        let (name, text, local) = self.place(span);
        let (l, c) = line_col(text, local.start);
        (name, l, c)
    }
}

impl LoadError {
    pub(crate) fn model(name: &str, text: &Arc<String>, errors: Vec<ModelError>) -> LoadError {
        LoadError::Model(ModelErrors {
            name: name.to_string(),
            text: Arc::clone(text),
            errors,
            files: SourceMap::default(),
        })
    }

    /// The same errors, some of which lie in `files` (spans past the model file's end).
    pub(crate) fn with_files(mut self, files: &SourceMap) -> LoadError {
        if let LoadError::Model(m) = &mut self {
            m.files = files.clone();
        }
        self
    }

    /// The model errors, if the file was read.
    pub fn errors(&self) -> &[ModelError] {
        match self {
            LoadError::Io { .. } => &[],
            LoadError::Model(m) => &m.errors,
        }
    }

    /// `(line, column)` of each error, 1-based, in the order reported.
    pub fn positions(&self) -> Vec<(usize, usize)> {
        self.places().into_iter().map(|(_, l, c)| (l, c)).collect()
    }

    /// `(file, line, column)` of each error, in the order reported: the file is the model
    /// file's name, or that of the `.gen` file the error lies in.
    pub fn places(&self) -> Vec<(&str, usize, usize)> {
        match self {
            LoadError::Io { .. } => Vec::new(),
            LoadError::Model(m) => m.errors.iter().map(|e| m.position(e.span)).collect(),
        }
    }

    /// One line per error: `file:line:col: message`, for logs and tests.
    pub fn summary(&self) -> String {
        match self {
            LoadError::Io { .. } => self.to_string(),
            LoadError::Model(m) => m
                .errors
                .iter()
                .map(|e| {
                    let (name, l, c) = m.position(e.span);
                    format!("{name}:{l}:{c}: {}", e.message)
                })
                .collect::<Vec<_>>()
                .join("\n"),
        }
    }
}

impl fmt::Debug for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.summary())
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoadError::Io { path, source } => write!(f, "cannot read {}: {source}", path.display()),
            LoadError::Model(m) => match m.errors.as_slice() {
                [one] => {
                    let (name, l, c) = m.position(one.span);
                    write!(f, "{name}:{l}:{c}: {}", one.message)
                }
                many => write!(f, "{}: {} errors in the model", m.name, many.len()),
            },
        }
    }
}

impl std::error::Error for LoadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            LoadError::Io { source, .. } => Some(source),
            LoadError::Model(_) => None,
        }
    }
}

/// One error rendered against its file.
struct Rendered {
    src: Excerpt,
    error: ModelError,
}

impl Rendered {
    /// The error against the file its span lies in; notes in other files are left out.
    fn new(errors: &ModelErrors, error: &ModelError) -> Rendered {
        let (name, text, span) = errors.place(error.span);
        let notes = error
            .notes
            .iter()
            .filter(|(s, _)| !s.is_none())
            .filter_map(|(s, n)| {
                let (note_name, _, local) = errors.place(*s);
                (note_name == name).then(|| (local, n.clone()))
            })
            .collect();
        let error = ModelError {
            span,
            notes,
            ..error.clone()
        };
        let spans: Vec<Span> = std::iter::once(error.span)
            .chain(error.notes.iter().map(|(s, _)| *s))
            .collect();
        Rendered {
            src: Excerpt::new(name, text, error.span, &spans),
            error,
        }
    }
}

impl fmt::Debug for Rendered {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.error.fmt(f)
    }
}

impl fmt::Display for Rendered {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.error.message)
    }
}

impl std::error::Error for Rendered {}

impl Diagnostic for Rendered {
    fn source_code(&self) -> Option<&dyn SourceCode> {
        Some(&self.src)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = LabeledSpan> + '_>> {
        let main = LabeledSpan::new_primary_with_span(
            self.error.label.clone(),
            self.src.span(self.error.span),
        );
        let notes = self
            .error
            .notes
            .iter()
            .filter(|(s, _)| !s.is_none())
            .map(|(s, n)| LabeledSpan::new_with_span(Some(n.clone()), self.src.span(*s)));
        Some(Box::new(std::iter::once(main).chain(notes)))
    }

    fn help(&self) -> Option<Box<dyn fmt::Display + '_>> {
        self.error
            .help
            .as_ref()
            .map(|h| Box::new(h.clone()) as Box<dyn fmt::Display>)
    }
}

/// A `LoadError` as a miette diagnostic: the first error is the main one, the others are
/// related diagnostics, each with its own caret.
pub struct LoadDiagnostic {
    first: Option<Rendered>,
    rest: Vec<Rendered>,
    text: String,
}

impl LoadError {
    pub fn diagnostic(&self) -> LoadDiagnostic {
        match self {
            LoadError::Io { .. } => LoadDiagnostic {
                first: None,
                rest: Vec::new(),
                text: self.to_string(),
            },
            LoadError::Model(m) => {
                let mut rendered = m.errors.iter().map(|e| Rendered::new(m, e));
                let first = rendered.next();
                LoadDiagnostic {
                    first,
                    rest: rendered.collect(),
                    text: self.to_string(),
                }
            }
        }
    }
}

impl fmt::Debug for LoadDiagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

impl fmt::Display for LoadDiagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.first {
            Some(r) => r.fmt(f),
            None => f.write_str(&self.text),
        }
    }
}

impl std::error::Error for LoadDiagnostic {}

impl Diagnostic for LoadDiagnostic {
    fn source_code(&self) -> Option<&dyn SourceCode> {
        self.first.as_ref().and_then(|r| r.source_code())
    }
    fn labels(&self) -> Option<Box<dyn Iterator<Item = LabeledSpan> + '_>> {
        self.first.as_ref().and_then(|r| r.labels())
    }
    fn help(&self) -> Option<Box<dyn fmt::Display + '_>> {
        self.first.as_ref().and_then(|r| r.help())
    }
    fn related<'a>(&'a self) -> Option<Box<dyn Iterator<Item = &'a dyn Diagnostic> + 'a>> {
        if self.rest.is_empty() {
            None
        } else {
            Some(Box::new(self.rest.iter().map(|r| r as &dyn Diagnostic)))
        }
    }
}
