//! Name resolution and type checking of expressions: from the syntax tree (`expr::Expr`)
//! to a compiled, folded [`eval::Expr`](bip_model::eval::Expr).

use std::collections::HashMap;

use crate::expr::{self, BinOp, ExprKind, QuantKind, UnOp};
use crate::source::Span;
use bip_model::eval::{self, Indexed, Quant, MAX_QUANT_DEPTH};
use bip_model::{family_indices, Atom, Component, Family};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ty {
    Int,
    Bool,
}

impl Ty {
    pub fn article(self) -> &'static str {
        match self {
            Ty::Int => "an integer",
            Ty::Bool => "a boolean",
        }
    }
}

/// An error in one expression; the span is relative to the expression's text.
#[derive(Clone, Debug)]
pub struct ResolveError {
    pub message: String,
    pub span: Span,
    pub help: Option<String>,
}

fn err<T>(span: Span, message: impl Into<String>) -> Result<T, ResolveError> {
    Err(ResolveError {
        message: message.into(),
        span,
        help: None,
    })
}

fn err_help<T>(
    span: Span,
    message: impl Into<String>,
    help: impl Into<String>,
) -> Result<T, ResolveError> {
    Err(ResolveError {
        message: message.into(),
        span,
        help: Some(help.into()),
    })
}

/// A constant: its value and type (booleans are 0 and 1).
#[derive(Clone, Copy, Debug)]
pub struct ConstInfo {
    pub value: i64,
    pub ty: Ty,
}

/// What names an expression can see.
pub struct Names<'a> {
    pub consts: &'a HashMap<String, ConstInfo>,
    pub atoms: &'a [Atom],
    pub families: &'a [Family],
    pub family_by_name: &'a HashMap<String, u32>,
    pub components: &'a [Component],
}

/// Where an expression appears, which decides what it may read.
#[derive(Clone, Copy)]
pub enum Place<'a> {
    /// Constants only (`count`, bounds, `init`, quantifier bounds).
    Constant,
    /// An atom's guard or action: its own variables and constants.
    Atom(&'a Atom),
    /// Connector guards and actions, priority conditions, properties: any component.
    Global,
}

/// A reference to a component in an expression.
enum CompRef {
    Static(u32),
    Dynamic { family: u32, index: eval::Expr },
}

/// How many quantifier bodies one expression may evaluate, all its quantifiers together (a
/// nested quantifier counts once per run of its outer one's body). Enough to quantify over
/// the largest family; beyond it, one evaluation would run for seconds, and constants and
/// guards are evaluated at load time and in every state.
pub const MAX_QUANT_WORK: i128 = 10_000_000;

/// A chain of more operands than this is compiled flat or balanced rather than as the
/// left-leaning tree of binary nodes that short chains keep.
const SHORT_CHAIN: usize = 8;

/// A compiled chain: `&&` and `||` are associative, also in what they evaluate and when they
/// fail, so a long one becomes a balanced tree; arithmetic is not (an intermediate result may
/// overflow), so a long one stays a left-to-right chain.
fn chain(first: eval::Expr, rest: Vec<(BinOp, eval::Expr)>) -> eval::Expr {
    use eval::Expr as C;
    if rest.len() < SHORT_CHAIN {
        return rest.into_iter().fold(first, |acc, (op, x)| {
            C::Binary(op, Box::new(acc), Box::new(x))
        });
    }
    match rest[0].0 {
        op @ (BinOp::And | BinOp::Or) => {
            let items: Vec<C> = std::iter::once(first)
                .chain(rest.into_iter().map(|(_, x)| x))
                .collect();
            balanced(op, items)
        }
        _ => C::Chain(Box::new(first), rest),
    }
}

/// `x0 op x1 op … op xn` as a tree of depth log2(n), built without recursion: pairs are
/// joined level by level.
fn balanced(op: BinOp, mut items: Vec<eval::Expr>) -> eval::Expr {
    while items.len() > 1 {
        let mut next = Vec::with_capacity(items.len().div_ceil(2));
        let mut it = items.into_iter();
        while let Some(a) = it.next() {
            next.push(match it.next() {
                Some(b) => eval::Expr::Binary(op, Box::new(a), Box::new(b)),
                None => a,
            });
        }
        items = next;
    }
    items
        .pop()
        .unwrap_or(eval::Expr::Const(i64::from(op == BinOp::And)))
}

