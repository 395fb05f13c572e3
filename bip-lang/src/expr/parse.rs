//! A hand-written lexer and precedence-climbing parser for expressions, actions and
//! `forall` ranges. Every error carries the byte range it concerns.

use super::{Assign, BinOp, Expr, ExprKind, Ident, QuantKind, Range, UnOp};
use crate::source::Span;

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    pub message: String,
    /// Byte range within the parsed text.
    pub span: Span,
}

type PResult<T> = Result<T, ParseError>;

/// Parses an expression.
pub fn parse_expr(text: &str) -> PResult<Expr> {
    let mut p = Parser::new(text)?;
    let e = p.expr()?;
    p.expect_end()?;
    check_depth(&e)?;
    Ok(e)
}

/// Parses an action: assignments `target = value` separated by `;` (a trailing `;` and an
/// empty action are allowed).
pub fn parse_action(text: &str) -> PResult<Vec<Assign>> {
    let mut p = Parser::new(text)?;
    let mut out = Vec::new();
    while !p.at(&Tok::End) {
        if p.eat(&Tok::Semi) {
            continue;
        }
        let target = p.postfix()?;
        if !p.eat(&Tok::Assign) {
            return Err(p.error_here("expected `=` after the assigned variable"));
        }
        let value = p.expr()?;
        check_depth(&value)?;
        out.push(Assign { target, value });
        if !p.at(&Tok::End) && !p.eat(&Tok::Semi) {
            return Err(p.error_here("expected `;` between assignments"));
        }
    }
    Ok(out)
}

/// Parses a `forall` range: `i in lo..hi`.
pub fn parse_range(text: &str) -> PResult<Range> {
    let mut p = Parser::new(text)?;
    let r = p.range()?;
    p.expect_end()?;
    check_depth(&r.lo)?;
    check_depth(&r.hi)?;
    Ok(r)
}

/// The magnitude of `i64::MIN`: a literal may be this large only right after a minus.
const MIN_MAGNITUDE: u64 = 1 << 63;

