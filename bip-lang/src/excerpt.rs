//! What a diagnostic shows of its file: the lines around its labels, with every long line
//! cut to a window around the label on it.
//!
//! Generated models have lines of megabytes; miette's graphical printer pads with format
//! widths, which panic past 65,535 columns, and a caret under column 70,000 helps no one.
//! The excerpt is what miette reads instead of the file: offsets are the excerpt's own,
//! but line numbers, and the column in the header, are the file's.

use std::sync::Arc;

use miette::{MietteError, MietteSpanContents, SourceCode, SourceSpan, SpanContents};

use crate::source::{line_col, Span};

/// A line longer than this (in bytes) is cut to a window.
const LONG_LINE: usize = 240;
/// Characters kept before and after the point a cut line is shown around.
const BEFORE: usize = 60;
const AFTER: usize = 120;
/// How a cut is marked.
const CUT: &str = "…";

/// A copied range of the file and where it starts in the excerpt.
#[derive(Clone, Copy, Debug)]
struct Segment {
    start: usize,
    end: usize,
    shown: usize,
}

#[derive(Debug)]
pub(crate) struct Excerpt {
    name: String,
    original: Arc<String>,
    shown: String,
    /// Lines of the file before the excerpt's first line.
    first_line: usize,
    segments: Vec<Segment>,
}

impl Excerpt {
    /// The lines of `text` from one line before the first of `spans` to one line after the
    /// last; a long line is shown around `focus` if it lies on that line, else around the
    /// first span boundary on it, else from its start.
    pub(crate) fn new(name: &str, text: &Arc<String>, focus: Span, spans: &[Span]) -> Excerpt {
        let len = text.len();
        let clamp = |o: usize| floor_boundary(text, o.min(len));
        let lo = spans.iter().map(|s| clamp(s.start)).min().unwrap_or(0);
        let hi = spans
            .iter()
            .map(|s| clamp(s.end))
            .max()
            .unwrap_or(0)
            .max(lo);
        let b = text.as_bytes();
        let line_start = |o: usize| {
            b[..o]
                .iter()
                .rposition(|&c| c == b'\n')
                .map_or(0, |p| p + 1)
        };
        let line_end = |o: usize| {
            b[o..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(len, |p| o + p)
        };
        let mut start = line_start(lo);
        if start > 0 {
            start = line_start(start - 1);
        }
        let mut end = line_end(hi);
        if end < len {
            end = line_end(end + 1);
        }
        let first_line = b[..start].iter().filter(|&&c| c == b'\n').count();
        let marks: Vec<usize> = std::iter::once(focus.start)
            .chain(spans.iter().flat_map(|s| [s.start, s.end]))
            .map(clamp)
            .collect();

        let mut shown = String::new();
        let mut segments = Vec::new();
        let mut ls = start;
        loop {
            let le = line_end(ls);
            // the newline is shown too, but not the one after the excerpt's last line
            let newline = if le < end { le + 1 } else { le };
            if le - ls <= LONG_LINE {
                segments.push(Segment {
                    start: ls,
                    end: newline,
                    shown: shown.len(),
                });
                shown.push_str(&text[ls..newline]);
            } else {
                let at = marks
                    .iter()
                    .copied()
                    .find(|&m| (ls..=le).contains(&m))
                    .unwrap_or(ls);
                let from = back_chars(text, at, BEFORE).max(ls);
                let to = forward_chars(text, at, AFTER).min(le);
                if from > ls {
                    shown.push_str(CUT);
                }
                segments.push(Segment {
                    start: from,
                    end: to,
                    shown: shown.len(),
                });
                shown.push_str(&text[from..to]);
                if to < le {
                    shown.push_str(CUT);
                }
                if newline > le {
                    segments.push(Segment {
                        start: le,
                        end: newline,
                        shown: shown.len(),
                    });
                    shown.push('\n');
                }
            }
            if le >= end {
                break;
            }
            ls = le + 1;
        }
        Excerpt {
            name: name.to_string(),
            original: Arc::clone(text),
            shown,
            first_line,
            segments,
        }
    }

    /// A span of the file as a span of the excerpt (the parts of it that were cut away
    /// shrink to the cut).
    pub(crate) fn span(&self, s: Span) -> SourceSpan {
        let start = self.to_shown(s.start);
        let end = self.to_shown(s.end.max(s.start)).max(start);
        (start, end - start).into()
    }

    fn to_shown(&self, o: usize) -> usize {
        let k = self.segments.partition_point(|s| s.start <= o);
        match k.checked_sub(1).map(|k| self.segments[k]) {
            None => 0,
            Some(s) if o <= s.end => s.shown + (o - s.start),
            Some(s) => s.shown + (s.end - s.start),
        }
    }

    fn to_original(&self, shown: usize) -> usize {
        let k = self.segments.partition_point(|s| s.shown <= shown);
        match k.checked_sub(1).map(|k| self.segments[k]) {
            None => self.segments.first().map_or(0, |s| s.start),
            Some(s) => (s.start + (shown - s.shown)).min(s.end),
        }
    }
}

impl SourceCode for Excerpt {
    fn read_span<'a>(
        &'a self,
        span: &SourceSpan,
        context_lines_before: usize,
        context_lines_after: usize,
    ) -> Result<Box<dyn SpanContents<'a> + 'a>, MietteError> {
        let inner =
            self.shown
                .as_str()
                .read_span(span, context_lines_before, context_lines_after)?;
        let column = if context_lines_before == 0 {
            let at = floor_boundary(&self.original, self.to_original(inner.span().offset()));
            line_col(&self.original, at).1 - 1
        } else {
            inner.column()
        };
        Ok(Box::new(MietteSpanContents::new_named(
            self.name.clone(),
            inner.data(),
            *inner.span(),
            inner.line() + self.first_line,
            column,
            inner.line_count(),
        )))
    }
}

