//! The other files of a model: a model that takes modules from `.gen` files (and the files
//! those include) reports errors in them. Their spans are byte offsets past the end of the
//! model file, each file at its own base, so one `Span` type serves every file and a
//! diagnostic finds its file from its offset alone.

use std::sync::Arc;

use crate::source::Span;

/// A file besides the model file, placed at `base` in the offsets of a model's spans.
#[derive(Clone, Debug)]
pub struct SourceFile {
    pub name: String,
    pub text: Arc<String>,
    pub base: usize,
}

/// The files besides the model file, in the order they were read.
#[derive(Clone, Debug, Default)]
pub struct SourceMap {
    files: Vec<SourceFile>,
}

impl SourceMap {
    /// Places a file after `main_len` (the model file's length) and every file already
    /// placed, and returns its base. A gap of one byte keeps an end-of-file span of one
    /// file apart from the start of the next.
    pub fn add(&mut self, main_len: usize, name: impl Into<String>, text: Arc<String>) -> usize {
        let after = self
            .files
            .last()
            .map_or(main_len, |f| f.base + f.text.len());
        let base = after + 1;
        self.files.push(SourceFile {
            name: name.into(),
            text,
            base,
        });
        base
    }

    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    pub fn files(&self) -> &[SourceFile] {
        &self.files
    }

    /// The file a span lies in, and the span in that file's own offsets; `None` for a span
    /// of the model file.
    pub fn locate(&self, span: Span) -> Option<(&SourceFile, Span)> {
        let i = self.files.partition_point(|f| f.base <= span.start);
        let file = self.files.get(i.checked_sub(1)?)?;
        let local = |o: usize| o.saturating_sub(file.base).min(file.text.len());
        Some((file, Span::new(local(span.start), local(span.end))))
    }
}
