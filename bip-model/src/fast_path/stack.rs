//! Stack code: the expressions without families or quantifiers that neither tests nor a
//! table cover, compiled for a small stack machine whose depth is bounded.

use crate::prelude::*;

use crate::eval::{binary, Expr};
use crate::ops::BinOp;

use super::FlatCode;

impl FlatCode {
    /// Runs stack code `ops[start..end]`; `Err` if the expression fails (its tree says how).
    pub(crate) fn run(&self, start: u32, end: u32, slots: &[i64], base: u32) -> Result<i64, ()> {
        // compile() keeps every stack position below STACK; masking the positions tells
        // the compiler so, which drops the bounds checks of the inner loop
        const M: usize = STACK - 1;
        let mut stack = [0i64; STACK];
        let mut sp = 0usize;
        let mut pc = start as usize;
        while pc < end as usize {
            match self.ops[pc] {
                Op::Const(v) => {
                    stack[sp & M] = v;
                    sp += 1;
                }
                Op::Slot(s) => {
                    stack[sp & M] = slots[s as usize];
                    sp += 1;
                }
                Op::Local(n) => {
                    stack[sp & M] = slots[(base + n) as usize];
                    sp += 1;
                }
                Op::At(s, loc) => {
                    stack[sp & M] = (slots[s as usize] == i64::from(loc)) as i64;
                    sp += 1;
                }
                Op::Not => stack[(sp - 1) & M] = (stack[(sp - 1) & M] == 0) as i64,
                Op::Neg => stack[(sp - 1) & M] = stack[(sp - 1) & M].checked_neg().ok_or(())?,
                Op::Bool => stack[(sp - 1) & M] = (stack[(sp - 1) & M] != 0) as i64,
                Op::Bin(op) => {
                    sp -= 1;
                    let (a, b) = (stack[(sp - 1) & M], stack[sp & M]);
                    stack[(sp - 1) & M] = binary(op, a, b).map_err(|_| ())?;
                }
                Op::BinConst(op, b) => {
                    let a = stack[(sp - 1) & M];
                    stack[(sp - 1) & M] = binary(op, a, b).map_err(|_| ())?;
                }
                Op::And(to) => {
                    // a zero left operand is the result
                    if stack[(sp - 1) & M] == 0 {
                        pc = to as usize;
                        continue;
                    }
                    sp -= 1;
                }
                Op::Or(to) => {
                    if stack[(sp - 1) & M] != 0 {
                        stack[(sp - 1) & M] = 1;
                        pc = to as usize;
                        continue;
                    }
                    sp -= 1;
                }
                Op::Implies(to) => {
                    if stack[(sp - 1) & M] == 0 {
                        stack[(sp - 1) & M] = 1;
                        pc = to as usize;
                        continue;
                    }
                    sp -= 1;
                }
                Op::Else(to) => {
                    sp -= 1;
                    if stack[sp & M] == 0 {
                        pc = to as usize;
                        continue;
                    }
                }
                Op::Jump(to) => {
                    pc = to as usize;
                    continue;
                }
            }
            pc += 1;
        }
        Ok(stack[0])
    }
}

/// The deepest stack code may use (a power of two); deeper expressions keep their trees.
const STACK: usize = 16;

/// An instruction of the stack machine. Jumps are to absolute positions in `ops`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Op {
    Const(i64),
    Slot(u32),
    Local(u32),
    At(u32, u32),
    Not,
    Neg,
    /// The top as a boolean (0 or 1).
    Bool,
    /// Pops the right operand and replaces the left one by the result.
    Bin(BinOp),
    /// Replaces the top by the top `op` a constant (a right operand that is a constant).
    BinConst(BinOp, i64),
    /// `a && b`, `a || b`, `a => b` with `a` on top: jumps to the end with the result if
    /// `a` decides it, else pops `a` (then `b` and `Bool` follow).
    And(u32),
    Or(u32),
    Implies(u32),
    /// Pops the condition of `c ? a : b`; jumps to `b` if it is zero.
    Else(u32),
    Jump(u32),
}

/// Appends stack code for `e` to `ops`: its `(start, end)`, or `None` (nothing appended)
/// if `e` reads a family by index, has a quantifier, or needs too deep a stack.
pub(super) fn compile(e: &Expr, ops: &mut Vec<Op>) -> Option<(u32, u32)> {
    let start = ops.len();
    if emit(e, ops, 1) {
        Some((start as u32, ops.len() as u32))
    } else {
        ops.truncate(start);
        None
    }
}

