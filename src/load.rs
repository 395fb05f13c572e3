//! The model a command works on: loaded, or its diagnostic printed on stderr and the
//! command ends with [`exit::ERROR`](crate::exit::ERROR).

use std::path::Path;

use bip_lang::syntax::SystemDef;
use bip_lang::LoadError;
use bip_model::System;

use crate::report;

/// The compiled model in `file`; `None` once its diagnostic is printed.
pub fn system(file: &Path) -> Option<System> {
    reported(bip_lang::load_file(file))
}

/// The model in `file` compiled as a timed model, whether or not it says `time: Exact`
/// (as `bip sched --exact` explores it); `None` once its diagnostic is printed.
pub fn timed_system(file: &Path) -> Option<System> {
    reported(bip_lang::load_file_timed(file))
}

/// The compiled model in `file`; `None` once its diagnostic is printed on stdout as a
/// JSON document (for `--format json`: a reader of stdout gets a document either way).
pub fn system_or_json(file: &Path) -> Option<System> {
    bip_lang::load_file(file)
        .map_err(|e| println!("{}", report::load_error_json(file, &e)))
        .ok()
}

/// The model in `file` with its GenoM layer expanded into BIP core, not compiled; `None`
/// once its diagnostic is printed.
pub fn expanded(file: &Path) -> Option<SystemDef> {
    reported(bip_lang::expand_file(file))
}

fn reported<T>(loaded: Result<T, LoadError>) -> Option<T> {
    loaded.map_err(|e| report::load_error(&e)).ok()
}
