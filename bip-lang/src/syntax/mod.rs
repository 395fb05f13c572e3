//! The model file format: what a user writes in a `.ron` file (docs/model.md), as serde types.
//!
//! These types hold the text as written (names are strings with their positions;
//! expressions and actions are [`ExprDef`]/[`ActionDef`]: a text as written, or a tree the
//! GenoM expansion built); `compile` resolves them into a [`bip_model::System`]. They also
//! serialize back to RON, which is how `bip expand` prints an expanded model.

mod code;
mod task;
mod timed;
mod var;

use std::fmt;

use ron::extensions::Extensions;
use serde::de::{self, Deserialize, Deserializer, EnumAccess, MapAccess, VariantAccess, Visitor};
use serde::ser::{Serialize, SerializeStructVariant, Serializer};

pub use crate::genom::syntax::{
    CodelDef, ConnectionDef, ConstraintDef, DataTypeDef, FieldDef, ModuleDef, PortDef, ServiceDef,
    ServiceKind, TaskDef,
};
pub use crate::source::Text;
use crate::source::{ident_has_parens, ConstExpr, OrderedMap, Span};
use crate::source_map::SourceMap;
pub use bip_model::Role;
pub use code::{
    parse_action_in_file, parse_in_file, parse_range_in_file, syntax_error, ActionDef, ExprDef,
};
pub use task::AtomTaskDef;
pub use timed::{CpuDef, Policy, Preemption, TimeDef};
pub use var::{TypeDef, VarDef};

/// The `ron` options every model file is read and printed with (docs/model.md:
/// `implicit_some` and `unwrap_newtypes` are on); trace files share them.
pub fn ron_options() -> ron::Options {
    ron::Options::default()
        .with_default_extension(Extensions::IMPLICIT_SOME | Extensions::UNWRAP_NEWTYPES)
}

/// A whole model file: one `System(...)`.
#[derive(Clone, Debug, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename = "System", deny_unknown_fields)]
pub struct SystemDef {
    pub name: Text,
    /// Real-time length of one model tick in milliseconds (used by the engine's clock).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tick_ms: Option<ConstExpr>,
    /// `Exact`: the GenoM layer's codels take time on their CPUs' cores in the verified
    /// model (docs/model.md, "Time budgets"); absent: codels are instants.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<TimeDef>,
    /// The CPUs the tasks (of the GenoM layer, and atoms') run on, for the scheduling
    /// analysis (docs/model.md, "Time budgets"); none declared: one.
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "timed::deserialize_cpus"
    )]
    pub cpus: Vec<CpuDef>,
    #[serde(default, skip_serializing_if = "OrderedMap::is_empty")]
    pub constants: OrderedMap<Text, ConstExpr>,
    #[serde(default, skip_serializing_if = "OrderedMap::is_empty")]
    pub atoms: OrderedMap<Text, AtomDef>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub components: Vec<ComponentDef>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub connectors: Vec<ConnectorDef>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub priorities: Vec<PriorityDef>,
    /// The GenoM layer (docs/model.md, "The GenoM layer"), expanded into the core before compilation.
    /// `Gen("file.gen")` entries are read into modules by the loader (docs/genom.md, "GenoM3 files").
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "crate::gen3::entries::deserialize_modules"
    )]
    pub modules: Vec<ModuleDef>,
    /// Which out port each connected in port of a module reads (docs/model.md, "Connections").
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub connections: Vec<ConnectionDef>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<ConstraintDef>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub properties: Vec<PropertyDef>,
    /// The files besides this one that its spans may point into (`.gen` modules).
    #[serde(skip)]
    pub sources: SourceMap,
}

impl SystemDef {
    /// The model as RON text that [`crate::load_str`] reads back (how `bip expand` prints
    /// an expanded model).
    pub fn to_ron(&self) -> Result<String, ron::Error> {
        self.to_ron_nested(4)
    }

