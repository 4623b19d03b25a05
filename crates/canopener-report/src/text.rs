//! Text helpers shared by the formats: escaping, source snippets, URIs and a stable hash.

use std::fmt::Write as _;

use canopener_eds::xml_text::{XmlPlace, XmlStyle, escape};

/// Tab stops used when showing a source line (tabs are expanded so carets line up).
const TAB_WIDTH: usize = 4;

/// A source line prepared for display: tabs expanded, control characters replaced, split around the
/// span, with the caret position in display columns.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Snippet {
    /// Text before the span.
    pub(crate) before: String,
    /// The text the span covers (empty for a point or a span past the end of the line).
    pub(crate) marked: String,
    /// Text after the span.
    pub(crate) after: String,
    /// Display columns before the first caret.
    pub(crate) caret_offset: usize,
    /// Number of carets (at least one).
    pub(crate) caret_width: usize,
}

impl Snippet {
    /// The whole line as displayed.
    pub(crate) fn line(&self) -> String {
        format!("{}{}{}", self.before, self.marked, self.after)
    }
}

/// Prepares `line` for display with a caret under `len` characters from the 1-based `column`
/// (columns count characters, as [`canopener_eds::Span`] does).
pub(crate) fn snippet(line: &str, column: u32, len: u32) -> Snippet {
    let start = usize::try_from(column.max(1) - 1).unwrap_or(usize::MAX);
    let end = start.saturating_add(usize::try_from(len).unwrap_or(usize::MAX));
    let (mut before, mut marked, mut after) = (String::new(), String::new(), String::new());
    let mut width = 0usize;
    let mut caret_offset = None;
    let mut caret_end = None;
    for (i, c) in line.chars().enumerate() {
        if i == start {
            caret_offset = Some(width);
        }
        if i == end {
            caret_end = Some(width);
        }
        let target = if i < start {
            &mut before
        } else if i < end {
            &mut marked
        } else {
            &mut after
        };
        if c == '\t' {
            let spaces = TAB_WIDTH - width % TAB_WIDTH;
            target.extend(std::iter::repeat_n(' ', spaces));
            width += spaces;
        } else {
            target.push(visible(c));
            width += 1;
        }
    }
    // A span starting at or past the end of the line points just after its last character (also
    // keeps a bogus huge column from producing a huge line of spaces).
    let caret_offset = caret_offset.unwrap_or(width);
    let caret_end = caret_end.unwrap_or(width);
    let caret_width = caret_end.saturating_sub(caret_offset).max(1);
    Snippet {
        before,
        marked,
        after,
        caret_offset,
        caret_width,
    }
}

/// Whether a character is a control character that must not reach a terminal or a markup file.
fn is_control(c: char) -> bool {
    c.is_control() && c != '\t' && c != '\n'
}

/// Replaces a control character by U+FFFD so file content cannot drive the terminal.
fn visible(c: char) -> char {
    if c.is_control() { '\u{FFFD}' } else { c }
}

/// Text from a file or a message made safe for a terminal: control characters other than tab and
/// newline become U+FFFD.
pub(crate) fn terminal_safe(text: &str) -> String {
    text.chars()
        .map(|c| if is_control(c) { '\u{FFFD}' } else { c })
        .collect()
}

/// Escapes text for XML element content or (`attribute`) a quoted attribute value, with the decimal
/// references and `&apos;` JUnit reports have always had (the escaper is the one the XDD writer uses,
/// in its other style).
pub(crate) fn xml_escape(text: &str, attribute: bool) -> String {
    let place = if attribute {
        XmlPlace::Attribute
    } else {
        XmlPlace::Content
    };
    escape(text, place, XmlStyle::DECIMAL)
}

/// Percent-encodes everything but RFC 3986 unreserved characters and the characters in `keep`.
pub(crate) fn percent_encode(text: &str, keep: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_ascii_alphanumeric() || matches!(c, '-' | '.' | '_' | '~') || keep.contains(c) {
            out.push(c);
        } else {
            let mut buf = [0u8; 4];
            for byte in c.encode_utf8(&mut buf).bytes() {
                // Writing to a String cannot fail.
                let _ = write!(out, "%{byte:02X}");
            }
        }
    }
    out
}

