//! The front end's pipeline, from a model file to a [`System`]: RON parsing with
//! positions, the expansion of a GenoM layer into BIP core, then compilation.

use std::path::Path;
use std::sync::Arc;

use crate::compile::compile_core;
use crate::diag::{LoadError, ModelError};
use crate::gen3;
use crate::genom;
use crate::source::{normalized, offset_of, with_positions, Span};
use crate::syntax::{ron_options, SystemDef};
use bip_model::System;

/// The parts of a model's GenoM layer, as `ron` names them in errors: their fields are
/// described in docs/model.md's section on the GenoM layer.
const GENOM_PARTS: &[&str] = &[
    "ModuleDef",
    "TaskDef",
    "PortDef",
    "ServiceDef",
    "CodelDef",
    "Exclusive",
    "Requires",
    "Fresh",
    "Guard",
    "AtMost",
];

/// Reads a file's text. Errors name the file.
pub fn read_model_file(path: &Path) -> Result<String, LoadError> {
    std::fs::read_to_string(path).map_err(|source| LoadError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Parses a model's text into its file-format types, without compiling it.
pub fn parse_str(name: &str, text: &str) -> Result<SystemDef, LoadError> {
    let shared = Arc::new(normalized(text).into_owned());
    parse_shared(name, &shared)
}

fn parse_shared(name: &str, text: &Arc<String>) -> Result<SystemDef, LoadError> {
    if is_blank(text) {
        return Err(LoadError::model(
            name,
            text,
            vec![ModelError::new("the file is empty", Span::NONE)
                .with_help("a model file holds one `System(name: \"…\", …)`")],
        ));
    }
    let (parsed, entries) = gen3::entries::collecting(|| {
        with_positions(text, || ron_options().from_str::<SystemDef>(text))
    });
    let mut def = parsed.map_err(|e| {
        let start = offset_of(text, e.span.start.line, e.span.start.col);
        let end = offset_of(text, e.span.end.line, e.span.end.col).max(start);
        let mut err = ModelError::new(e.code.to_string(), Span::new(start, end));
        if let ron::Error::NoSuchStructField { outer, .. }
        | ron::Error::MissingStructField { outer, .. } = &e.code
        {
            // model.md holds the field tables of every part, the GenoM layer's included
            let section = match outer {
                Some(o) if GENOM_PARTS.contains(&o.as_str()) => {
                    "docs/model.md, \"The GenoM layer\""
                }
                _ => "docs/model.md",
            };
            err = err.with_help(format!(
                "see {section} for the fields of each part of a model"
            ));
        }
        LoadError::model(name, text, vec![err])
    })?;
    if !entries.is_empty() {
        gen3::resolve(&mut def, entries, name, text)
            .map_err(|errors| LoadError::model(name, text, errors).with_files(&def.sources))?;
    }
    Ok(def)
}

/// Parses and compiles a model's text; `name` is how diagnostics call the file.
pub fn load_str(name: &str, text: &str) -> Result<System, LoadError> {
    let shared = Arc::new(normalized(text).into_owned());
    let def = parse_shared(name, &shared)?;
    compile_def(name, &shared, &def)
}

/// Parses a model and expands its GenoM layer into BIP core (a model without one comes
/// back as written). The expanded model is compiled too, so that it is known to load.
pub fn expand_str(name: &str, text: &str) -> Result<SystemDef, LoadError> {
    let shared = Arc::new(normalized(text).into_owned());
    let def = parse_shared(name, &shared)?;
    if !def.has_genom_layer() {
        compile_def(name, &shared, &def)?;
        return Ok(def);
    }
    let expansion = genom::expand_in(&def, Some(&shared))
        .map_err(|errors| LoadError::model(name, &shared, errors).with_files(&def.sources))?;
    compile_def(name, &shared, &def)?;
    Ok(expansion.def)
}

/// Reads a model file and expands its GenoM layer (see [`expand_str`]).
pub fn expand_file(path: impl AsRef<Path>) -> Result<SystemDef, LoadError> {
    let path = path.as_ref();
    let text = read_model_file(path)?;
    expand_str(&path.display().to_string(), &text)
}

/// Compiles a parsed model. On failure, returns every error found.
///
/// A model with a GenoM layer (`modules`, `constraints`) is first expanded into BIP core
/// ([`genom::expand`]); the compiled system then carries the map the engine binds codels
/// and requests with ([`System::genom`]).
pub fn compile(def: &SystemDef) -> Result<System, Vec<ModelError>> {
    compile_in(def, None)
}

/// Compiles parsed file-format types; `text` is the file they came from (for positions).
pub fn compile_def(name: &str, text: &Arc<String>, def: &SystemDef) -> Result<System, LoadError> {
    compile_in(def, Some(text))
        .map_err(|errors| LoadError::model(name, text, errors).with_files(&def.sources))
}

fn compile_in(def: &SystemDef, text: Option<&str>) -> Result<System, Vec<ModelError>> {
    if def.has_genom_layer() {
        return genom::expand_in(def, text)?.compile(def);
    }
    compile_core(def, &[], None).map(|(system, _)| system)
}

/// Reads, parses and compiles a model file.
pub fn load_file(path: impl AsRef<Path>) -> Result<System, LoadError> {
    let path = path.as_ref();
    let text = read_model_file(path)?;
    load_str(&path.display().to_string(), &text)
}

/// Reads and compiles a model file as a timed model (`time: Exact`, docs/model.md,
/// "Timed semantics") whether or not it says so: its codels' budgets become durations on
/// its CPUs as declared (a CPU named by a string alone: one core, fixed priority,
/// preemptive). `bip sched --exact` and `bip simulate --codel-time` explore and run a model
/// this way.
pub fn load_file_timed(path: impl AsRef<Path>) -> Result<System, LoadError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let shared = Arc::new(normalized(&read_model_file(path)?).into_owned());
    let mut def = parse_shared(&name, &shared)?;
    def.time.get_or_insert_with(Default::default);
    compile_def(&name, &shared, &def)
}

/// True if the text holds nothing but whitespace and comments.
fn is_blank(text: &str) -> bool {
    let mut rest = text.trim_start();
    loop {
        if let Some(r) = rest.strip_prefix("//") {
            rest = r
                .split_once('\n')
                .map_or("", |(_, after)| after)
                .trim_start();
        } else if let Some(r) = rest.strip_prefix("/*") {
            match r.find("*/") {
                Some(end) => rest = r[end + 2..].trim_start(),
                None => return false,
            }
        } else {
            return rest.is_empty();
        }
    }
}

/// `bip import`: a `.gen` file as the model that holds its components as modules,
/// checked as [`load_file`] checks a model; `include` is the search path of `#include`.
pub fn import_gen_file(
    path: &Path,
    include: &[std::path::PathBuf],
) -> Result<SystemDef, LoadError> {
    import_gen_files(&[path], include, &[])
}

/// A `.gen` file as read (its IDL types and codel functions, which the model leaves out),
/// once checked as [`import_gen_file`] checks it: for tools such as bip-codegen's C
/// headers.
pub fn read_gen_file(path: &Path, include: &[std::path::PathBuf]) -> Result<gen3::Spec, LoadError> {
    let (mut specs, _) = read_checked_gen_files(&[path], include, &[])?;
    Ok(specs.remove(0))
}

/// `bip import` of several files: their components as modules, file after file, with the
/// `connections` given as `(in port, out port)` names (`("flight.state", "pose.frame")`),
/// checked as [`load_file`] checks a model.
pub fn import_gen_files(
    paths: &[&Path],
    include: &[std::path::PathBuf],
    connections: &[(String, String)],
) -> Result<SystemDef, LoadError> {
    read_checked_gen_files(paths, include, connections).map(|(_, def)| def)
}

/// The files as read, one spec each, and the model of their components.
fn read_checked_gen_files(
    paths: &[&Path],
    include: &[std::path::PathBuf],
    connections: &[(String, String)],
) -> Result<(Vec<gen3::Spec>, SystemDef), LoadError> {
    let shown: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    let shown_all = shown.join(", ");
    let empty = Arc::new(String::new());
    let mut files = crate::source_map::SourceMap::default();
    let fail = |errors: Vec<ModelError>, files: &crate::source_map::SourceMap| {
        LoadError::model(&shown_all, &empty, errors).with_files(files)
    };
    let mut specs = Vec::new();
    for (path, shown) in paths.iter().zip(shown) {
        let spec = gen3::read(path, &shown, include, &mut files, 0, Span::NONE)
            .map_err(|e| fail(vec![e], &files))?;
        specs.push((spec, shown));
    }
    let mut def = gen3::import(&specs).map_err(|e| fail(e, &files))?;
    def.connections = connections
        .iter()
        .map(|(port, reads)| crate::syntax::ConnectionDef {
            port: crate::syntax::Text::new(port.clone(), Span::NONE),
            reads: crate::syntax::Text::new(reads.clone(), Span::NONE),
        })
        .collect();
    def.sources = files;
    compile(&def).map_err(|e| fail(e, &def.sources))?;
    Ok((specs.into_iter().map(|(spec, _)| spec).collect(), def))
}