    /// The model as RON, structures nested deeper than `depth` on one line.
    pub fn to_ron_nested(&self, depth: usize) -> Result<String, ron::Error> {
        let config = ron::ser::PrettyConfig::new()
            .struct_names(true)
            .depth_limit(depth)
            .extensions(ron::extensions::Extensions::IMPLICIT_SOME);
        let text = ron_options().to_string_pretty(self, config)?;
        Ok(tidy_ron(&text))
    }

    /// True if the model has a GenoM layer to expand.
    pub fn has_genom_layer(&self) -> bool {
        !self.modules.is_empty() || !self.constraints.is_empty() || !self.connections.is_empty()
    }
}

/// Writes printed RON the way docs/model.md does: the inner structs without their type names
/// (`(from: …)`, not `TransitionDef(from: …)`), and lists of plain values on one line.
fn tidy_ron(text: &str) -> String {
    const INNER: [&str; 13] = [
        "CpuDef(",
        "VarDef(",
        "TransitionDef(",
        "ComponentDef(",
        "ConnectorDef(",
        "PriorityDef(",
        "ModuleDef(",
        "TaskDef(",
        "PortDef(",
        "ServiceDef(",
        "CodelDef(",
        "FieldDef(",
        "ConnectionDef(",
    ];
    let lines: Vec<&str> = text.lines().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        if line.trim_end().ends_with('[') {
            // a list whose items are all plain strings or numbers goes on one line
            let mut items = Vec::new();
            let mut j = i + 1;
            while j < lines.len() {
                let item = lines[j].trim();
                let scalar = item.ends_with(',')
                    && (item.starts_with('"') && item.ends_with("\",")
                        || item[..item.len() - 1].parse::<i64>().is_ok());
                if !scalar {
                    break;
                }
                items.push(&item[..item.len() - 1]);
                j += 1;
            }
            let close = lines.get(j).map(|l| l.trim());
            if !items.is_empty() && matches!(close, Some("]") | Some("],")) {
                let suffix = if close == Some("],") { "," } else { "" };
                out.push_str(&strip_inner(line, &INNER));
                out.push_str(&items.join(", "));
                out.push(']');
                out.push_str(suffix);
                out.push('\n');
                i = j + 1;
                continue;
            }
        }
        if line.trim() == "ConnectionDef(" {
            // a connection, two names, goes on one line
            let fields: Vec<&str> = lines[i + 1..]
                .iter()
                .map(|l| l.trim())
                .take_while(|l| !l.starts_with(')'))
                .collect();
            let close = i + 1 + fields.len();
            if let Some(end) = lines.get(close) {
                let indent = &line[..line.len() - line.trim_start().len()];
                let joined = fields.join(" ");
                out.push_str(indent);
                out.push('(');
                out.push_str(joined.trim_end_matches(','));
                out.push_str(end.trim());
                out.push('\n');
                i = close + 1;
                continue;
            }
        }
        out.push_str(&strip_inner(line, &INNER));
        out.push('\n');
        i += 1;
    }
    out
}

/// Removes the struct names that start a value on the line (its content, or an item of a
/// list or a field's value written on it), outside strings.
fn strip_inner(line: &str, names: &[&str]) -> String {
    let mut out = String::with_capacity(line.len());
    let mut in_string = false;
    let mut escaped = false;
    // a value starts the line's content or follows `(`, `[`, `,` or `:`
    let mut value_starts = true;
    let mut i = 0;
    while let Some(ch) = line[i..].chars().next() {
        if !in_string && value_starts {
            if let Some(n) = names.iter().find(|n| line[i..].starts_with(**n)) {
                i += n.len() - 1;
                continue;
            }
        }
        out.push(ch);
        i += ch.len_utf8();
        if in_string {
            match ch {
                _ if escaped => escaped = false,
                '\\' => escaped = true,
                '"' => in_string = false,
                _ => {}
            }
        } else if ch == '"' {
            in_string = true;
            value_starts = false;
        } else if !ch.is_whitespace() {
            value_starts = matches!(ch, '(' | '[' | ',' | ':');
        }
    }
    out
}

