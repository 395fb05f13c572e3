//! The subset of the C preprocessor that `.gen` files use: `#include` of local files
//! (`"file"` from the including file's directory, then the search path; `<file>` from the
//! search path), `#define` of object-like and function-like macros (`#define MS(x) ((x) *
//! 1000)`, without the `#` and `##` operators or variadic parameters) and `#undef`,
//! `#if`/`#ifdef`/`#ifndef`/`#elif`/
//! `#else`/`#endif` on them, `#pragma` (accepted and ignored: `require` and `native` say
//! how to build the codels), and `#error`. Anything else is an error naming it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::consts::{self, Value};
use super::cursor::Cursor;
use super::lexer::{tokenize, Tok, Token};
use crate::diag::ModelError;
use crate::source::{normalized, Span};
use crate::source_map::SourceMap;

/// `#include` nesting bound (an include cycle without guards meets it).
const MAX_INCLUDE_DEPTH: usize = 32;
/// Macro expansion nesting bound: a macro's replacement within another's, and a macro
/// call in another's argument (`F(F(F(1)))`), counted together.
const MAX_MACRO_DEPTH: usize = 64;
/// `#if` nesting bound.
const MAX_IF_DEPTH: usize = 256;
/// Tokens the expansion may write, its arguments and replacements counted: a bound on what
/// macros may multiply.
const MAX_TOKENS: usize = 1_000_000;

/// Where the files come from and go to.
pub struct Input<'a> {
    /// The search path of `#include`.
    pub include: &'a [PathBuf],
    /// Where each file read is placed.
    pub files: &'a mut SourceMap,
    /// The model file's length (files are placed after it).
    pub main_len: usize,
}

/// The tokens of `path` once preprocessed; `shown` is its name in messages, `at` where
/// it is asked for (an error reading it points there).
pub fn preprocess(
    input: Input,
    path: &Path,
    shown: &str,
    at: Span,
) -> Result<Vec<Token>, ModelError> {
    let mut p = Preprocessor {
        input,
        macros: HashMap::new(),
        out: Vec::new(),
        depth: 0,
        arguments: 0,
        written: 0,
    };
    p.file(path, shown, at)?;
    Ok(p.out)
}

struct Macro {
    /// The parameters of a function-like macro; `None` for an object-like one.
    params: Option<Vec<String>>,
    body: Vec<Token>,
}

struct Cond {
    /// This group's tokens are kept (the groups around it included).
    active: bool,
    /// The groups around it are kept.
    outer: bool,
    /// A group of this `#if` chain was kept (or the chain is inside a skipped group).
    taken: bool,
    seen_else: bool,
    span: Span,
}

struct Preprocessor<'a> {
    input: Input<'a>,
    macros: HashMap<String, Macro>,
    out: Vec<Token>,
    depth: usize,
    /// Macro arguments being expanded within each other.
    arguments: usize,
    /// Tokens written so far, to the output, an argument or a replacement.
    written: usize,
}

