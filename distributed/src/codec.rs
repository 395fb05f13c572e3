//! How the model's data cross the network: one [`Codec`] per port, per service's
//! arguments and per service's output, each a Rust type to and from JSON. The model's
//! `Bool`, `Int` and `Float` have theirs by default; a record or a `Rust(..)` type is
//! given its codec by the controller ([`Types::port`] and the others), from serde or
//! from two functions.

use std::any::{type_name, Any};
use std::marker::PhantomData;
use std::sync::Arc;

use bip_engine::bip_model::genom::map::DataType;
use bip_engine::{Ctx, Handle, HostedModule, Output, PendingReply, System};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;

/// A Rust type's conversions to and from JSON, for every place its values go.
#[derive(Clone)]
pub struct Codec(Arc<dyn Convert>);

/// The conversions, as the engine's and the module process's sides use them.
trait Convert: Send + Sync {
    fn type_name(&self) -> &'static str;
    /// Reads port `module.port` as the engine holds it (reading it as another type than
    /// the port's is the codel's fault, as in one process).
    fn read_port(&self, ctx: &Ctx<'_>, module: &str, port: &str) -> Option<Value>;
    fn write_port(&self, ctx: &mut Ctx<'_>, port: &str, v: &Value) -> Result<(), String>;
    fn read_args(&self, ctx: &Ctx<'_>) -> Option<Value>;
    fn decode(&self, v: &Value) -> Result<Box<dyn Any + Send>, String>;
    fn set_output(&self, ctx: &mut Ctx<'_>, v: &Value) -> Result<(), String>;
    fn output(&self, o: &Output) -> Option<Value>;
    fn host_set_port(
        &self,
        h: &mut HostedModule,
        module: &str,
        port: &str,
        v: &Value,
    ) -> Result<(), String>;
    fn host_port(&self, h: &HostedModule, module: &str, port: &str) -> Option<Value>;
    fn request(
        &self,
        handle: &Handle,
        module: &str,
        service: &str,
        v: &Value,
    ) -> Result<PendingReply, String>;
}

struct Typed<T> {
    to: fn(&T) -> Value,
    from: fn(&Value) -> Result<T, String>,
    _t: PhantomData<fn() -> T>,
}

impl<T: Any + Send + Sync + Clone + Default> Convert for Typed<T> {
    fn type_name(&self) -> &'static str {
        type_name::<T>()
    }
    fn read_port(&self, ctx: &Ctx<'_>, module: &str, port: &str) -> Option<Value> {
        ctx.port::<T>(module, port).map(self.to)
    }
    fn write_port(&self, ctx: &mut Ctx<'_>, port: &str, v: &Value) -> Result<(), String> {
        ctx.write_port(port, (self.from)(v)?);
        Ok(())
    }
    fn read_args(&self, ctx: &Ctx<'_>) -> Option<Value> {
        ctx.args::<T>().map(self.to)
    }
    fn decode(&self, v: &Value) -> Result<Box<dyn Any + Send>, String> {
        Ok(Box::new((self.from)(v)?))
    }
    fn set_output(&self, ctx: &mut Ctx<'_>, v: &Value) -> Result<(), String> {
        ctx.set_output((self.from)(v)?);
        Ok(())
    }
    fn output(&self, o: &Output) -> Option<Value> {
        o.get::<T>().map(self.to)
    }
    fn host_set_port(
        &self,
        h: &mut HostedModule,
        module: &str,
        port: &str,
        v: &Value,
    ) -> Result<(), String> {
        h.set_port(module, port, (self.from)(v)?)
    }
    fn host_port(&self, h: &HostedModule, module: &str, port: &str) -> Option<Value> {
        h.port::<T>(module, port).map(self.to)
    }
    fn request(
        &self,
        handle: &Handle,
        module: &str,
        service: &str,
        v: &Value,
    ) -> Result<PendingReply, String> {
        handle
            .request(module, service, (self.from)(v)?)
            .map_err(|e| e.to_string())
    }
}

impl Codec {
    /// A type that serde serializes: JSON as serde_json writes it.
    pub fn serde<T: Serialize + DeserializeOwned + Any + Send + Sync + Clone + Default>() -> Codec {
        Codec::with::<T>(
            |t| serde_json::to_value(t).unwrap_or(Value::Null),
            |v| T::deserialize(v).map_err(|e| e.to_string()),
        )
    }

    /// A type converted by two functions (for a type without serde, such as the records
    /// bip-codegen generates).
    pub fn with<T: Any + Send + Sync + Clone + Default>(
        to: fn(&T) -> Value,
        from: fn(&Value) -> Result<T, String>,
    ) -> Codec {
        Codec(Arc::new(Typed {
            to,
            from,
            _t: PhantomData,
        }))
    }

    /// The codec of a model's `Bool`, `Int` or `Float` (`bool`, `i64`, `f64`).
    fn of_model(ty: &DataType) -> Option<Codec> {
        match ty {
            DataType::Bool => Some(Codec::serde::<bool>()),
            DataType::Int { .. } => Some(Codec::serde::<i64>()),
            DataType::Float => Some(Codec::serde::<f64>()),
            DataType::Record { .. } | DataType::Rust(_) => None,
        }
    }

    pub fn type_name(&self) -> &'static str {
        self.0.type_name()
    }

    pub(crate) fn read_port(&self, ctx: &Ctx<'_>, module: &str, port: &str) -> Option<Value> {
        self.0.read_port(ctx, module, port)
    }
    pub(crate) fn write_port(
        &self,
        ctx: &mut Ctx<'_>,
        port: &str,
        v: &Value,
    ) -> Result<(), String> {
        self.0.write_port(ctx, port, v)
    }
    pub(crate) fn read_args(&self, ctx: &Ctx<'_>) -> Option<Value> {
        self.0.read_args(ctx)
    }
    pub(crate) fn decode(&self, v: &Value) -> Result<Box<dyn Any + Send>, String> {
        self.0.decode(v)
    }
    pub(crate) fn set_output(&self, ctx: &mut Ctx<'_>, v: &Value) -> Result<(), String> {
        self.0.set_output(ctx, v)
    }
    pub(crate) fn output(&self, o: &Output) -> Option<Value> {
        self.0.output(o)
    }
    pub(crate) fn host_set_port(
        &self,
        h: &mut HostedModule,
        module: &str,
        port: &str,
        v: &Value,
    ) -> Result<(), String> {
        self.0.host_set_port(h, module, port, v)
    }
    pub(crate) fn host_port(&self, h: &HostedModule, module: &str, port: &str) -> Option<Value> {
        self.0.host_port(h, module, port)
    }
    /// Sends a request with arguments `v`, read as this codec's type.
    pub(crate) fn request(
        &self,
        handle: &Handle,
        module: &str,
        service: &str,
        v: &Value,
    ) -> Result<PendingReply, String> {
        self.0.request(handle, module, service, v)
    }
}

/// Where the data go: (module, name, codec).
type Table = Vec<(String, String, Codec)>;

/// The codecs of a layer's data: per out port, per service's arguments and output.
#[derive(Clone, Default)]
pub struct Types {
    ports: Table,
    args: Table,
    outputs: Table,
}

/// What a [`Types`] must cover: per port, service's arguments and output, the model's
/// type: (module, name, type).
struct Declared {
    ports: Vec<(String, String, DataType)>,
    args: Vec<(String, String, DataType)>,
    outputs: Vec<(String, String, DataType)>,
}

fn declared(system: &System) -> Declared {
    let mut d = Declared {
        ports: Vec::new(),
        args: Vec::new(),
        outputs: Vec::new(),
    };
    for m in system.genom.iter().flat_map(|g| &g.modules) {
        for p in &m.ports {
            if let Some(ty) = &p.ty {
                d.ports.push((m.name.clone(), p.name.clone(), ty.clone()));
            }
        }
        for s in &m.services {
            if let Some(ty) = &s.args {
                d.args.push((m.name.clone(), s.name.clone(), ty.clone()));
            }
            if let Some(ty) = &s.output {
                d.outputs.push((m.name.clone(), s.name.clone(), ty.clone()));
            }
        }
    }
    d
}

fn set(table: &mut Table, module: &str, name: &str, codec: Codec) {
    table.retain(|(m, n, _)| (m.as_str(), n.as_str()) != (module, name));
    table.push((module.to_string(), name.to_string(), codec));
}

fn find<'a>(table: &'a Table, module: &str, name: &str) -> Option<&'a Codec> {
    table
        .iter()
        .find(|(m, n, _)| m == module && n == name)
        .map(|(_, _, c)| c)
}

