//! The tokens of a `.gen` file: C-style comments, identifiers (with GenoM's hyphenated
//! keywords `codels-require(s)`, `clock-rate` and `real-time`), numbers, strings,
//! characters and punctuation, with the digraphs and operator words GenoM3's lexer reads
//! as punctuation (`<%` is `{`, `bitand` is `&`). Each token knows whether a line starts before it, for the
//! preprocessor's directives, and carries its span at the file's base in the model's
//! offsets.

use crate::diag::ModelError;
use crate::source::Span;

#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    Ident(String),
    Int(i128),
    Float(f64),
    Str(String),
    Char(char),
    /// Punctuation: one of [`PUNCT`].
    Punct(&'static str),
}

#[derive(Clone, Debug)]
pub struct Token {
    pub tok: Tok,
    pub span: Span,
    /// A new line starts between the previous token and this one.
    pub line_start: bool,
}

impl Token {
    pub fn is_punct(&self, p: &str) -> bool {
        matches!(&self.tok, Tok::Punct(q) if *q == p)
    }

    pub fn ident(&self) -> Option<&str> {
        match &self.tok {
            Tok::Ident(s) => Some(s),
            _ => None,
        }
    }

    pub fn is_ident(&self, word: &str) -> bool {
        self.ident() == Some(word)
    }

    /// How the token reads in a message.
    pub fn describe(&self) -> String {
        match &self.tok {
            Tok::Ident(s) => format!("`{s}`"),
            Tok::Int(i) => format!("`{i}`"),
            Tok::Float(f) => format!("`{f}`"),
            Tok::Str(s) => format!("the string {s:?}"),
            Tok::Char(c) => format!("the character {c:?}"),
            Tok::Punct(p) => format!("`{p}`"),
        }
    }
}

/// Punctuation, longest first.
const PUNCT: &[&str] = &[
    "::", "<<", ">>", "==", "!=", "<=", ">=", "&&", "||", "{", "}", "[", "]", "(", ")", ";", ":",
    ",", "<", ">", "=", "+", "-", "*", "/", "%", "^", "&", "|", "~", "!", ".", "#", "?",
];

/// Keywords written with a hyphen: the word before it, and what follows (the longer
/// spelling first).
const HYPHENATED: &[(&str, &str)] = &[
    ("codels", "-requires"),
    ("codels", "-require"),
    ("clock", "-rate"),
    ("real", "-time"),
];

/// Digraphs and the words GenoM3's lexer reads as punctuation, always (they are not names).
const ALTERNATIVE: &[(&str, &str)] = &[
    ("<%", "{"),
    ("%>", "}"),
    ("<:", "["),
    (":>", "]"),
    ("xor", "^"),
    ("bitand", "&"),
    ("bitor", "|"),
    ("compl", "~"),
    ("not", "!"),
];

/// The punctuation `word` stands for, if it is one of [`ALTERNATIVE`].
fn alternative(word: &str) -> Option<&'static str> {
    ALTERNATIVE
        .iter()
        .find(|(w, _)| *w == word)
        .map(|(_, p)| *p)
}

/// The tokens of `text`, a file placed at `base`.
pub fn tokenize(text: &str, base: usize) -> Result<Vec<Token>, ModelError> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let mut line_start = true;
    let span = |s: usize, e: usize| Span::new(base + s, base + e);
    while i < b.len() {
        let c = b[i];
        match c {
            b'\n' => {
                line_start = true;
                i += 1;
                continue;
            }
            b' ' | b'\t' | b'\r' | 0x0b | 0x0c => {
                i += 1;
                continue;
            }
            // a line continuation: the directive goes on
            b'\\' if matches!(b.get(i + 1), Some(b'\n')) => {
                i += 2;
                continue;
            }
            b'\\' if b.get(i + 1) == Some(&b'\r') && b.get(i + 2) == Some(&b'\n') => {
                i += 3;
                continue;
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                let start = i;
                i += 2;
                loop {
                    if i + 1 >= b.len() {
                        return Err(ModelError::new(
                            "unterminated comment",
                            span(start, start + 2),
                        )
                        .with_label("this comment has no `*/`"));
                    }
                    if b[i] == b'\n' {
                        line_start = true;
                    }
                    if b[i] == b'*' && b[i + 1] == b'/' {
                        i += 2;
                        break;
                    }
                    i += 1;
                }
                continue;
            }
            _ => {}
        }
        let start = i;
        let tok = if c.is_ascii_alphabetic() || c == b'_' {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            let word = &text[start..i];
            for (w, tail) in HYPHENATED {
                if word == *w && text[i..].starts_with(tail) {
                    let end = i + tail.len();
                    let after = b.get(end);
                    if !after.is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'_') {
                        i = end;
                        break;
                    }
                }
            }
            match alternative(&text[start..i]) {
                Some(p) => Tok::Punct(p),
                None => Tok::Ident(text[start..i].to_string()),
            }
        } else if c.is_ascii_digit() || (c == b'.' && b.get(i + 1).is_some_and(u8::is_ascii_digit))
        {
            let (end, tok) =
                number(text, start).map_err(|m| ModelError::new(m, span(start, start + 1)))?;
            i = end;
            tok
        } else if c == b'"' {
            let (end, s) = quoted(text, start, b'"')
                .ok_or_else(|| ModelError::new("unterminated string", span(start, start + 1)))?;
            i = end;
            Tok::Str(s)
        } else if c == b'\'' {
            let (end, s) = quoted(text, start, b'\'')
                .ok_or_else(|| ModelError::new("unterminated character", span(start, start + 1)))?;
            i = end;
            Tok::Char(s.chars().next().unwrap_or('\0'))
        } else if let Some((d, p)) = ALTERNATIVE.iter().find(|(d, _)| {
            // `<::a` is `<` and `::a`, as in C++
            text[i..].starts_with(*d) && !(*d == "<:" && text[i + 2..].starts_with(':'))
        }) {
            i += d.len();
            Tok::Punct(p)
        } else if let Some(p) = PUNCT.iter().find(|p| text[i..].starts_with(**p)) {
            i += p.len();
            Tok::Punct(p)
        } else {
            let ch = text[i..].chars().next().unwrap_or('?');
            return Err(ModelError::new(
                format!("unexpected character {ch:?}"),
                span(start, start + ch.len_utf8()),
            ));
        };
        out.push(Token {
            tok,
            span: span(start, i),
            line_start,
        });
        line_start = false;
    }
    Ok(out)
}