/// An atom type: an automaton with ports and bounded data.
#[derive(Clone, Debug, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename = "Atom", deny_unknown_fields)]
pub struct AtomDef {
    pub locations: Vec<Text>,
    pub initial: Text,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ports: Vec<Text>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub vars: Vec<VarDef>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub transitions: Vec<TransitionDef>,
    /// Each component of the atom stands for a periodic task (docs/model.md, "Time
    /// budgets").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<AtomTaskDef>,
}

#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct TransitionDef {
    pub from: Text,
    /// Absent for an internal transition.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub port: Option<Text>,
    pub to: Text,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub guard: Option<ExprDef>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub action: Option<ActionDef>,
}

#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ComponentDef {
    pub name: Text,
    pub atom: Text,
    /// Number of instances `name[0]`..`name[count-1]`; absent for a single instance `name`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<ConstExpr>,
    /// Per-family initial values, overriding the atom's; may use `self_index`.
    #[serde(default, skip_serializing_if = "OrderedMap::is_empty")]
    pub vars_init: OrderedMap<Text, ConstExpr>,
}

#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConnectorDef {
    pub name: Text,
    /// `"i in a..b"`: one connector instance `name[i]` per value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub forall: Option<Text>,
    /// Required except in a connector that extends a generated one (docs/genom.md), which
    /// may add only a guard.
    #[serde(default)]
    pub ports: Vec<ExprDef>,
    #[serde(default, skip_serializing_if = "ConnectorKindDef::is_rendezvous")]
    pub kind: ConnectorKindDef,
    /// What the connector's steps stand for, for deadlock detection (docs/model.md).
    #[serde(default, skip_serializing_if = "Role::is_progress")]
    pub role: Role,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub guard: Option<ExprDef>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub action: Option<ActionDef>,
    /// Of a `Time` connector: the time units its step stands for (default 1), evaluated on
    /// the state the step leaves; its action reads it as `advance`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub advance: Option<ExprDef>,
}

#[derive(Clone, Debug, Default, serde::Deserialize, serde::Serialize)]
pub enum ConnectorKindDef {
    #[default]
    Rendezvous,
    Broadcast {
        trigger: ExprDef,
    },
}

impl ConnectorKindDef {
    fn is_rendezvous(&self) -> bool {
        matches!(self, ConnectorKindDef::Rendezvous)
    }
}

/// The role of a connector's steps in deadlock detection.
///
/// A model with a clock can always let time pass, and a model open to its environment can
/// always receive a request; neither is progress of the system itself. `DeadlockFree` is
/// therefore checked against progress steps: a state is a deadlock when no progress step is
/// enabled in it, nor in any state reached from it by `Time` steps alone (docs/model.md).
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct PriorityDef {
    pub low: ExprDef,
    pub high: ExprDef,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub when: Option<ExprDef>,
}

/// A property to verify. `DeadlockFree` may be written bare or with a `terminal` condition.
///
/// A response property's `trigger`/`response` (`from`/`to`) is a state condition or steps
/// (docs/model.md, "Response and liveness"): `fires(c)`, `changes(before, after)`, in the
/// GenoM layer `request(m.S)`, `reply(m.S)`, `yield(m.S.codel)`; the expansion turns
/// `Replies` and `Terminates` into `Response` and `LeadsTo` of the core.
#[derive(Clone, Debug)]
pub enum PropertyDef {
    DeadlockFree {
        terminal: Option<ExprDef>,
    },
    Invariant {
        name: Text,
        expr: ExprDef,
    },
    Reachable {
        name: Text,
        expr: ExprDef,
    },
    Response {
        name: Text,
        trigger: ExprDef,
        response: ExprDef,
        within: ConstExpr,
    },
    LeadsTo {
        name: Text,
        from: ExprDef,
        to: ExprDef,
    },
    Replies {
        name: Option<Text>,
        service: Text,
        within: Option<ConstExpr>,
    },
    Terminates {
        name: Option<Text>,
        service: Text,
    },
}

