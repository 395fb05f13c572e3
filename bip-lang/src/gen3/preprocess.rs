//! The subset of the C preprocessor that `.gen` files use: `#include` of local files
//! (`"file"` from the including file's directory, then the search path; `<file>` from the
//! search path), object-like `#define` and `#undef`, `#if`/`#ifdef`/`#ifndef`/`#elif`/
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
/// Macro expansion nesting bound.
const MAX_MACRO_DEPTH: usize = 64;
/// Tokens after expansion: a bound on what macros may multiply.
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
    };
    p.file(path, shown, at)?;
    Ok(p.out)
}

struct Macro {
    body: Vec<Token>,
}

struct Cond {
    /// This group's tokens are kept.
    active: bool,
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
        let mut i = 0;
        while i < toks.len() {
            let t = &toks[i];
            let active = conds.iter().all(|c| c.active);
            if t.is_punct("#") && t.line_start {
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
                self.expand(t, &mut Vec::new())?;
            }
            i += 1;
        }
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
                let value = if active {
                    self.condition(word, args, span)?
                } else {
                    false
                };
                conds.push(Cond {
                    active: value,
                    taken: value || !active,
                    seen_else: false,
                    span,
                });
            }
            "elif" | "else" => {
                let parent_active =
                    conds.len() < 2 || conds[..conds.len() - 1].iter().all(|c| c.active);
                let Some(top) = conds.last_mut() else {
                    return Err(ModelError::new(format!("`#{word}` without `#if`"), span));
                };
                if top.seen_else {
                    return Err(ModelError::new(format!("`#{word}` after `#else`"), span)
                        .with_note(top.span, "in this `#if`"));
                }
                let taken = top.taken;
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
                if let Some(paren) = args.get(1) {
                    if paren.is_punct("(") && paren.span.start == name.1.end {
                        return Err(ModelError::new(
                            "function-like macros are not supported",
                            Span::new(name.1.start, paren.span.end),
                        )
                        .with_help("only `#define NAME value` is read in a `.gen` file"));
                    }
                }
                self.macros.insert(
                    name.0.to_string(),
                    Macro {
                        body: args[1..].to_vec(),
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
            let before = std::mem::take(&mut self.out);
            let r = self.expand(t, &mut Vec::new());
            let expanded = std::mem::replace(&mut self.out, before);
            r?;
            toks.extend(expanded);
            k += 1;
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

    /// Appends a token, or what a macro it names expands to; `active` are the macros being
    /// expanded, which are not expanded again (as in C).
    fn expand(&mut self, t: &Token, active: &mut Vec<String>) -> Result<(), ModelError> {
        if self.out.len() >= MAX_TOKENS {
            return Err(ModelError::new(
                "the file expands to too many tokens",
                t.span,
            ));
        }
        let name = match &t.tok {
            Tok::Ident(n) if self.macros.contains_key(n) && !active.contains(n) => n.clone(),
            _ => {
                self.out.push(t.clone());
                return Ok(());
            }
        };
        if active.len() >= MAX_MACRO_DEPTH {
            return Err(ModelError::new("macros nested too deeply", t.span));
        }
        let body: Vec<Token> = self
            .macros
            .get(&name)
            .map(|m| m.body.clone())
            .unwrap_or_default();
        active.push(name);
        for b in &body {
            // an expanded token is shown where the macro is used
            let placed = Token {
                tok: b.tok.clone(),
                span: t.span,
                line_start: false,
            };
            self.expand(&placed, active)?;
        }
        active.pop();
        Ok(())
    }
}
