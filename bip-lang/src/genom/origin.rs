//! Where the expansion's texts come from, so that an error the compiler finds in an
//! expanded model points at the user's text in the file.
//!
//! A generated guard often holds a user's text (a `Guard` condition inside a codel
//! connector's guard, a connector's guard conjoined to a generated one), and a user's text
//! may have been rewritten (`active(m.S)` became `!m_S@ether`). Such texts are built from
//! [`Src`] pieces; each user piece knows its [`Origin`]. A text with user pieces is given a
//! private span far beyond any file; [`Origins::locate`] maps a span inside it back to the
//! file: through the piece, then through the rewrite (the printed expression is parsed
//! again and matched node by node with the tree it was printed from, which kept the
//! original positions).

use std::ops::Range;

use crate::diag::ModelError;
use crate::expr::{reprint, Expr, ExprKind};
use crate::source::{Span, Spanned};
use crate::syntax::Text;

/// Private spans start here; each composite text gets `STRIDE` bytes of them.
const BASE: usize = usize::MAX / 2;
const STRIDE: usize = 1 << 20;

/// A user text as it enters the expansion.
#[derive(Clone, Debug)]
pub(super) struct Origin {
    original: Text,
    /// For a rewritten text: pairs (span in the printed text, span in the original text),
    /// outermost first. `None`: the text is the original's value.
    pairs: Option<Vec<(Span, Span)>>,
}

/// A text under construction: generated pieces and user pieces.
#[derive(Clone, Debug, Default)]
pub(super) struct Src(Vec<Piece>);

#[derive(Clone, Debug)]
struct Piece {
    text: String,
    origin: Option<usize>,
}

impl Src {
    /// Generated text.
    pub fn gen(s: impl Into<String>) -> Src {
        Src(vec![Piece {
            text: s.into(),
            origin: None,
        }])
    }

    /// The text, without origins.
    pub fn plain(&self) -> String {
        self.0.iter().map(|p| p.text.as_str()).collect()
    }

    fn is_generated(&self) -> bool {
        self.0.iter().all(|p| p.origin.is_none())
    }

    /// Generated text printed with the fewest parentheses; user text as it is.
    fn tidy(self) -> Src {
        if self.is_generated() {
            Src::gen(reprint(&self.plain()))
        } else {
            self
        }
    }

    fn push(&mut self, other: Src) {
        self.0.extend(other.0);
    }

    /// `a ⊕ b ⊕ …` of the parts, each parenthesised when there are several; `None` if
    /// there are none.
    pub fn join(parts: Vec<Src>, op: &str) -> Option<Src> {
        let n = parts.len();
        let mut out = Src::default();
        for (k, p) in parts.into_iter().enumerate() {
            if k > 0 {
                out.push(Src::gen(format!(" {op} ")));
            }
            if n == 1 {
                out.push(p.tidy());
            } else {
                out.push(Src::gen("("));
                out.push(p.tidy());
                out.push(Src::gen(")"));
            }
        }
        (n > 0).then(|| out.tidy())
    }

    /// `a && b && …`.
    pub fn and(parts: Vec<Src>) -> Option<Src> {
        Src::join(parts, "&&")
    }

    /// `prefix || (self)`.
    pub fn or_after(self, prefix: &str) -> Src {
        let mut out = Src::gen(format!("{prefix} || ("));
        out.push(self);
        out.push(Src::gen(")"));
        out.tidy()
    }

    /// `self; other` for actions.
    pub fn then(mut self, other: Src) -> Src {
        self.push(Src::gen("; "));
        self.push(other);
        self
    }
}

/// The origins of the texts of one expansion.
#[derive(Clone, Debug, Default)]
pub struct Origins {
    origins: Vec<Origin>,
    /// For each composite text: its pieces' ranges and origins.
    composites: Vec<Vec<(Range<usize>, usize)>>,
}

impl Origins {
    /// A user's text, possibly rewritten into `printed` from the tree `tree` (which kept
    /// the original's positions); `is_action` says how to parse `printed` back.
    pub(super) fn user(&mut self, original: &Text, rewrite: Option<(String, Rewrite)>) -> Src {
        let (text, pairs) = match rewrite {
            None => (original.value.clone(), None),
            Some((printed, tree)) => {
                let pairs = pairs_of(&printed, &tree);
                (printed, Some(pairs))
            }
        };
        self.origins.push(Origin {
            original: original.clone(),
            pairs,
        });
        Src(vec![Piece {
            text,
            origin: Some(self.origins.len() - 1),
        }])
    }

    /// The text to compile: a user's text unchanged keeps its own span; a generated text
    /// has none; anything else gets a private span that [`Origins::locate`] maps back.
    pub(super) fn text(&mut self, src: Src) -> Text {
        if let [Piece {
            origin: Some(o), ..
        }] = src.0.as_slice()
        {
            let origin = &self.origins[*o];
            if origin.pairs.is_none() {
                return origin.original.clone();
            }
        }
        let value = src.plain();
        if src.is_generated() {
            return Spanned::generated(value);
        }
        let id = self.composites.len();
        if value.len() >= STRIDE || id >= (usize::MAX - BASE) / STRIDE - 1 {
            // beyond what private spans can hold: point at the first user text as a whole
            let first = src
                .0
                .iter()
                .find_map(|p| p.origin)
                .map_or(Span::NONE, |o| self.origins[o].original.span);
            return Spanned::new(value, first);
        }
        let mut segments = Vec::new();
        let mut at = 0;
        for p in &src.0 {
            if let Some(o) = p.origin {
                segments.push((at..at + p.text.len(), o));
            }
            at += p.text.len();
        }
        self.composites.push(segments);
        let start = BASE + id * STRIDE;
        Spanned {
            value,
            span: Span::new(start, start + at),
            verbatim: true,
        }
    }

