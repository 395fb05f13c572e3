//! The architecture's invariants, read from the source: inside each crate, the modules
//! import one another in one direction only, along a declared order of layers.
//!
//! Each `.rs` file is a module. An import is any `crate::` or `super::` path in it (in a
//! `use` or inline); it is resolved to the file that defines it, following the re-exports
//! of a `mod.rs`, so `use super::Thing` counts as an import of the file `Thing` lives in. A
//! module's file may name its own submodules (it declares them), and everyone may name the
//! crate root (it only declares modules and the prelude). Everything else must go down
//! the layers, or sideways within one layer without a cycle.
//!
//! To add a module, put it in its crate's layer below. To move the order, change it here
//! and in ARCHITECTURE.md, which states the same layers.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A crate's layers, lowest first; each names module paths (a path covers its submodules).
struct Layers {
    src: &'static str,
    layers: &'static [(&'static str, &'static [&'static str])],
}

const CRATES: &[Layers] = &[
    Layers {
        src: "bip-model/src",
        layers: &[
            (
                "values",
                &["ops", "rng", "radix", "ordered_map", "state", "eval"],
            ),
            ("parts", &["model", "steps", "budgets", "genom::map"]),
            (
                "tables",
                &[
                    "fast_path",
                    "choices",
                    "priority_graph",
                    "priority_masks",
                    "step_tables",
                    "enable_index",
                ],
            ),
            ("system", &["system"]),
            (
                "semantics",
                &[
                    "step",
                    "suppression",
                    "assemble",
                    "deadlock",
                    "response",
                    "timelock",
                    "trace",
                    "genom",
                ],
            ),
            (
                "acceleration",
                &[
                    "watches",
                    "found",
                    "plan_effects",
                    "fire_plan",
                    "incremental",
                    "state_cache",
                    "gate",
                ],
            ),
        ],
    },
    Layers {
        src: "bip-engine/src",
        layers: &[
            (
                "values",
                &[
                    "clock", "policy", "ports", "error", "budgets", "types", "bounded",
                ],
            ),
            (
                "codels",
                &[
                    "codel",
                    "event",
                    "bind",
                    "chosen",
                    "per_state",
                    "record",
                    "signature",
                ],
            ),
            ("remote", &["handle", "threads"]),
            ("engine", &["engine"]),
            ("drivers", &["replay", "simulate", "hosted"]),
        ],
    },
    Layers {
        src: "distributed/src",
        layers: &[
            (
                "wire",
                &["runtime", "network", "wire", "link", "codec", "deploy"],
            ),
            (
                "sides",
                &["presence", "remote", "host", "requests", "launch", "client"],
            ),
            ("layer", &["layer"]),
        ],
    },
    Layers {
        src: "verifier/src",
        layers: &[
            (
                "values",
                &[
                    "error",
                    "options",
                    "progress",
                    "properties",
                    "report",
                    "memory",
                    "watch",
                ],
            ),
            ("stores", &["visited", "promela"]),
            ("explicit", &["explore"]),
            ("symbolic", &["symbolic"]),
            ("schedulability", &["schedulability"]),
            ("auto", &["auto", "time_stops"]),
        ],
    },
    Layers {
        src: "sched/src",
        layers: &[
            ("values", &["error", "task"]),
            ("analysis", &["rta"]),
            ("schedules", &["analysis", "simulate"]),
            ("pictures", &["svg"]),
        ],
    },
    Layers {
        src: "picture/src",
        layers: &[
            ("text", &["xml"]),
            ("parts", &["svg", "graph"]),
            ("layout", &["layout"]),
            ("pictures", &["dot", "render", "chart", "timeline"]),
        ],
    },
    Layers {
        src: "codegen/src",
        layers: &[
            ("names", &["names"]),
            ("types", &["types"]),
            ("parts", &["context", "requests", "signature"]),
            ("text", &["emit"]),
            // the C headers of a GenoM3 component's codels, apart from the Rust bindings
            ("c", &["c"]),
        ],
    },
    Layers {
        src: "genom-c/src",
        layers: &[
            // data of C that Rust lacks: owning its buffers, a long double, a multiple port
            ("values", &["owned", "long_double", "multiple"]),
            ("context", &["context"]),
            ("events", &["events"]),
        ],
    },
    Layers {
        src: "src",
        layers: &[
            (
                "basics",
                &[
                    "exit",
                    "startup",
                    "interrupt",
                    "memory_guard",
                    "names",
                    "report",
                    "load",
                ],
            ),
            // the commands whose views other commands reuse
            ("views", &["trace", "graph"]),
            (
                "commands",
                &[
                    "check", "codegen", "expand", "explore", "export", "import", "replay",
                    "request", "run", "sched", "simulate", "verify",
                ],
            ),
        ],
    },
    Layers {
        src: "bip-lang/src",
        layers: &[
            ("positions", &["source", "source_map", "excerpt", "diag"]),
            (
                "syntax",
                &["syntax", "expr", "genom::syntax", "gen3::entries"],
            ),
            ("compile", &["compile"]),
            ("expansion", &["genom", "gen3"]),
            ("files", &["load", "trace_file"]),
        ],
    },
];