fn too_big(span: Span) -> ParseError {
    ParseError {
        message: "integer literal does not fit in 64 bits".into(),
        span,
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    /// A literal's magnitude, at most [`MIN_MAGNITUDE`].
    Int(u64),
    Ident(String),
    LParen,
    RParen,
    LBracket,
    RBracket,
    Dot,
    DotDot,
    At,
    Comma,
    Colon,
    Semi,
    Question,
    Bang,
    Assign,
    Op(BinOp),
    End,
}

impl Tok {
    fn describe(&self) -> String {
        match self {
            Tok::Int(i) => format!("`{i}`"),
            Tok::Ident(s) => format!("`{s}`"),
            Tok::LParen => "`(`".into(),
            Tok::RParen => "`)`".into(),
            Tok::LBracket => "`[`".into(),
            Tok::RBracket => "`]`".into(),
            Tok::Dot => "`.`".into(),
            Tok::DotDot => "`..`".into(),
            Tok::At => "`@`".into(),
            Tok::Comma => "`,`".into(),
            Tok::Colon => "`:`".into(),
            Tok::Semi => "`;`".into(),
            Tok::Question => "`?`".into(),
            Tok::Bang => "`!`".into(),
            Tok::Assign => "`=`".into(),
            Tok::Op(op) => format!("`{}`", op.symbol()),
            Tok::End => "the end of the expression".into(),
        }
    }
}

fn lex(text: &str) -> PResult<Vec<(Tok, Span)>> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let start = i;
        let c = b[i];
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        let two = |s: &str| text[i..].starts_with(s);
        let (tok, len) = if c.is_ascii_digit() {
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'_') {
                j += 1;
            }
            if j < b.len() && (b[j].is_ascii_alphabetic()) {
                return Err(ParseError {
                    message: "a number cannot be followed by a letter".into(),
                    span: Span::new(i, j + 1),
                });
            }
            let digits: String = text[i..j].chars().filter(|&c| c != '_').collect();
            let v = digits
                .parse::<u64>()
                .ok()
                .filter(|&v| v <= MIN_MAGNITUDE)
                .ok_or_else(|| too_big(Span::new(i, j)))?;
            (Tok::Int(v), j - i)
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_alphanumeric() || b[j] == b'_') {
                j += 1;
            }
            (Tok::Ident(text[i..j].to_string()), j - i)
        } else if two("..") {
            (Tok::DotDot, 2)
        } else if two("==") {
            (Tok::Op(BinOp::Eq), 2)
        } else if two("!=") {
            (Tok::Op(BinOp::Ne), 2)
        } else if two("<=") {
            (Tok::Op(BinOp::Le), 2)
        } else if two(">=") {
            (Tok::Op(BinOp::Ge), 2)
        } else if two("&&") {
            (Tok::Op(BinOp::And), 2)
        } else if two("||") {
            (Tok::Op(BinOp::Or), 2)
        } else if two("=>") {
            (Tok::Op(BinOp::Implies), 2)
        } else {
            let t = match c {
                b'(' => Tok::LParen,
                b')' => Tok::RParen,
                b'[' => Tok::LBracket,
                b']' => Tok::RBracket,
                b'.' => Tok::Dot,
                b'@' => Tok::At,
                b',' => Tok::Comma,
                b':' => Tok::Colon,
                b';' => Tok::Semi,
                b'?' => Tok::Question,
                b'!' => Tok::Bang,
                b'=' => Tok::Assign,
                b'<' => Tok::Op(BinOp::Lt),
                b'>' => Tok::Op(BinOp::Gt),
                b'+' => Tok::Op(BinOp::Add),
                b'-' => Tok::Op(BinOp::Sub),
                b'*' => Tok::Op(BinOp::Mul),
                b'/' => Tok::Op(BinOp::Div),
                b'%' => Tok::Op(BinOp::Rem),
                _ => {
                    let ch = text[i..].chars().next().unwrap_or('?');
                    let hint = match ch {
                        '&' => " (logical and is `&&`)",
                        '|' => " (logical or is `||`)",
                        _ => "",
                    };
                    return Err(ParseError {
                        message: format!("unexpected character `{ch}`{hint}"),
                        span: Span::new(i, i + ch.len_utf8()),
                    });
                }
            };
            (t, 1)
        };
        i += len;
        out.push((tok, Span::new(start, i)));
    }
    out.push((Tok::End, Span::new(b.len(), b.len())));
    Ok(out)
}

/// Real nesting (parentheses, the operands of `!`, `-`, `=>` and `?:`, indices, call
/// arguments, quantifier bodies, postfix chains) is bounded, so that every pass over a tree,
/// here and later, recurses at most this deep: a pathological input is an error instead of a
/// stack overflow. A chain of operators of one precedence (`a && b && …`, `x + y - z + …`)
/// is one node however long, and one level deep.
pub const MAX_DEPTH: usize = 200;

/// Checks a tree's depth once, without recursion (trees are also built by the GenoM
/// expansion, not only by this parser).
pub fn check_depth(e: &Expr) -> PResult<()> {
    let mut stack = vec![(e, 1usize)];
    while let Some((e, d)) = stack.pop() {
        if d > MAX_DEPTH {
            return Err(ParseError {
                message: format!(
                    "expression nested more than {MAX_DEPTH} levels deep (parentheses, \
                     `!`, `-`, `=>`, `?:`, indices and quantifiers count; a chain of `&&`, \
                     `||`, `+` or `*` does not)"
                ),
                span: e.span,
            });
        }
        match &e.kind {
            ExprKind::Int(_) | ExprKind::Bool(_) | ExprKind::Name(_) => {}
            ExprKind::Index(a, b) | ExprKind::Binary(_, a, b) => {
                stack.push((a, d + 1));
                stack.push((b, d + 1));
            }
            ExprKind::Chain(first, rest) => {
                stack.push((first, d + 1));
                stack.extend(rest.iter().map(|(_, x)| (x, d + 1)));
            }
            ExprKind::Member(a, _) | ExprKind::At(a, _) | ExprKind::Unary(_, a) => {
                stack.push((a, d + 1))
            }
            ExprKind::Call(_, args) => stack.extend(args.iter().map(|a| (a, d + 1))),
            ExprKind::Cond(a, b, c) => {
                stack.push((a, d + 1));
                stack.push((b, d + 1));
                stack.push((c, d + 1));
            }
            ExprKind::Quant(_, r, body) => {
                stack.push((&r.lo, d + 1));
                stack.push((&r.hi, d + 1));
                stack.push((body, d + 1));
            }
        }
    }
    Ok(())
}

