//! What the end-to-end tests share.

#![allow(dead_code)]

use std::process::Command;

/// True if `tool` is on PATH (the SPIN cross-checks run only where SPIN and gcc are).
pub fn have(tool: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {tool}")])
        .output()
        .is_ok_and(|o| o.status.success())
}