#[test]
fn modules_import_along_the_declared_layers_without_cycles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut problems = Vec::new();
    for krate in CRATES {
        let files = read_tree(&root.join(krate.src));
        problems.extend(
            check(&files, krate.layers)
                .into_iter()
                .map(|p| format!("{}: {p}", krate.src)),
        );
    }
    assert!(problems.is_empty(), "\n{}", problems.join("\n"));
}

/// The checker finds what it is for: a cycle, an import against the order, a module
/// outside every layer, and it follows a `mod.rs`'s re-exports.
#[test]
fn the_checker_finds_cycles_and_upward_imports() {
    let tree = |files: &[(&str, &str)]| -> BTreeMap<String, String> {
        files
            .iter()
            .map(|(m, text)| (m.to_string(), text.to_string()))
            .collect()
    };
    let layers: &[(&str, &[&str])] = &[("low", &["a", "b"]), ("high", &["c"])];
    let clean = tree(&[
        ("", "mod a; mod b; mod c;"),
        ("a", "use crate::prelude::*;"),
        ("b", "use crate::a::Thing;"),
        ("c", "use crate::{a::X, b::Y};"),
    ]);
    assert_eq!(check(&clean, layers), Vec::<String>::new());

    let cycle = tree(&[
        ("", ""),
        ("a", "fn f() { crate::b::g() }"),
        ("b", "use crate::a;"),
        ("c", ""),
    ]);
    let found = check(&cycle, layers);
    assert!(
        found
            .iter()
            .any(|p| p.contains("cycle") && p.contains("a -> b -> a")),
        "{found:?}"
    );

    let upward = tree(&[("", ""), ("a", "use crate::c::Z;"), ("b", ""), ("c", "")]);
    let found = check(&upward, layers);
    assert!(
        found
            .iter()
            .any(|p| p.contains("`a` (layer low) imports `c` (layer high)")),
        "{found:?}"
    );

    let stray = tree(&[("", ""), ("a", ""), ("b", ""), ("c", ""), ("d", "")]);
    assert!(check(&stray, layers)
        .iter()
        .any(|p| p.contains("`d` is in no layer")));

    // `super::Thing` re-exported by a directory's mod.rs is an import of the file it is in
    let reexport = tree(&[
        ("", ""),
        ("a", "mod x; mod y; pub use x::Thing;"),
        ("a::x", "use super::y::helper;"),
        ("a::y", "use super::Thing;"),
        ("b", ""),
        ("c", ""),
    ]);
    let found = check(&reexport, layers);
    assert!(
        found.iter().any(|p| p.contains("a::x -> a::y -> a::x")),
        "{found:?}"
    );
}

/// Every `.rs` file under `src`, by module path (`""` for the crate root).
fn read_tree(src: &Path) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut dirs = vec![PathBuf::from(src)];
    while let Some(dir) = dirs.pop() {
        let entries = std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path
                    .strip_prefix(src)
                    .expect("under src")
                    .with_extension("");
                let mut parts: Vec<String> = rel
                    .iter()
                    .map(|p| p.to_string_lossy().into_owned())
                    .collect();
                if matches!(
                    parts.last().map(String::as_str),
                    Some("mod" | "lib" | "main")
                ) {
                    parts.pop();
                }
                let text = std::fs::read_to_string(&path).expect("readable source");
                out.insert(parts.join("::"), text);
            }
        }
    }
    out
}