    /// The place in the file of a span of the expanded model.
    pub fn locate(&self, span: Span) -> Span {
        if span.start < BASE {
            return span;
        }
        let id = (span.start - BASE) / STRIDE;
        let inner = (span.start - BASE) % STRIDE;
        let inner_end = inner + span.len();
        let Some(segments) = self.composites.get(id) else {
            return Span::NONE;
        };
        let found = segments
            .iter()
            .find(|(r, _)| r.start <= inner && inner < r.end.max(r.start + 1))
            .or_else(|| segments.first());
        let Some((range, o)) = found else {
            return Span::NONE;
        };
        let origin = &self.origins[*o];
        let rel = inner.saturating_sub(range.start).min(range.len());
        let rel_end = inner_end
            .saturating_sub(range.start)
            .clamp(rel, range.len());
        let within = match &origin.pairs {
            None => rel..rel_end,
            Some(pairs) => {
                // the innermost printed node that covers the span, else the whole text
                let hit = pairs
                    .iter()
                    .filter(|(p, _)| p.start <= rel && rel_end <= p.end)
                    .min_by_key(|(p, _)| p.len());
                match hit {
                    Some((_, orig)) => orig.start..orig.end,
                    None => 0..origin.original.value.len(),
                }
            }
        };
        origin.original.sub_span(within)
    }

    /// Puts compiler errors back at their places in the file. Errors without a place
    /// (from generated texts that fail only because a user's text failed) are dropped
    /// when some error has a place; duplicates (a condition compiled twice) are merged.
    pub fn locate_errors(&self, errors: Vec<ModelError>) -> Vec<ModelError> {
        let mut out: Vec<ModelError> = Vec::new();
        for mut e in errors {
            e.span = self.locate(e.span);
            for (s, _) in &mut e.notes {
                *s = self.locate(*s);
            }
            if !out.contains(&e) {
                out.push(e);
            }
        }
        if out.iter().any(|e| !e.span.is_none()) {
            out.retain(|e| !e.span.is_none());
        }
        out
    }
}

/// A rewritten expression or action, as a tree with the original's positions.
pub(super) enum Rewrite {
    Expr(Expr),
    Action(Vec<crate::expr::Assign>),
}

/// Matches the printed text's tree with the rewritten tree, node by node.
fn pairs_of(printed: &str, tree: &Rewrite) -> Vec<(Span, Span)> {
    let mut out = Vec::new();
    match tree {
        Rewrite::Expr(r) => {
            if let Ok(q) = crate::expr::parse_expr(printed) {
                pair(r, &q, &mut out);
            }
        }
        Rewrite::Action(rs) => {
            if let Ok(qs) = crate::expr::parse_action(printed) {
                for (r, q) in rs.iter().zip(&qs) {
                    pair(&r.target, &q.target, &mut out);
                    pair(&r.value, &q.value, &mut out);
                }
            }
        }
    }
    out
}

fn ident(a: &crate::expr::Ident, b: &crate::expr::Ident, out: &mut Vec<(Span, Span)>) {
    if !a.span.is_none() {
        out.push((b.span, a.span));
    }
}

fn pair(r: &Expr, q: &Expr, out: &mut Vec<(Span, Span)>) {
    if !r.span.is_none() {
        out.push((q.span, r.span));
    }
    match (&r.kind, &q.kind) {
        (ExprKind::Index(a, i), ExprKind::Index(b, j)) => {
            pair(a, b, out);
            pair(i, j, out);
        }
        (ExprKind::Member(a, x), ExprKind::Member(b, y))
        | (ExprKind::At(a, x), ExprKind::At(b, y)) => {
            ident(x, y, out);
            pair(a, b, out);
        }
        (ExprKind::Call(f, xs), ExprKind::Call(g, ys)) => {
            ident(f, g, out);
            for (x, y) in xs.iter().zip(ys) {
                pair(x, y, out);
            }
        }
        (ExprKind::Unary(_, a), ExprKind::Unary(_, b)) => pair(a, b, out),
        (ExprKind::Binary(_, a1, a2), ExprKind::Binary(_, b1, b2)) => {
            pair(a1, b1, out);
            pair(a2, b2, out);
        }
        (ExprKind::Chain(a, xs), ExprKind::Chain(b, ys)) => {
            pair(a, b, out);
            for ((_, x), (_, y)) in xs.iter().zip(ys) {
                pair(x, y, out);
            }
        }
        (ExprKind::Cond(a1, a2, a3), ExprKind::Cond(b1, b2, b3)) => {
            pair(a1, b1, out);
            pair(a2, b2, out);
            pair(a3, b3, out);
        }
        (ExprKind::Quant(_, r1, a), ExprKind::Quant(_, r2, b)) => {
            ident(&r1.var, &r2.var, out);
            pair(&r1.lo, &r2.lo, out);
            pair(&r1.hi, &r2.hi, out);
            pair(a, b, out);
        }
        _ => {}
    }
}
