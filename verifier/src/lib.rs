//! `bip-verifier`: proves the properties of a `bip_model::System`.
