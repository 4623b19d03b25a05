//! What each portability check is. The tool behaviour every explanation cites was observed by running
//! the quirk matrix of `canopen-tools-survey.md` §1c (python canopen 2.4.1, Lely dcfchk 2.4.0,
//! canopen-host 0.6.1, libEDSsharp main) or read in the parsers' sources (`eds-format-and-checks.md`
//! §11).
//!
//! Severity policy: Warning when a tool crashes, rejects the file or silently reads something else
//! than CiA 306 means; Info when the difference is cosmetic or only a diagnostic.

use canopener_eds::Severity;

use crate::check_info::{CheckInfo, Group};

const fn warning(
    code: &'static str,
    slug: &'static str,
    title: &'static str,
    reference: &'static [u8],
    spec: &'static str,
    explanation: &'static str,
) -> CheckInfo {
    CheckInfo {
        code,
        slug,
        severity: Severity::Warning,
        group: Group::Portability,
        title,
        reference,
        spec,
        explanation,
        fixable: false,
    }
}

const fn info(
    code: &'static str,
    slug: &'static str,
    title: &'static str,
    reference: &'static [u8],
    spec: &'static str,
    explanation: &'static str,
) -> CheckInfo {
    CheckInfo {
        severity: Severity::Info,
        ..warning(code, slug, title, reference, spec, explanation)
    }
}

pub(super) const COMPACT_UNNAMED: CheckInfo = warning(
    "T001",
    "compact-sub-obj-partly-created",
    "a CompactSubObj array whose sub-objects python canopen does not all create",
    &[41, 42],
    "CiA 306 V1.3 §4.6.3.4.2",
    "\
An ARRAY with CompactSubObj=n has the sub-objects 0..n, and [<index>Name] may rename some of them \
(CiA 306 §4.6.3.4.2). This check reports a compact array that python canopen will not build \
completely: without a [<index>Name] section it creates only sub 0 (default None) and sub 1; with \
one it creates the subs up to NrOfEntries. The other sub-indices appear only when accessed, named \
<name>_<hex>.

The other tools differ too: canopen-host 0.6.1 reads the array as a single VAR; CANopenEditor \
creates all n subs but names them <name>01, <name>02 in hex instead of the spec's <name>1, \
<name>2; Lely creates them as CiA 306 says.

It is a warning because python canopen silently builds a different dictionary (a sub 0 without a \
value, sub-objects missing from iteration and export). The file itself is valid.

Fix: if python canopen must read the file, describe the sub-objects explicitly with SubNumber and \
[<index>sub<n>] sections.",
);

pub(super) const COMPACT_NAMES_GAP: CheckInfo = warning(
    "T002",
    "compact-names-gap",
    "a sparse [<index>Name] section, on which python canopen crashes",
    &[42],
    "CiA 306 V1.3 §4.6.3.4.2",
    "\
CiA 306 §4.6.3.4.2 lets [<index>Name] rename only some sub-objects: its own example lists the \
entries 1, 2 and 15 with NrOfEntries=3. This check reports a names section in which an entry \
1..NrOfEntries is missing.

python canopen 2.4.1 reads the entries 1..NrOfEntries one after the other and crashes on the first \
missing one (NoOptionError). Lely reads sparse names; canopen-host 0.6.1 and CANopenEditor ignore \
the names.

It is a warning because the whole import fails in python canopen, although the file is valid.

Fix: list the entries 1..NrOfEntries without gaps (repeat the default name <name><n> where you do \
not want a different one).",
);

pub(super) const LEADING_ZERO: CheckInfo = warning(
    "T003",
    "leading-zero-number",
    "a number with a leading zero, which every tool reads differently",
    &[7],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 §4.2 reads a number with a leading 0 as octal: 012 is 10 and 0254 is 172. This check \
reports integers written with a leading zero in keys that the tools read as numbers.

The tools disagree: Lely's loader and CANopenEditor read octal as the spec says; canopen-host \
0.6.1 reads decimal (0254 is 254); python canopen 2.4.1 cannot read it, because Python's int(x, 0) \
rejects leading zeros (a DefaultValue silently becomes None, a DataType makes the import fail); \
Lely dcfchk 2.4.0 crashes with a ValueError on such a value.

It is a warning because one file means different values, or nothing, depending on the tool. Zero \
padding such as 001 is the usual cause: the writer meant decimal.

Fix: write the number without leading zeros, in decimal or with 0x (0254 meant as decimal is 254 \
or 0xFE).",
);

