//! XML text: the one escaping function every picture and report of the workspace uses.

/// `text` as XML character data or attribute value: markup characters escaped, control
/// characters XML 1.0 cannot hold dropped.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && c != '\n' && c != '\t' && c != '\r' => {}
            c => out.push(c),
        }
    }
    out
}

/// What the pictures' tests read back from an SVG (which must parse as XML): its texts and
/// the class of each element.
#[cfg(test)]
pub(crate) mod read {
    pub(crate) fn texts(doc: &str) -> Vec<String> {
        parsed(doc)
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter_map(|n| n.text().map(str::to_string))
            .collect()
    }

    pub(crate) fn classes(doc: &str) -> Vec<String> {
        parsed(doc)
            .descendants()
            .filter_map(|n| n.attribute("class").map(str::to_string))
            .collect()
    }

    fn parsed(doc: &str) -> roxmltree::Document<'_> {
        roxmltree::Document::parse(doc).expect("well-formed XML")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_and_drops_control_characters() {
        assert_eq!(
            escape("a<b & \"c\"\u{1}'"),
            "a&lt;b &amp; &quot;c&quot;&apos;"
        );
        assert_eq!(escape("plain\ttext"), "plain\ttext");
    }
}
