//! Source positions for a RON model file.
//!
//! `ron` reports positions for syntax errors only; once a value is deserialized its
//! position is gone. Every later diagnostic (an unknown port, a type error inside an
//! expression) must still point into the file, so before deserializing we tokenize the
//! file once and record where each string, integer and identifier token sits. serde visits
//! a document in file order, so the value types below ([`Spanned<String>`],
//! [`Spanned<ConstValue>`]) claim the next matching token after the previously claimed
//! one. A value that is not found (which would only happen for a value that did not come
//! from the file) gets an empty span rather than a wrong one.

use std::cell::RefCell;
use std::collections::HashMap;
use std::fmt;

use serde::de::{self, Deserialize, Deserializer, Visitor};
use serde::ser::{Serialize, Serializer};

/// A byte range in a model file. `Span::NONE` marks values made by the tool itself.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Span {
    pub start: usize,
    pub end: usize,
}

impl Span {
    pub const NONE: Span = Span { start: 0, end: 0 };

    pub fn new(start: usize, end: usize) -> Span {
        Span { start, end }
    }

    pub fn is_none(&self) -> bool {
        self.start == 0 && self.end == 0
    }

    pub fn len(&self) -> usize {
        self.end - self.start
    }

    pub fn is_empty(&self) -> bool {
        self.start == self.end
    }
}

/// A value with the span of the token it was read from.
///
/// For strings, `verbatim` says that the characters between the quotes are exactly the
/// string's value (no escapes); then `span` covers just those characters, and a position
/// inside the string (an expression error) maps to a position in the file by offset.
/// Otherwise `span` covers the whole literal, quotes included.
#[derive(Clone, Debug, Default)]
pub struct Spanned<T> {
    pub value: T,
    pub span: Span,
    pub verbatim: bool,
}

impl<T> Spanned<T> {
    pub fn new(value: T, span: Span) -> Self {
        Spanned {
            value,
            span,
            verbatim: false,
        }
    }

    /// A value the tool made (GenoM expansion, tests): no position in any file.
    pub fn generated(value: T) -> Self {
        Spanned::new(value, Span::NONE)
    }
}

/// A string as written in the file (a name, an expression), with its position.
pub type Text = Spanned<String>;

impl Spanned<String> {
    pub fn as_str(&self) -> &str {
        &self.value
    }

    /// The file span of the byte range `inner` of this string's value.
    pub fn sub_span(&self, inner: std::ops::Range<usize>) -> Span {
        if self.verbatim && !self.span.is_none() {
            // a verbatim string's span is its content, between the quotes
            Span::new(self.span.start + inner.start, self.span.start + inner.end)
        } else {
            self.span
        }
    }
}

impl<T: PartialEq> PartialEq for Spanned<T> {
    fn eq(&self, other: &Self) -> bool {
        self.value == other.value
    }
}

impl<T: Eq> Eq for Spanned<T> {}

impl<T: std::hash::Hash> std::hash::Hash for Spanned<T> {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.value.hash(state)
    }
}

impl<T: fmt::Display> fmt::Display for Spanned<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.value.fmt(f)
    }
}

impl<T> std::ops::Deref for Spanned<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.value
    }
}

impl From<&str> for Spanned<String> {
    fn from(s: &str) -> Self {
        Spanned::generated(s.to_string())
    }
}

impl From<String> for Spanned<String> {
    fn from(s: String) -> Self {
        Spanned::generated(s)
    }
}

impl<T: Serialize> Serialize for Spanned<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.value.serialize(s)
    }
}

impl<'de> Deserialize<'de> for Spanned<String> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let value = String::deserialize(d)?;
        Ok(locate_string(value))
    }
}

fn locate_string(value: String) -> Spanned<String> {
    let key = TokenKey::Str(value);
    let found = claim(&key);
    let TokenKey::Str(value) = key else {
        return Spanned::generated(String::new());
    };
    match found {
        Some(tok) => Spanned {
            value,
            span: tok.span,
            verbatim: tok.verbatim,
        },
        None => Spanned::generated(value),
    }
}

/// A constant written in the file: an integer, a boolean, or an expression over constants
/// in a string (`"N - 1"`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ConstValue {
    Int(i64),
    Bool(bool),
    Expr(String),
}

impl fmt::Display for ConstValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConstValue::Int(i) => write!(f, "{i}"),
            ConstValue::Bool(b) => write!(f, "{b}"),
            ConstValue::Expr(e) => write!(f, "{e}"),
        }
    }
}