/// An integer (decimal, `0x` hexadecimal, `0` octal) or a floating-point number, with C's
/// suffixes. A suffix letter is taken only where it ends the number, so that `10us` reads
/// as 10 followed by the unit `us`.
fn number(text: &str, start: usize) -> Result<(usize, Tok), String> {
    let b = text.as_bytes();
    let word_end = |mut i: usize| {
        while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
            i += 1;
        }
        i
    };
    let digits_end = |mut i: usize, hex: bool| {
        while i < b.len() && (b[i].is_ascii_digit() || hex && b[i].is_ascii_hexdigit()) {
            i += 1;
        }
        i
    };
    let suffix = |i: usize, letters: &[u8]| {
        let mut j = i;
        while j < b.len() && letters.contains(&b[j]) {
            j += 1;
        }
        if j > i && word_end(j) == j {
            j
        } else {
            i
        }
    };
    if (text[start..].starts_with("0x") || text[start..].starts_with("0X"))
        && b.get(start + 2).is_some_and(u8::is_ascii_hexdigit)
    {
        let end = digits_end(start + 2, true);
        let v = i128::from_str_radix(&text[start + 2..end], 16)
            .map_err(|_| "this hexadecimal number is too large".to_string())?;
        return Ok((suffix(end, b"uUlL"), Tok::Int(v)));
    }
    let int_end = digits_end(start, false);
    let mut end = int_end;
    let mut float = false;
    if b.get(end) == Some(&b'.') && b.get(end + 1) != Some(&b'.') {
        float = true;
        end = digits_end(end + 1, false);
    }
    if matches!(b.get(end), Some(b'e' | b'E')) {
        let mut j = end + 1;
        if matches!(b.get(j), Some(b'+' | b'-')) {
            j += 1;
        }
        if b.get(j).is_some_and(u8::is_ascii_digit) {
            float = true;
            end = digits_end(j, false);
        }
    }
    if float {
        let v: f64 = text[start..end]
            .parse()
            .map_err(|_| "this number does not read".to_string())?;
        return Ok((suffix(end, b"fFlLdD"), Tok::Float(v)));
    }
    let s = &text[start..int_end];
    let v = if s.len() > 1 && s.starts_with('0') {
        i128::from_str_radix(&s[1..], 8).map_err(|_| format!("`{s}` is not an octal number"))?
    } else {
        s.parse::<i128>()
            .map_err(|_| "this number is too large".to_string())?
    };
    Ok((suffix(int_end, b"uUlL"), Tok::Int(v)))
}

/// A string or character literal from its opening quote: its end and its value.
fn quoted(text: &str, start: usize, quote: u8) -> Option<(usize, String)> {
    let b = text.as_bytes();
    let mut i = start + 1;
    let mut value = String::new();
    while i < b.len() {
        match b[i] {
            c if c == quote => return Some((i + 1, value)),
            b'\n' => return None,
            b'\\' => {
                let esc = text[i + 1..].chars().next()?;
                value.push(match esc {
                    'n' => '\n',
                    't' => '\t',
                    'r' => '\r',
                    '0' => '\0',
                    other => other,
                });
                i += 1 + esc.len_utf8();
            }
            _ => {
                let ch = text[i..].chars().next()?;
                value.push(ch);
                i += ch.len_utf8();
            }
        }
    }
    None
}