/// What is wrong with a crate's imports: cycles, imports against the layer order,
/// modules in no layer.
fn check(files: &BTreeMap<String, String>, layers: &[(&str, &[&str])]) -> Vec<String> {
    let code: BTreeMap<&str, String> = files
        .iter()
        .map(|(m, t)| (m.as_str(), strip_comments(t)))
        .collect();
    let mut problems = Vec::new();
    let layer_of = |m: &str| -> Option<usize> {
        layers
            .iter()
            .enumerate()
            .flat_map(|(k, (_, mods))| mods.iter().map(move |p| (k, *p)))
            .filter(|(_, p)| m == *p || m.starts_with(&format!("{p}::")))
            .max_by_key(|(_, p)| p.len())
            .map(|(k, _)| k)
    };
    for (_, mods) in layers {
        for m in *mods {
            if !code.contains_key(m) {
                problems.push(format!("layer module `{m}` does not exist"));
            }
        }
    }
    let mut edges: BTreeMap<&str, BTreeSet<String>> = BTreeMap::new();
    for (&m, text) in &code {
        if m.is_empty() {
            continue;
        }
        // unit tests sit beside the code they test and may reach anything
        if m == "tests" || m.ends_with("::tests") {
            continue;
        }
        if layer_of(m).is_none() {
            problems.push(format!("`{m}` is in no layer"));
        }
        for path in paths(text) {
            let Some(target) = resolve(&code, m, &path) else {
                continue;
            };
            // the root only declares; a module may name what it declares
            if target.is_empty() || target == m || is_below(&target, m) {
                continue;
            }
            edges.entry(m).or_default().insert(target);
        }
    }
    for (&from, tos) in &edges {
        for to in tos {
            if let (Some(a), Some(b)) = (layer_of(from), layer_of(to)) {
                if b > a {
                    problems.push(format!(
                        "`{from}` (layer {}) imports `{to}` (layer {})",
                        layers[a].0, layers[b].0
                    ));
                }
            }
        }
    }
    for cycle in cycles(&edges) {
        problems.push(format!("import cycle: {}", cycle.join(" -> ")));
    }
    problems
}

/// True if `m` is a module inside `parent`.
fn is_below(m: &str, parent: &str) -> bool {
    !parent.is_empty() && m.starts_with(&format!("{parent}::"))
        || parent.is_empty() && !m.is_empty()
}

/// The text without comments and string literals (a path in a doc comment or a message is
/// not an import).
fn strip_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '/' if chars.peek() == Some(&'/') => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            '/' if chars.peek() == Some(&'*') => {
                let mut prev = ' ';
                for c in chars.by_ref() {
                    if prev == '*' && c == '/' {
                        break;
                    }
                    prev = c;
                }
            }
            '"' => {
                let mut escaped = false;
                for c in chars.by_ref() {
                    if c == '"' && !escaped {
                        break;
                    }
                    escaped = c == '\\' && !escaped;
                }
                out.push_str("\"\"");
            }
            _ => out.push(c),
        }
    }
    out
}

/// Every `crate::`/`super::` path in the code, with `use` groups expanded
/// (`use crate::{a::X, b::{Y, Z}}` gives `crate::a::X`, `crate::b::Y`, `crate::b::Z`), and
/// the modules a file re-exports from (`pub use x::Thing` in a `mod.rs`) as `self::x::Thing`.
fn paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    for stmt in code.split(';') {
        let stmt = stmt.trim();
        let Some(at) = stmt.find("use ") else {
            continue;
        };
        let head = &stmt[..at];
        if !head.trim().is_empty()
            && !head.trim_end().ends_with(')')
            && !head.trim().ends_with("pub")
        {
            continue;
        }
        let tree: String = stmt[at + 4..]
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect();
        expand_use("", &tree, &mut out);
    }
    // inline paths: `crate::a::b(...)`
    let bytes: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < bytes.len() {
        let rest: String = bytes[i..bytes.len().min(i + 7)].iter().collect();
        let boundary = i == 0
            || !(bytes[i - 1].is_alphanumeric() || bytes[i - 1] == '_' || bytes[i - 1] == ':');
        if boundary && (rest.starts_with("crate::") || rest.starts_with("super::")) {
            let mut j = i;
            while j < bytes.len()
                && (bytes[j].is_alphanumeric() || bytes[j] == '_' || bytes[j] == ':')
            {
                j += 1;
            }
            out.push(
                bytes[i..j]
                    .iter()
                    .collect::<String>()
                    .trim_end_matches(':')
                    .to_string(),
            );
            i = j;
        } else {
            i += 1;
        }
    }
    out.retain(|p| p.starts_with("crate::") || p.starts_with("super::") || p.starts_with("self::"));
    out
}

