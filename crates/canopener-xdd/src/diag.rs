//! Diagnostics produced while reading an XDD/XDC: the `X` series of stable codes, reported in the
//! shared [`Diagnostic`] shape of `canopener-eds` with a 1-based line/column in the XML text.
//!
//! Codes are stable across releases (tools and CI filters match on them). The `X` series belongs to
//! the XDD reader; the EDS loader uses the `P` series with the same shape and [`Severity`].

use canopener_eds::Diagnostic;
#[cfg(doc)]
use canopener_eds::Severity;

canopener_eds::diagnostic_codes! {
    /// The stable identity of an XDD reading diagnostic.
    pub enum XddCode {
    /// The root element is in no namespace (EdsDcfNet writes such files); CiA 311 files are not
    /// schema-valid that way, but the reader matches local names and reads it anyway.
    NoNamespace = "X001", "no-namespace", Warning;
    /// A CANopenEditor project wrapper (`.nxdd`); the single device inside was read.
    ProjectWrapper = "X002", "project-wrapper", Info;
    /// A profile, the object list or another part the reader needs is missing.
    MissingPart = "X003", "missing-part", Error;
    /// A `ProfileBody` without a CANopen `xsi:type`; its role was taken from its content.
    ProfileType = "X004", "profile-type", Warning;
    /// A `uniqueID` used twice; CiA 311 uses xsd:ID, unique in the document. The first is used.
    DuplicateUniqueId = "X005", "duplicate-unique-id", Error;
    /// A `uniqueIDRef` or `dataTypeIDRef` that names nothing (or the wrong kind of element).
    UnresolvedReference = "X006", "unresolved-reference", Error;
    /// An `index` or `subIndex` that is not a hex number in range; the entry is skipped.
    InvalidIndex = "X010", "invalid-index", Error;
    /// The same index or sub-index twice; the first one is used.
    DuplicateEntry = "X011", "duplicate-entry", Error;
    /// A hexBinary value with an unusual number of digits (`0000` for a subIndex, 8 digits for
    /// objFlags): valid xsd:hexBinary, but not the width CiA 311 writes.
    HexNotation = "X012", "hex-notation", Info;
    /// `subNumber` disagrees with the `CANopenSubObject` children; the children count. (The slug says
    /// `xml-` because the checker's registry already has P045 `sub-number-mismatch`.)
    SubNumberMismatch = "X013", "xml-sub-number-mismatch", Warning;
    /// A `CANopenObject` or `CANopenSubObject` without the required `name`.
    MissingName = "X014", "missing-name", Warning;
    /// A missing or unreadable `objectType`.
    InvalidObjectType = "X015", "invalid-object-type", Error;
    /// A number, hexBinary or ID attribute whose value is not of its CiA 311 schema type
    /// (xsd:hexBinary with `0x` or an odd number of digits, an unsignedByte written in hex or out of
    /// range, an ID that is no NCName). Read when the number is clear, else left out; never a default.
    SchemaType = "X016", "schema-type", Error;
    /// A `dataType` that is not a hex number, or an object whose data type cannot be determined.
    InvalidDataType = "X020", "invalid-data-type", Error;
    /// The object attribute and the referenced parameter say different things; the attribute is used.
    ConflictingValues = "X021", "conflicting-values", Warning;
    /// `access="noAccess"` has no CiA 306 access type; `AccessType` is left out.
    NoAccess = "X022", "no-access", Info;
    /// A token outside its CiA 311 vocabulary (accessType, access, PDOmapping, boolean, baud rate, ...):
    /// read when its meaning is clear (`rwr`, `TRUE`), else left out; never the schema default.
    UnknownToken = "X023", "unknown-token", Error;
    /// A `BITSTRING` parameter without an inline `dataType`: read as OCTET_STRING, or DOMAIN when it
    /// has no default value (the CANopenEditor convention).
    AmbiguousBitstring = "X024", "ambiguous-bitstring", Info;
    /// Data type, access, default, limits or PDO mapping on an ARRAY/RECORD object itself; CiA 306
    /// gives these keys to sub-objects only, so they are not carried into the EDS model.
    ParentValuesIgnored = "X025", "parent-values-ignored", Info;
    /// An OCTET_STRING or DOMAIN value written as space-separated bytes (`C8 3D BB`); joined as CiA
    /// 306 writes it (`C83DBB`).
    SpacedOctets = "X026", "spaced-octets", Info;
    /// A `fileCreationDate`/`Time` or modification date/time that is not xsd:date/xsd:time: a schema
    /// type broken, so an error like X016; a time whose meaning is clear (`9:48:42 PM`) is read.
    DateTimeNotation = "X030", "date-time-notation", Error;
    /// A vendor or product ID in a questionable notation, or two sources that disagree.
    IdNotation = "X031", "id-notation", Warning;
    /// A baud rate that has no CiA 306 key (`100 Kbps`, `auto-baudRate`).
    BaudRateWithoutKey = "X032", "baud-rate-without-key", Info;
    /// An attribute CiA 311 does not define (CANopenEditor extensions and the like).
    NonStandardAttribute = "X034", "non-standard-attribute", Info;
    /// A `deviceCommissioning` value that is not usable as written (node-ID outside 1..=127, ...).
    Commissioning = "X035", "commissioning", Warning;
    /// A `dummy@entry` outside `Dummy0001=0` ... `Dummy0007=1`, the schema's enumeration: an error
    /// like X023.
    InvalidDummy = "X036", "invalid-dummy", Error;
    /// `key=value|...` pairs in `productText` (a Faulhaber/libedssharp convention) mapped to EDS keys.
    PackedDescription = "X037", "packed-description", Info;
    /// Text with line breaks, which an EDS value cannot hold; joined with spaces.
    LineBreaks = "X038", "line-breaks", Info;
    /// `property` elements (CANopenNode's `CO_*` and others) that have no CiA 306 key.
    UnmappedProperties = "X039", "unmapped-properties", Info;
    /// An object CANopenNode marks `CO_disabled`: CANopenEditor leaves it out of the device and of its
    /// EDS export; the reader keeps it, as CiA 311 describes it.
    DisabledObject = "X040", "disabled-object", Info;
    /// A canopener side-channel property that could not be applied.
    SideChannel = "X041", "side-channel", Warning;
    /// A default or actual value outside the parameter's `allowedValues` (a `value` list or several
    /// ranges; a single range becomes LowLimit/HighLimit, which the EDS checks cover). The `X1xx`
    /// codes are checks only XML needs, found while reading because only the reader sees the XML.
    ValueNotAllowed = "X101", "value-not-allowed", Error;
    }
}

