//! A small SVG writer: shapes and text appended to a document, every text and attribute
//! value escaped. Coordinates are written with two decimals at most.

use std::fmt::Write;

use crate::xml::escape;

/// The font the pictures use, and an estimate of its text widths (no font is read: the
/// estimate is generous so that text stays inside its box).
pub const FONT: &str = "sans-serif";

/// The width `text` takes at `size` pixels.
pub fn text_width(text: &str, size: f64) -> f64 {
    text.chars().count() as f64 * size * 0.6
}

/// A number as SVG writes it.
pub fn num(v: f64) -> String {
    let r = (v * 100.0).round() / 100.0;
    if r == r.trunc() {
        format!("{}", r as i64)
    } else {
        format!("{r}")
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    Start,
    Middle,
    End,
}

/// How a shape is painted. `dash` is an SVG `stroke-dasharray`, empty for a solid line.
#[derive(Clone, Copy, Debug)]
pub struct Paint<'a> {
    pub fill: &'a str,
    pub stroke: &'a str,
    pub width: f64,
    pub dash: &'a str,
}

impl<'a> Paint<'a> {
    pub fn stroke(stroke: &'a str) -> Self {
        Paint {
            fill: "none",
            stroke,
            width: 1.0,
            dash: "",
        }
    }

    pub fn filled(fill: &'a str, stroke: &'a str) -> Self {
        Paint {
            fill,
            stroke,
            width: 1.0,
            dash: "",
        }
    }

    pub fn width(mut self, width: f64) -> Self {
        self.width = width;
        self
    }

    pub fn dash(mut self, dash: &'a str) -> Self {
        self.dash = dash;
        self
    }

    fn attributes(&self) -> String {
        let mut s = format!(
            r#" fill="{}" stroke="{}""#,
            escape(self.fill),
            escape(self.stroke)
        );
        if self.width != 1.0 {
            let _ = write!(s, r#" stroke-width="{}""#, num(self.width));
        }
        if !self.dash.is_empty() {
            let _ = write!(s, r#" stroke-dasharray="{}""#, escape(self.dash));
        }
        s
    }
}

/// Text's look: size in pixels, bold or not, colour, anchor.
#[derive(Clone, Copy, Debug)]
pub struct Font<'a> {
    pub size: f64,
    pub bold: bool,
    pub italic: bool,
    pub colour: &'a str,
    pub anchor: Anchor,
}

impl<'a> Font<'a> {
    pub fn new(size: f64) -> Self {
        Font {
            size,
            bold: false,
            italic: false,
            colour: "#222222",
            anchor: Anchor::Start,
        }
    }

    pub fn bold(mut self) -> Self {
        self.bold = true;
        self
    }

    pub fn italic(mut self) -> Self {
        self.italic = true;
        self
    }

    pub fn colour(mut self, colour: &'a str) -> Self {
        self.colour = colour;
        self
    }

    pub fn anchor(mut self, anchor: Anchor) -> Self {
        self.anchor = anchor;
        self
    }
}

/// An SVG document being written.
pub struct Svg {
    body: String,
    defs: String,
    depth: usize,
}

impl Default for Svg {
    fn default() -> Self {
        Self::new()
    }
}

impl Svg {
    pub fn new() -> Self {
        Svg {
            body: String::new(),
            defs: String::new(),
            depth: 0,
        }
    }

    /// Adds raw definitions (markers); `text` must be well-formed SVG of our own.
    pub fn define(&mut self, text: &str) {
        self.defs.push_str(text);
        self.defs.push('\n');
    }

