//! The diagnostic vocabulary of every canopener reader and checker: a stable code, a severity, a
//! message, a span, the section and key concerned, and help.
//!
//! Codes are stable across releases (tools and CI filters match on them). Each series is an enum
//! made by [`diagnostic_codes!`](crate::diagnostic_codes): loading diagnostics use the `P` series
//! ([`Code`]), the XDD reader the `X` series; the checker's own codes and user rule ids are strings
//! in the same [`Diagnostic`] shape.

use std::fmt;

use serde::{Deserialize, Serialize};

/// How serious a finding is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    /// A hint about portability or style; the file is fine per CiA 306.
    Info,
    /// Allowed or tolerated, but likely to cause trouble.
    Warning,
    /// The file departs from CiA 306.
    Error,
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Info => "info",
            Self::Warning => "warning",
            Self::Error => "error",
        })
    }
}

/// A place in the source text: 1-based line and column (in characters), and a length in characters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
pub struct Span {
    /// 1-based line number.
    pub line: u32,
    /// 1-based column of the first character.
    pub column: u32,
    /// Number of characters covered (0 for a point).
    pub len: u32,
}

impl Span {
    /// A span covering `len` characters from `column` on `line`.
    pub fn new(line: u32, column: u32, len: u32) -> Self {
        Self { line, column, len }
    }
}

/// What every series of diagnostic codes says about each of its codes: the loader's `P` series
/// ([`Code`]), the XDD reader's `X` series, and any other series defined with
/// [`diagnostic_codes!`](crate::diagnostic_codes).
pub trait DiagnosticCode: Copy + fmt::Debug + fmt::Display {
    /// The stable code, e.g. `P020`.
    fn as_str(self) -> &'static str;
    /// A short kebab-case name, e.g. `duplicate-section`.
    fn slug(self) -> &'static str;
    /// The severity this code is reported with.
    fn severity(self) -> Severity;
}

/// Defines a series of stable diagnostic codes: an enum with one variant per code, its `ALL` list,
/// `as_str`, `slug`, `severity` and `from_name`, `Display` and `Serialize` as the code string, and
/// [`DiagnosticCode`]. Each line reads `Variant = "P020", "slug", Severity;` after its doc comment.
#[macro_export]
macro_rules! diagnostic_codes {
    (
        $(#[$enum_doc:meta])* $vis:vis enum $name:ident {
            $($(#[$doc:meta])* $variant:ident = $code:literal, $slug:literal, $severity:ident;)*
        }
    ) => {
        $(#[$enum_doc])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        $vis enum $name {
            $($(#[$doc])* $variant,)*
        }

        impl $name {
            /// Every code, in numeric order.
            pub const ALL: &'static [$name] = &[$($name::$variant,)*];

            /// The stable code, e.g. `P020`.
            pub fn as_str(self) -> &'static str {
                match self { $($name::$variant => $code,)* }
            }

            /// A short kebab-case name, e.g. `duplicate-section`.
            pub fn slug(self) -> &'static str {
                match self { $($name::$variant => $slug,)* }
            }

            /// The severity this code is reported with.
            pub fn severity(self) -> $crate::diag::Severity {
                match self { $($name::$variant => $crate::diag::Severity::$severity,)* }
            }

            /// Looks a code up by its stable string (case-insensitive) or its slug.
            pub fn from_name(name: &str) -> Option<$name> {
                $name::ALL.iter().copied().find(|c| c.as_str().eq_ignore_ascii_case(name) || c.slug() == name)
            }
        }

        impl $crate::diag::DiagnosticCode for $name {
            fn as_str(self) -> &'static str {
                $name::as_str(self)
            }

            fn slug(self) -> &'static str {
                $name::slug(self)
            }

            fn severity(self) -> $crate::diag::Severity {
                $name::severity(self)
            }
        }

        impl ::std::fmt::Display for $name {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl $crate::serde::Serialize for $name {
            fn serialize<S: $crate::serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                serializer.serialize_str(self.as_str())
            }
        }
    };
}