struct Parser {
    toks: Vec<(Tok, Span)>,
    pos: usize,
    depth: usize,
}

impl Parser {
    fn new(text: &str) -> PResult<Parser> {
        Ok(Parser {
            toks: lex(text)?,
            pos: 0,
            depth: 0,
        })
    }

    fn peek(&self) -> &Tok {
        &self.toks[self.pos].0
    }

    fn span(&self) -> Span {
        self.toks[self.pos].1
    }

    fn at(&self, t: &Tok) -> bool {
        self.peek() == t
    }

    fn bump(&mut self) -> (Tok, Span) {
        let t = self.toks[self.pos].clone();
        if self.pos + 1 < self.toks.len() {
            self.pos += 1;
        }
        t
    }

    fn eat(&mut self, t: &Tok) -> bool {
        if self.at(t) {
            self.bump();
            true
        } else {
            false
        }
    }

    fn error_here(&self, message: &str) -> ParseError {
        ParseError {
            message: format!("{message}, found {}", self.peek().describe()),
            span: self.span(),
        }
    }

    fn expect(&mut self, t: Tok) -> PResult<Span> {
        if self.at(&t) {
            Ok(self.bump().1)
        } else {
            Err(self.error_here(&format!("expected {}", t.describe())))
        }
    }

    fn expect_end(&self) -> PResult<()> {
        if self.at(&Tok::End) {
            Ok(())
        } else {
            Err(self.error_here("expected an operator or the end of the expression"))
        }
    }

    fn ident(&mut self, what: &str) -> PResult<Ident> {
        match self.peek().clone() {
            Tok::Ident(name) if !is_keyword(&name) => {
                let span = self.bump().1;
                Ok(Ident { name, span })
            }
            _ => Err(self.error_here(&format!("expected {what}"))),
        }
    }

