//! The small amount of XML text handling the crate needs: escaping for the writer, characters XML 1.0
//! cannot carry, and an indenting element writer.
//!
//! The writer emits a fixed, known set of names, so a full XML serialiser would add a dependency for
//! little gain; escaping is the only delicate part and is tested here (XML 1.0 §2.2, §2.4, §3.3.3).

use std::fmt::Write as _;

pub(crate) use canopener_eds::xml_text::is_xml_char;
use canopener_eds::xml_text::{XmlPlace, XmlStyle, escape};

/// Replaces characters XML cannot carry with U+FFFD (the side channel keeps the original).
pub(crate) fn sanitize(text: &str) -> String {
    text.chars()
        .map(|c| if is_xml_char(c) { c } else { '\u{FFFD}' })
        .collect()
}

/// Escapes text for a double-quoted attribute value, as CANopenEditor's .NET writer does (hexadecimal
/// references, `'` left as it is).
pub(crate) fn escape_attribute(text: &str) -> String {
    escape(text, XmlPlace::Attribute, XmlStyle::CANOPEN_EDITOR)
}

/// Escapes element content, as CANopenEditor's .NET writer does.
pub(crate) fn escape_text(text: &str) -> String {
    escape(text, XmlPlace::Content, XmlStyle::CANOPEN_EDITOR)
}

/// Encodes a side-channel value so that it survives XML: `%` and characters XML cannot carry become
/// `%XXXX` (the UTF-16 code unit in hex; these characters are all in the BMP).
pub(crate) fn percent_encode(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c == '%' || !is_xml_char(c) {
            let _ = write!(out, "%{:04X}", u32::from(c));
        } else {
            out.push(c);
        }
    }
    out
}

/// Reverses [`percent_encode`]; `None` if the text is not a valid encoding.
pub(crate) fn percent_decode(text: &str) -> Option<String> {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find('%') {
        out.push_str(rest.get(..at)?);
        let digits = rest.get(at + 1..at + 5)?;
        if !digits.bytes().all(|b| b.is_ascii_hexdigit()) {
            return None;
        }
        out.push(char::from_u32(u32::from_str_radix(digits, 16).ok()?)?);
        rest = rest.get(at + 5..)?;
    }
    out.push_str(rest);
    Some(out)
}

/// Whether text needs [`percent_encode`] to survive as an attribute value.
pub(crate) fn needs_encoding(text: &str) -> bool {
    text.chars().any(|c| !is_xml_char(c))
}

/// An indenting writer of elements with escaped attributes.
#[derive(Debug, Default)]
pub(crate) struct XmlOut {
    buf: String,
    depth: usize,
}

impl XmlOut {
    pub(crate) fn raw_line(&mut self, line: &str) {
        self.indent();
        self.buf.push_str(line);
        self.buf.push('\n');
    }

    fn indent(&mut self) {
        for _ in 0..self.depth {
            self.buf.push_str("  ");
        }
    }

    fn start_tag(&mut self, name: &str, attrs: &[(&str, String)]) {
        self.indent();
        self.buf.push('<');
        self.buf.push_str(name);
        for (key, value) in attrs {
            let _ = write!(self.buf, " {key}=\"{}\"", escape_attribute(value));
        }
    }

    /// `<name a="v">` and one level deeper.
    pub(crate) fn open(&mut self, name: &str, attrs: &[(&str, String)]) {
        self.start_tag(name, attrs);
        self.buf.push_str(">\n");
        self.depth += 1;
    }

    /// `</name>` one level up.
    pub(crate) fn close(&mut self, name: &str) {
        self.depth = self.depth.saturating_sub(1);
        self.indent();
        let _ = writeln!(self.buf, "</{name}>");
    }

    /// `<name a="v" />`, the CANopenEditor (.NET XmlSerializer) spelling of an empty element.
    pub(crate) fn empty(&mut self, name: &str, attrs: &[(&str, String)]) {
        self.start_tag(name, attrs);
        self.buf.push_str(" />\n");
    }

    /// `<name a="v">text</name>`.
    pub(crate) fn text(&mut self, name: &str, attrs: &[(&str, String)], text: &str) {
        self.start_tag(name, attrs);
        let _ = writeln!(self.buf, ">{}</{name}>", escape_text(text));
    }

    pub(crate) fn finish(self) -> String {
        self.buf
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attribute_escaping_survives_a_parser() {
        let nasty = "a&b<c>d\"e'f\tg\nh\ri  j";
        let xml = format!("<e v=\"{}\"/>", escape_attribute(nasty));
        let doc = roxmltree::Document::parse(&xml).expect("escaped attribute parses");
        assert_eq!(doc.root_element().attribute("v"), Some(nasty));
    }

    #[test]
    fn text_escaping_survives_a_parser() {
        let nasty = "x < y && z > w\r\nnext ]]> line";
        let xml = format!("<e>{}</e>", escape_text(nasty));
        let doc = roxmltree::Document::parse(&xml).expect("escaped text parses");
        assert_eq!(doc.root_element().text(), Some(nasty));
    }

    #[test]
    fn characters_xml_cannot_carry_are_replaced_or_encoded() {
        assert_eq!(sanitize("a\u{1}b\u{FFFE}"), "a\u{FFFD}b\u{FFFD}");
        assert_eq!(escape_attribute("\u{0}"), "\u{FFFD}");
        assert!(needs_encoding("bell\u{7}"));
        assert!(!needs_encoding("tab\tok"));
        let original = "50% \u{1}\u{1F}\u{FFFF} done";
        let encoded = percent_encode(original);
        assert_eq!(encoded, "50%0025 %0001%001F%FFFF done");
        assert!(!needs_encoding(&encoded));
        assert_eq!(percent_decode(&encoded).as_deref(), Some(original));
        assert_eq!(percent_decode("bad %zz12"), None);
        assert_eq!(percent_decode("short %12"), None);
    }

    #[test]
    fn writer_indents_and_escapes() {
        let mut out = XmlOut::default();
        out.open("a", &[("x", "1&2".to_owned())]);
        out.empty("b", &[]);
        out.text("c", &[("lang", "en".to_owned())], "<hi>");
        out.close("a");
        assert_eq!(
            out.finish(),
            "<a x=\"1&amp;2\">\n  <b />\n  <c lang=\"en\">&lt;hi&gt;</c>\n</a>\n"
        );
    }
}
