//! A device description loaded from bytes in any format, with what loading found.

use std::fmt;

use canopener_eds::json::JsonError;
use canopener_eds::text::{Encoding, Unencodable, encode};
use canopener_eds::{Code, Diagnostic, DiagnosticCode, Document, Eds, Severity};
use canopener_xdd::{XddCode, XddError};
use serde::{Serialize, Serializer};

use crate::format::Format;

/// The code of a loading diagnostic: the EDS loader's `P` series or the XDD reader's `X` series.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum DescriptionCode {
    /// Found while loading EDS/DCF text.
    Eds(Code),
    /// Found while reading CiA 311 XML.
    Xdd(XddCode),
}

impl DiagnosticCode for DescriptionCode {
    fn as_str(self) -> &'static str {
        match self {
            Self::Eds(code) => code.as_str(),
            Self::Xdd(code) => code.as_str(),
        }
    }

    fn slug(self) -> &'static str {
        match self {
            Self::Eds(code) => code.slug(),
            Self::Xdd(code) => code.slug(),
        }
    }

    fn severity(self) -> Severity {
        match self {
            Self::Eds(code) => code.severity(),
            Self::Xdd(code) => code.severity(),
        }
    }
}

impl fmt::Display for DescriptionCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Serialize for DescriptionCode {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.as_str())
    }
}

