//! GenoM3 `.gen` files: a parser of the GenoM3 language (the preprocessor subset, OMG IDL
//! and GenoM's component declarations) and its mapping onto bip's GenoM layer, so that a
//! model takes its modules from the files its users already write
//! (`modules: [Gen("rflex.gen"), Gen(file: "ndd.gen", include: ["idl/"])]`) and
//! `bip import` writes the equivalent RON. docs/genom.md, "GenoM3 files", says what each
//! construct becomes.
//!
//! One concern per file: `lexer` (tokens), `preprocess` (`#include`, `#define`, `#if`),
//! `cursor` (reading tokens, and what was expected instead), `consts` (constant
//! expressions), `idl` (types and IDL declarations), `component` (GenoM's declarations),
//! `interfaces` (`provides`, `uses`, `extends`, and services refined), `ast` (what is
//! read), `mapping` (to modules), `params` (codel parameters resolved), `idl_type` (an IDL type's text as a tree), `types` (IDL types as data types), `entries` (the `Gen(...)` entries of a
//! model's `modules`). Every error names the construct, with the file, line and column
//! of its place in the `.gen` file.

pub mod ast;
mod component;
mod consts;
mod cursor;
pub mod entries;
mod idl;
pub mod idl_type;
mod interfaces;
mod lexer;
mod mapping;
mod params;
mod preprocess;
mod types;

use std::path::{Path, PathBuf};

use crate::diag::ModelError;
use crate::genom::syntax::ModuleDef;
use crate::source::{ConstValue, Span, Spanned};
use crate::source_map::SourceMap;
use crate::syntax::{PropertyDef, SystemDef};
pub use ast::Spec;
use entries::GenEntry;

/// Reads a `.gen` file (and what it includes, from its directory and then `include`),
/// placing each file in `files` after the model file's `main_len` bytes. `shown` is the
/// file's name in messages; `at` is where the model asks for it.
pub fn read(
    path: &Path,
    shown: &str,
    include: &[PathBuf],
    files: &mut SourceMap,
    main_len: usize,
    at: Span,
) -> Result<Spec, ModelError> {
    let input = preprocess::Input {
        include,
        files,
        main_len,
    };
    let toks = preprocess::preprocess(input, path, shown, at)?;
    let end = files.files().last().map_or(at, |f| {
        Span::new(f.base + f.text.len(), f.base + f.text.len())
    });
    let end = toks
        .last()
        .map_or(end, |t| Span::new(t.span.end, t.span.end));
    let mut c = cursor::Cursor::new(toks, end);
    component::spec(&mut c)
}

/// The modules of a file's components, for a model whose tick is `tick_us` microseconds.
pub fn modules(spec: &Spec, tick_us: u64) -> Result<Vec<ModuleDef>, Vec<ModelError>> {
    mapping::modules(spec, tick_us)
}

/// Reads the `.gen` entries of a parsed model (`model` is its file's name, `text` its
/// text) and puts their modules in their places in `def.modules`. The files read stay in
/// `def.sources` whether or not they load, for the errors to point into them.
pub(crate) fn resolve(
    def: &mut SystemDef,
    entries: Vec<GenEntry>,
    model: &str,
    text: &str,
) -> Result<(), Vec<ModelError>> {
    let main_len = text.len();
    let misnamed: Vec<ModelError> = entries
        .iter()
        .filter_map(|e| entries::misnamed(text, e))
        .collect();
    if !misnamed.is_empty() {
        return Err(misnamed);
    }
    let dir = Path::new(model).parent().unwrap_or(Path::new(""));
    let tick_us = model_tick_us(def, entries.first().map_or(Span::NONE, |e| e.file.span))
        .map_err(|e| vec![e])?;
    let mut errors = Vec::new();
    let mut inserted = 0;
    for entry in entries {
        let include: Vec<PathBuf> = entry.include.iter().map(|d| dir.join(&d.value)).collect();
        let path = dir.join(&entry.file.value);
        let shown = path.display().to_string();
        let read = read(
            &path,
            &shown,
            &include,
            &mut def.sources,
            main_len,
            entry.file.span,
        );
        let found = match read {
            Ok(spec) if spec.components.is_empty() => Err(vec![ModelError::new(
                format!("{shown} declares no component"),
                entry.file.span,
            )]),
            Ok(spec) => modules(&spec, tick_us),
            Err(e) => Err(vec![e]),
        };
        match found {
            Ok(modules) => {
                let at = entry.index + inserted;
                inserted += modules.len();
                let at = at.min(def.modules.len());
                def.modules.splice(at..at, modules);
            }
            Err(mut e) => errors.append(&mut e),
        }
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors)
    }
}

