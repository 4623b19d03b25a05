//! Which format a description is written in.

/// The format a description is read as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// CiA 306 EDS or DCF text.
    Eds,
    /// CiA 311 XML: XDD, XDC, XPD, or a CANopenEditor project.
    Xdd,
    /// canopener's JSON form (`docs/eds-json.md`).
    Json,
}

impl Format {
    /// Decides the format by the file's extension (case-insensitive: `json`; `xdd`, `xdc`, `xpd`,
    /// `nxdd`, `xml`; `eds`, `dcf`), and otherwise by the first character that is not white space
    /// (after a UTF-8 byte order mark): `{` is JSON, `<` is XML, anything else is EDS text.
    pub fn detect(extension: Option<&str>, bytes: &[u8]) -> Format {
        let extension = extension.unwrap_or_default().to_ascii_lowercase();
        match extension.as_str() {
            "json" => return Format::Json,
            "xdd" | "xdc" | "xpd" | "nxdd" | "xml" => return Format::Xdd,
            "eds" | "dcf" => return Format::Eds,
            _ => {}
        }
        let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        match body.iter().find(|b| !b.is_ascii_whitespace()) {
            Some(b'{') => Format::Json,
            Some(b'<') => Format::Xdd,
            _ => Format::Eds,
        }
    }

    /// Whether a file is CiA 311 XML (XDD, XDC, XPD, a CANopenEditor project), by content first:
    /// XML whatever its extension when, after a UTF-8 byte order mark and white space, it starts
    /// with `<`, or when it starts with a UTF-16 byte order mark; otherwise by an XML extension.
    /// EDS text cannot start with `<`, so a mislabelled file is read as what it is.
    pub fn is_xml(extension: Option<&str>, bytes: &[u8]) -> bool {
        if bytes.starts_with(b"\xFF\xFE") || bytes.starts_with(b"\xFE\xFF") {
            return true;
        }
        let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        match body.iter().find(|b| !b.is_ascii_whitespace()) {
            Some(b'<') => true,
            Some(_) => false,
            None => Self::detect(extension, bytes) == Format::Xdd,
        }
    }

    /// The short name reports use: `eds`, `xdd` or `json`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Eds => "eds",
            Format::Xdd => "xdd",
            Format::Json => "json",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extension_decides_before_the_content() {
        assert_eq!(Format::detect(Some("XDC"), b"[FileInfo]"), Format::Xdd);
        assert_eq!(Format::detect(Some("eds"), b"<?xml"), Format::Eds);
        assert_eq!(Format::detect(Some("Json"), b""), Format::Json);
        assert_eq!(Format::detect(Some("nxdd"), b""), Format::Xdd);
    }

    #[test]
    fn without_a_known_extension_the_first_character_decides() {
        assert_eq!(Format::detect(None, b"\xEF\xBB\xBF \n{\"format\"}"), Format::Json);
        assert_eq!(
            Format::detect(Some("txt"), b"\r\n  <ISO15745ProfileContainer"),
            Format::Xdd
        );
        assert_eq!(Format::detect(Some(""), b"[FileInfo]\n"), Format::Eds);
        assert_eq!(Format::detect(None, b""), Format::Eds);
        assert_eq!(Format::detect(None, b"\xFF\xFE<"), Format::Eds);
    }

    #[test]
    fn xml_is_recognised_by_content_before_extension() {
        assert!(Format::is_xml(
            Some("eds"),
            b"\xEF\xBB\xBF\r\n<?xml version=\"1.0\"?>"
        ));
        assert!(Format::is_xml(None, b"\xFF\xFE<\0"));
        assert!(Format::is_xml(Some("XDC"), b""));
        assert!(!Format::is_xml(Some("xdd"), b"[FileInfo]\n"));
        assert!(!Format::is_xml(Some("eds"), b""));
        assert!(!Format::is_xml(None, b"{\"format\": 1}"));
    }

    #[test]
    fn names_are_lowercase() {
        let names: Vec<&str> = [Format::Eds, Format::Xdd, Format::Json]
            .map(Format::name)
            .to_vec();
        assert_eq!(names, ["eds", "xdd", "json"]);
    }
}