pub(super) const NODEID_SUFFIX: CheckInfo = warning(
    "T004",
    "nodeid-suffix",
    "a $NODEID formula with the node-ID last, which Lely rejects",
    &[47],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 §4.2 writes a node-ID-relative value as $NODEID+offset, with $NODEID first. This check \
reports the reversed form offset+$NODEID (the loader reports it as P056).

python canopen 2.4.1 and CANopenEditor accept both orders; Lely dcfchk 2.4.0 rejects the value as \
invalid. canopen-host 0.6.1 reads both orders alike.

It is a warning because Lely's tools refuse the file, while others read the intended value.

Fix: write $NODEID+0x180 instead of 0x180+$NODEID.",
);

pub(super) const NODEID_COMPOUND: CheckInfo = warning(
    "T005",
    "nodeid-compound",
    "a $NODEID formula with several terms, which python canopen reads as None",
    &[47],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 §4.2 allows exactly one offset: $NODEID+offset. This check reports formulas with more \
terms, such as 0x40000000+$NODEID+0x180 or $NODEID+0x100+0x80 (the loader reports them as P056).

python canopen 2.4.1 strips $NODEID and one '+' and then fails to read the rest, so the value \
silently becomes None; Lely rejects it; canopen-host 0.6.1 adds all terms; CANopenEditor keeps the \
text on load and would reject it when exporting.

It is a warning because the same file gives a value, no value or an error depending on the tool.

Fix: add the constant terms up and write a single offset: $NODEID+0x40000180.",
);

pub(super) const DUMMY_USAGE_PARTIAL: CheckInfo = warning(
    "T006",
    "dummy-usage-partial",
    "a [DummyUsage] section without all of Dummy0001..Dummy0007, on which python canopen crashes",
    &[21],
    "CiA 306 V1.3 §4.6.2",
    "\
[DummyUsage] says which data types may be mapped as dummy entries (CiA 306 §4.6.2). This check \
reports a [DummyUsage] section in which one of Dummy0001..Dummy0007 is missing, spelt in other \
letter case, or not a plain decimal number.

python canopen 2.4.1 reads the seven keys with getint and no fallback, matching keys \
case-sensitively, so the import crashes (NoOptionError or ValueError). Lely, canopen-host 0.6.1 \
and CANopenEditor read such a file.

It is a warning because the whole import fails in python canopen.

Fix: list all seven keys Dummy0001..Dummy0007 with the value 0 or 1.",
);

pub(super) const DUPLICATE_SECTION: CheckInfo = warning(
    "T007",
    "duplicate-section-tools",
    "a repeated section, which tools crash on or merge differently",
    &[4],
    "CiA 306 V1.3 §4.2",
    "\
A section name must appear once (CiA 306 §4.2; the loader reports repeats as P020 and keeps the \
first). This check says what other tools do with a repeated section.

python canopen 2.4.1 crashes (DuplicateSectionError) when the name is spelt the same, and reads \
two different sections when only the letter case differs; Lely dcfchk 2.4.0 crashes; Lely's loader \
and canopen-host 0.6.1 merge the sections, so later values win; CANopenEditor warns and keeps the \
first.

It is a warning because the tools crash or build different dictionaries from one file.

Fix: merge the two sections into one and keep the value that is meant.",
);

pub(super) const DUPLICATE_KEY: CheckInfo = warning(
    "T008",
    "duplicate-key-tools",
    "a repeated key, which tools crash on or resolve differently",
    &[4],
    "CiA 306 V1.3 §4.2",
    "\
A key must appear once per section (CiA 306 §4.2; the loader reports repeats as P021 and keeps the \
first value). This check says what other tools do with it.

python canopen 2.4.1 crashes (DuplicateOptionError) when the key is spelt the same, and sees two \
different keys when only the letter case differs; Lely dcfchk 2.4.0 crashes; CANopenEditor warns \
and keeps the first value; canopen-host 0.6.1 silently keeps the last.

It is a warning because the tools crash or disagree about the value when the two lines differ.

Fix: delete the line that is not meant.",
);

