//! The operators of the expression language, shared by the syntax tree (`expr`, with the
//! `std` feature) and compiled expressions (`eval`).

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BinOp {
    Mul,
    Div,
    Rem,
    Add,
    Sub,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
    Implies,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum QuantKind {
    Forall,
    Exists,
    Sum,
    Count,
}

impl BinOp {
    /// Binding strength; higher binds tighter. `?:` is 1, unary operators 8.
    pub fn precedence(self) -> u8 {
        match self {
            BinOp::Implies => 2,
            BinOp::Or => 3,
            BinOp::And => 4,
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge | BinOp::Eq | BinOp::Ne => 5,
            BinOp::Add | BinOp::Sub => 6,
            BinOp::Mul | BinOp::Div | BinOp::Rem => 7,
        }
    }

    pub fn symbol(self) -> &'static str {
        match self {
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Rem => "%",
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
            BinOp::And => "&&",
            BinOp::Or => "||",
            BinOp::Implies => "=>",
        }
    }

    pub fn is_comparison(self) -> bool {
        self.precedence() == 5
    }
}

impl QuantKind {
    pub fn keyword(self) -> &'static str {
        match self {
            QuantKind::Forall => "forall",
            QuantKind::Exists => "exists",
            QuantKind::Sum => "sum",
            QuantKind::Count => "count",
        }
    }
}