impl PropertyDef {
    /// The property's name as reports show it: `Replies` and `Terminates` without a
    /// `name` are named after their service (`Replies(ndd.GoTo)`).
    pub fn name(&self) -> std::borrow::Cow<'_, str> {
        match self {
            PropertyDef::DeadlockFree { .. } => "DeadlockFree".into(),
            PropertyDef::Invariant { name, .. }
            | PropertyDef::Reachable { name, .. }
            | PropertyDef::Response { name, .. }
            | PropertyDef::LeadsTo { name, .. } => name.as_str().into(),
            PropertyDef::Replies {
                name: Some(name), ..
            }
            | PropertyDef::Terminates {
                name: Some(name), ..
            } => name.as_str().into(),
            PropertyDef::Replies {
                name: None,
                service,
                within,
            } => match within {
                Some(k) => format!("Replies({service}, within: {})", k.value).into(),
                None => format!("Replies({service})").into(),
            },
            PropertyDef::Terminates {
                name: None,
                service,
            } => format!("Terminates({service})").into(),
        }
    }

    /// Where the property's name is, or where it would be (its service, its keyword's
    /// first expression), for messages about it.
    pub fn name_span(&self) -> Span {
        match self {
            PropertyDef::DeadlockFree { terminal } => {
                terminal.as_ref().map_or(Span::NONE, ExprDef::span)
            }
            PropertyDef::Invariant { name, .. }
            | PropertyDef::Reachable { name, .. }
            | PropertyDef::Response { name, .. }
            | PropertyDef::LeadsTo { name, .. } => name.span,
            PropertyDef::Replies { name, service, .. }
            | PropertyDef::Terminates { name, service } => {
                name.as_ref().map_or(service.span, |n| n.span)
            }
        }
    }
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ResponseFields {
    name: Text,
    trigger: ExprDef,
    response: ExprDef,
    within: ConstExpr,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct LeadsToFields {
    name: Text,
    from: ExprDef,
    to: ExprDef,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct RepliesFields {
    #[serde(default)]
    name: Option<Text>,
    service: Text,
    #[serde(default)]
    within: Option<ConstExpr>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct TerminatesFields {
    #[serde(default)]
    name: Option<Text>,
    service: Text,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct NamedExprDef {
    name: Text,
    expr: ExprDef,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct TerminalDef {
    #[serde(default)]
    terminal: Option<ExprDef>,
}

#[derive(serde::Deserialize)]
#[serde(variant_identifier)]
enum PropertyTag {
    DeadlockFree,
    Invariant,
    Reachable,
    Response,
    LeadsTo,
    Replies,
    Terminates,
}

const PROPERTY_VARIANTS: &[&str] = &[
    "DeadlockFree",
    "Invariant",
    "Reachable",
    "Response",
    "LeadsTo",
    "Replies",
    "Terminates",
];

impl<'de> Deserialize<'de> for PropertyDef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct PropertyVisitor;
        impl<'de> Visitor<'de> for PropertyVisitor {
            type Value = PropertyDef;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("DeadlockFree, Invariant(name, expr), Reachable(name, expr), Response(name, trigger, response, within), LeadsTo(name, from, to), Replies(service) or Terminates(service)")
            }
            fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<PropertyDef, A::Error> {
                let (tag, variant) = data.variant::<PropertyTag>()?;
                match tag {
                    PropertyTag::DeadlockFree => {
                        if ident_has_parens("DeadlockFree") {
                            let t: TerminalDef = variant.struct_variant(&["terminal"], fields())?;
                            Ok(PropertyDef::DeadlockFree {
                                terminal: t.terminal,
                            })
                        } else {
                            variant.unit_variant()?;
                            Ok(PropertyDef::DeadlockFree { terminal: None })
                        }
                    }
                    PropertyTag::Invariant => {
                        let n: NamedExprDef =
                            variant.struct_variant(&["name", "expr"], fields())?;
                        Ok(PropertyDef::Invariant {
                            name: n.name,
                            expr: n.expr,
                        })
                    }
                    PropertyTag::Reachable => {
                        let n: NamedExprDef =
                            variant.struct_variant(&["name", "expr"], fields())?;
                        Ok(PropertyDef::Reachable {
                            name: n.name,
                            expr: n.expr,
                        })
                    }
                    PropertyTag::Response => {
                        let r: ResponseFields = variant
                            .struct_variant(&["name", "trigger", "response", "within"], fields())?;
                        Ok(PropertyDef::Response {
                            name: r.name,
                            trigger: r.trigger,
                            response: r.response,
                            within: r.within,
                        })
                    }
                    PropertyTag::LeadsTo => {
                        let r: LeadsToFields =
                            variant.struct_variant(&["name", "from", "to"], fields())?;
                        Ok(PropertyDef::LeadsTo {
                            name: r.name,
                            from: r.from,
                            to: r.to,
                        })
                    }
                    PropertyTag::Replies => {
                        let r: RepliesFields =
                            variant.struct_variant(&["name", "service", "within"], fields())?;
                        Ok(PropertyDef::Replies {
                            name: r.name,
                            service: r.service,
                            within: r.within,
                        })
                    }
                    PropertyTag::Terminates => {
                        let r: TerminatesFields =
                            variant.struct_variant(&["name", "service"], fields())?;
                        Ok(PropertyDef::Terminates {
                            name: r.name,
                            service: r.service,
                        })
                    }
                }
            }
        }
        d.deserialize_enum("Property", PROPERTY_VARIANTS, PropertyVisitor)
    }
}

/// Deserializes the fields of a struct variant into the derived struct `T`.
struct FieldsVisitor<T>(std::marker::PhantomData<T>);

fn fields<T>() -> FieldsVisitor<T> {
    FieldsVisitor(std::marker::PhantomData)
}

impl<'de, T: Deserialize<'de>> Visitor<'de> for FieldsVisitor<T> {
    type Value = T;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("named fields")
    }
    fn visit_map<M: MapAccess<'de>>(self, map: M) -> Result<T, M::Error> {
        T::deserialize(de::value::MapAccessDeserializer::new(map))
    }
}