fn floor_boundary(text: &str, mut i: usize) -> usize {
    while i > 0 && !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// The offset `n` characters before `at` (or 0).
fn back_chars(text: &str, at: usize, n: usize) -> usize {
    text[..at]
        .char_indices()
        .rev()
        .nth(n.saturating_sub(1))
        .map_or(0, |(i, _)| i)
}

/// The offset `n` characters after `at` (or the end).
fn forward_chars(text: &str, at: usize, n: usize) -> usize {
    text[at..]
        .char_indices()
        .nth(n)
        .map_or(text.len(), |(i, _)| at + i)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_lines_are_shown_as_written() {
        let text = Arc::new("a\nbb\nccc\ndddd\n".to_string());
        let e = Excerpt::new("f", &text, Span::new(5, 6), &[Span::new(5, 6)]);
        assert_eq!(e.shown, "bb\nccc\ndddd");
        assert_eq!(e.first_line, 1);
        assert_eq!(e.span(Span::new(5, 6)), (3, 1).into());
    }

    #[test]
    fn a_long_line_is_cut_around_the_label() {
        let text = Arc::new(format!(
            "x\n{}y{}\nz",
            " ".repeat(70_000),
            " ".repeat(70_000)
        ));
        let at = 2 + 70_000;
        let e = Excerpt::new("f", &text, Span::new(at, at + 1), &[Span::new(at, at + 1)]);
        assert!(e.shown.len() < 1_000, "{}", e.shown.len());
        let s = e.span(Span::new(at, at + 1));
        assert_eq!(&e.shown[s.offset()..s.offset() + 1], "y");
        let c = e.read_span(&s, 0, 0).unwrap();
        assert_eq!((c.line(), c.column()), (1, 70_000));
    }

    #[test]
    fn a_long_label_shrinks_to_the_window() {
        let text = Arc::new(format!("\"{}\"", "a".repeat(100_000)));
        let e = Excerpt::new(
            "f",
            &text,
            Span::new(0, text.len()),
            &[Span::new(0, text.len())],
        );
        let s = e.span(Span::new(0, text.len()));
        assert!(s.len() <= AFTER + 1, "{}", s.len());
    }
}
