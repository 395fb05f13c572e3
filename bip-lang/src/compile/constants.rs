//! The model's constants, evaluated first: every later part (ranges, counts, `forall`
//! bounds, initial values) may be written as a constant expression over them. The GenoM
//! expansion evaluates its own constant expressions (periods, ages) by the same rules,
//! through [`Constants`].

use super::resolve::{ConstInfo, Place, Resolver, Ty};
use super::{check_name, expr_error, unique, Compiler};
use crate::diag::ModelError;
use crate::expr::{self};
use crate::source::{ConstExpr, ConstValue};
use crate::syntax::{parse_in_file, SystemDef};

/// A model's constants, evaluated by the compiler's rules, for the GenoM expansion (task
/// periods, ages and limits written as constant expressions).
pub(crate) struct Constants {
    c: Compiler,
}

impl Constants {
    /// Evaluates the constants of `def`; errors in them are returned (and would be
    /// reported again by the compilation of the expanded model).
    pub(crate) fn new(def: &SystemDef) -> (Constants, Vec<ModelError>) {
        let mut c = Compiler::default();
        c.constants(def);
        let errors = std::mem::take(&mut c.errors.list);
        (Constants { c }, errors)
    }

    /// An integer written as a number or a constant expression.
    pub(crate) fn int(&self, v: &ConstExpr) -> Result<i64, ModelError> {
        self.c.const_value(v, Ty::Int, &[])
    }

    /// The value of a parsed expression if it is an integer constant expression.
    pub(crate) fn int_expr(&self, e: &expr::Expr) -> Option<i64> {
        let names = self.c.names();
        Resolver::new(&names, Place::Constant, &[])
            .constant(e, Ty::Int)
            .ok()
    }
}

impl Compiler {
    /// Evaluates a constant written as a number, a boolean or an expression string.
    pub(super) fn const_value(
        &self,
        v: &ConstExpr,
        want: Ty,
        fixed: &[(&str, i64)],
    ) -> Result<i64, ModelError> {
        let (value, ty) = self.const_any(v, fixed)?;
        if ty != want {
            return Err(ModelError::new(
                format!("expected {}, found {}", want.article(), ty.article()),
                v.span,
            ));
        }
        Ok(value)
    }

    /// Evaluates a constant of either type.
    fn const_any(&self, v: &ConstExpr, fixed: &[(&str, i64)]) -> Result<(i64, Ty), ModelError> {
        match &v.value {
            ConstValue::Int(i) => Ok((*i, Ty::Int)),
            ConstValue::Bool(b) => Ok((*b as i64, Ty::Bool)),
            ConstValue::Expr(_) => {
                let e = parse_in_file(&v.as_text())?;
                let names = self.names();
                let mut r = Resolver::new(&names, Place::Constant, fixed);
                r.constant_any(&e).map_err(expr_error)
            }
        }
    }

    pub(super) fn constants(&mut self, def: &SystemDef) {
        unique(
            &mut self.errors,
            def.constants.iter().map(|(k, _)| k),
            "constant",
        );
        for (name, value) in def.constants.iter() {
            if !check_name(&mut self.errors, name, "constant")
                || self.consts.contains_key(name.as_str())
            {
                continue;
            }
            match self.const_any(value, &[]) {
                Ok((v, ty)) => {
                    self.consts
                        .insert(name.value.clone(), ConstInfo { value: v, ty });
                    self.const_list.push((name.value.clone(), v));
                }
                Err(e) => self.errors.push(e),
            }
        }
    }
}
