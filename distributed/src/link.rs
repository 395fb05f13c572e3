//! The engine's link to one module's process for its codel runs: each run published on
//! the module's `run` key, its answer received on its `ran` key. A publication each way is
//! half the messages of a zenoh query (which has its reply, its final message and a timer
//! task of its own), and the engine thread is the only one that waits for it.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use zenoh::qos::{CongestionControl, Priority};
use zenoh::Wait;

use crate::network::NetworkError;
use crate::wire::{keys, Answer, Message};

/// The largest message zenoh's low-latency transport carries (its batch, headers
/// included); a larger one would close the link.
const LOW_LATENCY_BATCH: usize = 65_535;
/// Room left in a batch for zenoh's headers beside the key.
const HEADERS: usize = 512;

/// Why `bytes` cannot be published on `key`, on a low-latency link.
pub(crate) fn too_large(low_latency: bool, key: &str, bytes: usize) -> Option<String> {
    let most = LOW_LATENCY_BATCH.saturating_sub(HEADERS + key.len());
    (low_latency && bytes > most).then(|| {
        format!(
            "a message of {bytes} bytes on `{key}` is more than zenoh's low-latency transport \
             carries ({most}); turn it off (`low_latency: false` in the deployment)"
        )
    })
}

/// The publisher and subscriber of a run publication and its answer, held by the engine.
pub(crate) struct RunLink {
    key: String,
    answer_key: String,
    low_latency: bool,
    publisher: zenoh::pubsub::Publisher<'static>,
    answers: mpsc::Receiver<Vec<u8>>,
    _subscriber: zenoh::pubsub::Subscriber<()>,
    /// The number of the last run published.
    seq: u64,
    /// How long the engine's thread polls for an answer before it sleeps.
    spin: Duration,
}

/// The publisher of a layer's runs or answers: never dropped under congestion (a run
/// lost would be a fault), sent at once (not batched), first in line when zenoh's
/// priorities are on.
pub(crate) fn publisher(
    session: &zenoh::Session,
    key: &str,
) -> Result<zenoh::pubsub::Publisher<'static>, NetworkError> {
    session
        .declare_publisher(key.to_string())
        .congestion_control(CongestionControl::Block)
        .priority(Priority::RealTime)
        .express(true)
        .wait()
        .map_err(|e| NetworkError::Open(format!("cannot publish on `{key}`: {e}")))
}

/// A subscriber that hands each payload received on `key` to `deliver` (on zenoh's
/// receiving thread: it only passes it on).
pub(crate) fn subscriber(
    session: &zenoh::Session,
    key: &str,
    deliver: impl Fn(Vec<u8>) + Send + Sync + 'static,
) -> Result<zenoh::pubsub::Subscriber<()>, NetworkError> {
    session
        .declare_subscriber(key.to_string())
        .callback(move |sample| deliver(sample.payload().to_bytes().into_owned()))
        .wait()
        .map_err(|e| NetworkError::Open(format!("cannot subscribe to `{key}`: {e}")))
}

impl RunLink {
    pub(crate) fn new(
        session: &zenoh::Session,
        prefix: &str,
        module: &str,
        low_latency: bool,
        spin: Duration,
    ) -> Result<RunLink, NetworkError> {
        let key = keys::run(prefix, module);
        let answer_key = keys::ran(prefix, module);
        let (sink, answers) = mpsc::channel();
        // the receiver is gone only when the link is dropped
        let subscriber = subscriber(session, &answer_key, move |a| {
            let _ = sink.send(a);
        })?;
        Ok(RunLink {
            publisher: publisher(session, &key)?,
            key,
            answer_key,
            low_latency,
            answers,
            _subscriber: subscriber,
            seq: 0,
            spin,
        })
    }

    /// The next answer: polled until `spin_until` (the answer often comes sooner than a
    /// sleeping thread is woken), then waited for at most `left`.
    fn receive(&self, spin_until: Instant, left: Duration) -> Option<Vec<u8>> {
        while Instant::now() < spin_until {
            match self.answers.try_recv() {
                Ok(payload) => return Some(payload),
                Err(mpsc::TryRecvError::Empty) => std::hint::spin_loop(),
                Err(mpsc::TryRecvError::Disconnected) => return None,
            }
        }
        self.answers.recv_timeout(left).ok()
    }

    /// The number of the next run.
    pub(crate) fn next_seq(&mut self) -> u64 {
        self.seq += 1;
        self.seq
    }

    /// Publishes run `message` (numbered [`RunLink::next_seq`]) and waits for its answer
    /// until `deadline` has passed; answers to earlier runs are dropped.
    pub(crate) fn exchange(
        &mut self,
        message: &Message,
        deadline: Duration,
    ) -> Result<Answer, String> {
        let start = Instant::now();
        while self.answers.try_recv().is_ok() {}
        let bytes = message.to_bytes();
        if let Some(why) = too_large(self.low_latency, &self.key, bytes.len()) {
            return Err(why);
        }
        self.publisher
            .put(bytes)
            .wait()
            .map_err(|e| format!("cannot publish on `{}`: {e}", self.key))?;
        let spin_until = Instant::now() + self.spin;
        loop {
            let left = deadline.saturating_sub(start.elapsed());
            let Some(payload) = self.receive(spin_until, left) else {
                return Err(format!(
                    "no answer on `{}` within {} ms",
                    self.answer_key,
                    deadline.as_millis()
                ));
            };
            let answer: Answer = serde_json::from_slice(&payload)
                .map_err(|e| format!("an unreadable answer on `{}`: {e}", self.answer_key))?;
            let seq = match &answer {
                Answer::Ran(r) => Some(r.seq),
                Answer::Refused { seq, .. } => *seq,
                Answer::Hello { .. } => None,
            };
            // an answer without a number answers a message it could not read: this one
            if seq.is_none_or(|s| s == self.seq) {
                return Ok(answer);
            }
        }
    }
}
