//! Codels: what a codel returns ([`Next`]), what it sees ([`Ctx`]), and how the engine
//! runs one (bound, by default, or on its task's thread).

use core::any::{type_name, Any};
use core::cell::Cell;

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::genom::map::DataType;

use crate::event::Output;
use crate::ports::{PortStore, WrongType};

/// What a codel returns: where its activity goes next, or an exception.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Next {
    /// The codel's `k`-th declared outcome: its yields, then its exceptions, in the
    /// model's order. What generated bindings return: no text to look up, and the
    /// numbering is checked against the model when they are bound
    /// ([`crate::CodelSignature`]). A `k` past the codel's outcomes is a fault.
    Declared(u16),
    /// A yield as the model writes it: `"main"`, `"pause::main"` or `"ether"`.
    Yield(&'static str),
    /// One of the codel's declared `throws`.
    Throw(&'static str),
}

impl Next {
    /// The activity ends successfully.
    pub const ETHER: Next = Next::Yield("ether");
}

/// A codel: a closure over a [`Ctx`]. It must be `Send` so that a task thread can run it.
pub type CodelFn = Box<dyn FnMut(&mut Ctx<'_>) -> Next + Send>;

/// The codels of one module as one object (bound with [`crate::EngineBuilder::module`]):
/// called with the codel's index among the module's codels, in the GenoM map's order
/// (services, then their codels, as declared). One object serves them all without a lock:
/// the engine calls one codel at a time.
pub type ModuleFn = Box<dyn FnMut(usize, &mut Ctx<'_>) -> Next + Send>;

/// An ids field of a module.
#[derive(Clone, Debug)]
pub(crate) struct Field {
    pub name: String,
    pub slot: u32,
    pub lo: i64,
    pub hi: i64,
}

/// What a codel may see and do, fixed when the engine is built.
#[derive(Clone, Debug)]
pub(crate) struct CodelInfo {
    pub module: String,
    pub service: String,
    pub state: String,
    /// The module's ids fields, in order.
    pub fields: Vec<Field>,
    /// The fields the codel may write (bit `k` for field `k`).
    pub writable: u64,
    /// The ports the codel may write: (index in the port store, name).
    pub ports: Vec<(usize, String)>,
    /// The declared type of its service's output.
    pub output: Option<DataType>,
}

/// Something a codel did that the model does not allow; the engine makes it a fault.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum CtxFault {
    IdsWrite(String),
    PortWrite(String),
    NoPort(String),
    WrongType {
        what: String,
        expected: String,
        given: &'static str,
    },
    Remote(String),
}

impl From<CtxFault> for crate::event::FaultKind {
    fn from(f: CtxFault) -> Self {
        use crate::event::FaultKind;
        match f {
            CtxFault::IdsWrite(x) => FaultKind::UndeclaredIdsWrite(x),
            CtxFault::PortWrite(p) => FaultKind::PortWrite(p),
            CtxFault::NoPort(p) => FaultKind::NoSuchPort(p),
            CtxFault::WrongType {
                what,
                expected,
                given,
            } => FaultKind::WrongType {
                what,
                expected,
                given,
            },
            CtxFault::Remote(why) => FaultKind::Remote(why),
        }
    }
}

impl CtxFault {
    fn port(verb: &str, w: WrongType) -> CtxFault {
        CtxFault::WrongType {
            what: format!("{verb} port `{}`", w.port),
            expected: w.expected,
            given: w.given,
        }
    }
}

/// The codel's view: its module's ids (staged: the engine commits them with the codel's
/// step, if the step is a normal outcome), ports, the request's arguments, the time.
pub struct Ctx<'a> {
    pub(crate) info: &'a CodelInfo,
    pub(crate) ids: &'a mut [i64],
    pub(crate) written: &'a mut u64,
    /// The first rule it broke (a cell: reading a port with the wrong type is one).
    pub(crate) fault: &'a Cell<Option<CtxFault>>,
    pub(crate) ports: &'a mut PortStore,
    pub(crate) args: Option<&'a (dyn Any + Send)>,
    /// The output of the request the activity serves.
    pub(crate) output: Option<&'a mut Option<Output>>,
    pub(crate) now_us: u64,
    pub(crate) tick: u64,
}

impl Ctx<'_> {
    pub fn module(&self) -> &str {
        &self.info.module
    }

    pub fn service(&self) -> &str {
        &self.info.service
    }

    /// The codel state being run (`"start"`, `"main"`, ...).
    pub fn state(&self) -> &str {
        &self.info.state
    }

    /// Makes this run a fault of its own kind, [`crate::FaultKind::Remote`]: the codel
    /// was to run in another process, which did not run it (gone, hung, cut off, or it
    /// refused the run). For the proxies of modules in other processes (bip-zenoh); what
    /// the proxy returns after it is not looked at.
    #[cold]
    pub fn remote_fault(&self, why: String) {
        self.fault(CtxFault::Remote(why));
    }

    /// Notes what the codel did wrong, if it did nothing wrong before.
    #[cold]
    fn fault(&self, f: CtxFault) {
        let first = self.fault.take();
        self.fault.set(Some(first.unwrap_or(f)));
    }

    fn field(&self, name: &str) -> Option<usize> {
        self.info.fields.iter().position(|f| f.name == name)
    }

    /// The value of an ids field of the module (as this codel left it so far); `None` if
    /// the module has no such field. Booleans are 0 and 1.
    pub fn get(&self, field: &str) -> Option<i64> {
        self.field(field).map(|k| self.ids[k])
    }

    pub fn get_bool(&self, field: &str) -> Option<bool> {
        self.get(field).map(|v| v != 0)
    }

    /// Writes an ids field. The codel must list it in `writes`, and the value must be in
    /// the field's range when the codel returns; otherwise the codel is faulty and its
    /// activity takes its error path (no ids are written then).
    pub fn set(&mut self, field: &str, value: i64) {
        match self.field(field) {
            Some(k) if self.info.writable >> k & 1 == 1 => {
                self.ids[k] = value;
                *self.written |= 1 << k;
            }
            _ => self.fault(CtxFault::IdsWrite(field.to_string())),
        }
    }

    pub fn set_bool(&mut self, field: &str, value: bool) {
        self.set(field, i64::from(value));
    }

    /// Whether [`Ctx::port`] has data to read at `module.port`: an out port, or an in
    /// port the model connects to one (asked without a fault, for a reader that has its
    /// own answer to an unconnected port, as GenoM3's port handles do).
    pub fn port_is_connected(&self, module: &str, port: &str) -> bool {
        self.ports.index(module, port).is_some()
    }

    /// The data last written on port `port` of module `module`, if any. Reading a port
    /// the model does not have, or as another type than the port's (the model's type, or
    /// the type of the data it holds), is a fault (and gives `None`).
    pub fn port<T: Any>(&self, module: &str, port: &str) -> Option<&T> {
        let Some(k) = self.ports.index(module, port) else {
            self.fault(CtxFault::NoPort(format!("{module}.{port}")));
            return None;
        };
        match self.ports.read::<T>(k) {
            Ok(v) => v,
            Err(w) => {
                self.fault(CtxFault::port("read", w));
                None
            }
        }
    }

    /// The data of an out port of this codel's module that it lists in `writes`, created
    /// with `T::default()` on first use, for the codel to update in place. Any other port,
    /// or data of another type than the port's (the model's type, or the type of the
    /// data it holds), is a fault (and gives `None`).
    ///
    /// Port data is written in place: the model restarts the port's age only on a normal
    /// outcome, so a reader that checks `age` (a `Fresh` constraint) never relies on data
    /// a failed codel left half written. It is `Clone`: an async codel works on a copy of
    /// the ports taken at its start (docs/engine.md, "Threads").
    pub fn port_mut<T: Any + Send + Clone + Default>(&mut self, port: &str) -> Option<&mut T> {
        let slot = self
            .info
            .ports
            .iter()
            .find(|(_, name)| name == port)
            .map(|&(k, _)| k);
        let Some(k) = slot else {
            self.fault(CtxFault::PortWrite(port.to_string()));
            return None;
        };
        match self.ports.get_mut_or_default::<T>(k) {
            Ok(v) => Some(v),
            Err(w) => {
                let first = self.fault.take();
                self.fault
                    .set(Some(first.unwrap_or(CtxFault::port("wrote", w))));
                None
            }
        }
    }

    /// Replaces the data of an out port this codel writes (see [`Ctx::port_mut`]).
    pub fn write_port<T: Any + Send + Clone + Default>(&mut self, port: &str, value: T) {
        if let Some(p) = self.port_mut::<T>(port) {
            *p = value;
        }
    }

    /// The arguments of the request the activity serves, if they are a `T`.
    pub fn args<T: Any>(&self) -> Option<&T> {
        self.args.and_then(|a| a.downcast_ref())
    }

    /// Gives the output of the request the activity serves: its reply
    /// ([`crate::Reply::Done`]) carries the last output its codels gave.
    /// An output of another type than the model declares for the service is a fault.
    pub fn set_output<T: Any + Send + Sync>(&mut self, value: T) {
        if let Some(ty) = &self.info.output {
            if !ty.accepts(type_name::<T>()) {
                self.fault(CtxFault::WrongType {
                    what: format!("gave {}.{} an output", self.info.module, self.info.service),
                    expected: format!("{ty} (a Rust `{}`)", ty.rust_name()),
                    given: type_name::<T>(),
                });
                return;
            }
        }
        if let Some(o) = self.output.as_deref_mut() {
            *o = Some(Output::new(value));
        }
    }

    /// The engine's time, in microseconds since it started.
    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    /// Ticks fired so far.
    pub fn tick(&self) -> u64 {
        self.tick
    }
}

