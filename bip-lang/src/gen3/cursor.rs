//! A cursor over the preprocessed tokens of a `.gen` file, with the helpers every part of
//! the parser uses to read a keyword, a name or a punctuation mark, or to say what it
//! expected instead.

use super::lexer::{Tok, Token};
use crate::diag::ModelError;
use crate::source::{Span, Text};

pub struct Cursor {
    toks: Vec<Token>,
    pos: usize,
    /// Where the input ends, for "found the end of the file".
    end: Span,
}

impl Cursor {
    pub fn new(toks: Vec<Token>, end: Span) -> Cursor {
        Cursor { toks, pos: 0, end }
    }

    pub fn peek(&self) -> Option<&Token> {
        self.toks.get(self.pos)
    }

    pub fn peek_at(&self, n: usize) -> Option<&Token> {
        self.toks.get(self.pos + n)
    }

    pub fn at_end(&self) -> bool {
        self.pos >= self.toks.len()
    }

    pub fn next(&mut self) -> Option<Token> {
        let t = self.toks.get(self.pos).cloned();
        if t.is_some() {
            self.pos += 1;
        }
        t
    }

    /// The span of the next token, or the end of the input.
    pub fn here(&self) -> Span {
        self.peek().map_or(self.end, |t| t.span)
    }

    /// The span of the token before the next one.
    pub fn last_span(&self) -> Span {
        self.pos
            .checked_sub(1)
            .and_then(|i| self.toks.get(i))
            .map_or(self.end, |t| t.span)
    }

    pub fn at_ident(&self, word: &str) -> bool {
        self.peek().is_some_and(|t| t.is_ident(word))
    }

    pub fn at_punct(&self, p: &str) -> bool {
        self.peek().is_some_and(|t| t.is_punct(p))
    }

    pub fn eat_ident(&mut self, word: &str) -> Option<Token> {
        if self.at_ident(word) {
            self.next()
        } else {
            None
        }
    }

    pub fn eat_punct(&mut self, p: &str) -> Option<Token> {
        if self.at_punct(p) {
            self.next()
        } else {
            None
        }
    }

    /// "expected WHAT, found …" at the next token.
    pub fn expected(&self, what: &str) -> ModelError {
        let found = self
            .peek()
            .map_or("the end of the file".to_string(), Token::describe);
        ModelError::new(format!("expected {what}, found {found}"), self.here())
    }

    pub fn expect_punct(&mut self, p: &str) -> Result<Token, ModelError> {
        self.eat_punct(p)
            .ok_or_else(|| self.expected(&format!("`{p}`")))
    }

    /// A `>` closing a template (`sequence<sequence<long>>` ends with one `>>` token).
    pub fn expect_close_angle(&mut self) -> Result<(), ModelError> {
        if let Some(t) = self.toks.get_mut(self.pos) {
            if t.is_punct(">>") {
                t.tok = Tok::Punct(">");
                t.span = Span::new(t.span.start + 1, t.span.end);
                return Ok(());
            }
        }
        self.expect_punct(">").map(|_| ())
    }

    /// An identifier, as a name with its position.
    pub fn expect_name(&mut self, what: &str) -> Result<Text, ModelError> {
        match self.peek() {
            Some(Token {
                tok: Tok::Ident(s),
                span,
                ..
            }) => {
                let t = Text {
                    value: s.clone(),
                    span: *span,
                    verbatim: true,
                };
                self.pos += 1;
                Ok(t)
            }
            _ => Err(self.expected(what)),
        }
    }

    /// One string literal or more, adjacent ones joined (as in C).
    pub fn expect_strings(&mut self) -> Result<Text, ModelError> {
        let start = self.here();
        let mut value = String::new();
        let mut end = start;
        let mut any = false;
        while let Some(Token {
            tok: Tok::Str(s),
            span,
            ..
        }) = self.peek()
        {
            value.push_str(s);
            end = *span;
            any = true;
            self.pos += 1;
        }
        if !any {
            return Err(self.expected("a string"));
        }
        Ok(Text::new(value, Span::new(start.start, end.end)))
    }

    /// `a, b, c`: one item or more, separated by commas.
    pub fn list<T>(
        &mut self,
        mut item: impl FnMut(&mut Cursor) -> Result<T, ModelError>,
    ) -> Result<Vec<T>, ModelError> {
        let mut out = vec![item(self)?];
        while self.eat_punct(",").is_some() {
            out.push(item(self)?);
        }
        Ok(out)
    }

    /// A name, possibly scoped: `a::b::c` or `::a`.
    pub fn scoped_name(&mut self, what: &str) -> Result<Text, ModelError> {
        let start = self.here();
        let mut value = String::new();
        if self.eat_punct("::").is_some() {
            value.push_str("::");
        }
        let first = self.expect_name(what)?;
        value.push_str(&first.value);
        while self.at_punct("::") && self.peek_at(1).is_some_and(|t| t.ident().is_some()) {
            self.next();
            let n = self.expect_name(what)?;
            value.push_str("::");
            value.push_str(&n.value);
        }
        Ok(Text::new(
            value,
            Span::new(start.start, self.last_span().end),
        ))
    }
}
