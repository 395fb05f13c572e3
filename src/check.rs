//! `bip check FILE...`: load, validate and summarise models.

use std::path::PathBuf;

use crate::{exit, load};

pub fn run(files: &[PathBuf]) -> u8 {
    let mut code = exit::OK;
    for path in files {
        match load::system(path) {
            Some(system) => print_summary(path, &system),
            None => code = exit::ERROR,
        }
    }
    code
}

fn print_summary(path: &std::path::Path, system: &bip_model::System) {
    let s = system.summary();
    println!("{}: ok, system `{}`", path.display(), system.name);
    println!(
        "  components    {} ({} families of {} atom types)",
        s.components, s.families, s.atoms
    );
    println!(
        "  interactions  {} ({} connectors, {} with step tables), {} internal transitions",
        s.interactions, s.connectors, s.tabulated_interactions, s.internal_transitions
    );
    println!("  locations     {} (summed over components)", s.locations);
    println!("  variables     {}", s.variables);
    println!(
        "  priorities    {} declared, chains of up to {} in their closure",
        s.priorities_declared, s.priority_depth
    );
    // the list `bip verify` checks, in its order: range errors are always checked, time
    // progress with `Time` connectors, and deadlock freedom when the model declares nothing
    let mut names: Vec<&str> = system.properties.iter().map(|p| p.name.as_str()).collect();
    let declared = if names.is_empty() {
        names.push("DeadlockFree");
        "none declared: deadlock freedom"
    } else {
        "declared"
    };
    let timed = system.has_time();
    if timed {
        names.push(bip_verifier::TIME_PROGRESS);
    }
    names.push(bip_verifier::RANGE_ERRORS);
    let budgets = bip_verifier::has_time_budgets(system);
    if budgets {
        names.push(bip_verifier::SCHEDULABLE);
    }
    println!(
        "  properties    {} checked ({declared}{}, range errors{}): {}",
        names.len(),
        if timed { ", time progress" } else { "" },
        if budgets { ", schedulability" } else { "" },
        names.join(", ")
    );
    println!(
        "  state         {} bits ({} bytes packed)",
        s.bits_per_state,
        s.bits_per_state.div_ceil(8)
    );
}