/// A description that could not be read at all (loading EDS text never fails; it reports).
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// Not canopener's JSON form, or a version it cannot read.
    #[error(transparent)]
    Json(#[from] JsonError),
    /// Not a CiA 311 CANopen description (malformed XML, POWERLINK, several devices, ...).
    #[error(transparent)]
    Xdd(#[from] XddError),
}

/// A loaded device description.
#[derive(Debug, Clone)]
pub struct Description {
    /// The format it was read as.
    pub format: Format,
    /// The object dictionary and device information.
    pub eds: Eds,
    /// The lossless document, for EDS/DCF text (every byte kept, with line and column spans).
    pub document: Option<Document>,
    /// What loading found, in file order (nothing for the JSON form, which is canopener's own).
    pub diagnostics: Vec<Diagnostic<DescriptionCode>>,
}

impl Description {
    /// Loads a description, choosing the format by the file's extension and content
    /// ([`Format::detect`]). Only JSON and XML that cannot be read are errors.
    pub fn load(extension: Option<&str>, bytes: &[u8]) -> Result<Description, LoadError> {
        Self::load_as(Format::detect(extension, bytes), bytes)
    }

    /// Loads a description in a known format.
    pub fn load_as(format: Format, bytes: &[u8]) -> Result<Description, LoadError> {
        match format {
            Format::Json => Ok(Description {
                format,
                eds: canopener_eds::json::from_json(&String::from_utf8_lossy(bytes))?,
                document: None,
                diagnostics: Vec::new(),
            }),
            Format::Xdd => {
                let loaded = canopener_xdd::read(bytes)?;
                Ok(Description {
                    format,
                    eds: loaded.eds,
                    document: None,
                    diagnostics: loaded
                        .diagnostics
                        .into_iter()
                        .map(|d| d.map_code(DescriptionCode::Xdd))
                        .collect(),
                })
            }
            Format::Eds => {
                let loaded = canopener_eds::load(bytes);
                Ok(Description {
                    format,
                    eds: loaded.eds,
                    document: Some(loaded.document),
                    diagnostics: loaded
                        .diagnostics
                        .into_iter()
                        .map(|d| d.map_code(DescriptionCode::Eds))
                        .collect(),
                })
            }
        }
    }

    /// How many loading diagnostics have this severity.
    pub fn count(&self, severity: Severity) -> usize {
        self.diagnostics.iter().filter(|d| d.severity == severity).count()
    }

    /// `eds` as canonical CiA 306 text (`canopener eds fmt`), comments and values kept from this
    /// description's document, in its encoding: a Windows-1252 EDS stays Windows-1252; everything
    /// else is UTF-8 without a byte order mark.
    pub fn canonical_bytes(&self, eds: &Eds) -> Result<Vec<u8>, Unencodable> {
        let text = canopener_eds::write::to_canonical(eds, self.document.as_ref());
        let encoding = match self.document.as_ref().map(Document::encoding) {
            Some(Encoding::Windows1252) if self.format == Format::Eds => Encoding::Windows1252,
            _ => Encoding::Utf8,
        };
        encode(&text, encoding)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const EDS: &[u8] = b"[FileInfo]\nFileName=a.eds\n[FileInfo]\n[1000]\nParameterName=Device type\n";

    #[test]
    fn eds_text_keeps_its_document_and_reports_with_p_codes() {
        let d = Description::load(Some("eds"), EDS).expect("EDS loads");
        assert_eq!(d.format, Format::Eds);
        assert_eq!(
            d.document.as_ref().and_then(|doc| doc.to_bytes().ok()).as_deref(),
            Some(EDS)
        );
        let duplicate = d
            .diagnostics
            .iter()
            .find(|d| d.code == DescriptionCode::Eds(Code::DuplicateSection))
            .expect("the second [FileInfo] is reported");
        assert_eq!((duplicate.span.line, duplicate.code.as_str()), (3, "P020"));
        assert_eq!(
            d.count(Severity::Error),
            d.diagnostics
                .iter()
                .filter(|d| d.severity == Severity::Error)
                .count()
        );
    }

    #[test]
    fn xml_is_read_as_xdd_with_x_codes_and_refusals_are_errors() {
        let refused = Description::load(None, b"<notxdd/>").expect_err("not a device description");
        assert!(matches!(refused, LoadError::Xdd(_)), "{refused:?}");
        let eds = canopener_eds::load(EDS).eds;
        let xml = canopener_xdd::write(&eds, &canopener_xdd::WriteOptions::CANOPEN_EDITOR);
        let d = Description::load(Some("xdd"), xml.as_bytes()).expect("canopener reads what it writes");
        assert_eq!((d.format, d.document.is_none()), (Format::Xdd, true));
        assert!(
            d.diagnostics
                .iter()
                .all(|d| matches!(d.code, DescriptionCode::Xdd(_)))
        );
        assert!(d.eds.objects.contains_key(&0x1000));
    }

    #[test]
    fn json_round_trips_and_garbage_is_an_error() {
        let eds = canopener_eds::load(EDS).eds;
        let json = canopener_eds::json::to_json(&eds);
        let d = Description::load(Some("json"), json.as_bytes()).expect("canopener reads its JSON");
        assert_eq!((d.format, d.diagnostics.len()), (Format::Json, 0));
        assert_eq!(d.eds.objects.len(), eds.objects.len());
        let bad = Description::load(None, b"{ not json").expect_err("not JSON");
        assert!(matches!(bad, LoadError::Json(_)));
    }

    #[test]
    fn codes_serialise_and_display_as_their_string() {
        let code = DescriptionCode::Xdd(XddCode::NoAccess);
        assert_eq!((code.to_string(), code.slug()), ("X022".to_owned(), "no-access"));
        assert_eq!(code.severity(), XddCode::NoAccess.severity());
        assert_eq!(serde_json::to_string(&code).ok().as_deref(), Some("\"X022\""));
    }

    #[test]
    fn canonical_text_keeps_windows_1252_for_eds_only() {
        let latin = b"[FileInfo]\nDescription=Ger\xe4t\n";
        let d = Description::load(Some("eds"), latin).expect("EDS loads");
        let bytes = d
            .canonical_bytes(&d.eds)
            .expect("every character came from Windows-1252");
        assert!(bytes.windows(4).any(|w| w == b"Ger\xe4"), "{bytes:?}");
        let utf8 =
            Description::load(Some("eds"), "[FileInfo]\nDescription=Gerät\n".as_bytes()).expect("loads");
        let bytes = utf8.canonical_bytes(&utf8.eds).expect("UTF-8 encodes everything");
        assert!(String::from_utf8(bytes).is_ok_and(|t| t.contains("Gerät")));
    }
}
