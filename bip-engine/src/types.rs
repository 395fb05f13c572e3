//! A request's arguments against the type its service declares (docs/model.md, "Data
//! types"), checked when the request is made: by the Rust type's name, and an `Int`'s
//! value against its range. Port data and outputs are checked where codels give them
//! (`ports.rs`, `codel.rs`).

use core::any::{type_name, Any, TypeId};

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::genom::map::DataType;

use crate::error::RequestError;

/// What a service takes as a request's arguments.
#[derive(Clone, Debug)]
pub(crate) struct Args {
    /// `module.Service`.
    pub service: String,
    /// The declared type.
    pub ty: Option<DataType>,
    /// An activity's codels read untyped arguments; a function has no codel to read any.
    pub has_codels: bool,
}

impl Args {
    /// Whether `args` may be sent: `()` (no arguments) always; else a value of the
    /// declared type, or anything to an activity that declares none.
    pub fn check<A: Any>(&self, args: &A) -> Result<(), RequestError> {
        if TypeId::of::<A>() == TypeId::of::<()>() {
            return Ok(());
        }
        let given = type_name::<A>();
        match &self.ty {
            None if self.has_codels => Ok(()),
            None => Err(RequestError::NoArguments {
                service: self.service.clone(),
                given,
            }),
            Some(ty) if !ty.accepts(given) => Err(RequestError::WrongArguments {
                service: self.service.clone(),
                declared: ty.to_string(),
                rust: ty.rust_name().to_string(),
                given,
            }),
            Some(DataType::Int { lo, hi }) => match (args as &dyn Any).downcast_ref::<i64>() {
                Some(&v) if v < *lo || v > *hi => Err(RequestError::ArgumentsOutOfRange {
                    service: self.service.clone(),
                    declared: format!("Int({lo}, {hi})"),
                    value: v,
                }),
                _ => Ok(()),
            },
            Some(_) => Ok(()),
        }
    }
}
