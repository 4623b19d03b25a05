//! Why a file could not be read as a CANopen XDD/XDC at all.
//!
//! Anything the reader can work around is a diagnostic instead; these errors mean there is no
//! CANopen device description to build a model from.

use thiserror::Error;

/// A file that is not a readable CANopen CiA 311 device description.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum XddError {
    /// The bytes are not text in an encoding the reader knows.
    #[error("{line}:{column}: the file is not valid {encoding} text; save it as UTF-8")]
    Encoding {
        /// The encoding the file declares or that was assumed.
        encoding: String,
        /// 1-based line of the first undecodable byte.
        line: u32,
        /// 1-based column of the first undecodable byte.
        column: u32,
    },
    /// The XML is malformed.
    #[error(
        "{line}:{column}: malformed XML: {message}; fix the XML syntax (an XML editor or `xmllint` shows it)"
    )]
    Xml {
        /// What the XML parser found.
        message: String,
        /// 1-based line.
        line: u32,
        /// 1-based column.
        column: u32,
    },
    /// An Ethernet POWERLINK device description (EPSG DS 311), which shares the ISO 15745 root.
    #[error(
        "this is an Ethernet POWERLINK XDD (EPSG DS 311), not a CANopen CiA 311 device description: \
         {evidence}; use a POWERLINK tool for it"
    )]
    Powerlink {
        /// What gave it away (namespace, profile type or technology), as written.
        evidence: String,
    },
    /// The root element is not `ISO15745ProfileContainer` (or a CANopenEditor project wrapper).
    #[error(
        "{line}:{column}: root element `{root}` is not a CiA 311 `ISO15745ProfileContainer`; \
         this is not an XDD/XDC file"
    )]
    NotXdd {
        /// The root element name as written.
        root: String,
        /// 1-based line.
        line: u32,
        /// 1-based column.
        column: u32,
    },
    /// The root element is in a namespace that is neither CiA 311 v1.0 nor v1.1.
    #[error(
        "root element is in namespace `{namespace}`, which is not CiA 311 (`http://www.canopen.org/xml/1.0` \
         or `http://www.canopen.org/xml/1.1`); this looks like another XML dialect, not an XDD"
    )]
    ForeignNamespace {
        /// The namespace URI found.
        namespace: String,
    },
    /// A profile declares a technology other than CANopen.
    #[error("{line}:{column}: profile technology `{technology}` is not CANopen; this is not a CiA 311 XDD")]
    NotCanopen {
        /// The `ProfileTechnology` or profile type as written.
        technology: String,
        /// 1-based line.
        line: u32,
        /// 1-based column.
        column: u32,
    },
    /// A CANopenEditor project wrapper without any device in it.
    #[error(
        "the CANopenEditor project `{root}` contains no ISO15745ProfileContainer, so there is no device to read"
    )]
    EmptyProject {
        /// The wrapper element name.
        root: String,
    },
    /// A CANopenEditor project wrapper with several devices, read with the single-device reader.
    #[error(
        "the CANopenEditor project `{root}` contains {count} devices; use `read_project` to read all of \
         them, or save each device as its own XDD"
    )]
    SeveralDevices {
        /// The wrapper element name.
        root: String,
        /// How many `ISO15745ProfileContainer` elements it holds.
        count: usize,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_are_lowercase_and_say_what_to_do() {
        let e = XddError::Powerlink {
            evidence: "namespace `http://www.ethernet-powerlink.org`".into(),
        };
        let text = e.to_string();
        assert!(text.starts_with("this is an Ethernet POWERLINK XDD (EPSG DS 311), not a CANopen CiA 311"));
        assert!(!text.ends_with('.'));
        let e = XddError::Xml {
            message: "unexpected end of stream".into(),
            line: 3,
            column: 9,
        };
        assert_eq!(
            e.to_string(),
            "3:9: malformed XML: unexpected end of stream; fix the XML syntax (an XML editor or `xmllint` shows it)"
        );
    }
}
