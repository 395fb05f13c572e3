//! `bip graph FILE`: the model as a picture, in DOT or SVG. Three views: the GenoM layer
//! as written (modules, their tasks, services and ports, who writes and reads a port, the
//! constraints between services), BIP core (components, connectors, priorities) and one
//! activity's codel automaton. The views build a `bip_picture::Graph`; the explorer draws
//! the same graphs.

mod activity;
mod core;
mod genom;

use std::path::{Path, PathBuf};

use bip_lang::syntax::SystemDef;
use bip_picture::Graph;

use crate::{exit, load};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Level {
    /// Modules, tasks, services, ports and constraints, as written.
    Genom,
    /// Components, connectors and priorities of BIP core (after the GenoM expansion).
    Core,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Graphviz's DOT, for `dot -Tsvg` or any graphviz tool.
    Dot,
    /// SVG, laid out by bip itself (no external program).
    Svg,
}

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The model file (RON).
    pub file: PathBuf,
    /// What to draw (default: genom for a model with modules, else core).
    #[arg(long, value_enum)]
    pub level: Option<Level>,
    /// Draw the codel automaton of one activity, written `module.Service`, or of a task's
    /// machine, `module.task`.
    #[arg(long, value_name = "MODULE.SERVICE", conflicts_with = "level")]
    pub activity: Option<String>,
    #[arg(long, value_enum, default_value = "svg")]
    pub format: Format,
    /// Write to FILE instead of stdout.
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
}

pub fn run(args: &Args) -> u8 {
    let Some(system) = load::system(&args.file) else {
        return exit::ERROR;
    };
    let Some(def) = written(&args.file) else {
        return exit::ERROR;
    };
    let graph = match (&args.activity, args.level) {
        (Some(name), _) => match activity::graph(&def, name) {
            Ok(g) => g,
            Err(message) => {
                eprintln!("error: {message}");
                return exit::ERROR;
            }
        },
        (None, Some(Level::Core)) => core::graph(&system, guards(&def, &system)),
        (None, Some(Level::Genom)) if def.modules.is_empty() => {
            eprintln!(
                "error: {} has no GenoM layer (no `modules`)\n  help: draw its BIP core with `--level core`",
                args.file.display()
            );
            return exit::ERROR;
        }
        (None, None) if def.modules.is_empty() => core::graph(&system, guards(&def, &system)),
        (None, _) => genom::graph(&def, &system),
    };
    let text = draw(&graph, args.format);
    write_out(args.output.as_deref(), &text)
}

/// The priorities' guards as written, when the compiled priorities are the written ones
/// (a GenoM layer adds its own).
fn guards(def: &SystemDef, system: &bip_model::System) -> Option<Vec<String>> {
    (def.modules.is_empty() && def.priorities.len() == system.priorities.len()).then(|| {
        def.priorities
            .iter()
            .map(|p| p.when.as_ref().map(|w| w.to_string()).unwrap_or_default())
            .collect()
    })
}

/// The graph in `format`.
pub fn draw(graph: &Graph, format: Format) -> String {
    match format {
        Format::Dot => bip_picture::dot::to_dot(graph),
        Format::Svg => bip_picture::render::to_svg(graph),
    }
}

/// The model as written, before its GenoM layer is expanded (it has loaded already, so
/// it parses).
fn written(file: &Path) -> Option<SystemDef> {
    let text = bip_lang::read_model_file(file)
        .map_err(|e| crate::report::load_error(&e))
        .ok()?;
    bip_lang::parse_str(&file.display().to_string(), &text)
        .map_err(|e| crate::report::load_error(&e))
        .ok()
}

/// Writes `text` to `output`, or to stdout.
pub fn write_out(output: Option<&Path>, text: &str) -> u8 {
    match output {
        Some(path) => match std::fs::write(path, text) {
            Ok(()) => exit::OK,
            Err(e) => {
                eprintln!("error: cannot write {}: {e}", path.display());
                exit::ERROR
            }
        },
        None => {
            print!("{text}");
            exit::OK
        }
    }
}