/// What unbound codels do (for simulation and replay).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DefaultCodels {
    /// Yield the first declared yield, write nothing.
    FirstYield,
    /// Yield or throw one of the declared outcomes at random (seeded), and write random
    /// values in range into the ids the codel writes.
    Random(u64),
}

/// Arguments of a request, for its activity's codels.
pub type Args = Box<dyn Any + Send>;

/// How a codel is run.
pub(crate) enum Body {
    Bound(CodelFn),
    /// Codel `local` of the module object `module` (the engine's list of them).
    Module {
        module: usize,
        local: usize,
    },
    Default,
    #[cfg(feature = "std")]
    Thread {
        worker: usize,
        local: usize,
    },
    /// An async codel on a thread of its own (`engine::apart`).
    #[cfg(feature = "std")]
    Apart {
        thread: usize,
    },
}

/// Calls a codel, catching a panic as a fault (its message). Inlined into the engine's
/// step, and generic so that a module object's codel is one indirect call, as a closure's
/// is (a call more costs some 15 instructions a step, 1.5%).
#[cfg(feature = "std")]
#[inline(always)]
pub(crate) fn call_guarded(
    ctx: &mut Ctx<'_>,
    mut f: impl FnMut(&mut Ctx<'_>) -> Next,
) -> Result<Next, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(ctx))).map_err(|e| {
        if let Some(s) = e.downcast_ref::<&str>() {
            (*s).to_string()
        } else if let Some(s) = e.downcast_ref::<String>() {
            s.clone()
        } else {
            "a panic".to_string()
        }
    })
}

/// Without `std` a panic cannot be caught: it is the platform's panic handler's.
#[cfg(not(feature = "std"))]
pub(crate) fn call_guarded(
    ctx: &mut Ctx<'_>,
    mut f: impl FnMut(&mut Ctx<'_>) -> Next,
) -> Result<Next, String> {
    Ok(f(ctx))
}