/// A path as a URI reference: forward slashes, a relative path stays relative (without a leading
/// `./`), an absolute path becomes a `file://` URI; everything else is percent-encoded.
pub(crate) fn path_uri(path: &str) -> String {
    let slashed = path.replace('\\', "/");
    if matches!(slashed.as_bytes(), [d, b':', b'/', ..] if d.is_ascii_alphabetic()) {
        // `C:/dir/file.eds`: the colon after a drive letter is allowed in a file URI path.
        return format!("file:///{}", percent_encode(&slashed, "/:"));
    }
    if let Some(rest) = slashed.strip_prefix("//") {
        // A UNC path `//server/share/file.eds`.
        return format!("file://{}", percent_encode(rest, "/"));
    }
    if slashed.starts_with('/') {
        return format!("file://{}", percent_encode(&slashed, "/"));
    }
    let mut relative = slashed.as_str();
    while let Some(rest) = relative.strip_prefix("./") {
        relative = rest;
    }
    percent_encode(relative, "/")
}

/// 64-bit FNV-1a: a small hash that is stable across Rust versions and platforms (unlike
/// `DefaultHasher`), for fingerprints that must not change between releases.
pub(crate) fn fnv1a64(parts: &[&str]) -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for part in parts {
        // Prefix each part with its length so ("ab", "c") and ("a", "bc") differ.
        for byte in (part.len() as u64).to_le_bytes().iter().chain(part.as_bytes()) {
            hash ^= u64::from(*byte);
            hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    hash
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snippet_puts_carets_under_the_span() {
        let s = snippet("VendorNumber=0x123", 14, 5);
        assert_eq!(s.before, "VendorNumber=");
        assert_eq!(s.marked, "0x123");
        assert_eq!(s.after, "");
        assert_eq!((s.caret_offset, s.caret_width), (13, 5));
    }

    #[test]
    fn snippet_point_and_past_the_end() {
        let point = snippet("[1018]", 1, 0);
        assert_eq!((point.caret_offset, point.caret_width), (0, 1));
        assert_eq!(point.marked, "");
        let past = snippet("Key=", 6, 3);
        assert_eq!((past.caret_offset, past.caret_width), (4, 1));
        let far = snippet("Key=", u32::MAX, u32::MAX);
        assert_eq!((far.caret_offset, far.caret_width), (4, 1));
        assert_eq!(past.line(), "Key=");
        let empty = snippet("", 1, 0);
        assert_eq!((empty.caret_offset, empty.caret_width), (0, 1));
    }

    #[test]
    fn snippet_expands_tabs_and_hides_control_characters() {
        let s = snippet("\tA=\u{1b}[31mX", 4, 1);
        assert_eq!(s.before, "    A=");
        assert_eq!(s.marked, "\u{FFFD}");
        assert_eq!((s.caret_offset, s.caret_width), (6, 1));
        let wide = snippet("a\tb", 2, 1);
        assert_eq!((wide.caret_offset, wide.caret_width), (1, 3));
    }

    #[test]
    fn snippet_counts_characters_not_bytes() {
        let s = snippet("Name=Ölpumpe Größe", 14, 5);
        assert_eq!(s.marked, "Größe");
        assert_eq!((s.caret_offset, s.caret_width), (13, 5));
    }

    #[test]
    fn xml_escape_handles_markup_quotes_and_forbidden_characters() {
        assert_eq!(xml_escape("a<b>&\"'", true), "a&lt;b&gt;&amp;&quot;&apos;");
        assert_eq!(xml_escape("a<b>&\"'", false), "a&lt;b&gt;&amp;\"'");
        assert_eq!(xml_escape("x\u{1}\u{FFFE}y", false), "x\u{FFFD}\u{FFFD}y");
        assert_eq!(xml_escape("a\nb\tc", true), "a&#10;b&#9;c");
        assert_eq!(xml_escape("a\nb", false), "a\nb");
    }

    #[test]
    fn path_uri_forms() {
        assert_eq!(path_uri("eds/dev ice.eds"), "eds/dev%20ice.eds");
        assert_eq!(path_uri(".\\eds\\Gerät#1.eds"), "eds/Ger%C3%A4t%231.eds");
        assert_eq!(path_uri("/home/u/a.eds"), "file:///home/u/a.eds");
        assert_eq!(path_uri("C:\\x\\a.eds"), "file:///C:/x/a.eds");
        assert_eq!(path_uri("\\\\srv\\share\\a.eds"), "file://srv/share/a.eds");
        assert_eq!(path_uri("a:b.eds"), "a%3Ab.eds");
    }

    #[test]
    fn fnv_is_stable_and_separates_parts() {
        assert_eq!(fnv1a64(&[]), 0xcbf2_9ce4_8422_2325);
        assert_ne!(fnv1a64(&["ab", "c"]), fnv1a64(&["a", "bc"]));
        assert_eq!(fnv1a64(&["C301", "x"]), fnv1a64(&["C301", "x"]));
    }
}
