//! Exit codes shared by every command.

pub const OK: u8 = 0;
pub const FAILED: u8 = 1;
pub const ERROR: u8 = 2;
pub const INCONCLUSIVE: u8 = 3;