impl Serialize for ConstValue {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            ConstValue::Int(i) => s.serialize_i64(*i),
            ConstValue::Bool(b) => s.serialize_bool(*b),
            ConstValue::Expr(e) => s.serialize_str(e),
        }
    }
}

/// A [`ConstValue`] with its position.
pub type ConstExpr = Spanned<ConstValue>;

impl ConstExpr {
    pub fn int(i: i64) -> Self {
        Spanned::generated(ConstValue::Int(i))
    }

    /// The expression text and its span, as a `Spanned<String>` for the expression parser.
    pub fn as_text(&self) -> Spanned<String> {
        match &self.value {
            ConstValue::Expr(e) => Spanned {
                value: e.clone(),
                span: self.span,
                verbatim: self.verbatim,
            },
            other => Spanned {
                value: other.to_string(),
                span: self.span,
                verbatim: true,
            },
        }
    }
}

impl<'de> Deserialize<'de> for Spanned<ConstValue> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Spanned<ConstValue>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an integer, a boolean or a constant expression in a string")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
                let tok = claim(&TokenKey::Int(v as i128));
                Ok(spanned_token(ConstValue::Int(v), tok))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
                let Ok(i) = i64::try_from(v) else {
                    return Err(E::custom(format!("integer {v} does not fit in 64 bits")));
                };
                self.visit_i64(i)
            }
            fn visit_i128<E: de::Error>(self, v: i128) -> Result<Self::Value, E> {
                match i64::try_from(v) {
                    Ok(i) => self.visit_i64(i),
                    Err(_) => Err(E::custom(format!("integer {v} does not fit in 64 bits"))),
                }
            }
            fn visit_u128<E: de::Error>(self, v: u128) -> Result<Self::Value, E> {
                match i64::try_from(v) {
                    Ok(i) => self.visit_i64(i),
                    Err(_) => Err(E::custom(format!("integer {v} does not fit in 64 bits"))),
                }
            }
            fn visit_bool<E: de::Error>(self, v: bool) -> Result<Self::Value, E> {
                let word = if v { "true" } else { "false" };
                let tok = claim(&TokenKey::Ident(word.to_string()));
                Ok(spanned_token(ConstValue::Bool(v), tok))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
                let s = locate_string(v.to_string());
                Ok(Spanned {
                    value: ConstValue::Expr(s.value),
                    span: s.span,
                    verbatim: s.verbatim,
                })
            }
            fn visit_string<E: de::Error>(self, v: String) -> Result<Self::Value, E> {
                self.visit_str(&v)
            }
        }
        d.deserialize_any(V)
    }
}

fn spanned_token<T>(value: T, tok: Option<Token>) -> Spanned<T> {
    match tok {
        Some(tok) => Spanned {
            value,
            span: tok.span,
            verbatim: true,
        },
        None => Spanned::generated(value),
    }
}

pub use bip_model::OrderedMap;

/// Whether the next identifier token `word` in the file is followed by `(`. Used where
/// the format allows both `DeadlockFree` and `DeadlockFree(terminal: …)`, which serde's
/// enum access cannot tell apart without looking ahead.
pub(crate) fn ident_has_parens(word: &str) -> bool {
    claim(&TokenKey::Ident(word.to_string())).is_some_and(|t| t.paren_follows)
}

/// Claims the next identifier token `word` (one of the claimed words: an enum variant
/// that a check reports at), with whether `(` follows it; no position if the value did
/// not come from a file.
pub(crate) fn claim_word(word: &str) -> (Span, bool) {
    claim(&TokenKey::Ident(word.to_string()))
        .map_or((Span::NONE, false), |t| (t.span, t.paren_follows))
}

// ---------------------------------------------------------------------------------------
// The tokenizer and the locator.

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum TokenKey {
    Str(String),
    Int(i128),
    Ident(String),
}

#[derive(Clone, Copy, Debug)]
struct Token {
    span: Span,
    verbatim: bool,
    paren_follows: bool,
}

/// The identifiers a value claims (booleans, the enum variants that may be written with or
/// without parentheses, and the variants of a CPU's scheduling, which checks report at);
/// other identifiers are field and variant names, which serde reads itself.
const CLAIMED_WORDS: &[&str] = &[
    "true",
    "false",
    "DeadlockFree",
    "Exact",
    "FixedPriority",
    "Edf",
    "Job",
    "Codel",
    "Preemptive",
];