pub(super) const SUB_CASE: CheckInfo = warning(
    "T009",
    "sub-section-case",
    "`sub` in a sub-object section name not in lower case, which python canopen or CANopenEditor lose",
    &[38],
    "CiA 306 V1.3 §4.2, §4.6.3.2",
    "\
Section names are case-insensitive (CiA 306 §4.2), and §4.6.3.2 writes sub-object sections as \
[<index>sub<sub-index>]. This check reports sub-object sections that write `sub` in another case.

python canopen 2.4.1 matches `sub` or `Sub` only, so it silently loses [1018SUB1]; CANopenEditor \
matches `sub` only, so it silently loses [1018Sub1] and [1018SUB1]. Lely and canopen-host 0.6.1 \
read them.

It is a warning because the sub-object disappears without a message in those tools.

Fix: rename the section with a lower-case `sub`: [1018sub1].",
);

pub(super) const ORPHAN_SUB: CheckInfo = warning(
    "T010",
    "orphan-sub-object-tools",
    "a sub-object section without its object, on which python canopen crashes",
    &[35],
    "CiA 306 V1.3 §4.6.3.2",
    "\
A [<index>sub<n>] section belongs to the object [<index>] (CiA 306 §4.6.3.2); the loader reports a \
sub-section without it as P040. This check says what the other tools do.

python canopen 2.4.1 crashes (KeyError); Lely dcfchk 2.4.0 reports it; canopen-host 0.6.1 keeps it \
as an orphan; CANopenEditor ignores it.

It is a warning because the import fails in python canopen, and the other tools keep or drop the \
data differently.

Fix: add the object section [<index>] or delete the sub-section.",
);

pub(super) const VAR_MISSING_KEY: CheckInfo = warning(
    "T011",
    "var-missing-key-tools",
    "a VAR or sub-object without ParameterName, DataType or AccessType, which crashes or vanishes",
    &[28, 30],
    "CiA 306 V1.3 §4.6.3.2",
    "\
CiA 306 §4.6.3.2 makes ParameterName, DataType and AccessType mandatory for a VAR, and \
ParameterName for every object; the loader reports a missing one as P073. This check says what the \
other tools do.

python canopen 2.4.1 reads the three keys without a fallback and crashes (NoOptionError); Lely \
dcfchk 2.4.0 crashes (KeyError) on a missing AccessType; canopen-host 0.6.1 assumes ro for it; \
CANopenEditor swallows the error and silently drops the object, printing only \"** ALL GONE WRONG \
**\" on its console.

It is a warning because the object is lost or the import fails.

Fix: add the missing key.",
);

pub(super) const HEX_SUFFIX: CheckInfo = warning(
    "T012",
    "hex-suffix-tools",
    "a hexadecimal value with an h suffix, which python canopen reads as None",
    &[7, 45],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 §4.2 writes hexadecimal numbers with a 0x prefix; FEh is not a CiA 306 number (the loader \
reports it as P052 and reads it as 0xFE). This check says what the other tools do.

python canopen 2.4.1 silently reads None; Lely dcfchk 2.4.0 reports it; canopen-host 0.6.1 rejects \
the whole file; CANopenEditor keeps the text.

It is a warning because the value is lost or the file refused.

Fix: write 0xFE.",
);

pub(super) const LISTED_MISSING: CheckInfo = info(
    "T013",
    "listed-object-missing-tools",
    "an object list names an object without a section; only Lely says so",
    &[23],
    "CiA 306 V1.3 §4.6.3.1",
    "\
Every index of [MandatoryObjects], [OptionalObjects] and [ManufacturerObjects] needs its section \
(CiA 306 §4.6.3.1); the loader reports a missing one as P042. This check says what the other tools \
do.

Lely dcfchk 2.4.0 reports \"object not found\". python canopen 2.4.1, canopen-host 0.6.1 and \
CANopenEditor load the file without the object and without a word.

It is information only: every tool ends up without the object, so none misreads the file; the \
finding tells you that only Lely's tools will complain.

Fix: add the section or remove the entry from the list.",
);

pub(super) const UNLISTED_OBJECT: CheckInfo = warning(
    "T014",
    "unlisted-object-tools",
    "an object section no list names, which Lely silently ignores",
    &[24],
    "CiA 306 V1.3 §4.6.3.1",
    "\
Every object section must be named in one of the object lists (CiA 306 §4.6.3.1); the loader \
reports an unlisted one as P043. This check says what the other tools do.

Lely's loader parses only the objects the lists name, so it silently leaves this one out, and \
dcfchk 2.4.0 does not report it. python canopen 2.4.1, canopen-host 0.6.1 and CANopenEditor ignore \
the lists and load it.

It is a warning because a device built with Lely lacks the object without any message.

Fix: add the index to the list it belongs in.",
);

