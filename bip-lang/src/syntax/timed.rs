//! What a model says of time beyond its tick (docs/model.md, "Time budgets"): whether codels take time in the verified model (`time: Exact`), and the CPUs
//! with their cores and scheduling.

use std::fmt;

use serde::de::{self, Deserialize, Deserializer, EnumAccess, MapAccess, VariantAccess, Visitor};
use serde::ser::{Serialize, SerializeStruct, SerializeStructVariant, Serializer};

use super::fields;
use crate::source::{claim_word, ConstExpr, Span, Spanned, Text};

/// `time: Exact` or `time: Exact(unit: "500us")`: codels hold a core for their execution
/// time and the tick advances one time unit (docs/model.md, "Time budgets").
#[derive(Clone, Debug, Default)]
pub struct TimeDef {
    /// Where `Exact` is written.
    pub span: Span,
    /// The declared time unit (a duration); by default derived from the model's durations.
    pub unit: Option<ConstExpr>,
}

#[derive(serde::Deserialize)]
#[serde(variant_identifier)]
enum TimeTag {
    Exact,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct UnitFields {
    unit: ConstExpr,
}

impl<'de> Deserialize<'de> for TimeDef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct TimeVisitor;
        impl<'de> Visitor<'de> for TimeVisitor {
            type Value = TimeDef;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("`Exact` or `Exact(unit: \"10us\")`")
            }
            fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<TimeDef, A::Error> {
                let (TimeTag::Exact, variant) = data.variant::<TimeTag>()?;
                let (span, parens) = claim_word("Exact");
                if parens {
                    let u: UnitFields = variant.struct_variant(&["unit"], fields())?;
                    Ok(TimeDef {
                        span,
                        unit: Some(u.unit),
                    })
                } else {
                    variant.unit_variant()?;
                    Ok(TimeDef { span, unit: None })
                }
            }
        }
        d.deserialize_enum("Time", &["Exact"], TimeVisitor)
    }
}

impl Serialize for TimeDef {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match &self.unit {
            None => s.serialize_unit_variant("Time", 0, "Exact"),
            Some(unit) => {
                let mut v = s.serialize_struct_variant("Time", 0, "Exact", 1)?;
                v.serialize_field("unit", unit)?;
                v.end()
            }
        }
    }
}

/// How a CPU chooses among its ready tasks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum Policy {
    /// The ready task of highest `priority`.
    #[default]
    FixedPriority,
    /// The ready task of earliest absolute deadline.
    Edf,
}

/// When a running task may lose its core to a more urgent one.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum Preemption {
    /// Never within a job: a task keeps its core until its period's work is done.
    Job,
    /// Between two codels of its job.
    Codel,
    /// At any time (what the response-time analysis of `bip sched` assumes).
    #[default]
    Preemptive,
}

impl Policy {
    pub fn word(self) -> &'static str {
        match self {
            Policy::FixedPriority => "FixedPriority",
            Policy::Edf => "Edf",
        }
    }
}

impl Preemption {
    pub fn word(self) -> &'static str {
        match self {
            Preemption::Job => "Job",
            Preemption::Codel => "Codel",
            Preemption::Preemptive => "Preemptive",
        }
    }
}

/// Deserializes a unit variant and gives it the position of its word in the file.
macro_rules! spanned_word {
    ($t:ty) => {
        impl<'de> Deserialize<'de> for Spanned<$t> {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let value = <$t>::deserialize(d)?;
                let (span, _) = claim_word(value.word());
                Ok(Spanned::new(value, span))
            }
        }
    };
}
spanned_word!(Policy);
spanned_word!(Preemption);

/// A CPU: `"main"` (one core, fixed priorities, preemptive), or
/// `(name: "main", cores: 2, policy: FixedPriority, preemption: Job)`.
#[derive(Clone, Debug, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CpuDef {
    pub name: Text,
    /// At least 1; by default 1.
    #[serde(default)]
    pub cores: Option<ConstExpr>,
    #[serde(default)]
    pub policy: Option<Spanned<Policy>>,
    #[serde(default)]
    pub preemption: Option<Spanned<Preemption>>,
}

impl CpuDef {
    /// A CPU written as its name alone.
    pub fn named(name: Text) -> CpuDef {
        CpuDef {
            name,
            ..CpuDef::default()
        }
    }

    /// True if only the name is given (the string form).
    pub fn is_named_only(&self) -> bool {
        self.cores.is_none() && self.policy.is_none() && self.preemption.is_none()
    }

    /// The preemption it declares, the string form's being [`Preemption::Preemptive`].
    pub fn preemption(&self) -> Preemption {
        self.preemption
            .as_ref()
            .map_or_else(Preemption::default, |p| p.value)
    }

    /// The policy it declares, [`Policy::FixedPriority`] by default.
    pub fn policy(&self) -> Policy {
        self.policy
            .as_ref()
            .map_or_else(Policy::default, |p| p.value)
    }
}

/// A CPU is read from a string or from a struct: the shape tells them apart.
struct CpuVisitor;

impl<'de> Visitor<'de> for CpuVisitor {
    type Value = CpuDef;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a CPU: `\"main\"` or `(name: \"main\", cores: 2, policy: FixedPriority, preemption: Job)`")
    }

    fn visit_str<E: de::Error>(self, v: &str) -> Result<CpuDef, E> {
        let name = Text::deserialize(de::value::StrDeserializer::<E>::new(v))?;
        Ok(CpuDef::named(name))
    }

    fn visit_string<E: de::Error>(self, v: String) -> Result<CpuDef, E> {
        self.visit_str(&v)
    }

    fn visit_map<M: MapAccess<'de>>(self, map: M) -> Result<CpuDef, M::Error> {
        // `ron` reads a struct's name and drops it here
        CpuDef::deserialize(de::value::MapAccessDeserializer::new(map))
    }
}

/// The `deserialize_with` of `SystemDef::cpus`' items.
pub(crate) fn deserialize_cpus<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<CpuDef>, D::Error> {
    struct Cpu(CpuDef);
    impl<'de> Deserialize<'de> for Cpu {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            d.deserialize_any(CpuVisitor).map(Cpu)
        }
    }
    let cpus = Vec::<Cpu>::deserialize(d)?;
    Ok(cpus.into_iter().map(|c| c.0).collect())
}

impl Serialize for CpuDef {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.is_named_only() {
            return self.name.serialize(s);
        }
        let mut v = s.serialize_struct("CpuDef", 4)?;
        v.serialize_field("name", &self.name)?;
        if let Some(cores) = &self.cores {
            v.serialize_field("cores", cores)?;
        }
        if let Some(policy) = &self.policy {
            v.serialize_field("policy", &policy.value)?;
        }
        if let Some(preemption) = &self.preemption {
            v.serialize_field("preemption", &preemption.value)?;
        }
        v.end()
    }
}
