//! What can go wrong in a verification besides the model's verdicts.

/// Something that went wrong besides the model's verdicts.
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    #[error("cannot start the worker threads: {0}")]
    Threads(String),
    /// A trace could not be rebuilt from the stored states: a bug in bip.
    #[error("internal error: {0}")]
    Internal(String),
}