/// FNV-1a: token keys are short and the locator hashes one per value of the file, where
/// SipHash's resistance to collisions chosen by an attacker buys nothing.
#[derive(Default, Clone, Copy)]
struct Fnv(u64);

impl std::hash::Hasher for Fnv {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        let mut h = if self.0 == 0 {
            0xcbf2_9ce4_8422_2325
        } else {
            self.0
        };
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        self.0 = h;
    }
}

type TokenMap = HashMap<TokenKey, Vec<Token>, std::hash::BuildHasherDefault<Fnv>>;

struct Locator {
    /// For each token value, its occurrences in file order.
    tokens: TokenMap,
    /// The end of the last claimed token: values are claimed in file order.
    cursor: usize,
}

impl Locator {
    fn claim(&mut self, key: &TokenKey) -> Option<Token> {
        let list = self.tokens.get(key)?;
        let i = list.partition_point(|t| t.span.start < self.cursor);
        let tok = *list.get(i)?;
        self.cursor = tok.span.end;
        Some(tok)
    }
}

thread_local! {
    static LOCATOR: RefCell<Option<Locator>> = const { RefCell::new(None) };
}

fn with_locator<R>(f: impl FnOnce(&mut Locator) -> R) -> Option<R> {
    LOCATOR.with(|cell| cell.borrow_mut().as_mut().map(f))
}

/// Claims the next token equal to `key`, if a locator is installed and has one.
fn claim(key: &TokenKey) -> Option<Token> {
    with_locator(|l| l.claim(key)).flatten()
}

/// Installs a locator for `text` while `f` deserializes it.
pub(crate) fn with_positions<R>(text: &str, f: impl FnOnce() -> R) -> R {
    struct Reset;
    impl Drop for Reset {
        fn drop(&mut self) {
            LOCATOR.with(|cell| *cell.borrow_mut() = None);
        }
    }
    let locator = Locator {
        tokens: tokenize(text),
        cursor: 0,
    };
    LOCATOR.with(|cell| *cell.borrow_mut() = Some(locator));
    let _reset = Reset;
    f()
}

/// One pass over the file: strings (with escapes decoded), raw strings, integers and
/// identifiers; comments and everything else skipped. Malformed input is tolerated here;
/// `ron` reports it.
fn tokenize(text: &str) -> TokenMap {
    let b = text.as_bytes();
    let mut out = TokenMap::default();
    let mut i = 0;
    let mut push = |key: TokenKey, start: usize, end: usize, verbatim: bool, b: &[u8]| {
        // only meaningful for identifiers
        let paren_follows = next_significant(b, end) == Some(b'(');
        out.entry(key).or_default().push(Token {
            span: Span::new(start, end),
            verbatim,
            paren_follows,
        });
    };
    while i < b.len() {
        let c = b[i];
        match c {
            b'/' if b.get(i + 1) == Some(&b'/') => i = skip_line(b, i),
            b'/' if b.get(i + 1) == Some(&b'*') => i = skip_block_comment(b, i),
            b'"' => {
                let (end, value, verbatim) = scan_string(text, i);
                let (s, e) = if verbatim { (i + 1, end - 1) } else { (i, end) };
                push(TokenKey::Str(value), s, e, verbatim, b);
                i = end;
            }
            b'r' if matches!(b.get(i + 1), Some(b'"') | Some(b'#')) && raw_start(b, i) => {
                let (end, value) = scan_raw_string(text, i);
                let hashes = end - i - value.len() - 3; // `r`, two quotes, hashes on both sides
                let content_start = i + 2 + hashes / 2;
                push(
                    TokenKey::Str(value.clone()),
                    content_start,
                    content_start + value.len(),
                    true,
                    b,
                );
                i = end;
            }
            b'b' if b.get(i + 1) == Some(&b'"') => {
                let (end, _, _) = scan_string(text, i + 1);
                i = end;
            }
            b'\'' => i = skip_char_literal(b, i),
            b'0'..=b'9' | b'+' | b'-' if starts_number(b, i) => {
                let start = i;
                i += 1;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                if let Some(v) = parse_int(&text[start..i]) {
                    push(TokenKey::Int(v), start, i, true, b);
                }
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                let start = i;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                let word = &text[start..i];
                if CLAIMED_WORDS.contains(&word) {
                    push(TokenKey::Ident(word.to_string()), start, i, true, b);
                }
            }
            _ => i += 1,
        }
    }
    out
}

