//! The constraints between services (`Exclusive`, `AtMost`, `Requires`, `Fresh`,
//! `Guard`), with the `"module.Service"` and `"module.port"` names they use resolved.

use super::connections::{module_index, split_dotted};
use super::{ConstraintKind, Layer, PortRef, ServiceRef};
use crate::compile::{one_of, unique, Constants};
use crate::diag::{Errors, ModelError};
use crate::source::Span;
use crate::syntax::{ConstraintDef, Text};

/// Resolves `"module.Service"`.
pub fn service_ref(errors: &mut Errors, layer: &Layer<'_>, t: &Text) -> Option<ServiceRef> {
    let (m, s, ms, ss) = split_dotted(errors, t, "`module.Service`")?;
    let mi = module_index(errors, layer, m, ms)?;
    let module = &layer.modules[mi];
    let Some(si) = module.services.iter().position(|x| x.name == s) else {
        errors.push(
            ModelError::new(format!("module `{m}` has no service `{s}`"), ss)
                .with_label("unknown service")
                .with_help(one_of(
                    "its services are",
                    module.services.iter().map(|x| x.name),
                )),
        );
        return None;
    };
    Some(ServiceRef {
        module: mi,
        service: si,
    })
}

/// Resolves `"module.port"`: an out port, or a connected in port (the out port it reads).
fn port_ref(errors: &mut Errors, layer: &Layer<'_>, t: &Text) -> Option<PortRef> {
    let (m, p, ms, ps) = split_dotted(errors, t, "`module.port`")?;
    let mi = module_index(errors, layer, m, ms)?;
    super::port_ref(layer, mi, p, ps)
        .map_err(|e| errors.push(e))
        .ok()
}

pub(super) fn constraint<'d>(
    errors: &mut Errors,
    consts: &Constants,
    layer: &Layer<'d>,
    c: &'d ConstraintDef,
) -> Option<ConstraintKind<'d>> {
    let svc = |errors: &mut Errors, t: &Text| service_ref(errors, layer, t);
    let activity = |errors: &mut Errors, t: &Text, why: &str| -> Option<ServiceRef> {
        let r = svc(errors, t)?;
        if layer.modules[r.module].services[r.service].is_activity() {
            Some(r)
        } else {
            errors.push(
                ModelError::new(format!("`{t}` is not an activity"), t.span)
                    .with_help(format!("{why}; functions and attributes are never active")),
            );
            None
        }
    };
    let list = |errors: &mut Errors, ts: &[Text], why: &str, min: usize, anchor: Span| {
        unique(errors, ts.iter(), "service");
        let out: Vec<Option<ServiceRef>> = ts.iter().map(|t| activity(errors, t, why)).collect();
        if ts.len() < min {
            errors.push(ModelError::new(
                format!("`{}` needs at least {min} services", c.kind()),
                ts.first().map_or(anchor, |t| t.span),
            ));
        }
        out.into_iter().collect::<Option<Vec<_>>>()
    };
    match c {
        ConstraintDef::Exclusive { services, .. } => {
            let why = "`Exclusive` is about activities being active";
            list(errors, services, why, 2, Span::NONE).map(ConstraintKind::Exclusive)
        }
        ConstraintDef::AtMost { max, services, .. } => {
            let why = "`AtMost` counts active activities";
            let l = list(errors, services, why, 2, max.span);
            let k = match consts.int(max) {
                Ok(k) if k >= 1 => Some(k),
                Ok(k) => {
                    errors.push(
                        ModelError::new(format!("`max` is {k}; it must be at least 1"), max.span)
                            .with_help("with `max: 0` none of the services could ever start"),
                    );
                    None
                }
                Err(e) => {
                    errors.push(e);
                    None
                }
            };
            Some(ConstraintKind::AtMost {
                max: k?,
                services: l?,
            })
        }
        ConstraintDef::Requires {
            service, active, ..
        } => {
            let s = svc(errors, service);
            let why = "`Requires` lists services that must be active";
            let l = list(errors, active, why, 1, service.span);
            let (s, l) = (s?, l?);
            if l.contains(&s) {
                errors.push(ModelError::new(
                    format!("`{service}` cannot require itself"),
                    service.span,
                ));
                return None;
            }
            Some(ConstraintKind::Requires {
                service: s,
                active: l,
            })
        }
        ConstraintDef::Fresh {
            service,
            port,
            max_age,
            ..
        } => {
            let s = svc(errors, service);
            let p = port_ref(errors, layer, port);
            let k = match consts.int(max_age) {
                Ok(k) if k == i64::MAX => {
                    errors.push(too_old(k, max_age.span));
                    None
                }
                Ok(k) if k >= 0 => Some(k),
                Ok(k) => {
                    errors.push(ModelError::new(
                        format!("`max_age` is {k}; an age is never negative"),
                        max_age.span,
                    ));
                    None
                }
                Err(e) => {
                    errors.push(e);
                    None
                }
            };
            Some(ConstraintKind::Fresh {
                service: s?,
                port: p?,
                max_age: k?,
            })
        }
        ConstraintDef::Guard { service, when, .. } => Some(ConstraintKind::Guard {
            service: svc(errors, service)?,
            when,
        }),
    }
}

/// An age compared with `k`: ages count up to one more than the largest such constant,
/// which must fit in 64 bits.
pub fn too_old(k: i64, span: Span) -> ModelError {
    ModelError::new(format!("an age cannot be compared with {k}"), span)
        .with_label("ages count up to one more than this, which does not fit in 64 bits")
        .with_help("an age is a number of ticks: compare it with a smaller constant")
}
