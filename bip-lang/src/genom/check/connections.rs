//! The model's `connections` (which out port each in port reads, as a deployment wires
//! components), and the resolution of the names that constraints, connections and
//! expressions give: a module, and a port, which is an out port or an in port that
//! stands for the out port it is connected to.

use super::{Layer, PortRef};
use crate::compile::one_of;
use crate::diag::{Errors, ModelError};
use crate::source::Span;
use crate::syntax::{ConnectionDef, Text};

/// Checks each connection and records on its in port the out port it reads: both ends
/// exist, the first is an in port and the second an out port, their data types agree,
/// and no in port is connected twice.
pub(super) fn connect(errors: &mut Errors, layer: &mut Layer<'_>, defs: &[ConnectionDef]) {
    let mut first: Vec<Vec<Option<Span>>> = layer
        .modules
        .iter()
        .map(|m| vec![None; m.in_ports.len()])
        .collect();
    for c in defs {
        let Some((m, p, ms, ps)) = split_dotted(errors, &c.port, "`module.port`") else {
            continue;
        };
        let reads = split_dotted(errors, &c.reads, "`module.port`");
        let Some(mi) = module_index(errors, layer, m, ms) else {
            continue;
        };
        let module = &layer.modules[mi];
        let Some(pi) = module.in_ports.iter().position(|x| x.name == p) else {
            let what = match module.ports.contains(&p) {
                true => format!("`{m}.{p}` is an out port: a connection's `port` is an in port"),
                false => format!("module `{m}` has no in port `{p}`"),
            };
            errors.push(ModelError::new(what, ps).with_help(one_of(
                "its in ports are",
                module.in_ports.iter().map(|x| x.name),
            )));
            continue;
        };
        let Some((n, q, ns, qs)) = reads else {
            continue;
        };
        let Some(ni) = module_index(errors, layer, n, ns) else {
            continue;
        };
        let writer = &layer.modules[ni];
        let Some(qi) = writer.ports.iter().position(|&x| x == q) else {
            let what = match writer.in_ports.iter().any(|x| x.name == q) {
                true => format!("`{n}.{q}` is an in port: a connection reads an out port"),
                false => format!("module `{n}` has no out port `{q}`"),
            };
            errors.push(
                ModelError::new(what, qs)
                    .with_help(one_of("its out ports are", writer.ports.iter().copied())),
            );
            continue;
        };
        if let (Some(want), Some(given)) = (&module.in_ports[pi].ty, &writer.port_types[qi]) {
            if want != given {
                errors.push(
                    ModelError::new(
                        format!(
                            "in port `{m}.{p}` takes `{}`, and out port `{n}.{q}` carries `{}`",
                            want.written(),
                            given.written()
                        ),
                        c.reads.span,
                    )
                    .with_help("a connected in port reads the out port's data: give both one type"),
                );
                continue;
            }
        }
        if let Some(at) = first[mi][pi] {
            errors.push(
                ModelError::new(format!("in port `{m}.{p}` is connected twice"), c.port.span)
                    .with_note(at, "first connected here")
                    .with_help("an in port reads one out port"),
            );
            continue;
        }
        first[mi][pi] = Some(c.port.span);
        layer.modules[mi].in_ports[pi].reads = Some(PortRef {
            module: ni,
            port: qi,
        });
    }
}

/// The out port that port `name` of module `module` stands for: the port itself, or the
/// out port an in port is connected to. `span` is where the name is written.
pub fn port_ref(
    layer: &Layer<'_>,
    module: usize,
    name: &str,
    span: Span,
) -> Result<PortRef, ModelError> {
    let m = &layer.modules[module];
    if let Some(port) = m.ports.iter().position(|&x| x == name) {
        return Ok(PortRef { module, port });
    }
    match m.in_ports.iter().find(|x| x.name == name) {
        Some(p) => p.reads.ok_or_else(|| {
            ModelError::new(
                format!("in port `{}.{name}` is connected to no out port", m.name),
                span,
            )
            .with_help(format!(
                "its data comes from the out port a connection names: \
                 `connections: [(port: \"{}.{name}\", reads: \"module.port\")]`",
                m.name
            ))
        }),
        None => Err(
            ModelError::new(format!("module `{}` has no port `{name}`", m.name), span).with_help(
                one_of(
                    "its ports are",
                    m.ports
                        .iter()
                        .copied()
                        .chain(m.in_ports.iter().map(|x| x.name)),
                ),
            ),
        ),
    }
}

/// The index of module `m` (written at `span`), or an error listing the modules.
pub(super) fn module_index(
    errors: &mut Errors,
    layer: &Layer<'_>,
    m: &str,
    span: Span,
) -> Option<usize> {
    let found = layer.modules.iter().position(|x| x.name == m);
    if found.is_none() {
        errors.push(
            ModelError::new(format!("unknown module `{m}`"), span).with_help(one_of(
                "the modules are",
                layer.modules.iter().map(|x| x.name),
            )),
        );
    }
    found
}

/// Splits `"a.b"` into its two names and their spans in the file.
pub(super) fn split_dotted<'t>(
    errors: &mut Errors,
    t: &'t Text,
    form: &str,
) -> Option<(&'t str, &'t str, Span, Span)> {
    let text = t.as_str();
    let ok = |s: &str| {
        s.chars()
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    match text.split_once('.') {
        Some((a, b)) if ok(a) && ok(b) => Some((
            a,
            b,
            t.sub_span(0..a.len()),
            t.sub_span(a.len() + 1..text.len()),
        )),
        _ => {
            errors.push(ModelError::new(
                format!("expected {form}, found `{text}`"),
                t.span,
            ));
            None
        }
    }
}