impl Serialize for PropertyDef {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            PropertyDef::DeadlockFree { terminal: None } => {
                s.serialize_unit_variant("Property", 0, "DeadlockFree")
            }
            PropertyDef::DeadlockFree {
                terminal: Some(term),
            } => {
                let mut v = s.serialize_struct_variant("Property", 0, "DeadlockFree", 1)?;
                v.serialize_field("terminal", term)?;
                v.end()
            }
            PropertyDef::Invariant { name, expr } => {
                let mut v = s.serialize_struct_variant("Property", 1, "Invariant", 2)?;
                v.serialize_field("name", name)?;
                v.serialize_field("expr", expr)?;
                v.end()
            }
            PropertyDef::Reachable { name, expr } => {
                let mut v = s.serialize_struct_variant("Property", 2, "Reachable", 2)?;
                v.serialize_field("name", name)?;
                v.serialize_field("expr", expr)?;
                v.end()
            }
            PropertyDef::Response {
                name,
                trigger,
                response,
                within,
            } => {
                let mut v = s.serialize_struct_variant("Property", 3, "Response", 4)?;
                v.serialize_field("name", name)?;
                v.serialize_field("trigger", trigger)?;
                v.serialize_field("response", response)?;
                v.serialize_field("within", within)?;
                v.end()
            }
            PropertyDef::LeadsTo { name, from, to } => {
                let mut v = s.serialize_struct_variant("Property", 4, "LeadsTo", 3)?;
                v.serialize_field("name", name)?;
                v.serialize_field("from", from)?;
                v.serialize_field("to", to)?;
                v.end()
            }
            PropertyDef::Replies {
                name,
                service,
                within,
            } => {
                let mut v = s.serialize_struct_variant("Property", 5, "Replies", 3)?;
                if let Some(n) = name {
                    v.serialize_field("name", n)?;
                }
                v.serialize_field("service", service)?;
                if let Some(k) = within {
                    v.serialize_field("within", k)?;
                }
                v.end()
            }
            PropertyDef::Terminates { name, service } => {
                let mut v = s.serialize_struct_variant("Property", 6, "Terminates", 2)?;
                if let Some(n) = name {
                    v.serialize_field("name", n)?;
                }
                v.serialize_field("service", service)?;
                v.end()
            }
        }
    }
}