/// True if `e`'s value is always 0 or 1 (it needs no [`Op::Bool`]).
fn is_boolean(e: &Expr) -> bool {
    use BinOp::*;
    match e {
        Expr::Const(v) => *v == 0 || *v == 1,
        Expr::At(..) | Expr::Not(_) => true,
        Expr::Binary(op, _, _) => matches!(op, Lt | Le | Gt | Ge | Eq | Ne | And | Or | Implies),
        Expr::Chain(_, rest) => rest.iter().all(|(op, _)| matches!(op, And | Or)),
        _ => false,
    }
}

/// Emits code leaving the value of `e` at stack depth `depth`.
fn emit(e: &Expr, ops: &mut Vec<Op>, depth: usize) -> bool {
    if depth > STACK {
        return false;
    }
    let patch = |ops: &mut Vec<Op>, at: usize| {
        let to = ops.len() as u32;
        ops[at] = match ops[at] {
            Op::And(_) => Op::And(to),
            Op::Or(_) => Op::Or(to),
            Op::Implies(_) => Op::Implies(to),
            Op::Else(_) => Op::Else(to),
            Op::Jump(_) => Op::Jump(to),
            op => op,
        };
    };
    match e {
        Expr::Const(v) => ops.push(Op::Const(*v)),
        Expr::Slot(s) => ops.push(Op::Slot(*s)),
        Expr::Local(n) => ops.push(Op::Local(*n)),
        Expr::At(s, loc) => ops.push(Op::At(*s, *loc)),
        Expr::Indexed(_) | Expr::Bound(_) | Expr::Quant(_) | Expr::Advance => return false,
        Expr::Not(a) | Expr::Neg(a) => {
            if !emit(a, ops, depth) {
                return false;
            }
            ops.push(if matches!(e, Expr::Not(_)) {
                Op::Not
            } else {
                Op::Neg
            });
        }
        Expr::Binary(op @ (BinOp::And | BinOp::Or | BinOp::Implies), a, b) => {
            if !emit(a, ops, depth) {
                return false;
            }
            let at = ops.len();
            ops.push(match op {
                BinOp::And => Op::And(0),
                BinOp::Or => Op::Or(0),
                _ => Op::Implies(0),
            });
            if !emit(b, ops, depth) {
                return false;
            }
            if !is_boolean(b) {
                ops.push(Op::Bool);
            }
            patch(ops, at);
        }
        Expr::Binary(op, a, b) => {
            if !emit(a, ops, depth) {
                return false;
            }
            // a constant right operand goes into the instruction
            match **b {
                Expr::Const(c) => ops.push(Op::BinConst(*op, c)),
                _ => {
                    if !emit(b, ops, depth + 1) {
                        return false;
                    }
                    ops.push(Op::Bin(*op));
                }
            }
        }
        Expr::Chain(first, rest) => {
            if !emit(first, ops, depth) {
                return false;
            }
            for (op, x) in rest {
                if let BinOp::And | BinOp::Or = op {
                    let at = ops.len();
                    ops.push(if *op == BinOp::And {
                        Op::And(0)
                    } else {
                        Op::Or(0)
                    });
                    if !emit(x, ops, depth) {
                        return false;
                    }
                    if !is_boolean(x) {
                        ops.push(Op::Bool);
                    }
                    patch(ops, at);
                    continue;
                }
                match *x {
                    Expr::Const(c) => ops.push(Op::BinConst(*op, c)),
                    _ => {
                        if !emit(x, ops, depth + 1) {
                            return false;
                        }
                        ops.push(Op::Bin(*op));
                    }
                }
            }
        }
        Expr::Cond(c, a, b) => {
            if !emit(c, ops, depth) {
                return false;
            }
            let at_else = ops.len();
            ops.push(Op::Else(0));
            if !emit(a, ops, depth) {
                return false;
            }
            let at_jump = ops.len();
            ops.push(Op::Jump(0));
            patch(ops, at_else);
            if !emit(b, ops, depth) {
                return false;
            }
            patch(ops, at_jump);
        }
    }
    true
}
