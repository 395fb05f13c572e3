//! Constant expressions: IDL's (`const` values, periods, sizes, bounds) and the
//! preprocessor's `#if` conditions, which add C's comparisons and logical operators. One
//! evaluator serves both, with C's precedence; names are looked up by the caller.

use super::cursor::Cursor;
use super::lexer::Tok;
use crate::diag::ModelError;
use crate::source::Span;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Int(i128),
    Float(f64),
}

impl Value {
    pub fn as_f64(self) -> f64 {
        match self {
            Value::Int(i) => i as f64,
            Value::Float(f) => f,
        }
    }

    fn truth(self) -> bool {
        self.as_f64() != 0.0
    }
}

/// How a name in an expression gets its value: `None` if it has none.
pub type Lookup<'a> = &'a dyn Fn(&str) -> Option<Value>;

/// Binary operators by precedence, loosest first.
const LEVELS: &[&[&str]] = &[
    &["||"],
    &["&&"],
    &["|"],
    &["^"],
    &["&"],
    &["==", "!="],
    &["<", ">", "<=", ">="],
    &["<<", ">>"],
    &["+", "-"],
    &["*", "/", "%"],
];

/// Operators an IDL constant may use (`#if` may use them all). Comparisons are not among
/// them: `<` and `>` close templates there.
const IDL_OPS: &[&str] = &["|", "^", "&", "<<", ">>", "+", "-", "*", "/", "%"];

/// Reads and evaluates an expression; `c_ops` allows the operators of `#if`.
pub fn expression(
    c: &mut Cursor,
    lookup: Lookup,
    c_ops: bool,
) -> Result<(Value, Span), ModelError> {
    let start = c.here();
    let v = binary(c, lookup, c_ops, 0, 0)?;
    Ok((v, Span::new(start.start, c.last_span().end)))
}

/// Nesting bound: a file of a million `(` must give an error, not overflow the stack.
const MAX_DEPTH: usize = 200;

fn binary(
    c: &mut Cursor,
    lookup: Lookup,
    c_ops: bool,
    level: usize,
    depth: usize,
) -> Result<Value, ModelError> {
    if level == LEVELS.len() {
        return unary(c, lookup, c_ops, depth);
    }
    let mut lhs = binary(c, lookup, c_ops, level + 1, depth)?;
    loop {
        let Some(op) = c.peek().and_then(|t| match &t.tok {
            Tok::Punct(p) if LEVELS[level].contains(p) && (c_ops || IDL_OPS.contains(p)) => {
                Some((*p, t.span))
            }
            _ => None,
        }) else {
            return Ok(lhs);
        };
        c.next();
        let rhs = binary(c, lookup, c_ops, level + 1, depth)?;
        lhs = apply(op.0, lhs, rhs).map_err(|m| ModelError::new(m, op.1))?;
    }
}

fn unary(c: &mut Cursor, lookup: Lookup, c_ops: bool, depth: usize) -> Result<Value, ModelError> {
    if depth > MAX_DEPTH {
        return Err(ModelError::new(
            "this expression is nested too deeply",
            c.here(),
        ));
    }
    for op in ["-", "+", "~", "!"] {
        if op == "!" && !c_ops {
            continue;
        }
        if c.eat_punct(op).is_some() {
            let at = c.last_span();
            let v = unary(c, lookup, c_ops, depth + 1)?;
            return Ok(match (op, v) {
                ("-", Value::Int(i)) => Value::Int(
                    i.checked_neg()
                        .ok_or_else(|| ModelError::new("`-` overflows here", at))?,
                ),
                ("-", Value::Float(f)) => Value::Float(-f),
                ("~", Value::Int(i)) => Value::Int(!i),
                ("!", v) => Value::Int(i128::from(!v.truth())),
                (_, v) => v,
            });
        }
    }
    if c.eat_punct("(").is_some() {
        let v = binary(c, lookup, c_ops, 0, depth + 1)?;
        c.expect_punct(")")?;
        return Ok(v);
    }
    let Some(t) = c.peek().cloned() else {
        return Err(c.expected("a constant"));
    };
    match &t.tok {
        Tok::Int(i) => {
            c.next();
            Ok(Value::Int(*i))
        }
        Tok::Float(f) => {
            c.next();
            Ok(Value::Float(*f))
        }
        Tok::Ident(w) if w == "TRUE" => {
            c.next();
            Ok(Value::Int(1))
        }
        Tok::Ident(w) if w == "FALSE" => {
            c.next();
            Ok(Value::Int(0))
        }
        Tok::Ident(_) | Tok::Punct("::") => {
            let name = c.scoped_name("a constant")?;
            lookup(&name.value).ok_or_else(|| {
                ModelError::new(format!("unknown constant `{}`", name.value), name.span)
                    .with_help("a constant here is a number, an IDL `const`, an enumerator or a `#define`d number")
            })
        }
        _ => Err(c.expected("a constant")),
    }
}

fn apply(op: &str, a: Value, b: Value) -> Result<Value, String> {
    use Value::{Float, Int};
    let overflow = || format!("`{op}` overflows here");
    Ok(match (a, b) {
        (Int(x), Int(y)) => match op {
            "+" => Int(x.checked_add(y).ok_or_else(overflow)?),
            "-" => Int(x.checked_sub(y).ok_or_else(overflow)?),
            "*" => Int(x.checked_mul(y).ok_or_else(overflow)?),
            "/" | "%" if y == 0 => return Err("division by zero".into()),
            "/" => Int(x.checked_div(y).ok_or_else(overflow)?),
            "%" => Int(x.checked_rem(y).ok_or_else(overflow)?),
            "<<" | ">>" if !(0..128).contains(&y) => return Err(format!("`{op}` by {y}")),
            "<<" => Int(x.checked_shl(y as u32).ok_or_else(overflow)?),
            ">>" => Int(x >> y),
            "|" => Int(x | y),
            "^" => Int(x ^ y),
            "&" => Int(x & y),
            _ => Int(i128::from(compare(
                op,
                x as f64,
                y as f64,
                a.truth(),
                b.truth(),
            ))),
        },
        _ => {
            let (x, y) = (a.as_f64(), b.as_f64());
            match op {
                "+" => Float(x + y),
                "-" => Float(x - y),
                "*" => Float(x * y),
                "/" if y == 0.0 => return Err("division by zero".into()),
                "/" => Float(x / y),
                "%" | "<<" | ">>" | "|" | "^" | "&" => {
                    return Err(format!("`{op}` takes integers"))
                }
                _ => Int(i128::from(compare(op, x, y, a.truth(), b.truth()))),
            }
        }
    })
}

fn compare(op: &str, x: f64, y: f64, a: bool, b: bool) -> bool {
    match op {
        "==" => x == y,
        "!=" => x != y,
        "<" => x < y,
        ">" => x > y,
        "<=" => x <= y,
        ">=" => x >= y,
        "&&" => a && b,
        _ => a || b,
    }
}