fn expand_use(prefix: &str, tree: &str, out: &mut Vec<String>) {
    let tree = tree.trim_start_matches("::");
    if let Some(open) = tree.find('{') {
        let base = format!("{prefix}{}", &tree[..open]);
        let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
        let mut depth = 0;
        let mut start = 0;
        for (k, c) in inner.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand_use(&base, &inner[start..k], out);
                    start = k + 1;
                }
                _ => {}
            }
        }
        expand_use(&base, &inner[start..], out);
    } else if !tree.is_empty() {
        let path = tree
            .split(" as ")
            .next()
            .unwrap_or(tree)
            .split("as")
            .next()
            .unwrap_or(tree);
        let full = format!("{prefix}{path}");
        if full.starts_with("crate::") || full.starts_with("super::") || full.starts_with("self::")
        {
            out.push(full);
        } else {
            // a module's own submodule (`pub use x::Thing` in its mod.rs)
            out.push(format!("self::{full}"));
        }
    }
}

/// The module whose file defines `path` as written in module `from`, or `None` for a path
/// outside the crate.
fn resolve(code: &BTreeMap<&str, String>, from: &str, path: &str) -> Option<String> {
    let mut segs: Vec<String> = path.split("::").map(str::to_string).collect();
    let mut at: Vec<String> = from
        .split("::")
        .filter(|s| !s.is_empty())
        .map(str::to_string)
        .collect();
    match segs.first().map(String::as_str) {
        Some("crate") => at.clear(),
        Some("self") => {}
        Some("super") => {
            while segs.first().map(String::as_str) == Some("super") {
                at.pop();
                segs.remove(0);
            }
            segs.insert(0, "self".to_string());
        }
        _ => return None,
    }
    segs.remove(0);
    // each step follows one re-export; a chain of them ends within a few
    for _ in 0..8 {
        // the longest prefix that is a file
        let mut used = 0;
        while let Some(s) = segs.get(used) {
            let mut next = at.clone();
            next.push(s.clone());
            if !code.contains_key(next.join("::").as_str()) {
                break;
            }
            at = next;
            used += 1;
        }
        let module = at.join("::");
        let reexported = segs
            .get(used)
            .and_then(|item| reexport_of(code.get(module.as_str())?, item));
        match reexported {
            Some(inner) => segs = inner,
            None => return Some(module),
        }
    }
    Some(at.join("::"))
}

/// Where a module's `pub use` of one of its own submodules takes `item` from, as a path
/// inside the module.
fn reexport_of(code: &str, item: &str) -> Option<Vec<String>> {
    for stmt in code.split(';') {
        let stmt = stmt.trim();
        let Some(tree) = stmt
            .strip_prefix("pub use ")
            .or_else(|| stmt.strip_prefix("pub(crate) use "))
        else {
            continue;
        };
        let compact: String = tree.chars().filter(|c| !c.is_whitespace()).collect();
        let mut out = Vec::new();
        expand_use("", &compact, &mut out);
        for p in out {
            if let Some(inner) = p.strip_prefix("self::") {
                if inner.contains("::") && inner.rsplit("::").next() == Some(item) {
                    return Some(inner.split("::").map(str::to_string).collect());
                }
            }
        }
    }
    None
}

/// The cycles of the import graph, one per strongly connected component of more than
/// one module, each written as a path that closes.
fn cycles(edges: &BTreeMap<&str, BTreeSet<String>>) -> Vec<Vec<String>> {
    let nodes: BTreeSet<String> = edges
        .iter()
        .flat_map(|(k, v)| std::iter::once(k.to_string()).chain(v.iter().cloned()))
        .collect();
    let succ = |n: &str| -> Vec<String> {
        edges
            .get(n)
            .map(|s| s.iter().cloned().collect())
            .unwrap_or_default()
    };
    let mut out = Vec::new();
    let mut done: BTreeSet<String> = BTreeSet::new();
    for start in &nodes {
        if done.contains(start) {
            continue;
        }
        // a shortest path from `start` back to itself, breadth first
        let mut parent: BTreeMap<String, String> = BTreeMap::new();
        let mut queue = std::collections::VecDeque::from([start.clone()]);
        let mut found = None;
        while let Some(n) = queue.pop_front() {
            for s in succ(&n) {
                if s == *start {
                    found = Some(n.clone());
                    break;
                }
                if !parent.contains_key(&s) {
                    parent.insert(s.clone(), n.clone());
                    queue.push_back(s);
                }
            }
            if found.is_some() {
                break;
            }
        }
        if let Some(last) = found {
            let mut path = vec![last.clone()];
            let mut n = last;
            while let Some(p) = parent.get(&n) {
                path.push(p.clone());
                n = p.clone();
            }
            path.push(start.clone());
            path.reverse();
            if path.first() != Some(start) {
                path.insert(0, start.clone());
            }
            path.dedup();
            for m in &path {
                done.insert(m.clone());
            }
            path.push(start.clone());
            out.push(path);
        }
    }
    out
}
