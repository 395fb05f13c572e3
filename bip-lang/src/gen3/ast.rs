//! A GenoM3 component as written, with what matters to behaviour and timing and, as
//! information, what does not (documentation, IDL types, codel functions and their
//! parameters). Names carry their positions; IDL types are kept as their text
//! (`sequence<or::pose>`, `double[3]`) for the mapping onto typed ports and arguments.

use crate::source::{Span, Text};

/// A whole `.gen` file once preprocessed: its components and the IDL declarations around
/// them.
#[derive(Clone, Debug, Default)]
pub struct Spec {
    pub components: Vec<Component>,
    /// The `interface` declarations: what a component that `provides` one takes in.
    pub interfaces: Vec<Component>,
    pub types: Vec<TypeDecl>,
}

/// An IDL declaration of a type or a constant (information only).
#[derive(Clone, Debug)]
pub struct TypeDecl {
    /// The scoped name: `or::pose::state`.
    pub name: Text,
    /// `struct`, `union`, `enum`, `typedef`, `native`, `const`, `exception`.
    pub kind: &'static str,
    /// The IDL type (`typedef`, `const`), or the members (`struct`, `union`, `exception`).
    pub members: Vec<Member>,
    /// A union's discriminator type (`switch (long)`): `None` for the other kinds.
    pub switch: Option<String>,
    /// A numeric constant's value, as C writes it (`200`, `0.5`): `None` for the other
    /// kinds and for string and character constants.
    pub value: Option<String>,
}

/// A member of a structure, an ids field, a local variable: a name and its IDL type.
#[derive(Clone, Debug)]
pub struct Member {
    pub name: Text,
    pub ty: String,
}

#[derive(Clone, Debug, Default)]
pub struct Component {
    pub name: Text,
    pub doc: Vec<Text>,
    pub version: Option<Text>,
    pub lang: Option<Text>,
    pub email: Option<Text>,
    pub require: Vec<Text>,
    pub codels_require: Vec<Text>,
    /// `clock-rate`, in microseconds.
    pub clock_rate: Option<(u64, Span)>,
    /// The interfaces it provides (their objects are in it, where `provides` is written).
    pub provides: Vec<Text>,
    /// The interfaces it uses: their ports are the component's with the direction
    /// reversed, their services its remote ones (`remotes`).
    pub uses: Vec<Text>,
    /// The services of the interfaces it uses, which its codels may call (information:
    /// the model does not hold remote calls).
    pub remotes: Vec<Text>,
    pub ids: Vec<Member>,
    pub tasks: Vec<Task>,
    pub ports: Vec<Port>,
    pub services: Vec<Service>,
    pub exceptions: Vec<TypeDecl>,
    pub types: Vec<TypeDecl>,
}

#[derive(Clone, Debug, Default)]
pub struct Task {
    pub name: Text,
    pub doc: Vec<Text>,
    /// In microseconds; `None` for a task without a period.
    pub period: Option<(u64, Span)>,
    /// In microseconds; zero or more.
    pub delay: Option<(u64, Span)>,
    /// GenoM's priority, 0 the most urgent.
    pub priority: Option<(i128, Span)>,
    /// In bytes.
    pub stack: Option<(i128, Span)>,
    pub real_time: bool,
    /// The task's own state machine, run from the component's start.
    pub codels: Vec<Codel>,
    pub throws: Vec<Text>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PortDir {
    In,
    Out,
}

#[derive(Clone, Debug)]
pub struct Port {
    pub name: Text,
    pub dir: PortDir,
    pub multiple: bool,
    /// The IDL type of its data.
    pub ty: String,
    pub doc: Vec<Text>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Attribute,
    Function,
    Activity,
}

impl Kind {
    pub fn word(self) -> &'static str {
        match self {
            Kind::Attribute => "attribute",
            Kind::Function => "function",
            Kind::Activity => "activity",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dir {
    In,
    Out,
    InOut,
}

impl Dir {
    pub fn writes(self) -> bool {
        self != Dir::In
    }
}

/// A service parameter: `in double x = 0 : "doc"`, or for an attribute an ids member
/// (`in speed.max`, without a type).
#[derive(Clone, Debug)]
pub struct Param {
    pub dir: Dir,
    /// The name, or the ids member path of an attribute (`sensor_time.rate`).
    pub name: Text,
    /// Its IDL type; `None` for an attribute's ids member (the type is the member's).
    pub ty: Option<String>,
    /// Where its default value (and documentation) is written.
    pub init: Option<Span>,
}

impl Param {
    /// The name a codel gives it (`local in x`): an attribute's ids member by its last
    /// member (`in speed.max` is `max`), as GenoM3 names it.
    pub fn local_name(&self) -> &str {
        self.name
            .value
            .rsplit('.')
            .next()
            .unwrap_or(&self.name.value)
    }
}

#[derive(Clone, Debug)]
pub struct Service {
    pub name: Text,
    pub kind: Kind,
    pub params: Vec<Param>,
    pub doc: Vec<Text>,
    pub task: Option<Text>,
    pub interrupts: Vec<Text>,
    pub after: Vec<Text>,
    pub before: Vec<Text>,
    pub validate: Option<Codel>,
    pub locals: Vec<Member>,
    pub throws: Vec<Text>,
    /// Codels with states (an activity's state machine).
    pub codels: Vec<Codel>,
    /// A function's simple codels (no states).
    pub simple: Vec<Codel>,
}

/// Where a codel parameter comes from, when written (`ids in x`, `port out p`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    Ids,
    Local,
    Port,
    Remote,
}

#[derive(Clone, Debug)]
pub struct CodelParam {
    pub source: Option<Source>,
    pub dir: Dir,
    /// The variable: `x`, `a.b[2]`; empty for `::name` alone.
    pub path: Vec<String>,
    /// Its first name (or the `::name`), with its position.
    pub name: Text,
}

#[derive(Clone, Debug)]
pub struct Codel {
    /// The states it runs in (`codel<start, sleep>`); empty for a simple codel.
    pub states: Vec<Text>,
    pub function: Text,
    pub params: Vec<CodelParam>,
    /// As written: `s`, `pause::s`, `ether`.
    pub yields: Vec<Text>,
    pub asynchronous: bool,
    /// The timed dialect's `wcet`, in microseconds.
    pub wcet: Option<(u64, Span)>,
    /// bip's `bcet` beside it, in microseconds: the shortest run.
    pub bcet: Option<(u64, Span)>,
}