impl Preprocessor<'_> {
    fn file(&mut self, path: &Path, shown: &str, at: Span) -> Result<(), ModelError> {
        if self.depth >= MAX_INCLUDE_DEPTH {
            return Err(ModelError::new(
                format!("`#include` nested more than {MAX_INCLUDE_DEPTH} deep"),
                at,
            )
            .with_help("an include cycle? guard the file with `#ifndef`/`#define`/`#endif`"));
        }
        let text = std::fs::read_to_string(path)
            .map_err(|e| ModelError::new(format!("cannot read {shown}: {e}"), at))?;
        let text = Arc::new(normalized(&text).into_owned());
        let base = self
            .input
            .files
            .add(self.input.main_len, shown, Arc::clone(&text));
        let toks = tokenize(&text, base)?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut conds: Vec<Cond> = Vec::new();
        // the kept tokens since the last directive: a macro's arguments may span lines
        let mut run: Vec<Token> = Vec::new();
        let mut i = 0;
        while i < toks.len() {
            let t = &toks[i];
            let active = conds.last().is_none_or(|c| c.active);
            if t.is_punct("#") && t.line_start {
                self.expand(&std::mem::take(&mut run), &mut Vec::new())?;
                let mut j = i + 1;
                while j < toks.len() && !toks[j].line_start {
                    j += 1;
                }
                let line = &toks[i..j];
                i = j;
                self.directive(line, &mut conds, active, &text, base, &dir)?;
                continue;
            }
            if active {
                run.push(t.clone());
            }
            i += 1;
        }
        self.expand(&run, &mut Vec::new())?;
        if let Some(c) = conds.last() {
            return Err(ModelError::new("this `#if` has no `#endif`", c.span));
        }
        Ok(())
    }

    fn directive(
        &mut self,
        line: &[Token],
        conds: &mut Vec<Cond>,
        active: bool,
        text: &str,
        base: usize,
        dir: &Path,
    ) -> Result<(), ModelError> {
        let hash = &line[0];
        let Some(word_tok) = line.get(1) else {
            return Ok(()); // the null directive
        };
        let span = Span::new(hash.span.start, word_tok.span.end);
        let args = &line[2..];
        let word = match &word_tok.tok {
            Tok::Ident(w) => w.as_str(),
            Tok::Int(_) => "line",
            _ => "",
        };
        match word {
            "if" | "ifdef" | "ifndef" => {
                if conds.len() >= MAX_IF_DEPTH {
                    return Err(ModelError::new(
                        format!("`#if` nested more than {MAX_IF_DEPTH} deep"),
                        span,
                    ));
                }
                let value = if active {
                    self.condition(word, args, span)?
                } else {
                    false
                };
                conds.push(Cond {
                    active: value,
                    outer: active,
                    taken: value || !active,
                    seen_else: false,
                    span,
                });
            }
            "elif" | "else" => {
                let Some(top) = conds.last_mut() else {
                    return Err(ModelError::new(format!("`#{word}` without `#if`"), span));
                };
                if top.seen_else {
                    return Err(ModelError::new(format!("`#{word}` after `#else`"), span)
                        .with_note(top.span, "in this `#if`"));
                }
                let taken = top.taken;
                let parent_active = top.outer;
                top.seen_else = word == "else";
                let value = if taken || !parent_active {
                    false
                } else if word == "else" {
                    true
                } else {
                    self.condition("if", args, span)?
                };
                let Some(top) = conds.last_mut() else {
                    return Ok(());
                };
                top.active = value;
                top.taken = taken || value;
            }
            "endif" => {
                if conds.pop().is_none() {
                    return Err(ModelError::new("`#endif` without `#if`", span));
                }
            }
            _ if !active => {}
            "define" => {
                let Some(name) = args.first().and_then(|t| t.ident().map(|n| (n, t.span))) else {
                    return Err(ModelError::new("`#define` needs a name", span));
                };
                let function_like = args
                    .get(1)
                    .is_some_and(|p| p.is_punct("(") && p.span.start == name.1.end);
                let (params, body) = if function_like {
                    let (params, rest) = parameters(&args[2..], span)?;
                    (Some(params), rest)
                } else {
                    (None, &args[1..])
                };
                if let Some(op) = body.iter().find(|t| t.is_punct("#")) {
                    return Err(ModelError::new(
                        "the `#` and `##` operators are not supported",
                        op.span,
                    )
                    .with_help("a `.gen` file's macros substitute their arguments as they are"));
                }
                self.macros.insert(
                    name.0.to_string(),
                    Macro {
                        params,
                        body: body.to_vec(),
                    },
                );
            }
            "undef" => {
                if let Some(n) = args.first().and_then(Token::ident) {
                    self.macros.remove(n);
                }
            }
            "include" => self.include(args, span, text, base, dir)?,
            "pragma" | "warning" => {}
            "error" => {
                let msg = match (args.first(), args.last()) {
                    (Some(a), Some(b)) => text
                        .get(a.span.start - base..b.span.end - base)
                        .unwrap_or(""),
                    _ => "",
                };
                return Err(ModelError::new(format!("#error {msg}"), span));
            }
            _ => {
                let what = text.get(span.start - base..span.end - base).unwrap_or("#");
                return Err(ModelError::new(
                    format!("the preprocessor directive `{what}` is not supported"),
                    span,
                )
                .with_help("a `.gen` file may use #include, #define, #undef, #if, #ifdef, #ifndef, #elif, #else, #endif, #pragma and #error"));
            }
        }
        Ok(())
    }

    /// The value of `#if EXPR`, `#ifdef NAME` or `#ifndef NAME`.
    fn condition(&mut self, word: &str, args: &[Token], span: Span) -> Result<bool, ModelError> {
        if word != "if" {
            let Some(name) = args.first().and_then(Token::ident) else {
                return Err(ModelError::new(format!("`#{word}` needs a name"), span));
            };
            return Ok(self.macros.contains_key(name) == (word == "ifdef"));
        }
        // `defined NAME` and `defined(NAME)` first, then macros; other names are 0
        let mut toks = Vec::new();
        let mut k = 0;
        while k < args.len() {
            let t = &args[k];
            if t.is_ident("defined") {
                let paren = args.get(k + 1).is_some_and(|t| t.is_punct("("));
                let name_at = if paren { k + 2 } else { k + 1 };
                let Some(name) = args.get(name_at).and_then(Token::ident) else {
                    return Err(ModelError::new("`defined` needs a name", t.span));
                };
                let value = i128::from(self.macros.contains_key(name));
                k = name_at + 1;
                if paren {
                    if !args.get(k).is_some_and(|t| t.is_punct(")")) {
                        return Err(ModelError::new("expected `)` after `defined(NAME`", t.span));
                    }
                    k += 1;
                }
                toks.push(Token {
                    tok: Tok::Int(value),
                    span: t.span,
                    line_start: false,
                });
                continue;
            }
            // up to the next `defined`, expanded together (a macro call is whole)
            let end = (k + 1..args.len())
                .find(|&e| args[e].is_ident("defined"))
                .unwrap_or(args.len());
            toks.extend(self.expanded(&args[k..end], &mut Vec::new())?);
            k = end;
        }
        if toks.is_empty() {
            return Err(ModelError::new("`#if` needs a condition", span));
        }
        let end = toks.last().map_or(span, |t| t.span);
        let mut c = Cursor::new(toks, Span::new(end.end, end.end));
        let zero = |_: &str| Some(Value::Int(0));
        let (v, _) = consts::expression(&mut c, &zero, true)?;
        if let Some(extra) = c.peek() {
            return Err(ModelError::new(
                format!("unexpected {} in `#if`", extra.describe()),
                extra.span,
            ));
        }
        Ok(v.as_f64() != 0.0)
    }

    fn include(
        &mut self,
        args: &[Token],
        span: Span,
        text: &str,
        base: usize,
        dir: &Path,
    ) -> Result<(), ModelError> {
        let (name, local, at) = match args {
            [Token {
                tok: Tok::Str(s),
                span: s_span,
                ..
            }] => (s.clone(), true, *s_span),
            [first, .., last] if first.is_punct("<") && last.is_punct(">") => {
                let inner = text
                    .get(first.span.end - base..last.span.start - base)
                    .unwrap_or("")
                    .trim()
                    .to_string();
                (inner, false, Span::new(first.span.start, last.span.end))
            }
            _ => {
                return Err(ModelError::new(
                    "`#include` needs a file: `\"file.gen\"` or `<file.idl>`",
                    span,
                ))
            }
        };
        let mut searched: Vec<PathBuf> = Vec::new();
        if local {
            searched.push(dir.to_path_buf());
        }
        searched.extend(self.input.include.iter().cloned());
        let found = searched.iter().map(|d| d.join(&name)).find(|p| p.is_file());
        let Some(path) = found else {
            let dirs: Vec<String> = searched
                .iter()
                .map(|d| {
                    let s = d.display().to_string();
                    if s.is_empty() {
                        ".".to_string()
                    } else {
                        s
                    }
                })
                .collect();
            return Err(ModelError::new(format!("cannot find the included file `{name}`"), at)
                .with_help(format!(
                    "searched in: {}; add a directory to the search path (`include: [\"dir/\"]` in the model, `-I dir` for `bip import`)",
                    dirs.join(", ")
                )));
        };
        let shown = path.display().to_string();
        self.depth += 1;
        let r = self.file(&path, &shown, at);
        self.depth -= 1;
        r
    }

    /// Counts `n` tokens written, which the bound on the expansion limits.
    fn count(&mut self, n: usize, at: Span) -> Result<(), ModelError> {
        self.written = self.written.saturating_add(n);
        if self.written > MAX_TOKENS {
            return Err(ModelError::new("the file expands to too many tokens", at)
                .with_help("a macro multiplies its tokens beyond what a `.gen` file needs"));
        }
        Ok(())
    }

    /// `toks` with their macros expanded, aside from the output.
    fn expanded(
        &mut self,
        toks: &[Token],
        active: &mut Vec<String>,
    ) -> Result<Vec<Token>, ModelError> {
        let before = std::mem::take(&mut self.out);
        let r = self.expand(toks, active);
        let out = std::mem::replace(&mut self.out, before);
        r.map(|()| out)
    }

    /// Appends `toks`, each macro they name replaced by its expansion; `active` are the
    /// macros being expanded, which are not expanded again (as in C). A function-like
    /// macro's name not followed by `(` is kept as it is.
    fn expand(&mut self, toks: &[Token], active: &mut Vec<String>) -> Result<(), ModelError> {
        let mut i = 0;
        while i < toks.len() {
            let t = &toks[i];
            i += 1;
            self.count(1, t.span)?;
            let Some((name, m)) = t.ident().and_then(|n| {
                let m = self.macros.get(n)?;
                (!active.iter().any(|a| a == n)).then(|| (n.to_string(), m))
            }) else {
                self.out.push(t.clone());
                continue;
            };
            let call = m.params.is_some() && toks.get(i).is_some_and(|p| p.is_punct("("));
            if m.params.is_some() && !call {
                self.out.push(t.clone());
                continue;
            }
            if active.len() + self.arguments >= MAX_MACRO_DEPTH {
                return Err(ModelError::new(
                    format!("macros nested more than {MAX_MACRO_DEPTH} deep"),
                    t.span,
                ));
            }
            let (params, body) = (m.params.clone(), m.body.clone());
            // an expanded token of the body is shown where the macro is used
            let placed = |b: &Token| Token {
                tok: b.tok.clone(),
                span: t.span,
                line_start: false,
            };
            let replacement: Vec<Token> = match params {
                None => body.iter().map(placed).collect(),
                Some(params) => {
                    let (args, next) = arguments(toks, i, &name, t.span)?;
                    i = next;
                    let wanted = params.len().max(1);
                    if args.len() != wanted && !(params.is_empty() && args.len() == 1) {
                        return Err(ModelError::new(
                            format!(
                                "macro `{name}` takes {} argument{}, given {}",
                                params.len(),
                                if params.len() == 1 { "" } else { "s" },
                                args.len()
                            ),
                            t.span,
                        ));
                    }
                    if params.is_empty() && args.first().is_some_and(|a| !a.is_empty()) {
                        return Err(ModelError::new(
                            format!("macro `{name}` takes no argument"),
                            t.span,
                        ));
                    }
                    // each argument is expanded on its own, then put in place
                    self.count(args.iter().map(Vec::len).sum(), t.span)?;
                    let mut values = Vec::with_capacity(args.len());
                    self.arguments += 1;
                    let expanded: Result<(), ModelError> = args.iter().try_for_each(|a| {
                        values.push(self.expanded(a, active)?);
                        Ok(())
                    });
                    self.arguments -= 1;
                    expanded?;
                    let mut out = Vec::new();
                    for b in &body {
                        match b.ident().and_then(|n| params.iter().position(|p| p == n)) {
                            Some(k) => {
                                self.count(values[k].len(), t.span)?;
                                out.extend(values[k].iter().cloned());
                            }
                            None => out.push(placed(b)),
                        }
                    }
                    out
                }
            };
            active.push(name);
            let r = self.expand(&replacement, active);
            active.pop();
            r?;
        }
        Ok(())
    }
}

