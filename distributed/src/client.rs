//! A client's request from the command line (`bip request`, the example's `--request`):
//! `module.Service` and its arguments as text, read against the model's types before
//! anything is sent, so that a malformed request is refused with a message in the
//! model's terms; then the request, its replies printed as they come.

use std::time::Duration;

use bip_engine::bip_model::genom::map::DataType;
use bip_engine::System;
use serde_json::Value;

use crate::network::Network;
use crate::requests::{request, ServiceReply};

/// A request to send: the service and its arguments, checked against the model.
#[derive(Clone, Debug, PartialEq)]
pub struct ClientRequest {
    pub module: String,
    pub service: String,
    pub args: Option<Value>,
}

impl ClientRequest {
    /// Reads `target` (`module.Service`) and `args` (JSON; a bare word is a JSON string)
    /// against `system`: the service exists, takes arguments if and only if given some,
    /// of its type (`Bool` a boolean, `Int(lo, hi)` an integer in range, `Float` a
    /// number, a record an object of exactly its fields, each of its type; a `Rust(..)`
    /// type is the layer's codec's to read).
    pub fn parse(system: &System, target: &str, args: Option<&str>) -> Result<Self, String> {
        let (module, service) = target
            .split_once('.')
            .ok_or_else(|| format!("`{target}` is not `module.Service`"))?;
        let modules: Vec<_> = system.genom.iter().flat_map(|g| &g.modules).collect();
        let m = modules.iter().find(|m| m.name == module).ok_or_else(|| {
            let names: Vec<&str> = modules.iter().map(|m| m.name.as_str()).collect();
            format!(
                "the model has no module `{module}` (its modules: {})",
                names.join(", ")
            )
        })?;
        let s = m
            .services
            .iter()
            .find(|s| s.name == service)
            .ok_or_else(|| {
                let names: Vec<&str> = m.services.iter().map(|s| s.name.as_str()).collect();
                format!(
                    "module `{module}` has no service `{service}` (its services: {})",
                    names.join(", ")
                )
            })?;
        let args = match (&s.args, args) {
            (None, None) => None,
            (None, Some(a)) => {
                return Err(format!("{target} takes no arguments, yet was given `{a}`"))
            }
            (Some(ty), None) => {
                return Err(format!("{target} takes arguments of type {ty}; give them"))
            }
            (Some(ty), Some(a)) => {
                let v = serde_json::from_str(a).unwrap_or_else(|_| Value::String(a.into()));
                check(&v, ty).map_err(|why| {
                    format!("the arguments of {target} (`{a}`) are not of its type {ty}: {why}")
                })?;
                Some(v)
            }
        };
        Ok(ClientRequest {
            module: module.into(),
            service: service.into(),
            args,
        })
    }

    /// Sends it to the layer on `network` and calls `each` with each reply until the
    /// last or `timeout`. An error if no engine answered or the request was not made
    /// (the engine's `error`, or `unavailable`: its module's process is absent).
    pub fn send(
        &self,
        network: &Network,
        timeout: Duration,
        each: impl FnMut(&ServiceReply),
    ) -> Result<Vec<ServiceReply>, String> {
        let session = network.open().map_err(|e| e.to_string())?;
        let replies = request(
            &session,
            &network.prefix,
            &self.module,
            &self.service,
            self.args.clone(),
            timeout,
            each,
        )?;
        match replies.last() {
            Some(ServiceReply::Error { .. } | ServiceReply::Unavailable { .. }) => {
                Err("the request was not made".into())
            }
            _ => Ok(replies),
        }
    }
}

/// Whether `v` is a value of `ty`: why not.
fn check(v: &Value, ty: &DataType) -> Result<(), String> {
    match ty {
        DataType::Bool if v.is_boolean() => Ok(()),
        DataType::Int { lo, hi } => match v.as_i64() {
            Some(k) if (*lo..=*hi).contains(&k) => Ok(()),
            Some(k) => Err(format!("{k} is outside {lo}..={hi}")),
            None => Err(format!("{v} is not an integer")),
        },
        DataType::Float if v.is_number() => Ok(()),
        DataType::Record { fields, .. } => {
            let Some(o) = v.as_object() else {
                return Err(format!("{v} is not an object of its fields"));
            };
            if let Some(extra) = o.keys().find(|k| !fields.iter().any(|(f, _)| f == *k)) {
                return Err(format!("it has no field `{extra}`"));
            }
            for (f, fty) in fields {
                let x = o.get(f).ok_or_else(|| format!("field `{f}` is missing"))?;
                check(x, fty).map_err(|why| format!("field `{f}`: {why}"))?;
            }
            Ok(())
        }
        DataType::Rust(_) => Ok(()),
        _ => Err(format!("{v} is not a {}", ty.rust_name())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ty(text: &str) -> DataType {
        match text {
            "bool" => DataType::Bool,
            "float" => DataType::Float,
            "int" => DataType::Int { lo: 0, hi: 10 },
            _ => DataType::Record {
                name: "Goal".into(),
                fields: vec![("x".into(), DataType::Float), ("n".into(), ty("int"))],
            },
        }
    }

    #[test]
    fn values_are_checked_against_the_model_s_types() {
        let ok = |v: &str, t: &str| check(&serde_json::from_str(v).expect("json"), &ty(t));
        assert!(ok("true", "bool").is_ok());
        assert!(ok("1", "bool").is_err());
        assert!(ok("0.5", "float").is_ok());
        assert!(ok("3", "float").is_ok());
        assert!(ok("\"fast\"", "float").is_err());
        assert!(ok("3", "int").is_ok());
        assert_eq!(ok("11", "int"), Err("11 is outside 0..=10".into()));
        assert!(ok("2.5", "int").is_err());
        assert!(ok(r#"{"x": 1.5, "n": 2}"#, "rec").is_ok());
        assert_eq!(
            ok(r#"{"x": 1.5}"#, "rec"),
            Err("field `n` is missing".into())
        );
        assert_eq!(
            ok(r#"{"x": 1.5, "n": 2, "y": 0}"#, "rec"),
            Err("it has no field `y`".into())
        );
        assert_eq!(
            ok(r#"{"x": 1.5, "n": 20}"#, "rec"),
            Err("field `n`: 20 is outside 0..=10".into())
        );
    }
}