fn next_significant(b: &[u8], mut i: usize) -> Option<u8> {
    while i < b.len() {
        match b[i] {
            b' ' | b'\t' | b'\n' | b'\r' => i += 1,
            b'/' if b.get(i + 1) == Some(&b'/') => i = skip_line(b, i),
            b'/' if b.get(i + 1) == Some(&b'*') => i = skip_block_comment(b, i),
            c => return Some(c),
        }
    }
    None
}

fn skip_line(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && b[i] != b'\n' {
        i += 1;
    }
    i
}

fn skip_block_comment(b: &[u8], mut i: usize) -> usize {
    let mut depth = 0usize;
    while i < b.len() {
        if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
            depth += 1;
            i += 2;
        } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
            depth -= 1;
            i += 2;
            if depth == 0 {
                return i;
            }
        } else {
            i += 1;
        }
    }
    i
}

fn skip_char_literal(b: &[u8], mut i: usize) -> usize {
    i += 1;
    if b.get(i) == Some(&b'\\') {
        i += 2;
    }
    while i < b.len() && b[i] != b'\'' && b[i] != b'\n' {
        i += 1;
    }
    i + 1
}

fn starts_number(b: &[u8], i: usize) -> bool {
    let c = b[i];
    if c == b'+' || c == b'-' {
        return b.get(i + 1).is_some_and(u8::is_ascii_digit);
    }
    // a digit that is not the tail of an identifier
    i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_')
}

fn parse_int(s: &str) -> Option<i128> {
    let (neg, s) = match s.as_bytes().first() {
        Some(b'-') => (true, &s[1..]),
        Some(b'+') => (false, &s[1..]),
        _ => (false, s),
    };
    let digits: String = s.chars().filter(|&c| c != '_').collect();
    let (radix, body) = if let Some(r) = digits.strip_prefix("0x") {
        (16, r.to_string())
    } else if let Some(r) = digits.strip_prefix("0b") {
        (2, r.to_string())
    } else if let Some(r) = digits.strip_prefix("0o") {
        (8, r.to_string())
    } else {
        (10, digits)
    };
    let v = i128::from_str_radix(&body, radix).ok()?;
    Some(if neg { -v } else { v })
}

fn raw_start(b: &[u8], i: usize) -> bool {
    let mut j = i + 1;
    while b.get(j) == Some(&b'#') {
        j += 1;
    }
    b.get(j) == Some(&b'"') && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'))
}

/// Scans `"…"` starting at the quote; returns the end (after the closing quote), the
/// decoded value and whether it has no escapes.
fn scan_string(text: &str, start: usize) -> (usize, String, bool) {
    let b = text.as_bytes();
    let mut i = start + 1;
    let mut value = String::new();
    let mut verbatim = true;
    while i < b.len() {
        match b[i] {
            b'"' => return (i + 1, value, verbatim),
            b'\\' => {
                verbatim = false;
                i += 1;
                match b.get(i) {
                    Some(b'n') => value.push('\n'),
                    Some(b't') => value.push('\t'),
                    Some(b'r') => value.push('\r'),
                    Some(b'0') => value.push('\0'),
                    Some(b'\\') => value.push('\\'),
                    Some(b'"') => value.push('"'),
                    Some(b'\'') => value.push('\''),
                    Some(b'u') => {
                        // \u{XXXX}
                        let rest = &text[i + 1..];
                        if let Some(close) = rest.find('}') {
                            let hex = rest.get(1..close).unwrap_or("");
                            if let Some(ch) =
                                u32::from_str_radix(hex, 16).ok().and_then(char::from_u32)
                            {
                                value.push(ch);
                            }
                            i += close + 1;
                        }
                    }
                    Some(b'x') => {
                        if let Some(hex) = text.get(i + 1..i + 3) {
                            if let Ok(v) = u8::from_str_radix(hex, 16) {
                                value.push(v as char);
                            }
                        }
                        i += 2;
                    }
                    Some(b'\n') => {
                        // line continuation: skip leading whitespace of the next line
                        while matches!(b.get(i + 1), Some(b' ' | b'\t' | b'\n' | b'\r')) {
                            i += 1;
                        }
                    }
                    _ => {}
                }
                i += 1;
            }
            _ => {
                let ch_len = utf8_len(b[i]);
                value.push_str(&text[i..(i + ch_len).min(b.len())]);
                i += ch_len;
            }
        }
    }
    (b.len(), value, verbatim)
}

