//! Running the tools a controller's build runs: the C compiler, `ar`, and rustc against
//! this crate's own dependency bip-genom-c (which names bip-engine), as cargo would.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The newest `lib{name}-*.rlib` in `deps`.
pub fn rlib(deps: &Path, name: &str) -> PathBuf {
    let prefix = format!("lib{name}-");
    std::fs::read_dir(deps)
        .expect("the deps folder")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with(&prefix) && n.ends_with(".rlib"))
        })
        .max_by_key(|p| p.metadata().and_then(|m| m.modified()).ok())
        .unwrap_or_else(|| panic!("no {prefix}*.rlib in {}", deps.display()))
}

pub fn run(cmd: &mut Command) -> (bool, String) {
    let out = cmd.output().unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    let said =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    (out.status.success(), said)
}

/// rustc with bip-genom-c, this crate's dependency (the newest built: the one this test
/// was built with), and the crates it depends on, bip-engine among them, found by rustc
/// as that build of it names them.
pub fn rustc() -> Command {
    let exe = std::env::current_exe().expect("the test's path");
    let deps = exe.parent().expect("its folder");
    let mut cmd = Command::new(std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into()));
    cmd.args(["--edition", "2021"])
        .arg("--extern")
        .arg(format!(
            "bip_genom_c={}",
            rlib(deps, "bip_genom_c").display()
        ))
        .arg("-L")
        .arg(format!("dependency={}", deps.display()));
    cmd
}