    fn enter(&mut self) -> PResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(ParseError {
                message: format!("expression nested more than {MAX_DEPTH} levels deep"),
                span: self.span(),
            });
        }
        Ok(())
    }

    fn expr(&mut self) -> PResult<Expr> {
        self.enter()?;
        let r = self.cond();
        self.depth -= 1;
        r
    }

    fn cond(&mut self) -> PResult<Expr> {
        let c = self.implies()?;
        if self.eat(&Tok::Question) {
            let a = self.implies()?;
            self.expect(Tok::Colon)?;
            let b = self.expr()?;
            let span = Span::new(c.span.start, b.span.end);
            return Ok(Expr::new(
                ExprKind::Cond(Box::new(c), Box::new(a), Box::new(b)),
                span,
            ));
        }
        Ok(c)
    }

    /// `a => b => c` is `a => (b => c)`: each `=>` to the right nests one level.
    fn implies(&mut self) -> PResult<Expr> {
        let lhs = self.chain(BinOp::Or.precedence())?;
        if !self.eat(&Tok::Op(BinOp::Implies)) {
            return Ok(lhs);
        }
        self.enter()?;
        let rhs = self.implies();
        self.depth -= 1;
        let rhs = rhs?;
        let span = Span::new(lhs.span.start, rhs.span.end);
        Ok(Expr::new(
            ExprKind::Binary(BinOp::Implies, Box::new(lhs), Box::new(rhs)),
            span,
        ))
    }

    /// The operands joined by operators of precedence `p` (each operand made of tighter
    /// operators), read by a loop: a chain of any length is one node.
    fn chain(&mut self, p: u8) -> PResult<Expr> {
        let first = self.operand(p)?;
        let mut rest = Vec::new();
        while let Tok::Op(op) = *self.peek() {
            if op.precedence() != p {
                break;
            }
            self.bump();
            let x = self.operand(p)?;
            if op.is_comparison() {
                if let Tok::Op(next) = *self.peek() {
                    if next.is_comparison() {
                        return Err(ParseError {
                            message: "comparisons do not chain; use `&&` or parentheses".into(),
                            span: self.span(),
                        });
                    }
                }
            }
            rest.push((op, x));
        }
        Ok(join(first, rest))
    }

    fn operand(&mut self, p: u8) -> PResult<Expr> {
        if p >= BinOp::Mul.precedence() {
            self.unary()
        } else {
            self.chain(p + 1)
        }
    }

    fn unary(&mut self) -> PResult<Expr> {
        let start = self.span().start;
        let op = match self.peek() {
            Tok::Bang => UnOp::Not,
            Tok::Op(BinOp::Sub) => UnOp::Neg,
            _ => return self.postfix(),
        };
        self.bump();
        if let (UnOp::Neg, Tok::Int(MIN_MAGNITUDE)) = (op, self.peek()) {
            // the minus belongs to the literal: this is i64::MIN, whose magnitude alone
            // does not fit
            let end = self.bump().1.end;
            return Ok(Expr::new(ExprKind::Int(i64::MIN), Span::new(start, end)));
        }
        self.enter()?;
        let e = self.unary();
        self.depth -= 1;
        let e = e?;
        let span = Span::new(start, e.span.end);
        // fold `-literal` so that printing stays simple
        if let (UnOp::Neg, ExprKind::Int(v)) = (op, &e.kind) {
            if let Some(neg) = v.checked_neg() {
                return Ok(Expr::new(ExprKind::Int(neg), span));
            }
        }
        Ok(Expr::new(ExprKind::Unary(op, Box::new(e)), span))
    }

    fn postfix(&mut self) -> PResult<Expr> {
        let mut e = self.primary()?;
        loop {
            match self.peek() {
                Tok::LBracket => {
                    self.bump();
                    let index = self.expr()?;
                    let end = self.expect(Tok::RBracket)?.end;
                    let span = Span::new(e.span.start, end);
                    e = Expr::new(ExprKind::Index(Box::new(e), Box::new(index)), span);
                }
                Tok::Dot => {
                    self.bump();
                    let name = self.ident("a name after `.`")?;
                    let span = Span::new(e.span.start, name.span.end);
                    e = Expr::new(ExprKind::Member(Box::new(e), name), span);
                }
                Tok::At => {
                    self.bump();
                    let loc = self.ident("a location name after `@`")?;
                    let span = Span::new(e.span.start, loc.span.end);
                    e = Expr::new(ExprKind::At(Box::new(e), loc), span);
                }
                _ => return Ok(e),
            }
        }
    }

    fn primary(&mut self) -> PResult<Expr> {
        let (tok, span) = (self.peek().clone(), self.span());
        match tok {
            Tok::Int(v) => {
                self.bump();
                let v = i64::try_from(v).map_err(|_| too_big(span))?;
                Ok(Expr::new(ExprKind::Int(v), span))
            }
            Tok::LParen => {
                self.bump();
                let mut e = self.expr()?;
                let end = self.expect(Tok::RParen)?.end;
                // keep the parentheses in the span so carets cover what the user wrote
                e.span = Span::new(span.start, end);
                Ok(e)
            }
            Tok::Ident(name) => match name.as_str() {
                "true" | "false" => {
                    self.bump();
                    Ok(Expr::new(ExprKind::Bool(name == "true"), span))
                }
                "forall" | "exists" | "sum" | "count" => {
                    self.bump();
                    let kind = match name.as_str() {
                        "forall" => QuantKind::Forall,
                        "exists" => QuantKind::Exists,
                        "sum" => QuantKind::Sum,
                        _ => QuantKind::Count,
                    };
                    let range = self.range()?;
                    self.expect(Tok::Colon)?;
                    let body = self.expr()?;
                    let full = Span::new(span.start, body.span.end);
                    Ok(Expr::new(
                        ExprKind::Quant(kind, Box::new(range), Box::new(body)),
                        full,
                    ))
                }
                "in" => Err(self.error_here("expected an expression")),
                _ => {
                    self.bump();
                    if self.at(&Tok::LParen) {
                        self.bump();
                        let mut args = Vec::new();
                        if !self.at(&Tok::RParen) {
                            loop {
                                args.push(self.expr()?);
                                if !self.eat(&Tok::Comma) {
                                    break;
                                }
                            }
                        }
                        let end = self.expect(Tok::RParen)?.end;
                        return Ok(Expr::new(
                            ExprKind::Call(Ident { name, span }, args),
                            Span::new(span.start, end),
                        ));
                    }
                    Ok(Expr::new(ExprKind::Name(name), span))
                }
            },
            _ => Err(self.error_here("expected an expression")),
        }
    }

    fn range(&mut self) -> PResult<Range> {
        let var = self.ident("a variable name")?;
        match self.peek() {
            Tok::Ident(k) if k == "in" => {
                self.bump();
            }
            _ => return Err(self.error_here("expected `in`")),
        }
        let lo = self.chain(BinOp::Add.precedence())?;
        if !self.eat(&Tok::DotDot) {
            return Err(self.error_here("expected `..` in the range `lo..hi`"));
        }
        let hi = self.chain(BinOp::Add.precedence())?;
        Ok(Range { var, lo, hi })
    }
}