pub(super) const UNSIGNED_OVERFLOW: CheckInfo = warning(
    "T015",
    "unsigned-overflow-tools",
    "an unsigned value above its type's maximum, which canopen-host silently truncates",
    &[46],
    "CiA 306 V1.3 §4.6.3.2",
    "\
A DefaultValue or ParameterValue must fit its data type; the loader reports one that does not as \
P054. This check says what the other tools do with an unsigned value above the maximum.

canopen-host 0.6.1 silently truncates it to the type's width (300 in an UNSIGNED8 becomes 44); \
python canopen 2.4.1 accepts it as it is; Lely dcfchk 2.4.0 reports an overflow; CANopenEditor \
keeps the text.

It is a warning because one tool silently uses a different value.

Fix: correct the value, or the data type if the value is right.",
);

pub(super) const ACCESS_TYPE_TOKEN: CheckInfo = warning(
    "T016",
    "access-type-token-tools",
    "an AccessType that is not a CiA 306 token, which every tool handles differently",
    &[32],
    "CiA 306 V1.3 §4.6.3.2",
    "\
AccessType is one of ro, wo, rw, rwr, rww and const (CiA 306 §4.6.3.2); the loader reports others \
as P072. This check says what the other tools do.

python canopen 2.4.1 accepts the text verbatim; Lely dcfchk 2.4.0 reports it; canopen-host 0.6.1 \
rejects the file; CANopenEditor leaves the entry with an empty value and only prints a line on its \
console.

It is a warning because the access rights are lost or the file refused.

Fix: use one of the six tokens (readwrite is rw).",
);

pub(super) const REAL_BIT_PATTERN: CheckInfo = warning(
    "T017",
    "real-bit-pattern",
    "a REAL value written as an IEEE 754 bit pattern, which python canopen reads as None",
    &[48],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 V1.3 does not say how REAL32 and REAL64 values are written. This check reports REAL \
DefaultValue and ParameterValue entries written as a hexadecimal bit pattern such as 0x3F800000 \
(1.0).

Lely reads REAL values as bit patterns, so it reads 1.0. python canopen 2.4.1 calls float() on the \
text and silently reads None; canopen-host 0.6.1 rejects the file; CANopenEditor keeps the text.

It is a warning because the value is lost in python canopen and the file refused by canopen-host. \
No notation suits every tool (see T018).

Fix: choose the notation for the tool that matters: decimal (1.0) for python canopen, canopen-host \
and CiA's tools, the bit pattern for Lely.",
);

