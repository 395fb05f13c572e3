//! The first load error of a model that must be rejected, and where it points.

#![allow(dead_code)]

use bip_lang::load_str;

/// Loads `text`, expects it to fail, and returns the first error's message, the text its
/// span covers, and its (line, column).
pub fn first_error(text: &str) -> (String, String, (usize, usize)) {
    let err = match load_str("bad.ron", text) {
        Ok(_) => panic!("expected the model to be rejected"),
        Err(e) => e,
    };
    let e = err.errors().first().expect("at least one error").clone();
    let covered = text.get(e.span.start..e.span.end).unwrap_or("").to_string();
    (e.message, covered, err.positions()[0])
}

/// Asserts that the first error mentions `words` and points at `covered`.
pub fn assert_error(text: &str, words: &str, covered: &str) {
    let (msg, got, pos) = first_error(text);
    assert!(msg.contains(words), "message `{msg}` lacks `{words}`");
    assert_eq!(got, covered, "span of `{msg}` at {pos:?}");
}