/// One operand alone, two as a binary node, more as a chain.
fn join(first: Expr, mut rest: Vec<(BinOp, Expr)>) -> Expr {
    let Some((_, last)) = rest.last() else {
        return first;
    };
    let span = Span::new(first.span.start, last.span.end);
    if rest.len() == 1 {
        let (op, x) = rest.pop().expect("one operand");
        return Expr::new(ExprKind::Binary(op, Box::new(first), Box::new(x)), span);
    }
    Expr::new(ExprKind::Chain(Box::new(first), rest), span)
}

fn is_keyword(s: &str) -> bool {
    matches!(
        s,
        "true" | "false" | "forall" | "exists" | "sum" | "count" | "in"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> ParseError {
        parse_expr(text).expect_err("should not parse")
    }

    #[test]
    fn precedence_follows_the_model_spec() {
        // weakest first: ?:, =>, ||, &&, comparisons, + -, * / %, unary
        let e = parse_expr("a || b && c => d ? x : y").unwrap();
        let ExprKind::Cond(c, ..) = &e.kind else {
            panic!("expected ?: at the top, got {e:?}")
        };
        let ExprKind::Binary(BinOp::Implies, l, _) = &c.kind else {
            panic!("expected => under ?:")
        };
        assert!(matches!(l.kind, ExprKind::Binary(BinOp::Or, ..)));
        let e = parse_expr("1 + 2 * 3 < 8 && !q").unwrap();
        assert_eq!(e.to_string(), "1 + 2 * 3 < 8 && !q");
        let ExprKind::Binary(BinOp::And, l, r) = &e.kind else {
            panic!()
        };
        assert!(matches!(l.kind, ExprKind::Binary(BinOp::Lt, ..)));
        assert!(matches!(r.kind, ExprKind::Unary(UnOp::Not, _)));
    }

    #[test]
    fn implication_is_right_associative_and_arithmetic_left() {
        let e = parse_expr("a => b => c").unwrap();
        let ExprKind::Binary(BinOp::Implies, _, r) = &e.kind else {
            panic!()
        };
        assert!(matches!(r.kind, ExprKind::Binary(BinOp::Implies, ..)));
        let e = parse_expr("a - b - c").unwrap();
        let ExprKind::Chain(first, rest) = &e.kind else {
            panic!()
        };
        assert!(matches!(first.kind, ExprKind::Name(_)));
        assert_eq!(rest.len(), 2);
        assert_eq!(e.to_string(), "a - b - c");
        assert_eq!(
            parse_expr("a - (b - c)").unwrap().to_string(),
            "a - (b - c)"
        );
    }

    #[test]
    fn postfix_chains_and_quantifiers() {
        let e = parse_expr("forall i in 0..N: !(phil[i]@eating && phil[(i+1)%N]@eating)").unwrap();
        let ExprKind::Quant(QuantKind::Forall, r, body) = &e.kind else {
            panic!()
        };
        assert_eq!(r.var.name, "i");
        assert!(matches!(body.kind, ExprKind::Unary(UnOp::Not, _)));
        let e = parse_expr("m.S@start").unwrap();
        assert!(matches!(e.kind, ExprKind::At(..)));
        let e = parse_expr("age(pom.pose) <= 2").unwrap();
        assert!(matches!(e.kind, ExprKind::Binary(BinOp::Le, ..)));
    }

    #[test]
    fn spans_point_at_the_offending_token() {
        let e = err("x + * y");
        assert_eq!(e.span, Span::new(4, 5));
        let e = err("(a && b");
        assert_eq!(e.span, Span::new(7, 7));
        assert!(e.message.contains("`)`"), "{}", e.message);
        let e = err("a & b");
        assert!(e.message.contains("&&"));
        assert_eq!(e.span, Span::new(2, 3));
        let e = err("a < b < c");
        assert!(e.message.contains("chain"));
        let e = err("99999999999999999999");
        assert!(e.message.contains("64 bits"));
        let e = err("9223372036854775808");
        assert!(e.message.contains("64 bits"));
        assert_eq!(e.span, Span::new(0, 19));
        let e = err("");
        assert!(e.message.contains("expected an expression"));
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let text = "(".repeat(10_000) + "1" + &")".repeat(10_000);
        assert!(err(&text).message.contains("nested"));
        let text = "!".repeat(10_000) + "x";
        assert!(err(&text).message.contains("nested"));
        let text = "-(".repeat(10_000) + "1" + &")".repeat(10_000);
        assert!(err(&text).message.contains("nested"));
        let text = "a[".repeat(10_000) + "1" + &"]".repeat(10_000);
        assert!(err(&text).message.contains("nested"));
        let text = vec!["a"; 10_000].join(" => ");
        assert!(err(&text).message.contains("nested"));
        let text = "(".repeat(MAX_DEPTH - 1) + "1" + &")".repeat(MAX_DEPTH - 1);
        assert!(parse_expr(&text).is_ok());
        let text = "(".repeat(MAX_DEPTH) + "1" + &")".repeat(MAX_DEPTH);
        assert!(err(&text).message.contains("nested"));
    }

    #[test]
    fn a_flat_chain_is_one_level_however_long() {
        for op in ["&&", "||", "+", "*"] {
            let text = vec!["a"; 100_000].join(&format!(" {op} "));
            let e = parse_expr(&text).expect("a long chain parses");
            let ExprKind::Chain(_, rest) = &e.kind else {
                panic!("expected a chain")
            };
            assert_eq!(rest.len(), 99_999);
            assert_eq!(e.to_string(), text);
        }
        let e = parse_expr("a + b - c * d / e + f").unwrap();
        let ExprKind::Chain(first, rest) = &e.kind else {
            panic!()
        };
        assert!(matches!(first.kind, ExprKind::Name(_)));
        let ops: Vec<_> = rest.iter().map(|(op, _)| *op).collect();
        assert_eq!(ops, [BinOp::Add, BinOp::Sub, BinOp::Add]);
        assert!(matches!(rest[1].1.kind, ExprKind::Chain(..)));
    }

    #[test]
    fn the_minus_belongs_to_the_literal() {
        let e = parse_expr("-9223372036854775808").unwrap();
        assert_eq!(e.kind, ExprKind::Int(i64::MIN));
        assert_eq!(e.to_string(), "-9223372036854775808");
        let e = parse_expr("x - -9223372036854775808").unwrap();
        assert_eq!(e.to_string(), "x - -9223372036854775808");
        let e = parse_expr("--9223372036854775808").unwrap();
        assert!(matches!(e.kind, ExprKind::Unary(UnOp::Neg, _)));
        assert_eq!(parse_expr(&e.to_string()).unwrap(), e);
        let a = parse_action("x = -9223372036854775808").unwrap();
        assert_eq!(a[0].value.kind, ExprKind::Int(i64::MIN));
    }

    #[test]
    fn actions_and_ranges() {
        let a = parse_action("x = x + 1; y = b[i].v; ").unwrap();
        assert_eq!(a.len(), 2);
        assert_eq!(a[1].to_string(), "y = b[i].v");
        assert!(parse_action("").unwrap().is_empty());
        assert!(parse_action("x == 1").is_err());
        assert!(parse_action("x = 1 y = 2").is_err());
        let r = parse_range("i in 0..N-1").unwrap();
        assert_eq!(r.to_string(), "i in 0..N - 1");
        assert!(parse_range("i of 0..3").is_err());
    }
}