pub(super) const REAL_DECIMAL: CheckInfo = warning(
    "T018",
    "real-decimal",
    "a REAL value written in decimal, which Lely rejects or reads as a bit pattern",
    &[48],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 V1.3 does not say how REAL32 and REAL64 values are written. This check reports REAL \
DefaultValue and ParameterValue entries written in decimal (1.5, 100), except 0, which reads the \
same in every notation.

python canopen 2.4.1 and canopen-host 0.6.1 read 1.5. Lely reads REAL values as IEEE 754 bit \
patterns: dcfchk 2.4.0 reports 1.5 as invalid (CANopenNode's demoDevice.eds fails it this way), \
and an integer text such as 100 is read as the bit pattern 0x00000064, a tiny denormal number. \
CANopenEditor keeps the text.

It is a warning because Lely refuses the file or silently uses a different number.

Fix: choose the notation for the tool that matters: the bit pattern (0x3FC00000) for Lely, decimal \
for the others.",
);

pub(super) const SIGNED_LIMIT_BITS: CheckInfo = info(
    "T019",
    "signed-limit-bit-pattern",
    "a signed LowLimit/HighLimit written as an unsigned bit pattern, which Lely dcfchk flags",
    &[49],
    "CiA 306 V1.3 §4.6.3.2",
    "\
A signed limit written as an unsigned hexadecimal bit pattern, such as LowLimit=0x8000 for an \
INTEGER16, is read as two's complement by the loader (P055). This check says what the other tools \
do.

python canopen 2.4.1 reads it as two's complement (-32768); Lely dcfchk 2.4.0 range-checks 0x8000 \
as +32768 and reports a false overflow (cf. ros2_canopen #394).

It is information: the intended value is clear and read correctly by python canopen, but Lely's \
checker will fail the file.

Fix: write the limit as a negative number: -32768 (or -0x8000).",
);

pub(super) const INLINE_COMMENT: CheckInfo = warning(
    "T020",
    "inline-comment-tools",
    "a `;` or `#` inside a value, which the tools cut at different places or keep",
    &[5],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 §4.2 has comments only on their own line, starting with ';'. This check reports values \
that contain ';' or '#', which the tools read differently.

Lely's lexer ends a value at the first ';' or '#' anywhere, so ParameterName=Motor #1 becomes \
\"Motor\" and a module's Count=0;4 becomes 0. python canopen 2.4.1 cuts the value only at a ';' \
that follows white space. CANopenEditor keeps the whole text in the value (254 ; async), and \
canopen-host 0.6.1 rejects a number with a comment.

It is a warning when the value is a number, token or setting, because the tools then use different \
values or refuse the file. Names, descriptions and comment lines that contain '#' or ';' are \
reported once per file as information: only their text differs.

Fix: move the comment to its own line starting with ';', and avoid '#' and ';' in names.",
);

pub(super) const UTF8_BOM: CheckInfo = warning(
    "T021",
    "utf8-bom-tools",
    "a UTF-8 byte order mark, on which python canopen and Lely dcfchk crash",
    &[1],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 §4.2 allows only ISO 646 (ASCII) text, so an EDS has no byte order mark; the loader \
reports one as P002. This check says what the other tools do.

python canopen 2.4.1 crashes (MissingSectionHeaderError) and Lely dcfchk 2.4.0 crashes, because \
the first line no longer starts with '['. canopen-host 0.6.1 and CANopenEditor skip the mark.

It is a warning because the file does not load in two widely used tools.

Fix: save the file without the byte order mark (\"UTF-8\" rather than \"UTF-8 with BOM\").",
);

pub(super) const NOT_UTF8: CheckInfo = warning(
    "T022",
    "non-utf8-bytes-tools",
    "bytes that are not UTF-8 (Latin-1 `°`), on which python canopen and Lely dcfchk crash",
    &[1],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 §4.2 allows only ISO 646 (ASCII); the loader decodes other bytes as Windows-1252 and \
reports P001. This check says what the other tools do with them.

python canopen 2.4.1 opens the file in the platform's default encoding and crashes \
(UnicodeDecodeError) where that is UTF-8; Lely dcfchk 2.4.0 crashes; canopen-host 0.6.1 rejects \
the file (it needs UTF-8); CANopenEditor loads it but replaces the character with U+FFFD.

It is a warning because the file fails to load or the text is silently changed.

Fix: replace the character by ASCII (deg C for °C), or at least save the file as UTF-8.",
);

pub(super) const DOMAIN_WITHOUT_TYPES: CheckInfo = warning(
    "T023",
    "domain-without-types",
    "a DOMAIN without DataType or AccessType, as CiA 306 allows, on which python canopen crashes",
    &[30],
    "CiA 306 V1.3 §4.6.3.2",
    "\
CiA 306 §4.6.3.2 lets a DOMAIN object (ObjectType=0x2) omit DataType (DOMAIN is implied) and \
AccessType (rw is implied). This check reports DOMAIN objects that do.

python canopen 2.4.1 reads DataType and AccessType without a fallback and crashes (NoOptionError). \
Lely reads the object as the spec says, and CANopenEditor gives it DataType DOMAIN and AccessType \
rw.

It is a warning because the file is valid but fails to import in python canopen.

Fix: write the implied values explicitly: DataType=0x000F and AccessType=rw.",
);

pub(super) const CUSTOM_DATA_TYPE: CheckInfo = warning(
    "T024",
    "custom-data-type-python",
    "a DataType above 0x1B without the [<type>sub1] section python canopen looks for",
    &[31],
    "CiA 306 V1.3 §4.6.3.2",
    "\
Data types above 0x1B are structures, manufacturer types (0x40-0x5F) or profile types, defined by \
DEFTYPE/DEFSTRUCT objects. This check reports a VAR or sub-object whose DataType is above 0x1B \
when there is no section named exactly [<type>sub1] (for 0x0040: [40sub1]).

python canopen 2.4.1 resolves such a type only through the DefaultValue of [<type>sub1], the way \
CANFestival writes type definitions; otherwise it logs a warning and reads the entry as DOMAIN, \
i.e. as raw bytes.

It is a warning because python canopen silently uses raw bytes instead of the typed value.

Fix: add a [<type>sub1] section whose DefaultValue is the basic type (e.g. 0x0006), or use the \
basic type directly.",
);

pub(super) const DCF_BAUDRATE: CheckInfo = warning(
    "T025",
    "dcf-baudrate-not-decimal",
    "a DCF Baudrate that is not plain decimal, on which python canopen fails",
    &[59],
    "CiA 306 V1.3 §5",
    "\
[DeviceComissioning] Baudrate is the bit rate in kbit/s (CiA 306 §5), an Unsigned16 that §4.2 lets \
you write in decimal, hex or octal. This check reports a Baudrate that is not plain decimal.

python canopen 2.4.1 reads Baudrate with configparser's getint, which accepts only decimal, so a \
value such as 0xFA raises ValueError and the import fails.

It is a warning because a valid DCF does not import in python canopen.

Fix: write the bit rate in decimal: Baudrate=250.",
);

pub(super) const MISSING_INFO_SECTION: CheckInfo = warning(
    "T026",
    "missing-section-tools",
    "[FileInfo], [DeviceInfo] or [MandatoryObjects] missing, on which CANopenEditor throws",
    &[8, 13, 22],
    "CiA 306 V1.3 §4.4, §4.5, §4.6.3.1",
    "\
CiA 306 makes [FileInfo], [DeviceInfo] and [MandatoryObjects] mandatory; the loader reports a \
missing one as P029. This check says what CANopenEditor does.

CANopenEditor accesses the three sections unconditionally and throws KeyNotFoundException, so it \
opens nothing (cf. CANopenEditor issue #271). Lely's generated DCFs often lack [FileInfo].

It is a warning because the file cannot be opened in CANopenEditor at all.

Fix: add the section with its mandatory keys.",
);

pub(super) const SUB_BEFORE_PARENT: CheckInfo = warning(
    "T027",
    "sub-before-parent",
    "a sub-object section before its object section, which CANopenEditor loses",
    &[35],
    "CiA 306 V1.3 §4.2",
    "\
Sections may appear in any order (CiA 306 §4.2). This check reports a [<index>sub<n>] section that \
comes before its [<index>] section.

CANopenEditor attaches sub-sections to an object it has already parsed, so it silently loses a \
sub-section that comes first.

It is a warning because the sub-object disappears without a message in CANopenEditor, although the \
file is valid.

Fix: move the object section before its sub-sections.",
);

pub(super) const INFO_BOOLEAN: CheckInfo = warning(
    "T028",
    "info-boolean-spelling",
    "a [DeviceInfo] boolean meaning 1 but not written `1`, which CANopenEditor reads as false",
    &[15],
    "CiA 306 V1.3 §4.5",
    "\
The [DeviceInfo] booleans (BaudRate_*, SimpleBootUpMaster, SimpleBootUpSlave, GroupMessaging, \
LSS_Supported, ...) are 0 or 1 (CiA 306 §4.5), and §4.2 lets a number be written as 0x1 or 01. \
This check reports booleans whose value is 1 but not written as the literal 1.

CANopenEditor treats only the literal \"1\" as true, so it silently reads 0x1 as false: a \
supported baud rate or LSS becomes unsupported.

It is a warning because CANopenEditor silently reads the opposite value.

Fix: write 1.",
);

pub(super) const COMPACT_PDO_NO_MODULES: CheckInfo = warning(
    "T029",
    "compact-pdo-without-modules",
    "CompactPDO implies PDOs that CANopenEditor does not create without [SupportedModules]",
    &[18, 54],
    "CiA 306 V1.3 §4.6.3.4.1",
    "\
With [DeviceInfo] CompactPDO, the PDOs that NrOfRXPDO/NrOfTXPDO promise but the file does not \
describe exist implicitly (CiA 306 §4.6.3.4.1). This check reports implied PDOs in a file without \
[SupportedModules].

CANopenEditor expands CompactPDO only inside its handling of [SupportedModules], so in an ordinary \
device file the implied PDO objects are silently missing there (and where it does expand them, its \
filler appears to put the COB-ID at sub-index 5). Lely's loader builds them as the spec says.

It is a warning because CANopenEditor shows and exports a device without those PDOs.

Fix: describe the PDOs explicitly (communication and mapping objects with all their sub-objects).",
);

pub(super) const COMPACT_VALUES_IGNORED: CheckInfo = warning(
    "T030",
    "compact-values-ignored",
    "a DCF [<index>Value] section, which python canopen and CANopenEditor do not read",
    &[42, 50],
    "CiA 306 V1.3 §5.3.3",
    "\
In a DCF, [<index>Value] holds the configured values of a CompactSubObj array (CiA 306 §5.3.3). \
This check reports such sections.

python canopen 2.4.1 ignores [<index>Value], [<index>Denotation] and object links, and \
CANopenEditor does not parse them either, so both silently use the DefaultValue instead of the \
configured values. Lely reads them.

It is a warning because a configuration tool built on python canopen or CANopenEditor would \
download the wrong values.

Fix: if those tools must read the DCF, describe the array with explicit sub-object sections that \
carry ParameterValue.",
);

pub(super) const COMPACT_LIMITS: CheckInfo = warning(
    "T031",
    "compact-limits-copied",
    "limits on a CompactSubObj array, whose HighLimit CANopenEditor replaces by LowLimit",
    &[41, 46],
    "CiA 306 V1.3 §4.6.3.4.2",
    "\
A CompactSubObj array may carry LowLimit and HighLimit for its sub-objects (CiA 306 §4.6.3.2). \
This check reports compact arrays with a LowLimit whose HighLimit is different or missing.

When CANopenEditor expands CompactSubObj it copies LowLimit into HighLimit (an apparent copy-paste \
bug in libEDSsharp), so every generated sub-object gets the range LowLimit..LowLimit.

It is a warning because CANopenEditor silently narrows the range, and exports it that way.

Fix: if CANopenEditor must read the file, describe the sub-objects explicitly.",
);

pub(super) const SECTION_DIGITS: CheckInfo = warning(
    "T032",
    "section-name-digits",
    "an object section name with leading zeros or not four index digits, which a tool does not find",
    &[38],
    "CiA 306 V1.3 §4.6.3.2",
    "\
CiA 306 §4.6.3.2 writes object sections as the hex index and sub-index without leading zeros: \
[1018], [1018sub1]. This check reports names that some tool does not find.

Lely's loader looks sections up by the generated names [%X] and [%Xsub%X], so it does not find \
[01018] or [1018sub01]. python canopen 2.4.1 recognises object sections only with exactly four \
index digits, so it ignores [01018] and [01018sub1] (for indices below 1000h no spelling suits \
both tools, and only Lely's side is reported).

It is a warning because the object or sub-object silently disappears in those tools.

Fix: rename the section to the CiA 306 spelling.",
);

pub(super) const ARRAY_WITHOUT_SUB_NUMBER: CheckInfo = warning(
    "T033",
    "array-without-sub-number",
    "an ARRAY or RECORD without SubNumber or CompactSubObj, which CANopenEditor drops",
    &[30],
    "CiA 306 V1.3 §4.6.3.2",
    "\
CiA 306 §4.6.3.2 makes SubNumber mandatory for an ARRAY, RECORD or DEFSTRUCT without \
CompactSubObj; the loader reports a missing one as P073. This check says what the other tools do.

CANopenEditor requires SubNumber and silently drops the whole object (it drops [3003] of python \
canopen's own sample.eds this way). Lely's loader also requires SubNumber or CompactSubObj. python \
canopen 2.4.1 loads the object from its sub-sections.

It is a warning because the object disappears in CANopenEditor without a message.

Fix: add SubNumber with the number of sub-object sections.",
);

pub(super) const OBJECT_LINKS: CheckInfo = info(
    "T034",
    "object-links-section",
    "an [<index>ObjectLinks] section, which Lely dcfchk reports as unknown",
    &[43],
    "CiA 306 V1.3 §4.6.4",
    "\
[<index>ObjectLinks] groups related objects for configuration tools (CiA 306 §4.6.4). This check \
reports such sections.

Lely dcfchk 2.4.0 does not know them and reports an unknown section; python canopen 2.4.1, \
canopen-host 0.6.1 and CANopenEditor ignore them.

It is information: the section is valid and no tool misreads the dictionary because of it, but \
dcfchk will complain and the links are lost in every tool.

Fix: nothing is wrong; remove the section only if dcfchk must pass.",
);

pub(super) const TPDO_WITHOUT_MAPPING: CheckInfo = warning(
    "T035",
    "tpdo-without-mapping-tools",
    "a TPDO communication object without its mapping object, on which Lely dcfchk crashes",
    &[54],
    "CiA 301 V4.2 §7.5.2",
    "\
Every PDO needs its communication and its mapping object (CiA 301); the loader reports a missing \
one as P080. This check says what the tools do when a TPDO communication object 1800h+n has no \
mapping object 1A00h+n.

Lely dcfchk 2.4.0 crashes with a KeyError (KeyError: 6656 for 1A00h) instead of reporting it; \
python canopen 2.4.1 loads the file. The matrix that observed this did not test the RPDO case.

It is a warning because Lely's checker dies without saying why.

Fix: add the mapping object, or remove the communication object.",
);

pub(super) const VENDOR_NUMBER: CheckInfo = warning(
    "T036",
    "vendor-number-python",
    "a [DeviceInfo] VendorNumber python canopen cannot read, so its import crashes",
    &[13],
    "CiA 306 V1.3 §4.5",
    "\
VendorNumber is an Unsigned32 (CiA 306 §4.5). This check reports a VendorNumber that Python's \
int(x, 0) cannot read: empty (as CANopenEditor writes it into DS301_profile.eds), with leading \
zeros, or with an h suffix.

python canopen 2.4.1 reads it with int(x, 0) and crashes (ValueError: int('', 0)); Lely dcfchk \
2.4.0 accepts an empty one.

It is a warning because the whole import fails in python canopen.

Fix: write the vendor-ID as in 1018h sub 1, e.g. VendorNumber=0x00000ABC.",
);

pub(super) const KEY_CASE: CheckInfo = warning(
    "T037",
    "key-case-python",
    "a key in other letter case, which python canopen does not see",
    &[6],
    "CiA 306 V1.3 §4.2",
    "\
Key names are case-insensitive (CiA 306 §4.2); the loader notes other spellings as P032. This \
check reports the keys python canopen reads in object sections and [DeviceComissioning] when they \
are spelt otherwise (Parametername, PdoMapping, NodeId).

python canopen 2.4.1 matches keys case-sensitively: a ParameterName, DataType or AccessType it \
does not find makes the import fail (NoOptionError); an ObjectType it does not find makes the \
object a VAR; other keys (DefaultValue, PDOMapping, limits, NodeID) are silently ignored. Lely \
matches keys case-insensitively.

It is a warning because python canopen crashes or silently drops the value.

Fix: spell the key as CiA 306 does.",
);

pub(super) const SECTION_CASE: CheckInfo = warning(
    "T038",
    "section-case-python",
    "a section name in other letter case, which python canopen does not see",
    &[6],
    "CiA 306 V1.3 §4.2",
    "\
Section names are case-insensitive (CiA 306 §4.2). This check reports sections python canopen \
reads by name when they are spelt in other letter case: [DeviceComissioning], [DeviceInfo], \
[Comments] and [<index>Name].

python canopen 2.4.1 matches section names case-sensitively, so it does not read them: a DCF's \
NodeID and Baudrate are not applied, sub-object names of a compact array are not applied (and only \
sub 0 and sub 1 are created). Lely matches section names case-insensitively.

It is a warning for [DeviceComissioning] and [<index>Name], where python canopen builds a \
different dictionary, and information for [DeviceInfo] and [Comments], where only descriptive data \
is lost.

Fix: spell the section as CiA 306 does.",
);

pub(super) const UNKNOWN_KEYS: CheckInfo = info(
    "T039",
    "unknown-keys-dcfchk",
    "keys CiA 306 does not define, which Lely dcfchk reports as errors",
    &[20, 30],
    "CiA 306 V1.3 §4.2",
    "\
CiA 306 §4.2 allows extra keys for future extensions; the loader notes each as P033. This check \
summarises them once per file.

Lely dcfchk 2.4.0 checks the allowed keys of every section and reports each unknown key as an \
error (it does so for python canopen's own sample.eds, which has Factor, Unit and Description \
keys).

It is information: no tool misreads the dictionary because of them, but dcfchk will fail the file.

Fix: nothing is wrong; drop the keys or write them as ';' comment lines if dcfchk must pass.",
);

pub(super) const STRING_BACKSLASH: CheckInfo = warning(
    "T040",
    "string-backslash-tools",
    "a VISIBLE_STRING value with a backslash, which Lely reads as a C escape sequence",
    &[48],
    "CiA 306 V1.3 §4.2",
    "\
VISIBLE_STRING values are written as they are (CiA 306 §4.2 has no escapes). This check reports \
DefaultValue and ParameterValue of VISIBLE_STRING entries that contain a backslash.

Lely's lexer processes C escape sequences in such values, so \\n becomes a line feed and other \
backslash sequences change; CANopenEditor unescapes them when it sizes the string; python canopen \
2.4.1 keeps the text.

It is a warning because the string, and possibly its length, differs between tools.

Fix: avoid backslashes in string values (write / in paths).",
);
