//! Escaping text for XML 1.0, shared by every writer of XML in canopener (the XDD/XDC writer, the
//! JUnit reports, SVG drawings), and for the HTML pages ([`escape_html`]), which are well-formed XML too.
//!
//! The writers differ in two details on purpose, so the escaper takes them as a [`XmlStyle`]: the XDD
//! writer produces the bytes CANopenEditor's .NET writer produces (hexadecimal character references,
//! `'` left as it is), the JUnit report keeps the decimal references and `&apos;` it has always had.

/// How character references and apostrophes are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct XmlStyle {
    /// `&#xA;` instead of `&#10;`.
    pub hex_references: bool,
    /// `&apos;` for `'` in attribute values.
    pub escape_apostrophe: bool,
}

impl XmlStyle {
    /// As CANopenEditor writes XDD: `&#xA;`, `'` unescaped.
    pub const CANOPEN_EDITOR: XmlStyle = XmlStyle {
        hex_references: true,
        escape_apostrophe: false,
    };
    /// Decimal references and `&apos;`.
    pub const DECIMAL: XmlStyle = XmlStyle {
        hex_references: false,
        escape_apostrophe: true,
    };
}

/// Where the escaped text goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum XmlPlace {
    /// Element content.
    Content,
    /// A double-quoted attribute value.
    Attribute,
}

/// Whether XML 1.0 can carry a character at all (XML 1.0 §2.2 `Char`), escaped or not.
pub fn is_xml_char(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r' | '\u{20}'..='\u{D7FF}' | '\u{E000}'..='\u{FFFD}' | '\u{10000}'..)
}

/// Escapes `text` for `place`. Characters XML cannot carry become U+FFFD. In attributes, tab and line
/// breaks become character references so that attribute-value normalisation (XML 1.0 §3.3.3) gives them
/// back; in content, CR does, because parsers turn CR LF into LF (§2.11).
pub fn escape(text: &str, place: XmlPlace, style: XmlStyle) -> String {
    let attribute = place == XmlPlace::Attribute;
    let reference = |code: u32| {
        if style.hex_references {
            format!("&#x{code:X};")
        } else {
            format!("&#{code};")
        }
    };
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' if attribute => out.push_str("&quot;"),
            '\'' if attribute && style.escape_apostrophe => out.push_str("&apos;"),
            '\t' | '\n' if attribute => out.push_str(&reference(u32::from(c))),
            '\r' => out.push_str(&reference(u32::from(c))),
            c if is_xml_char(c) => out.push(c),
            _ => out.push('\u{FFFD}'),
        }
    }
    out
}

/// Escapes `text` for an HTML (or XHTML) page, in element content and quoted attribute values alike.
///
/// Control characters, which HTML and XML reject, are shown rather than dropped, so that a device's or
/// a file's odd bytes stay visible in a report: C0 controls and DEL as their Unicode control pictures
/// (`␀`, `␡`), C1 controls and the noncharacters U+FDD0–U+FDEF (HTML parse errors) as U+FFFD. Tab and
/// line feed stay as they are, written as references.
pub fn escape_html(text: &str) -> String {
    let visible: String = text
        .chars()
        .map(|c| match c {
            '\n' | '\t' => c,
            '\u{0}'..='\u{1F}' => char::from_u32(0x2400 + u32::from(c)).unwrap_or('\u{FFFD}'),
            '\u{7F}' => '\u{2421}',
            '\u{80}'..='\u{9F}' | '\u{FDD0}'..='\u{FDEF}' => '\u{FFFD}',
            _ => c,
        })
        .collect();
    escape(&visible, XmlPlace::Attribute, XmlStyle::DECIMAL)
}

#[cfg(test)]
mod tests {
    #[test]
    fn html_shows_controls_and_escapes_markup_for_content_and_attributes() {
        assert_eq!(
            escape_html("<script>&'\"\u{0}\u{1B}\u{7F}\u{85}\u{FDD0}\n"),
            "&lt;script&gt;&amp;&apos;&quot;\u{2400}\u{241B}\u{2421}\u{FFFD}\u{FFFD}&#10;"
        );
    }

    use super::*;

    #[test]
    fn both_styles_escape_markup_and_differ_only_in_references_and_apostrophes() {
        let text = "a<b>&\"'\t\n\r\u{1}";
        assert_eq!(
            escape(text, XmlPlace::Attribute, XmlStyle::CANOPEN_EDITOR),
            "a&lt;b&gt;&amp;&quot;'&#x9;&#xA;&#xD;\u{FFFD}"
        );
        assert_eq!(
            escape(text, XmlPlace::Attribute, XmlStyle::DECIMAL),
            "a&lt;b&gt;&amp;&quot;&apos;&#9;&#10;&#13;\u{FFFD}"
        );
        assert_eq!(
            escape(text, XmlPlace::Content, XmlStyle::CANOPEN_EDITOR),
            "a&lt;b&gt;&amp;\"'\t\n&#xD;\u{FFFD}"
        );
        assert_eq!(
            escape(text, XmlPlace::Content, XmlStyle::DECIMAL),
            "a&lt;b&gt;&amp;\"'\t\n&#13;\u{FFFD}"
        );
    }
}