fn scan_raw_string(text: &str, start: usize) -> (usize, String) {
    let b = text.as_bytes();
    let mut i = start + 1;
    let mut hashes = 0;
    while b.get(i) == Some(&b'#') {
        hashes += 1;
        i += 1;
    }
    i += 1; // opening quote
    let content_start = i;
    while i < b.len() {
        if b[i] == b'"'
            && b[i + 1..]
                .iter()
                .take(hashes)
                .filter(|&&c| c == b'#')
                .count()
                == hashes
        {
            let value = text[content_start..i].to_string();
            return (i + 1 + hashes, value);
        }
        i += 1;
    }
    (b.len(), text[content_start.min(b.len())..].to_string())
}

fn utf8_len(first: u8) -> usize {
    match first {
        0x00..=0x7f => 1,
        0xc0..=0xdf => 2,
        0xe0..=0xef => 3,
        _ => 4,
    }
}

/// Line and column (both 1-based, column in characters) of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..floor_char_boundary(text, offset)];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |p| p + 1);
    let col = before[line_start..].chars().count() + 1;
    (line, col)
}

/// The text a model is read as: without a UTF-8 byte-order mark, and with old Mac line
/// endings (a lone CR) read as LF. Replacing one byte by one keeps every later offset, so
/// positions in the normalized text are lines and columns of the file as an editor shows it.
pub fn normalized(text: &str) -> std::borrow::Cow<'_, str> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let b = text.as_bytes();
    let lone_cr = |i: usize| b[i] == b'\r' && b.get(i + 1) != Some(&b'\n');
    if !(0..b.len()).any(lone_cr) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = b.to_vec();
    for (i, c) in out.iter_mut().enumerate() {
        if lone_cr(i) {
            *c = b'\n';
        }
    }
    // only ASCII bytes were replaced by ASCII bytes
    std::borrow::Cow::Owned(String::from_utf8(out).unwrap_or_else(|_| text.to_string()))
}

/// Byte offset of a 1-based line and column (column in characters).
pub fn offset_of(text: &str, line: usize, col: usize) -> usize {
    let mut offset = 0;
    for (n, l) in text.split_inclusive('\n').enumerate() {
        if n + 1 == line {
            let within: usize = l
                .chars()
                .take(col.saturating_sub(1))
                .map(char::len_utf8)
                .sum();
            return offset + within;
        }
        offset += l.len();
    }
    text.len()
}

fn floor_char_boundary(text: &str, mut i: usize) -> usize {
    while i > 0 && !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_skip_comments_and_decode_strings() {
        let text = r##"// "not this"
        ( a: "x\"y", /* "nor /* nested */ this" */ b: r#"raw"#, c: -12, d: DeadlockFree(x) )"##;
        let toks = tokenize(text);
        assert!(!toks.contains_key(&TokenKey::Str("not this".into())));
        assert!(!toks.contains_key(&TokenKey::Str("nor /* nested */ this".into())));
        let s = &toks[&TokenKey::Str("x\"y".into())][0];
        assert!(!s.verbatim);
        assert_eq!(&text[s.span.start..s.span.end], r#""x\"y""#);
        let r = &toks[&TokenKey::Str("raw".into())][0];
        assert_eq!(&text[r.span.start..r.span.end], "raw");
        assert!(toks.contains_key(&TokenKey::Int(-12)));
        assert!(toks[&TokenKey::Ident("DeadlockFree".into())][0].paren_follows);
    }

    #[test]
    fn sub_span_maps_into_plain_and_raw_strings() {
        let text = r##"("ab cd", r#"ef gh"#)"##;
        let toks = tokenize(text);
        for (value, inner) in [("ab cd", "cd"), ("ef gh", "gh")] {
            let t = toks[&TokenKey::Str(value.into())][0];
            let s = Spanned {
                value: value.to_string(),
                span: t.span,
                verbatim: t.verbatim,
            };
            let sub = s.sub_span(3..5);
            assert_eq!(&text[sub.start..sub.end], inner);
        }
    }

    #[test]
    fn claims_follow_file_order() {
        let text = r#"["a", "b", "a"]"#;
        let v: Vec<Spanned<String>> = with_positions(text, || ron::from_str(text)).expect("parses");
        assert_eq!(v[0].span, Span::new(2, 3));
        assert_eq!(v[2].span, Span::new(12, 13));
    }

    #[test]
    fn line_col_round_trips() {
        let text = "ab\ncdé\nf";
        for off in [0, 1, 3, 5, 8] {
            let (l, c) = line_col(text, off);
            assert_eq!(offset_of(text, l, c), off, "offset {off}");
        }
    }
}