/// One finding about an XDD/XDC file: the shared diagnostic shape with an `X` code. Its span is the
/// 1-based line and column (in characters) of the element or attribute concerned, with length 0;
/// it names no section or key and has no help.
pub type XddDiagnostic = Diagnostic<XddCode>;

/// A finding before it has a position: the mapping functions report these and the reader places them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Note {
    pub code: XddCode,
    pub message: String,
}

impl Note {
    pub(crate) fn new(code: XddCode, message: impl Into<String>) -> Self {
        Self {
            code,
            message: message.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use canopener_eds::Span;

    use super::*;

    #[test]
    fn codes_are_unique_sorted_and_x_prefixed() {
        let names: Vec<&str> = XddCode::ALL.iter().map(|c| c.as_str()).collect();
        let mut sorted = names.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(names, sorted);
        assert!(names.iter().all(|n| n.starts_with('X') && n.len() == 4));
        let mut slugs: Vec<&str> = XddCode::ALL.iter().map(|c| c.slug()).collect();
        slugs.sort_unstable();
        slugs.dedup();
        assert_eq!(slugs.len(), XddCode::ALL.len());
    }

    #[test]
    fn lookup_and_display() {
        assert_eq!(XddCode::from_name("x013"), Some(XddCode::SubNumberMismatch));
        assert_eq!(XddCode::from_name("no-access"), Some(XddCode::NoAccess));
        assert_eq!(XddCode::from_name("X999"), None);
        let d = XddDiagnostic::new(XddCode::NoAccess, Span::new(3, 7, 0), "noAccess on 1001");
        assert_eq!(d.to_string(), "3:7: info[X022]: noAccess on 1001");
    }
}
