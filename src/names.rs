//! Whether a text of the model (a guard, a property, a why) names a module or component.

/// True if `text` names `name` as a module or component: `name.`, `name@` or `name[`, not
/// inside a longer name.
pub fn mentions(text: &str, name: &str) -> bool {
    text.match_indices(name).any(|(at, _)| {
        let before = text[..at].chars().next_back();
        let after = text[at + name.len()..].chars().next();
        !before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '.')
            && matches!(after, Some('.' | '@' | '['))
    })
}

#[cfg(test)]
mod tests {
    use super::mentions;

    #[test]
    fn a_name_is_mentioned_before_a_dot_an_at_or_a_bracket() {
        assert!(mentions("pack.level > RESERVE", "pack"));
        assert!(mentions("!backpack.x || pack[2].y", "pack"));
        assert!(mentions("ndd.GoTo@move", "ndd"));
        assert!(!mentions("backpack.level", "pack"));
        assert!(!mentions("pack > 1", "pack"));
        assert!(!mentions("sick.scan.pack.x", "pack"));
    }
}