/// The parameters of a function-like `#define` after its `(`, and the body after the `)`.
fn parameters(toks: &[Token], at: Span) -> Result<(Vec<String>, &[Token]), ModelError> {
    let mut params = Vec::new();
    let mut k = 0;
    if toks.first().is_some_and(|t| t.is_punct(")")) {
        return Ok((params, &toks[1..]));
    }
    loop {
        let Some(t) = toks.get(k) else {
            return Err(ModelError::new(
                "expected `)` closing the macro's parameters",
                at,
            ));
        };
        if t.is_punct(".") {
            return Err(ModelError::new("variadic macros are not supported", t.span));
        }
        let Some(n) = t.ident() else {
            return Err(ModelError::new(
                format!("expected a parameter name, found {}", t.describe()),
                t.span,
            ));
        };
        if params.iter().any(|p| p == n) {
            return Err(ModelError::new(
                format!("parameter `{n}` is repeated"),
                t.span,
            ));
        }
        params.push(n.to_string());
        match toks.get(k + 1) {
            Some(p) if p.is_punct(",") => k += 2,
            Some(p) if p.is_punct(")") => return Ok((params, &toks[k + 2..])),
            Some(p) => {
                return Err(ModelError::new(
                    format!("expected `,` or `)`, found {}", p.describe()),
                    p.span,
                ))
            }
            None => {
                return Err(ModelError::new(
                    "expected `)` closing the macro's parameters",
                    at,
                ))
            }
        }
    }
}

/// The arguments of a macro call whose `(` is at `toks[open]`: split at the commas outside
/// parentheses, and the index after the closing `)`.
fn arguments(
    toks: &[Token],
    open: usize,
    name: &str,
    at: Span,
) -> Result<(Vec<Vec<Token>>, usize), ModelError> {
    let mut args = vec![Vec::new()];
    let mut depth = 0usize;
    for (k, t) in toks.iter().enumerate().skip(open + 1) {
        if t.is_punct(")") && depth == 0 {
            return Ok((args, k + 1));
        }
        if t.is_punct("(") {
            depth += 1;
        } else if t.is_punct(")") {
            depth -= 1;
        } else if t.is_punct(",") && depth == 0 {
            args.push(Vec::new());
            continue;
        }
        if let Some(last) = args.last_mut() {
            last.push(t.clone());
        }
    }
    Err(
        ModelError::new(format!("the call of macro `{name}` has no closing `)`"), at)
            .with_help("a macro's arguments end before the next preprocessor directive"),
    )
}
