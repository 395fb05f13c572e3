//! What crosses the network: the key expressions and the messages, JSON-encoded
//! (docs/distributed.md, "Messages"). Plain data, so that a client written with zenoh's
//! own libraries in another language can speak it.

use serde::{Deserialize, Serialize};
use serde_json::Value;

/// The key expressions of a layer under its prefix.
pub mod keys {
    /// Where the engine publishes the runs of module `module`'s codels, to which its
    /// process subscribes (`<prefix>/module/<module>/run`).
    pub fn run(prefix: &str, module: &str) -> String {
        format!("{prefix}/module/{module}/run")
    }

    /// Where module `module`'s process publishes what its runs did, to which the engine
    /// subscribes (`<prefix>/module/<module>/ran`).
    pub fn ran(prefix: &str, module: &str) -> String {
        format!("{prefix}/module/{module}/ran")
    }

    /// Where module `module`'s process answers the engine's `hello` queries
    /// (`<prefix>/module/<module>/hello`).
    pub fn hello(prefix: &str, module: &str) -> String {
        format!("{prefix}/module/{module}/hello")
    }

    /// The liveliness token of module `module`'s process (`<prefix>/alive/<module>`),
    /// there while the process is.
    pub fn alive(prefix: &str, module: &str) -> String {
        format!("{prefix}/alive/{module}")
    }

    /// Where the engine answers requests to services (`<prefix>/service/<module>/<Service>`;
    /// `rest` is `<module>/<Service>`, or a pattern such as `**`).
    pub fn service(prefix: &str, rest: &str) -> String {
        format!("{prefix}/service/{rest}")
    }
}

/// What the engine sends a module process: a query on its `hello` key, a publication on
/// its `run` key.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "type")]
pub enum Message {
    /// Which codels do you run? (answered with [`Answer::Hello`]).
    Hello,
    /// Run a codel.
    Run(RunGrant),
}

/// A module process's answer: to a `hello` query, or published on its `ran` key.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "type")]
pub enum Answer {
    /// The module's codels, `Service.codel` in the order the engine numbers them.
    Hello {
        module: String,
        codels: Vec<String>,
    },
    Ran(RunResult),
    /// The message could not be read or names no codel of the module: why, and the run's
    /// number when it could be read.
    Refused {
        #[serde(default, skip_serializing_if = "Option::is_none")]
        seq: Option<u64>,
        reason: String,
    },
}

/// A codel run the engine granted: what the codel sees.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunGrant {
    /// The run's number, which its answer repeats: an answer to an earlier run (from a
    /// process that was hung) is not taken for this one's.
    pub seq: u64,
    /// The codel's index among its module's codels (services, then their codels, in the
    /// model's order).
    pub codel: u32,
    /// `Service.codel`, checked by the module process against its own numbering.
    pub name: String,
    /// The module's ids fields, in the model's order.
    pub ids: Vec<i64>,
    /// The request's arguments, if it has any and the codel's service takes some.
    pub args: Option<Value>,
    /// Port data that changed since the module process last saw it.
    pub ports: Vec<PortData>,
    /// The engine's time (µs since it started) and the ticks fired.
    pub now_us: u64,
    pub tick: u64,
}

/// The data of an out port.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PortData {
    pub module: String,
    pub port: String,
    pub data: Value,
}

/// What a codel run did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResult {
    /// The number of the run it answers.
    pub seq: u64,
    pub end: RunEnd,
    /// The ids fields as the codel left them, and which it wrote (bit `k`, field `k`).
    pub ids: Vec<i64>,
    pub written: u64,
    /// The data of the ports the codel may write, after it ran.
    pub ports: Vec<PortData>,
    /// The output it gave its service, if any.
    pub output: Option<Value>,
    /// How far the codel moved the module process's virtual clock (µs), when it acts out
    /// a slow computation on one (0 on a real clock).
    pub virtual_us: u64,
}

/// How the codel ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunEnd {
    /// Its `k`-th declared outcome (yields, then exceptions, in the model's order).
    Outcome(u16),
    /// It is faulty: why, in the engine's words.
    Fault(String),
}

impl Message {
    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).unwrap_or_default()
    }
}

impl Answer {
    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).unwrap_or_default()
    }
}