    /// Opens a group of class `class`, with a tooltip `title` if given. Groups nest.
    pub fn open(&mut self, class: &str, title: Option<&str>) {
        let _ = write!(self.body, r#"<g class="{}">"#, escape(class));
        if let Some(title) = title {
            let _ = write!(self.body, "<title>{}</title>", escape(title));
        }
        self.body.push('\n');
        self.depth += 1;
    }

    pub fn close(&mut self) {
        if self.depth > 0 {
            self.body.push_str("</g>\n");
            self.depth -= 1;
        }
    }

    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, radius: f64, paint: Paint) {
        let _ = write!(
            self.body,
            r#"<rect x="{}" y="{}" width="{}" height="{}""#,
            num(x),
            num(y),
            num(w.max(0.0)),
            num(h.max(0.0))
        );
        if radius > 0.0 {
            let _ = write!(self.body, r#" rx="{}""#, num(radius));
        }
        let _ = writeln!(self.body, "{}/>", paint.attributes());
    }

    pub fn ellipse(&mut self, cx: f64, cy: f64, rx: f64, ry: f64, paint: Paint) {
        let _ = writeln!(
            self.body,
            r#"<ellipse cx="{}" cy="{}" rx="{}" ry="{}"{}/>"#,
            num(cx),
            num(cy),
            num(rx),
            num(ry),
            paint.attributes()
        );
    }

    pub fn line(&mut self, x1: f64, y1: f64, x2: f64, y2: f64, paint: Paint) {
        let _ = writeln!(
            self.body,
            r#"<line x1="{}" y1="{}" x2="{}" y2="{}"{}/>"#,
            num(x1),
            num(y1),
            num(x2),
            num(y2),
            paint.attributes()
        );
    }

    /// A path; `marker` names a marker of the definitions for its end.
    pub fn path(&mut self, d: &str, paint: Paint, marker: Option<&str>) {
        let _ = write!(
            self.body,
            r#"<path d="{}"{}"#,
            escape(d),
            paint.attributes()
        );
        if let Some(m) = marker {
            let _ = write!(self.body, r#" marker-end="url(#{})""#, escape(m));
        }
        self.body.push_str("/>\n");
    }

    pub fn text(&mut self, x: f64, y: f64, text: &str, font: Font) {
        let anchor = match font.anchor {
            Anchor::Start => "",
            Anchor::Middle => r#" text-anchor="middle""#,
            Anchor::End => r#" text-anchor="end""#,
        };
        let _ = writeln!(
            self.body,
            r#"<text x="{}" y="{}" font-size="{}"{anchor}{}{} fill="{}">{}</text>"#,
            num(x),
            num(y),
            num(font.size),
            if font.bold {
                r#" font-weight="bold""#
            } else {
                ""
            },
            if font.italic {
                r#" font-style="italic""#
            } else {
                ""
            },
            escape(font.colour),
            escape(text)
        );
    }

    /// The document, `width` by `height`, its title `title`.
    pub fn finish(mut self, width: f64, height: f64, title: &str) -> String {
        while self.depth > 0 {
            self.close();
        }
        let mut s = String::with_capacity(self.body.len() + self.defs.len() + 400);
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="{FONT}">"#,
            w = num(width.ceil()),
            h = num(height.ceil())
        );
        let _ = writeln!(s, "<title>{}</title>", escape(title));
        if !self.defs.is_empty() {
            let _ = write!(s, "<defs>\n{}</defs>\n", self.defs);
        }
        let _ = writeln!(
            s,
            r##"<rect x="0" y="0" width="{}" height="{}" fill="#ffffff"/>"##,
            num(width.ceil()),
            num(height.ceil())
        );
        s.push_str(&self.body);
        s.push_str("</svg>\n");
        s
    }
}

/// An arrowhead marker for lines of `colour`, with its id.
pub fn arrow_marker(colour: &str) -> (String, String) {
    let id = format!(
        "arrow-{}",
        colour
            .chars()
            .filter(char::is_ascii_alphanumeric)
            .collect::<String>()
    );
    let def = format!(
        r#"<marker id="{id}" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z" fill="{}"/></marker>"#,
        escape(colour)
    );
    (id, def)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_document_is_well_formed_xml_with_its_text_escaped() {
        let mut svg = Svg::new();
        svg.open("node", Some("a <b>"));
        svg.rect(
            1.0,
            2.0,
            3.5,
            4.25,
            2.0,
            Paint::filled("#fff", "#000").dash("4 2"),
        );
        svg.text(5.0, 6.0, "x < y && z", Font::new(12.0).bold());
        let doc = svg.finish(100.0, 50.0, "T & U");
        let texts = crate::xml::read::texts(&doc);
        assert_eq!(texts, ["x < y && z"]);
        assert!(doc.contains(r#"width="3.5""#) && doc.contains(r#"height="4.25""#));
    }

    #[test]
    fn numbers_are_short() {
        assert_eq!(num(3.0), "3");
        assert_eq!(num(2.345), "2.35");
        assert_eq!(num(-0.5), "-0.5");
    }
}