impl Types {
    /// The codecs the model's own types give: every port, arguments and output of type
    /// `Bool`, `Int` or `Float`.
    pub fn of(system: &System) -> Types {
        let d = declared(system);
        let pick = |v: Vec<(String, String, DataType)>| -> Table {
            v.into_iter()
                .filter_map(|(m, n, ty)| Codec::of_model(&ty).map(|c| (m, n, c)))
                .collect()
        };
        Types {
            ports: pick(d.ports),
            args: pick(d.args),
            outputs: pick(d.outputs),
        }
    }

    /// The codec of out port `module.port`'s data.
    pub fn port(mut self, module: &str, port: &str, codec: Codec) -> Types {
        set(&mut self.ports, module, port, codec);
        self
    }

    /// The codec of `module.service`'s arguments.
    pub fn args(mut self, module: &str, service: &str, codec: Codec) -> Types {
        set(&mut self.args, module, service, codec);
        self
    }

    /// The codec of `module.service`'s output.
    pub fn output(mut self, module: &str, service: &str, codec: Codec) -> Types {
        set(&mut self.outputs, module, service, codec);
        self
    }

    /// Every typed port, arguments and output of `system` has a codec of its type: the
    /// first that has none or another, in words.
    pub fn check(&self, system: &System) -> Result<(), String> {
        let d = declared(system);
        let kinds = [
            ("port", &d.ports, &self.ports),
            ("arguments of", &d.args, &self.args),
            ("output of", &d.outputs, &self.outputs),
        ];
        for (what, declared, table) in kinds {
            for (m, n, ty) in declared.iter() {
                match find(table, m, n) {
                    None => {
                        return Err(format!(
                            "the {what} `{m}.{n}` ({ty}) has no codec to cross the network; give it one"
                        ))
                    }
                    Some(c) if !ty.accepts(c.type_name()) => {
                        return Err(format!(
                            "the {what} `{m}.{n}` is {ty} (a Rust `{}`), but its codec is for a `{}`",
                            ty.rust_name(),
                            c.type_name()
                        ))
                    }
                    Some(_) => {}
                }
            }
        }
        Ok(())
    }

    pub(crate) fn ports(&self) -> impl Iterator<Item = (&str, &str, &Codec)> {
        self.ports
            .iter()
            .map(|(m, p, c)| (m.as_str(), p.as_str(), c))
    }

    pub(crate) fn port_codec(&self, module: &str, port: &str) -> Option<&Codec> {
        find(&self.ports, module, port)
    }

    pub(crate) fn args_codec(&self, module: &str, service: &str) -> Option<&Codec> {
        find(&self.args, module, service)
    }

    pub(crate) fn output_codec(&self, module: &str, service: &str) -> Option<&Codec> {
        find(&self.outputs, module, service)
    }
}