crate::diagnostic_codes! {
    /// The stable identity of a loading diagnostic.
    pub enum Code {
    /// The file is not valid UTF-8 and was decoded as Windows-1252 (CiA 306 §4.2 wants ASCII).
    Windows1252 = "P001", "windows-1252-fallback", Error;
    /// The file starts with a UTF-8 byte order mark, which python canopen and lely cannot read.
    ByteOrderMark = "P002", "utf8-bom", Error;
    /// The file mixes LF and CR/LF line endings.
    MixedLineEndings = "P003", "mixed-line-endings", Info;
    /// A bare CR ends a line; CiA 306 §4.2 allows only LF or CR/LF.
    BareCarriageReturn = "P004", "bare-carriage-return", Warning;
    /// A `[` header that is not closed, or text after the `]`.
    MalformedSectionHeader = "P010", "malformed-section-header", Error;
    /// A line that is neither blank, a comment, a section header nor `key=value`.
    NotAnEntry = "P011", "not-an-entry", Error;
    /// A section header or key that does not start in column 1.
    Indented = "P012", "indented-line", Error;
    /// White space between a key and its `=` (CiA 306 §4.2: the key is immediately followed by `=`).
    SpaceBeforeEquals = "P013", "space-before-equals", Warning;
    /// A comment that does not start with `;` in column 1.
    NonStandardComment = "P014", "non-standard-comment", Warning;
    /// An entry before the first section header.
    EntryOutsideSection = "P015", "entry-outside-section", Error;
    /// A key containing characters other than letters, digits and `_`.
    UnusualKey = "P016", "unusual-key", Warning;
    /// The same section appears twice (names compare case-insensitively); the first one is used.
    DuplicateSection = "P020", "duplicate-section", Error;
    /// The same key appears twice in a section; the first value is used.
    DuplicateKey = "P021", "duplicate-key", Error;
    /// A section CiA 306 makes mandatory is missing (`[FileInfo]`, `[DeviceInfo]`, `[MandatoryObjects]`).
    MissingSection = "P029", "missing-section", Error;
    /// A section name CiA 306 does not define; it is kept as it is.
    UnknownSection = "P030", "unknown-section", Warning;
    /// A section name that is valid but spelt differently from the spec (`sub01`, `SUB`, `DeviceCommissioning`).
    NonCanonicalSectionName = "P031", "non-canonical-section-name", Warning;
    /// A known key spelt with different letter case (`NrOfRxPdo`).
    KeyCase = "P032", "key-case", Info;
    /// A key CiA 306 does not define for this section; it is kept as it is.
    UnknownKey = "P033", "unknown-key", Info;
    /// A key CiA 306 reserves for compatibility (`ProductVersion`, `LMT_ManufacturerName`, ...).
    ReservedKey = "P034", "reserved-key", Warning;
    /// A `[xxxxsubN]` section whose object `[xxxx]` does not exist.
    OrphanSubObject = "P040", "orphan-sub-object", Error;
    /// A `[xxxxName]`, `[xxxxValue]`, `[xxxxDenotation]` or `[xxxxObjectLinks]` section without its object.
    OrphanCompanion = "P041", "orphan-companion-section", Error;
    /// An object list names an index that has no section.
    ListedObjectMissing = "P042", "listed-object-missing", Error;
    /// An object section that no object list names.
    UnlistedObject = "P043", "unlisted-object", Error;
    /// An object list entry that is not an index, or a list whose count disagrees with its entries.
    MalformedObjectList = "P044", "malformed-object-list", Error;
    /// `SubNumber` disagrees with the sub-object sections present.
    SubNumberMismatch = "P045", "sub-number-mismatch", Error;
    /// A companion section entry (`[xxxxName]`, `[xxxxValue]`) outside 1..=CompactSubObj or not decimal.
    CompactEntryOutOfRange = "P046", "compact-entry-out-of-range", Error;
    /// A number that is not decimal, `0x` hexadecimal or `0` octal (CiA 306 §4.2).
    InvalidNumber = "P050", "invalid-number", Error;
    /// A number with a leading zero, which CiA 306 reads as octal (`0254` = 172).
    OctalLeadingZero = "P051", "octal-leading-zero", Warning;
    /// A hexadecimal number written with an `h` suffix (`FEh`); read as hexadecimal.
    HexSuffix = "P052", "hex-suffix", Error;
    /// Text after a `;` or `#` in a value; CiA 306 has no inline comments, canopener ignored it.
    InlineComment = "P053", "inline-comment", Warning;
    /// A value outside the range of its data type.
    OutOfRange = "P054", "value-out-of-range", Error;
    /// A signed value written as an unsigned bit pattern (`0x8000` for INTEGER16), read as two's complement.
    TwosComplement = "P055", "twos-complement", Warning;
    /// A `$NODEID` formula not in the form `$NODEID+offset`: `$NODEID` not first, or several offsets (CiA 306 §4.2).
    NodeIdFormula = "P056", "nodeid-formula", Error;
    /// A `$NODEID` formula on an entry that is not an integer.
    NodeIdOnNonInteger = "P057", "nodeid-on-non-integer", Error;
    /// A REAL written in a notation other tools misread (decimal vs IEEE 754 bit pattern).
    RealNotation = "P058", "real-notation", Info;
    /// Octet string or DOMAIN data that is not an even number of hex digits.
    InvalidOctets = "P059", "invalid-octets", Error;
    /// A boolean that is not `0` or `1`.
    InvalidBoolean = "P060", "invalid-boolean", Error;
    /// A value not valid for its data type (e.g. `0.5` for UNSIGNED32).
    InvalidValue = "P061", "invalid-value", Error;
    /// `$NODEID+offset` written with spaces or in other letter case; understood, but not every tool does.
    NodeIdSpelling = "P062", "nodeid-spelling", Info;
    /// An ObjectType code that CiA 306 does not define.
    UnknownObjectType = "P070", "unknown-object-type", Error;
    /// A DataType that is neither a CiA 301 type nor defined in the file.
    UnknownDataType = "P071", "unknown-data-type", Error;
    /// An AccessType other than ro, wo, rw, rwr, rww and const.
    UnknownAccessType = "P072", "unknown-access-type", Error;
    /// A key the object type requires is missing (CiA 306 §4.6.3.2 table).
    MissingKey = "P073", "missing-key", Error;
    /// `CompactSubObj` that cannot be applied (not a number, > 254, on a VAR, together with SubNumber).
    InvalidCompactSubObj = "P074", "invalid-compact-sub-obj", Error;
    /// A PDO communication object without its mapping object, or the reverse.
    PdoPairIncomplete = "P080", "pdo-pair-incomplete", Error;
    /// A module section (`M<x>...`) whose number is not declared in `[SupportedModules]`.
    UnlistedModule = "P090", "unlisted-module", Error;
    }
}

