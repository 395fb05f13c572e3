//! Rust names for the model's names: `TrackSpeed` and `track` give the enum
//! `TrackSpeedTrack` and the method `track_speed_track`; `pause::track` the variant
//! `PauseTrack`, `e_blocked` the variant `EBlocked`. A Rust keyword is written raw.

/// `UpperCamelCase` of a model name (`track_speed` or `TrackSpeed` or `pause::track`).
pub(crate) fn camel(name: &str) -> String {
    let mut out = String::new();
    for word in words(name) {
        let mut cs = word.chars();
        if let Some(c) = cs.next() {
            out.extend(c.to_uppercase());
            out.push_str(cs.as_str());
        }
    }
    out
}

/// `snake_case` of a model name, written raw if it is a keyword.
pub(crate) fn snake(name: &str) -> String {
    let s = words(name)
        .map(|w| w.to_lowercase())
        .collect::<Vec<_>>()
        .join("_");
    raw(s)
}

/// A module name as written (model names are identifiers), raw if it is a keyword.
pub(crate) fn ident(name: &str) -> String {
    raw(name.to_string())
}

fn raw(s: String) -> String {
    if KEYWORDS.contains(&s.as_str()) {
        format!("r#{s}")
    } else {
        s
    }
}

/// The words of a name: split at `_`, `::` and before an upper-case letter that follows
/// a lower-case letter or a digit.
fn words(name: &str) -> impl Iterator<Item = String> + '_ {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut prev_lower = false;
    for c in name.chars() {
        if c == '_' || c == ':' {
            if !word.is_empty() {
                out.push(std::mem::take(&mut word));
            }
            prev_lower = false;
            continue;
        }
        if c.is_uppercase() && prev_lower && !word.is_empty() {
            out.push(std::mem::take(&mut word));
        }
        prev_lower = c.is_lowercase() || c.is_ascii_digit();
        word.push(c);
    }
    if !word.is_empty() {
        out.push(word);
    }
    out.into_iter()
}

const KEYWORDS: &[&str] = &[
    "as", "async", "await", "break", "const", "continue", "crate", "dyn", "else", "enum", "extern",
    "false", "fn", "for", "gen", "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut",
    "pub", "ref", "return", "self", "Self", "static", "struct", "super", "trait", "true", "type",
    "unsafe", "use", "where", "while", "abstract", "become", "box", "do", "final", "macro",
    "override", "priv", "try", "typeof", "unsized", "virtual", "yield",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_names_become_rust_names() {
        assert_eq!(camel("TrackSpeed"), "TrackSpeed");
        assert_eq!(camel("pause::track"), "PauseTrack");
        assert_eq!(camel("e_blocked"), "EBlocked");
        assert_eq!(camel("ether"), "Ether");
        assert_eq!(snake("TrackSpeed"), "track_speed");
        assert_eq!(snake("GoTo"), "go_to");
        assert_eq!(snake("move"), "r#move");
        assert_eq!(ident("type"), "r#type");
        assert_eq!(ident("rflex"), "rflex");
    }
}