pub struct Resolver<'a> {
    pub names: &'a Names<'a>,
    pub place: Place<'a>,
    /// Names bound to fixed values: the `forall` variable of a connector, `self_index`.
    pub fixed: &'a [(&'a str, i64)],
    quant: Vec<String>,
    /// How many times each enclosing quantifier's body runs in one evaluation.
    runs: Vec<i128>,
    /// Body evaluations of all quantifiers resolved so far, per evaluation.
    work: i128,
    /// In a `Time` connector's action: `advance` names its step's time units.
    pub advance: bool,
}

impl<'a> Resolver<'a> {
    pub fn new(names: &'a Names<'a>, place: Place<'a>, fixed: &'a [(&'a str, i64)]) -> Self {
        Resolver {
            names,
            place,
            fixed,
            quant: Vec::new(),
            runs: Vec::new(),
            work: 0,
            advance: false,
        }
    }

    /// Resolves an expression that must have type `want`.
    pub fn expect(&mut self, e: &expr::Expr, want: Ty) -> Result<eval::Expr, ResolveError> {
        let (c, ty) = self.resolve(e)?;
        if ty != want {
            return err(
                e.span,
                format!("expected {}, found {}", want.article(), ty.article()),
            );
        }
        Ok(c.fold())
    }

    /// Resolves an expression that must evaluate to a constant of type `want`.
    pub fn constant(&mut self, e: &expr::Expr, want: Ty) -> Result<i64, ResolveError> {
        let c = self.expect(e, want)?;
        to_constant(c, e.span)
    }

    /// Resolves an expression that must evaluate to a constant, of either type.
    pub fn constant_any(&mut self, e: &expr::Expr) -> Result<(i64, Ty), ResolveError> {
        let (c, ty) = self.resolve(e)?;
        Ok((to_constant(c.fold(), e.span)?, ty))
    }

    pub fn resolve(&mut self, e: &expr::Expr) -> Result<(eval::Expr, Ty), ResolveError> {
        use eval::Expr as C;
        Ok(match &e.kind {
            ExprKind::Int(v) => (C::Const(*v), Ty::Int),
            ExprKind::Bool(b) => (C::Const(*b as i64), Ty::Bool),
            ExprKind::Name(n) => self.name(n, e.span)?,
            ExprKind::Member(base, field) => {
                let comp = self.component(base)?;
                let (fam, atom) = self.family_and_atom(&comp);
                let Some(var) = atom.var_index(&field.name) else {
                    let fam_name = &self.names.families[fam as usize].name;
                    return if atom.port_index(&field.name).is_some() {
                        err(
                            field.span,
                            format!("`{}` is a port of {fam_name}, not a variable", field.name),
                        )
                    } else {
                        err_help(
                            field.span,
                            format!("atom `{}` has no variable `{}`", atom.name, field.name),
                            one_of(
                                "its variables are",
                                atom.vars.iter().map(|v| v.name.as_str()),
                            ),
                        )
                    };
                };
                let ty = match atom.vars[var as usize].ty {
                    bip_model::VarType::Bool => Ty::Bool,
                    bip_model::VarType::Int { .. } => Ty::Int,
                };
                (self.slot_read(comp, 1 + var, None), ty)
            }
            ExprKind::At(base, loc) => {
                let comp = self.component(base)?;
                let (_, atom) = self.family_and_atom(&comp);
                let Some(l) = atom.location_index(&loc.name) else {
                    return err_help(
                        loc.span,
                        format!("atom `{}` has no location `{}`", atom.name, loc.name),
                        one_of(
                            "its locations are",
                            atom.locations.iter().map(String::as_str),
                        ),
                    );
                };
                (self.slot_read(comp, 0, Some(l)), Ty::Bool)
            }
            ExprKind::Index(..) => {
                return err_help(
                    e.span,
                    "a component is not a value",
                    "read one of its variables (`c[i].x`) or test its location (`c[i]@loc`)",
                )
            }
            ExprKind::Call(f, _) => {
                return err_help(
                    f.span,
                    format!("unknown function `{}`", f.name),
                    "`active`, `age` and `m.S@state` are names of the GenoM layer and need a \
                     `modules` section",
                )
            }
            ExprKind::Unary(op, inner) => {
                let (c, ty) = self.resolve(inner)?;
                match op {
                    UnOp::Not => {
                        self.want(inner.span, ty, Ty::Bool, "`!`")?;
                        (C::Not(Box::new(c)), Ty::Bool)
                    }
                    UnOp::Neg => {
                        self.want(inner.span, ty, Ty::Int, "`-`")?;
                        (C::Neg(Box::new(c)), Ty::Int)
                    }
                }
            }
            ExprKind::Binary(op, a, b) => {
                let (ca, ta) = self.resolve(a)?;
                let (cb, tb) = self.resolve(b)?;
                let ty = self.operator(*op, e.span, (a.span, ta), (b.span, tb))?;
                (C::Binary(*op, Box::new(ca), Box::new(cb)), ty)
            }
            ExprKind::Chain(first, rest) => {
                let (c0, mut ty) = self.resolve(first)?;
                let mut left = first.span;
                let mut out = Vec::with_capacity(rest.len());
                for (op, x) in rest {
                    let (cx, tx) = self.resolve(x)?;
                    ty = self.operator(*op, e.span, (left, ty), (x.span, tx))?;
                    left = Span::new(left.start, x.span.end);
                    out.push((*op, cx));
                }
                (chain(c0, out), ty)
            }
            ExprKind::Cond(c, a, b) => {
                let (cc, tc) = self.resolve(c)?;
                self.want(c.span, tc, Ty::Bool, "the condition of `?:`")?;
                let (ca, ta) = self.resolve(a)?;
                let (cb, tb) = self.resolve(b)?;
                if ta != tb {
                    return err(
                        e.span,
                        format!(
                            "the branches of `?:` differ: {} and {}",
                            ta.article(),
                            tb.article()
                        ),
                    );
                }
                (C::Cond(Box::new(cc), Box::new(ca), Box::new(cb)), ta)
            }
            ExprKind::Quant(kind, range, body) => {
                let lo = self.constant(&range.lo, Ty::Int).map_err(quant_bound)?;
                let hi = self.constant(&range.hi, Ty::Int).map_err(quant_bound)?;
                let depth = self.quant.len();
                if depth >= MAX_QUANT_DEPTH {
                    return err(
                        e.span,
                        format!("quantifiers nest at most {MAX_QUANT_DEPTH} deep"),
                    );
                }
                let size = (i128::from(hi) - i128::from(lo)).max(0);
                let runs = self.runs.last().copied().unwrap_or(1).saturating_mul(size);
                self.work = self.work.saturating_add(runs);
                if self.work > MAX_QUANT_WORK {
                    return err_help(
                        e.span,
                        format!(
                            "`{}` over {size} values: the quantifiers of one expression may \
                             evaluate their bodies at most {MAX_QUANT_WORK} times in all",
                            kind.keyword()
                        ),
                        "narrow the range, e.g. to the count of the family it quantifies over",
                    );
                }
                self.quant.push(range.var.name.clone());
                self.runs.push(runs);
                let body = self.resolve(body);
                self.runs.pop();
                self.quant.pop();
                let (cbody, tbody) = body?;
                let ty = match kind {
                    QuantKind::Forall | QuantKind::Exists | QuantKind::Count => {
                        self.want(body_span(e), tbody, Ty::Bool, kind.keyword())?;
                        if *kind == QuantKind::Count {
                            Ty::Int
                        } else {
                            Ty::Bool
                        }
                    }
                    QuantKind::Sum => {
                        self.want(body_span(e), tbody, Ty::Int, "sum")?;
                        Ty::Int
                    }
                };
                (
                    C::Quant(Box::new(Quant {
                        kind: *kind,
                        lo,
                        hi,
                        depth: depth as u32,
                        body: cbody,
                    })),
                    ty,
                )
            }
        })
    }

    /// The type of `a op b`, given the operands' spans and types.
    fn operator(
        &self,
        op: BinOp,
        whole: Span,
        (a, ta): (Span, Ty),
        (b, tb): (Span, Ty),
    ) -> Result<Ty, ResolveError> {
        let what = format!("`{}`", op.symbol());
        Ok(match op {
            BinOp::And | BinOp::Or | BinOp::Implies => {
                self.want(a, ta, Ty::Bool, &what)?;
                self.want(b, tb, Ty::Bool, &what)?;
                Ty::Bool
            }
            BinOp::Eq | BinOp::Ne => {
                if ta != tb {
                    return err(
                        whole,
                        format!("cannot compare {} with {}", ta.article(), tb.article()),
                    );
                }
                Ty::Bool
            }
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => {
                self.want(a, ta, Ty::Int, &what)?;
                self.want(b, tb, Ty::Int, &what)?;
                Ty::Bool
            }
            BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div | BinOp::Rem => {
                self.want(a, ta, Ty::Int, &what)?;
                self.want(b, tb, Ty::Int, &what)?;
                Ty::Int
            }
        })
    }

    fn want(&self, span: Span, got: Ty, want: Ty, what: &str) -> Result<(), ResolveError> {
        if got == want {
            Ok(())
        } else {
            err(
                span,
                format!(
                    "{what} needs {}, but this is {}",
                    want.article(),
                    got.article()
                ),
            )
        }
    }

    fn name(&self, n: &str, span: Span) -> Result<(eval::Expr, Ty), ResolveError> {
        use eval::Expr as C;
        if let Some(d) = self.quant.iter().rposition(|q| q == n) {
            return Ok((C::Bound(d as u32), Ty::Int));
        }
        if let Some(&(_, v)) = self.fixed.iter().rev().find(|(f, _)| *f == n) {
            return Ok((C::Const(v), Ty::Int));
        }
        if self.advance && n == "advance" {
            return Ok((C::Advance, Ty::Int));
        }
        if let Place::Atom(atom) = self.place {
            if let Some(v) = atom.var_index(n) {
                let ty = match atom.vars[v as usize].ty {
                    bip_model::VarType::Bool => Ty::Bool,
                    bip_model::VarType::Int { .. } => Ty::Int,
                };
                return Ok((C::Local(v), ty));
            }
        }
        if let Some(c) = self.names.consts.get(n) {
            return Ok((C::Const(c.value), c.ty));
        }
        if self.names.family_by_name.contains_key(n) {
            return err_help(
                span,
                format!("`{n}` is a component, not a value"),
                format!("read one of its variables (`{n}.x`) or test its location (`{n}@loc`)"),
            );
        }
        let help = match self.place {
            Place::Constant => "only constants can be used here".to_string(),
            Place::Atom(atom) => {
                let mut h = one_of(
                    "the atom's variables are",
                    atom.vars.iter().map(|v| v.name.as_str()),
                );
                if self.names.atoms.iter().any(|a| a.var_index(n).is_some()) {
                    h = format!("{h}; an atom reads only its own variables");
                }
                h
            }
            Place::Global => {
                if self.names.atoms.iter().any(|a| a.var_index(n).is_some()) {
                    format!("`{n}` is a variable of an atom; name its component: `comp.{n}`")
                } else {
                    "names are constants, quantified variables, and `comp.var` / `comp@loc`"
                        .to_string()
                }
            }
        };
        err_help(span, format!("unknown name `{n}`"), help)
    }

    fn component(&mut self, e: &expr::Expr) -> Result<CompRef, ResolveError> {
        if let Place::Atom(_) | Place::Constant = self.place {
            return err_help(
                e.span,
                "components cannot be read here",
                match self.place {
                    Place::Atom(_) => "an atom's guards and actions read only its own variables",
                    _ => "only constants can be used here",
                },
            );
        }
        match &e.kind {
            ExprKind::Name(n) => {
                let Some(&f) = self.names.family_by_name.get(n) else {
                    return err(e.span, format!("unknown component `{n}`"));
                };
                let fam = &self.names.families[f as usize];
                match fam.count {
                    None => Ok(CompRef::Static(fam.first)),
                    Some(count) => err_help(
                        e.span,
                        format!("`{n}` is a family of {count} components"),
                        format!("index it: `{n}[i]`"),
                    ),
                }
            }
            ExprKind::Index(base, idx) => {
                let ExprKind::Name(n) = &base.kind else {
                    return err(base.span, "expected a component family name");
                };
                let Some(&f) = self.names.family_by_name.get(n) else {
                    return err(base.span, format!("unknown component family `{n}`"));
                };
                let fam = &self.names.families[f as usize];
                let Some(count) = fam.count else {
                    return err_help(
                        e.span,
                        format!("`{n}` is a single component, not a family"),
                        format!("write `{n}` without an index"),
                    );
                };
                let index = self.expect(idx, Ty::Int)?;
                match index {
                    eval::Expr::Const(k) => {
                        if k < 0 || k >= i64::from(count) {
                            return err(
                                idx.span,
                                format!("index {k} is outside `{n}`, {}", family_indices(count)),
                            );
                        }
                        Ok(CompRef::Static(fam.first + k as u32))
                    }
                    index => Ok(CompRef::Dynamic { family: f, index }),
                }
            }
            _ => err(e.span, "expected a component (`name` or `name[index]`)"),
        }
    }

    fn family_and_atom(&self, c: &CompRef) -> (u32, &'a Atom) {
        let fam = match c {
            CompRef::Static(comp) => self.names.components[*comp as usize].family,
            CompRef::Dynamic { family, .. } => *family,
        };
        let atom = self.names.families[fam as usize].atom;
        (fam, &self.names.atoms[atom as usize])
    }

    /// A read of slot `offset` of a component (0: its location).
    fn slot_read(&self, c: CompRef, offset: u32, at: Option<u32>) -> eval::Expr {
        match c {
            CompRef::Static(comp) => {
                let slot = self.names.components[comp as usize].slot + offset;
                match at {
                    Some(l) => eval::Expr::At(slot, l),
                    None => eval::Expr::Slot(slot),
                }
            }
            CompRef::Dynamic { family, index } => {
                let fam = &self.names.families[family as usize];
                let first = &self.names.components[fam.first as usize];
                let stride = 1 + self.names.atoms[fam.atom as usize].vars.len() as u32;
                eval::Expr::Indexed(Box::new(Indexed {
                    index,
                    family,
                    count: fam.count.unwrap_or(1),
                    first_slot: first.slot,
                    stride,
                    offset,
                    at,
                }))
            }
        }
    }

    /// Resolves `comp.x` or `comp[k].x` with a constant index to the component and the
    /// member name, for port references and assignment targets.
    pub fn static_member<'e>(
        &mut self,
        e: &'e expr::Expr,
    ) -> Result<(u32, &'e expr::Ident), ResolveError> {
        let ExprKind::Member(base, member) = &e.kind else {
            return err(e.span, "expected `component.name`");
        };
        match self.component(base)? {
            CompRef::Static(c) => Ok((c, member)),
            CompRef::Dynamic { .. } => err(
                base.span,
                "the index must be a constant here (constants and the `forall` variable)",
            ),
        }
    }
}

/// The value of a folded expression that must be constant.
fn to_constant(c: eval::Expr, span: Span) -> Result<i64, ResolveError> {
    if let eval::Expr::Const(v) = c {
        return Ok(v);
    }
    if c.reads_nothing() {
        // folding leaves failing constants in place; say why this one fails
        match c.eval(&mut eval::Env::new(&[], 0)) {
            Ok(v) => return Ok(v),
            Err(eval::EvalError::DivisionByZero) => {
                return err(span, "division by zero in a constant expression")
            }
            Err(_) => return err(span, "this constant expression overflows 64-bit integers"),
        }
    }
    err(
        span,
        "expected a constant expression (it may use constants only)",
    )
}

fn body_span(e: &expr::Expr) -> Span {
    match &e.kind {
        ExprKind::Quant(_, _, body) => body.span,
        _ => e.span,
    }
}

fn quant_bound(mut e: ResolveError) -> ResolveError {
    if e.message.starts_with("expected a constant") {
        e.message = "quantifier bounds must be constant expressions".into();
    }
    e
}

/// `"its ports are a, b, c"`, or a note that there are none.
pub fn one_of<'s>(what: &str, names: impl Iterator<Item = &'s str>) -> String {
    let list: Vec<&str> = names.take(12).collect();
    if list.is_empty() {
        format!("{what}: (none)")
    } else {
        format!("{what}: {}", list.join(", "))
    }
}