/// One thing a reader or checker found in a file: which code, how serious, what, where, and how to
/// fix it. Every series shares this shape: `Diagnostic` (the loader's `P` codes),
/// `canopener_xdd::XddDiagnostic` (`X` codes), and the checker's findings, whose codes are check
/// codes or rule ids (`Diagnostic<String>`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Diagnostic<C = Code> {
    /// The stable code.
    pub code: C,
    /// The severity (normally that of the code).
    pub severity: Severity,
    /// What is wrong, naming the value as written.
    pub message: String,
    /// Where it is.
    pub span: Span,
    /// The section name as written, if the finding is inside one.
    pub section: Option<String>,
    /// The key as written, if the finding is about an entry.
    pub key: Option<String>,
    /// How to fix it, when there is something to say.
    pub help: Option<String>,
}

impl<C: DiagnosticCode> Diagnostic<C> {
    /// A diagnostic with the code's default severity.
    pub fn new(code: C, span: Span, message: impl Into<String>) -> Self {
        Self::from_parts(code, code.severity(), span, message)
    }

    /// The same diagnostic with its code as a string, for lists that mix series (checker findings,
    /// rule-pack findings).
    pub fn into_string_code(self) -> Diagnostic<String> {
        self.map_code(|code| code.as_str().to_owned())
    }
}

impl<C> Diagnostic<C> {
    /// A diagnostic with an explicit severity (for codes that carry none themselves, such as rule ids).
    pub fn from_parts(code: C, severity: Severity, span: Span, message: impl Into<String>) -> Self {
        Self {
            code,
            severity,
            message: message.into(),
            span,
            section: None,
            key: None,
            help: None,
        }
    }

    /// The same diagnostic with its code turned into another type (a series wrapped in a wider one).
    pub fn map_code<D>(self, f: impl FnOnce(C) -> D) -> Diagnostic<D> {
        Diagnostic {
            code: f(self.code),
            severity: self.severity,
            message: self.message,
            span: self.span,
            section: self.section,
            key: self.key,
            help: self.help,
        }
    }

    /// Adds the section and key the finding is about.
    pub fn at(mut self, section: Option<&str>, key: Option<&str>) -> Self {
        self.section = section.map(str::to_owned);
        self.key = key.map(str::to_owned);
        self
    }

    /// Adds a help line.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }
}

impl<C: fmt::Display> fmt::Display for Diagnostic<C> {
    /// `line:column: severity[code]: message`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}: {}[{}]: {}",
            self.span.line, self.span.column, self.severity, self.code, self.message
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_and_sorted() {
        let names: Vec<&str> = Code::ALL.iter().map(|c| c.as_str()).collect();
        let mut sorted = names.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(names, sorted);
        let mut slugs: Vec<&str> = Code::ALL.iter().map(|c| c.slug()).collect();
        slugs.sort_unstable();
        slugs.dedup();
        assert_eq!(slugs.len(), Code::ALL.len());
    }

    #[test]
    fn lookup_by_code_or_slug() {
        assert_eq!(Code::from_name("p020"), Some(Code::DuplicateSection));
        assert_eq!(Code::from_name("duplicate-key"), Some(Code::DuplicateKey));
        assert_eq!(Code::from_name("P999"), None);
    }
}