/// The model's tick in microseconds, which `.gen` periods (times) are divided by.
fn model_tick_us(def: &SystemDef, at: Span) -> Result<u64, ModelError> {
    let Some(tick) = &def.tick_ms else {
        return Err(ModelError::new(
            "a model with `.gen` modules needs `tick_ms`: their task periods are times",
            at,
        )
        .with_help("add `tick_ms: 10` (a tick that divides every period) to the System"));
    };
    let ms = match &tick.value {
        ConstValue::Int(n) => Some(*n),
        ConstValue::Expr(name) => def
            .constants
            .iter()
            .find(|(k, _)| k.value == *name)
            .and_then(|(_, v)| match v.value {
                ConstValue::Int(n) => Some(n),
                _ => None,
            }),
        ConstValue::Bool(_) => None,
    };
    match ms.and_then(|ms| u64::try_from(ms).ok()?.checked_mul(1000)) {
        Some(us) if us >= 1000 => Ok(us),
        _ => Err(ModelError::new(
            "with `.gen` modules, `tick_ms` must be a positive number (or a constant's name)",
            tick.span,
        )),
    }
}

/// The model that holds the components of `.gen` files as modules (what `bip import`
/// prints), file after file, with the tick their periods need: their `clock-rate`s, or
/// else the greatest common divisor of their periods and delays, in whole milliseconds.
/// Each file comes with its name as messages show it. The model is named after its one
/// component, or `layer` when the files declare several.
pub fn import(specs: &[(Spec, String)]) -> Result<SystemDef, Vec<ModelError>> {
    let mut components = specs.iter().flat_map(|(s, _)| &s.components);
    let Some(first) = components.next() else {
        let shown: Vec<&str> = specs.iter().map(|(_, n)| n.as_str()).collect();
        return Err(vec![ModelError::new(
            format!("{} declares no component", shown.join(", ")),
            Span::NONE,
        )]);
    };
    let name = match components.next() {
        None => first.name.clone(),
        Some(_) => crate::source::Text::new("layer".to_string(), Span::NONE),
    };
    let tick_us = import_tick_us(specs.iter().map(|(s, _)| s)).map_err(|e| vec![e])?;
    let mut modules_found = Vec::new();
    let mut errors = Vec::new();
    for (spec, _) in specs {
        match modules(spec, tick_us) {
            Ok(mut m) => modules_found.append(&mut m),
            Err(mut e) => errors.append(&mut e),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(SystemDef {
        name,
        tick_ms: Some(Spanned::generated(ConstValue::Int((tick_us / 1000) as i64))),
        modules: modules_found,
        properties: vec![PropertyDef::DeadlockFree { terminal: None }],
        ..SystemDef::default()
    })
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// The tick for files on their own: the gcd of their components' `clock-rate`s if any
/// declares one, else the gcd of the periods and delays.
fn import_tick_us<'s>(specs: impl Iterator<Item = &'s Spec> + Clone) -> Result<u64, ModelError> {
    let fold = |times: &mut dyn Iterator<Item = (u64, Span)>| {
        times.fold(None, |tick: Option<(u64, Span)>, (t, span)| {
            Some(tick.map_or((t, span), |(u, s)| (gcd(u, t), s)))
        })
    };
    let components = specs.flat_map(|s| &s.components);
    let rates = fold(&mut components.clone().filter_map(|c| c.clock_rate));
    // the periods and the delays (a delay of zero divides any tick)
    let tick = rates.or_else(|| {
        fold(&mut components.flat_map(|c| {
            c.tasks
                .iter()
                .flat_map(|t| [t.period, t.delay.filter(|d| d.0 > 0)])
                .flatten()
        }))
    });
    let Some((us, span)) = tick else {
        return Ok(1000);
    };
    if us % 1000 != 0 {
        return Err(ModelError::new(
            format!("the periods need a tick of {us} µs, and bip's `tick_ms` is a whole number of milliseconds"),
            span,
        ));
    }
    Ok(us)
}
