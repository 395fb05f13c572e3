//! An IDL type's text as the parser writes it (`unsigned long`, `sequence<rover::pose, 16>`,
//! `string<32>`, `struct inner_s`, `double[3][2]`, bounds and sizes already evaluated to
//! numbers) read back as a tree: for the model's data types (`types`) and for the C
//! headers of `bip-codegen`, which need the bounds the model leaves out.

use super::idl::{MANY_WORD_BASIC, ONE_WORD_BASIC};

/// An IDL type as the parser keeps its text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Idl<'t> {
    /// A basic type: `boolean`, `unsigned long long`, `double`, `any`, ...
    Basic(&'t str),
    /// `string`, `string<N>`, `wstring`, `wstring<N>`: the bound, if any.
    Text(Option<u64>),
    /// `sequence<T>` or `sequence<T, N>`: the element and the bound, if any.
    Sequence(Box<Idl<'t>>, Option<u64>),
    Optional(Box<Idl<'t>>),
    /// An array of the dimensions as written, outermost first.
    Array(Box<Idl<'t>>, Vec<&'t str>),
    /// A declared type, by its name as written (scoped or not).
    Named(&'t str),
}

/// The tree of an IDL type's text.
pub fn parse(text: &str) -> Idl<'_> {
    let text = text.trim();
    if text.ends_with(']') {
        let mut base = text;
        let mut dims = Vec::new();
        while let Some(rest) = base.strip_suffix(']') {
            let Some(open) = rest.rfind('[') else { break };
            dims.push(rest[open + 1..].trim());
            base = rest[..open].trim_end();
        }
        dims.reverse();
        return Idl::Array(Box::new(parse(base)), dims);
    }
    if MANY_WORD_BASIC.contains(&text) || ONE_WORD_BASIC.contains(&text) {
        return Idl::Basic(text);
    }
    let word = text.split(['<', ' ']).next().unwrap_or(text);
    let angled = || {
        text[word.len()..]
            .trim()
            .strip_prefix('<')
            .and_then(|t| t.strip_suffix('>'))
    };
    match word {
        "string" | "wstring" => Idl::Text(angled().and_then(|n| n.trim().parse().ok())),
        "sequence" | "optional" => {
            let inner = angled().unwrap_or("");
            // the bound, if any, follows the last comma outside angle brackets
            let mut depth = 0usize;
            let mut end = inner.len();
            for (i, ch) in inner.char_indices() {
                match ch {
                    '<' => depth += 1,
                    '>' => depth = depth.saturating_sub(1),
                    ',' if depth == 0 => end = i,
                    _ => {}
                }
            }
            let element = Box::new(parse(&inner[..end]));
            if word == "sequence" {
                let bound = inner.get(end + 1..).and_then(|n| n.trim().parse().ok());
                Idl::Sequence(element, bound)
            } else {
                Idl::Optional(element)
            }
        }
        "struct" | "union" | "enum" => Idl::Named(text[word.len()..].trim()),
        _ => Idl::Named(text),
    }
}

/// The declaration `name` refers to from within `scope` (`a::b`), as IDL resolves it: in
/// the scope, then in each enclosing one; `::a::b` is from the top. `lookup` finds a
/// declaration by its full name; the answer is that full name and what `lookup` found.
pub fn resolve_scoped<T>(
    name: &str,
    scope: &str,
    lookup: impl Fn(&str) -> Option<T>,
) -> Option<(String, T)> {
    if let Some(absolute) = name.strip_prefix("::") {
        return lookup(absolute).map(|d| (absolute.to_string(), d));
    }
    let mut scope = scope;
    loop {
        let full = if scope.is_empty() {
            name.to_string()
        } else {
            format!("{scope}::{name}")
        };
        if let Some(d) = lookup(&full) {
            return Some((full, d));
        }
        if scope.is_empty() {
            return None;
        }
        scope = scope.rsplit_once("::").map_or("", |(outer, _)| outer);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_are_kept() {
        assert_eq!(parse("string<32>"), Idl::Text(Some(32)));
        assert_eq!(parse("string"), Idl::Text(None));
        assert_eq!(
            parse("sequence<sequence<long, 2>, 16>"),
            Idl::Sequence(
                Box::new(Idl::Sequence(Box::new(Idl::Basic("long")), Some(2))),
                Some(16)
            )
        );
        assert_eq!(
            parse("double[3][2]"),
            Idl::Array(Box::new(Idl::Basic("double")), vec!["3", "2"])
        );
    }
}
