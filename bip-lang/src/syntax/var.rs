//! A bounded variable as declared: an atom's data, and a GenoM module's ids, which expand
//! into its module atom's data.

use crate::source::{ConstExpr, Text};

#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct VarDef {
    pub name: Text,
    pub ty: TypeDef,
    /// Initial value; defaults to the lower bound of an `Int` and `false` for a `Bool`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init: Option<ConstExpr>,
}

#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
pub enum TypeDef {
    Bool,
    /// `Int(lo, hi)`, both bounds included; bounds may be constant expressions.
    Int(ConstExpr, ConstExpr),
}
