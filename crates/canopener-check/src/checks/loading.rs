//! The `P` series: what loading found (see [`canopener_eds::diag::Code`]), reported as findings
//! unchanged. This module gives each loading diagnostic its registry entry: title, the catalogue checks it
//! implements, the clause that justifies its severity, and its explanation page.
//!
//! Code, slug and severity are written out here and tested against [`Code::ALL`], so the registry
//! and the loader can never drift apart.

use canopener_eds::Severity;

use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;

/// The loading diagnostics, in code order.
pub(crate) const CHECKS: &[CheckInfo] = &[
    CheckInfo {
        code: "P001",
        slug: "windows-1252-fallback",
        severity: Severity::Error,
        group: Group::Syntax,
        title: "the file is ASCII (it was not even UTF-8 and was read as Windows-1252)",
        reference: &[1],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
The bytes of the file are not valid UTF-8, so canopener decoded them as Windows-1252 (a superset of \
ISO 8859-1) and points at the first byte that is not UTF-8, typically a degree sign or an umlaut \
written by a Windows editor. canopener keeps the bytes and writes them back unchanged.

The same file reads differently in every tool: python canopen opens it with the locale's encoding \
and fails with UnicodeDecodeError on a UTF-8 system; lely's INI reader ends a value at the first \
byte that is not printable ASCII, so `Temperature setpoint °C` becomes `Temperature setpoint`; \
CANopenEditor replaces the byte with U+FFFD.

It is an error because CiA 306 §4.2 allows only ASCII (ISO 646) characters. Check C102 lists every \
line that carries such a character.

Fix: replace the characters with ASCII (`deg C` for `°C`, `ue` for `ü`).",
        fixable: false,
    },
    CheckInfo {
        code: "P002",
        slug: "utf8-bom",
        severity: Severity::Error,
        group: Group::Syntax,
        title: "the file does not start with a UTF-8 byte order mark",
        reference: &[1],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
The file starts with the three bytes EF BB BF, the UTF-8 byte order mark some Windows editors \
write. canopener skips it when reading and keeps it when writing.

python canopen reads the mark as part of the first line, which then no longer starts with `[`, \
and aborts with MissingSectionHeaderError; lely's dcfchk fails on it too, and its C loader reports \
the three bytes as unknown characters. CANopenEditor ignores the mark.

It is an error because the mark is three bytes outside the ASCII character set CiA 306 §4.2 \
allows, and two of the most used readers reject the whole file because of it.

Fix: save the file as plain ASCII or \"UTF-8 without signature\".",
        fixable: false,
    },
    CheckInfo {
        code: "P003",
        slug: "mixed-line-endings",
        severity: Severity::Info,
        group: Group::Syntax,
        title: "all lines end the same way (LF or CR/LF)",
        reference: &[],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
Some lines of the file end with LF and others with CR/LF; the finding points at the first line \
whose ending differs from the first line's.

Every reader surveyed handles both endings, but version control and diff tools show the file as \
changed wherever an editor normalises the endings, which hides real changes in reviews. \
canopener's fixes keep each line's ending and use the most frequent one for inserted lines.

It is only a hint: CiA 306 §4.2 allows both LF and CR/LF.

Fix: normalise the endings (dos2unix or unix2dos) if the file is kept under version control.",
        fixable: false,
    },
    CheckInfo {
        code: "P004",
        slug: "bare-carriage-return",
        severity: Severity::Warning,
        group: Group::Syntax,
        title: "lines end with LF or CR/LF, never with a bare CR",
        reference: &[],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A line ends with a carriage return that is not followed by a line feed, the line ending of classic \
Mac OS. canopener treats it as a line break and reports the first one.

python canopen (universal newlines), lely and CANopenEditor also break lines there, but tools that \
split on LF only (grep, diff, many small embedded parsers) see the whole file as one line, which is \
then far longer than the 255 characters CiA 306 allows.

It is a warning: CiA 306 §4.2 allows only LF and CR/LF, but the readers we surveyed tolerate a bare \
CR.

Fix: convert the line endings to LF or CR/LF.",
        fixable: false,
    },
    CheckInfo {
        code: "P010",
        slug: "malformed-section-header",
        severity: Severity::Error,
        group: Group::Syntax,
        title: "section headers are written `[name]` with nothing after the `]`",
        reference: &[2],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A line starts with `[` but has no closing `]`, or has text after the `]` (often an inline comment). \
canopener takes the text up to the `]` (or the end of the line) as the section name.

lely's INI reader reports \"expected ']' after section name\"; python canopen's configparser \
cannot read a header without `]` and rejects the file; tools that match headers with a strict \
pattern drop the whole section.

It is an error because CiA 306 §4.2 writes a section header as `[name]`, alone on its line, and \
defines no inline comments.

Fix: close the bracket, and move any text after it to a `;` comment line of its own.",
        fixable: false,
    },
    CheckInfo {
        code: "P011",
        slug: "not-an-entry",
        severity: Severity::Error,
        group: Group::Syntax,
        title: "every line is blank, a comment, a section header or `key=value`",
        reference: &[2],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A line is neither blank, a `;` comment, a section header nor an entry `key=value`: it has no `=`. \
canopener keeps the line when writing and ignores it otherwise.

python canopen's configparser raises a ParsingError on such a line and the import fails; lely's \
reader reports \"expected '=' after key\"; CANopenEditor skips it silently. Often it is a comment \
that lost its `;`, or an entry whose `=` was deleted by mistake.

It is an error because CiA 306 §4.2 knows only these four kinds of lines.

Fix: comment the line out with `;` in column 1, or restore the missing `=`.",
        fixable: false,
    },
    CheckInfo {
        code: "P012",
        slug: "indented-line",
        severity: Severity::Error,
        group: Group::Syntax,
        title: "section headers and keys start in column 1",
        reference: &[2],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A section header or an entry is preceded by spaces or tabs. canopener and lely skip the white \
space and read the line normally.

python canopen's configparser reads an indented line that follows an entry as a continuation of \
that entry's value: the indented key, or the indented section header with everything up to the \
next header, silently becomes part of the previous value and is lost.

It is an error because CiA 306 §4.2 requires the `[` of a section header in column 1 and writes \
entries as `keyname=value` from the start of the line, and because one of the most used readers \
loses data on it.

Fix: remove the leading white space.",
        fixable: false,
    },
    CheckInfo {
        code: "P013",
        slug: "space-before-equals",
        severity: Severity::Warning,
        group: Group::Syntax,
        title: "the key is immediately followed by `=`",
        reference: &[3],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
There is white space between a key and its `=` (`DefaultValue =0x7`). canopener reads the key \
without the white space.

python canopen, lely and CANopenEditor (since its bug #70, raised by Lenze files that write \
`1= 0x1003`) all tolerate it; small hand-written parsers that split at `=` and compare the key \
literally do not find `DefaultValue ` with its trailing blank.

It is a warning: CiA 306 §4.2 says the key is immediately followed by `=`, but every reader we \
surveyed accepts the space.

Fix: delete the white space before the `=`.",
        fixable: false,
    },
    CheckInfo {
        code: "P014",
        slug: "non-standard-comment",
        severity: Severity::Warning,
        group: Group::Syntax,
        title: "comments start with `;` in column 1",
        reference: &[2],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A comment line starts with `#`, or its `;` is indented. canopener treats the line as a comment.

python canopen and lely ignore such lines as well, but a reader that follows CiA 306 literally \
sees a line that is neither a comment nor an entry and rejects it.

It is a warning: CiA 306 §4.2 defines only `;` in column 1 as a comment, but the readers we \
surveyed tolerate the other forms.

Fix: write `;` in column 1.",
        fixable: false,
    },
    CheckInfo {
        code: "P015",
        slug: "entry-outside-section",
        severity: Severity::Error,
        group: Group::Syntax,
        title: "every entry belongs to a section",
        reference: &[2],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
An entry `key=value` comes before the first section header. canopener keeps the line but the \
value belongs to nothing.

python canopen's configparser aborts with MissingSectionHeaderError; lely files the entry under an \
empty section name where no one looks for it.

It is an error because CiA 306 §4.2 places every entry in a section.

Fix: move the entry into the section it belongs to, or delete it.",
        fixable: false,
    },
    CheckInfo {
        code: "P016",
        slug: "unusual-key",
        severity: Severity::Warning,
        group: Group::Syntax,
        title: "keys consist of letters, digits and `_`",
        reference: &[6],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A key contains characters other than letters, digits and `_`, for example a space \
(`Supported Objects`) or a hyphen. canopener keeps it as written.

No CiA 306 key looks like this, so every tool ignores the value. lely's INI reader even stops the \
key at the space and reports a missing `=`. A key such as `Supported Objects` usually hides the \
standard key `SupportedObjects`, whose value is then missing; this spelling broke Vector's CANeds \
check of a CANopenEditor file (libedssharp #110). Check C105 names the intended key when it can.

It is a warning: CiA 306 §4.2 builds keys from letters and digits (and its own keys use `_`), but \
an unknown key is allowed as an extension, so the finding is about the likely mistake behind it.

Fix: spell the key as CiA 306 does, or remove the entry.",
        fixable: false,
    },
    CheckInfo {
        code: "P020",
        slug: "duplicate-section",
        severity: Severity::Error,
        group: Group::Syntax,
        title: "no section appears twice",
        reference: &[4],
        spec: "CiA 306 V1.3 §4.2, §4.6.3.2",
        explanation: "\
A section appears a second time. Names compare without regard to letter case and by meaning, so \
`[1018]` and `[01018]` are the same object. canopener uses the first section and ignores the \
entries of the repeat; the message names the line of the first one.

The readers disagree on what the file means: python canopen's configparser aborts with \
DuplicateSectionError, lely's loader merges both sections (later keys win) and its dcfchk crashes, \
CANopenEditor keeps the first one as canopener does.

It is an error because a section name identifies one section (CiA 306 §4.2) and each object is \
described by one section (§4.6.3.2); with two, the file has more than one meaning.

Fix: merge the two sections into one and delete the other.",
        fixable: false,
    },
    CheckInfo {
        code: "P021",
        slug: "duplicate-key",
        severity: Severity::Error,
        group: Group::Syntax,
        title: "no key appears twice in a section",
        reference: &[4],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A key appears a second time in the same section (keys compare without regard to letter case). \
canopener uses the first value; the message names it and the line of the first entry.

python canopen's configparser aborts with DuplicateOptionError and lely's dcfchk crashes; lely's \
loader keeps the last value and CANopenEditor the first, so two tools that accept the file use \
different values.

It is an error because a key names one value of its section (CiA 306 §4.2).

Fix: delete the entry that is wrong.",
        fixable: false,
    },
    CheckInfo {
        code: "P029",
        slug: "missing-section",
        severity: Severity::Error,
        group: Group::Syntax,
        title: "[FileInfo], [DeviceInfo] and [MandatoryObjects] are present",
        reference: &[8, 13, 22],
        spec: "CiA 306 V1.3 §4.4, §4.5, §4.6.3.1",
        explanation: "\
One of the sections every EDS and DCF must have is missing: [FileInfo], [DeviceInfo] or \
[MandatoryObjects]; or the file is empty.

CANopenEditor throws KeyNotFoundException on a file without [FileInfo], [DeviceInfo] or \
[MandatoryObjects] (libedssharp #271). lely's loader reads only the objects the lists name, so \
without [MandatoryObjects] it does not load 1000h, 1001h and 1018h. In the corpus, lely's test \
DCFs and the master DCFs ros2_canopen generates with lely's dcfgen have no [FileInfo]; lely's own \
tools do not need it, but other tools reject the file.

It is an error because CiA 306 makes [FileInfo] (§4.4, DCF §5.2), [DeviceInfo] (§4.5) and the \
object lists (§4.6.3.1) mandatory.

Fix: add the section with its mandatory entries.",
        fixable: false,
    },
    CheckInfo {
        code: "P030",
        slug: "unknown-section",
        severity: Severity::Warning,
        group: Group::Syntax,
        title: "every section is one CiA 306 defines",
        reference: &[6, 38],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A section name is not one CiA 306 defines, or names a sub-index above FFh (`[4900sub100]`), which a \
CANopen object cannot have. canopener keeps the section and writes it back unchanged.

Extra sections are allowed as extensions, and tools add their own ([PreDefines], [ToolInfos]). But \
an unknown section is often a misspelt standard one (`[OptionalObject]`, `[Device Info]`) whose \
whole content then counts for nothing, or an object section with a decimal sub-index that no tool \
can place. Check C105 names the intended section when the name is close to a standard one.

It is a warning: CiA 306 §4.2 allows additional sections, and the CiA conformance tool reports \
them as warnings too.

Fix: rename a misspelt section; write sub-indices in hexadecimal (`sub64`, not `sub100`); leave a \
tool's own section as it is.",
        fixable: false,
    },
    CheckInfo {
        code: "P031",
        slug: "non-canonical-section-name",
        severity: Severity::Warning,
        group: Group::Syntax,
        title: "section names are spelt as CiA 306 writes them",
        reference: &[6, 38],
        spec: "CiA 306 V1.3 §4.6.3.2, §5.3.1",
        explanation: "\
A section name means a known section but is spelt differently from CiA 306: leading zeros \
(`[1018sub01]`, `[01018]`), `sub` not in lower case (`[1018SUB1]`, `[3010Sub0]`), or \
`[DeviceCommissioning]` with two m where CiA 306 writes `[DeviceComissioning]`. canopener reads \
them as the standard section.

lely looks objects and sub-objects up by the names it generates (`1018`, `1018sub1`), so it never \
finds `[01018]` or `[1018sub01]`; python canopen recognises an object only by four hex digits, so it \
loses `[01018]`, and finds `sub` and `Sub` but not `SUB`; CANopenEditor loses `SUB` too. python \
canopen reads node-ID and bit rate of a DCF only from `[DeviceComissioning]`.

It is a warning: names compare case-insensitively (CiA 306 §4.2), so these spellings are readable, \
but §4.6.3.2 writes indices without leading zeros and the readers above lose data on them.

Fix: `canopener eds fix` renames the section to the spelling in the message.",
        fixable: true,
    },
    CheckInfo {
        code: "P032",
        slug: "key-case",
        severity: Severity::Info,
        group: Group::Syntax,
        title: "keys are spelt with CiA 306's letter case",
        reference: &[6],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A known key is written in other letter case than CiA 306 uses (`NrOfRxPdo`, `PdoMapping`, \
`Vendorname`). canopener reads it as the standard key and reports each spelling once per file.

python canopen matches keys case-sensitively: it does not find `Parametername` and aborts, and \
silently takes the default for an optional key such as `PdoMapping`. lely and CANopenEditor compare \
keys without regard to case.

It is only a hint: CiA 306 §4.2 makes key names case-insensitive (its own example writes \
`NrOfRxPdo`), so the file is correct; the trouble is python canopen's.

Fix: `canopener eds fix` rewrites the key in CiA 306's spelling.",
        fixable: true,
    },
    CheckInfo {
        code: "P033",
        slug: "unknown-key",
        severity: Severity::Info,
        group: Group::Syntax,
        title: "every key is one CiA 306 defines for its section",
        reference: &[20],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A section that CiA 306 gives a fixed set of keys ([FileInfo], [DeviceInfo], object sections, \
[DeviceComissioning], module info) carries another key. canopener keeps it and writes it back.

Tools add their own keys: python canopen reads `Factor`, `Unit` and `Description` on objects, \
CANopenEditor writes `NG_Slave` into [DeviceInfo]. lely's dcfchk reports unknown keys as errors and \
the CiA conformance tool as warnings; the other readers ignore them.

It is only a hint: CiA 306 §4.2 allows additional keys for extensions. A misspelt standard key is \
more than that, and check C105 reports it as a warning.

Fix: nothing, if the key is a tool's extension; otherwise spell it as CiA 306 does.",
        fixable: false,
    },
    CheckInfo {
        code: "P034",
        slug: "reserved-key",
        severity: Severity::Warning,
        group: Group::DeviceInfo,
        title: "[DeviceInfo] carries no key CiA 306 reserves for compatibility",
        reference: &[20],
        spec: "CiA 306 V1.3 §4.5",
        explanation: "\
[DeviceInfo] carries a key CiA 306 reserves for compatibility with earlier versions: \
ProductVersion, ProductRevision, LMT_ManufacturerName, LMT_ProductName, ExtendedBootUpMaster or \
ExtendedBootUpSlave.

No current tool reads these keys, so information written there is lost; ProductVersion and \
ProductRevision in particular usually hold what belongs in RevisionNumber and 1018h sub 3.

It is a warning: CiA 306 §4.5 reserves the keys (they must not be given another meaning), so they \
are tolerated, but they suggest a file written to an outdated template.

Fix: move the information to the keys CiA 306 defines (RevisionNumber, VendorName, ProductName) \
and delete the reserved ones.",
        fixable: false,
    },
    CheckInfo {
        code: "P040",
        slug: "orphan-sub-object",
        severity: Severity::Error,
        group: Group::Objects,
        title: "every sub-object section has its object section",
        reference: &[35],
        spec: "CiA 306 V1.3 §4.6.3.2",
        explanation: "\
A sub-object section `[xxxxsubN]` exists but the object section `[xxxx]` does not. canopener keeps \
the sub-object under a placeholder object so that nothing is lost when the file is written back.

python canopen crashes with KeyError; CANopenEditor ignores the sub-object (older versions crashed \
on one in an AMC Digiflex EDS, libedssharp #161); lely reports it. Without the object section nobody knows the \
object's name, type or number of sub-indices.

It is an error because CiA 306 §4.6.3.2 describes sub-objects as parts of an object that has its \
own section.

Fix: add the `[xxxx]` section (ParameterName, ObjectType, SubNumber) or delete the sub-object.",
        fixable: false,
    },
    CheckInfo {
        code: "P041",
        slug: "orphan-companion-section",
        severity: Severity::Error,
        group: Group::Objects,
        title: "[xxxxName], [xxxxValue], [xxxxDenotation] and [xxxxObjectLinks] belong to an object",
        reference: &[42, 43],
        spec: "CiA 306 V1.3 §4.6.3.4.2, §4.6.4, §5.3.3",
        explanation: "\
A companion section ([xxxxName], [xxxxValue], [xxxxDenotation] or [xxxxObjectLinks]) exists for an \
index that has no object section. canopener keeps it under a placeholder object.

These sections only add names, values or links to an existing object; on their own they describe \
nothing, and EdsDcfNet reports them as INI_ORPHAN_COMPANION_SECTION. Usually the object section was deleted or \
its index mistyped.

It is an error because CiA 306 defines these sections as parts of their object (§4.6.3.4.2, \
§4.6.4, DCF §5.3.3).

Fix: add the object section, correct the index in the section name, or delete the section.",
        fixable: false,
    },
    CheckInfo {
        code: "P042",
        slug: "listed-object-missing",
        severity: Severity::Error,
        group: Group::ObjectLists,
        title: "every object an object list names has its section",
        reference: &[23],
        spec: "CiA 306 V1.3 §4.6.3.1",
        explanation: "\
An object list ([MandatoryObjects], [OptionalObjects], [ManufacturerObjects]) names an index for \
which the file has no `[xxxx]` section.

The list promises an object the file does not describe, so a master cannot configure or even name \
it. lely reports \"object not found\"; python canopen and CANopenEditor stay silent, and the \
device model silently lacks the object.

It is an error because CiA 306 §4.6.3.1 lists the objects the file describes, and the CiA \
conformance test checks that references point to existing entries.

Fix: `canopener eds fix` removes the entry and renumbers the list; if the object exists on the \
device, describe it instead.",
        fixable: true,
    },
    CheckInfo {
        code: "P043",
        slug: "unlisted-object",
        severity: Severity::Error,
        group: Group::ObjectLists,
        title: "every object section is named by an object list",
        reference: &[24],
        spec: "CiA 306 V1.3 §4.6.3.1",
        explanation: "\
An object section `[xxxx]` exists but no object list names its index.

lely's loader reads only the objects the lists name, so it silently drops this one, while python \
canopen and CANopenEditor load it: the same file gives different object dictionaries. EdsDcfNet \
reports it as INI_UNLISTED_OBJECT_SECTION.

It is an error because CiA 306 §4.6.3.1 makes the three lists the complete inventory of the \
objects described. In the corpus every case is a real omission: lists that fell behind the \
sections, or files written without object lists at all.

Fix: `canopener eds fix` adds the index to the list CiA 306 assigns to its range and updates \
SupportedObjects.",
        fixable: true,
    },
    CheckInfo {
        code: "P044",
        slug: "malformed-object-list",
        severity: Severity::Error,
        group: Group::ObjectLists,
        title: "object lists count, number and name their entries correctly",
        reference: &[22, 25],
        spec: "CiA 306 V1.3 §4.6.3.1",
        explanation: "\
An object list is inconsistent: SupportedObjects disagrees with the number of entries or is not a \
number, an entry is not numbered 1, 2, ... in decimal, an entry is not an object index, or an \
index is listed twice.

Readers walk the list from 1 to SupportedObjects: lely ignores entries above the count and its \
dcfchk reports missing ones, so objects disappear or the file is rejected. python canopen's own \
sample files carry `SupportedObjects=0` above a populated list.

It is an error because CiA 306 §4.6.3.1 defines SupportedObjects as the number of entries, \
numbered 1..SupportedObjects.

Fix: `canopener eds fix` renumbers the list, removes duplicates and recounts SupportedObjects.",
        fixable: true,
    },
    CheckInfo {
        code: "P045",
        slug: "sub-number-mismatch",
        severity: Severity::Error,
        group: Group::Objects,
        title: "SubNumber equals the number of sub-object sections",
        reference: &[34],
        spec: "CiA 306 V1.3 §4.6.3.2",
        explanation: "\
SubNumber of an ARRAY or RECORD differs from the number of `[xxxxsubN]` sections present (sub 0 \
included, sub FFh excluded).

lely's loader walks the sub-indices from 0 upwards and stops once it has found SubNumber sections: \
with SubNumber too low it silently drops the highest sub-objects (1018h with SubNumber=4 and \
sub 0..4 loses the serial number); with SubNumber too high its dcfchk reports missing \
sub-objects. A common cause is counting without sub 0.

It is an error because CiA 306 §4.6.3.2 defines SubNumber exactly as the number of sub-indices \
implemented, sub 0 included. Every case in the corpus is a real mismatch.

Fix: `canopener eds fix` sets SubNumber to the number of sub-object sections present; if \
sub-objects are missing instead, describe them.",
        fixable: true,
    },
    CheckInfo {
        code: "P046",
        slug: "compact-entry-out-of-range",
        severity: Severity::Error,
        group: Group::Objects,
        title: "[xxxxName], [xxxxValue] and [xxxxDenotation] entries are numbered 1..CompactSubObj",
        reference: &[42],
        spec: "CiA 306 V1.3 §4.6.3.4.2, §5.3.3",
        explanation: "\
An entry of [xxxxName], [xxxxValue] or [xxxxDenotation] is not a sub-index 1..CompactSubObj \
written in decimal (0, above CompactSubObj, `0x01`, `01`). canopener ignores the entry.

The entry names a sub-object that the compact description does not create, so its name or value \
applies to nothing; lely's dcfchk reports it.

It is an error because CiA 306 numbers these entries with the decimal sub-index 1..CompactSubObj \
(§4.6.3.4.2, DCF §5.3.3).

Fix: correct the entry number, or raise CompactSubObj if the object really has more sub-objects.",
        fixable: false,
    },
    CheckInfo {
        code: "P050",
        slug: "invalid-number",
        severity: Severity::Error,
        group: Group::Values,
        title: "integers are decimal, `0x` hexadecimal or `0` octal",
        reference: &[7, 45],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
An integer value is not written in one of the three forms CiA 306 allows: decimal, hexadecimal \
with `0x`, or octal with a leading `0`. Seen in real files: C suffixes (`0x1234LL`), escaped signs \
(`\\+384`), decimals on integer types (`0.0` on UNSIGNED32), and leading zeros followed by 8 or 9 \
(`089`, not octal).

Readers disagree on such text: python canopen reads None or aborts, lely's strtoul stops at the \
first bad character and keeps the digits before it, CANopenEditor failed on `DefaultValue=0.0` \
for an UNSIGNED32 (libedssharp #219).

It is an error because the value has no meaning under CiA 306 §4.2.

Fix: write the number as `0x...` or in plain decimal.",
        fixable: false,
    },
    CheckInfo {
        code: "P051",
        slug: "octal-leading-zero",
        severity: Severity::Warning,
        group: Group::Values,
        title: "no integer is written with a leading zero",
        reference: &[7],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
An integer is written with a leading zero (`0254`), which CiA 306 reads as octal: 0254 = 172, not \
254. canopener reads it as CiA 306 does and the message gives the value.

The author almost always meant decimal. python canopen's int(x, 0) rejects the text (issue #313, \
`VendorNumber=001`) and lely's dcfchk crashes on it, while lely's C loader and CANopenEditor read \
octal.

It is a warning: the text is valid CiA 306 (§4.2 defines the octal form), but it is ambiguous in \
practice and rejected by python tools.

Fix: write the value in hexadecimal or in decimal without the leading zero.",
        fixable: false,
    },
    CheckInfo {
        code: "P052",
        slug: "hex-suffix",
        severity: Severity::Error,
        group: Group::Values,
        title: "hexadecimal numbers use the `0x` prefix, not an `h` suffix",
        reference: &[7],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A number is written with an `h` suffix (`FEh`), the notation of CiA documents but not of EDS \
files. canopener reads it as hexadecimal.

python canopen reads None silently, lely reports it, canopen-host rejects the whole file and \
CANopenEditor keeps the text as a string.

It is an error because CiA 306 §4.2 writes hexadecimal numbers with the `0x` prefix only.

Fix: write `0xFE`.",
        fixable: false,
    },
    CheckInfo {
        code: "P053",
        slug: "inline-comment",
        severity: Severity::Warning,
        group: Group::Values,
        title: "object entries carry no inline comment",
        reference: &[5],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A typed entry of an object section carries text after its value introduced by `;` or `#` \
(`DataType=0x0007 ; UNSIGNED32`). canopener ignores the text from the comment character on.

python canopen strips ` ;...` and lely cuts the value at `;` or `#`, so both read the number; \
CANopenEditor keeps the whole text as the value and fails to use it. Check C103 reports `;` and \
`#` in the other values of the file.

It is a warning: CiA 306 §4.2 has only whole-line comments, so strictly the value is not a number, \
but its meaning is unambiguous and two of the three readers surveyed take it.

Fix: move the comment to its own line starting with `;`.",
        fixable: false,
    },
    CheckInfo {
        code: "P054",
        slug: "value-out-of-range",
        severity: Severity::Error,
        group: Group::Values,
        title: "values lie within the range of their data type",
        reference: &[46],
        spec: "CiA 306 V1.3 §4.6.3.2, CiA 301",
        explanation: "\
A DefaultValue, LowLimit, HighLimit or ParameterValue lies outside the range of the entry's data \
type (`300` for UNSIGNED8, `65535` for INTEGER16, `-30` for UNSIGNED8), or a `$NODEID` formula \
leaves the range for some node-ID 1..127.

No device can hold the value. lely reports an overflow; canopen-host silently truncates 300 to 44 \
for an UNSIGNED8; limits out of range make every range check of the entry meaningless.

It is an error because the value contradicts the data type the same section declares (CiA 306 \
§4.6.3.2, data type ranges of CiA 301).

Fix: correct the value, or the DataType if the value is right. For signed types write negative \
limits as negative decimals (`-32768`).",
        fixable: false,
    },
    CheckInfo {
        code: "P055",
        slug: "twos-complement",
        severity: Severity::Warning,
        group: Group::Values,
        title: "signed values are written as signed numbers",
        reference: &[49],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A value of a signed type is written as an unsigned bit pattern (`LowLimit=0x80000000` for \
INTEGER32). canopener reads it as two's complement and the message gives the signed value.

python canopen converts it as two's complement too, but lely range-checks `0x80000000` as \
+2147483648 and reports an overflow, a false positive many users hit (ros2_canopen #394).

It is a warning: CiA 306 does not say how negative numbers are written in hexadecimal, so the \
form is tolerated, but readers disagree on it.

Fix: write the value as a negative decimal (`-2147483648`).",
        fixable: false,
    },
    CheckInfo {
        code: "P056",
        slug: "nodeid-formula",
        severity: Severity::Error,
        group: Group::Values,
        title: "`$NODEID` formulas are written `$NODEID+offset`",
        reference: &[47],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A `$NODEID` formula does not start with `$NODEID`, or adds more than one offset \
(`0x180+$NODEID`, `0x40000000+$NODEID+0x180`). canopener sums the terms and the message gives the \
meaning.

lely rejects both forms as an invalid value; python canopen accepts the suffix form but reads \
None for several offsets; CANopenEditor accepts both orders. Generators such as CANopenNode's \
editor write the suffix form, so such files fail in lely-based masters (ros2_canopen).

It is an error because CiA 306 §4.2 defines the formula as `$NODEID` followed by one additive \
offset and says a value not starting with `$NODEID` is read without formula, which makes the text \
an invalid number.

Fix: write `$NODEID+0x180` (sum several offsets into one).",
        fixable: false,
    },
    CheckInfo {
        code: "P057",
        slug: "nodeid-on-non-integer",
        severity: Severity::Error,
        group: Group::Values,
        title: "`$NODEID` is used only on integer entries",
        reference: &[47],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A value mentions `$NODEID` although the entry's data type is not an integer (a string, REAL, \
octet string or DOMAIN).

Readers substitute the node-ID only in integer values: in a string the text `$NODEID` stays as it \
is, and in other types the value becomes unreadable.

It is an error because CiA 306 §4.2 allows the formula only for integer data types.

Fix: write the value without the formula, or correct the DataType.",
        fixable: false,
    },
    CheckInfo {
        code: "P058",
        slug: "real-notation",
        severity: Severity::Info,
        group: Group::Values,
        title: "REAL values are written in a notation every tool reads the same way",
        reference: &[48],
        spec: "CiA 306 V1.3 §4.2 (REAL notation not specified)",
        explanation: "\
A REAL32 or REAL64 value is written either as a decimal (`1.5`) or as an IEEE 754 bit pattern \
(`0x3FC00000`); the message says which one and which tool misreads it.

The tools disagree: lely reads REAL values only as bit patterns and rejects `1.5`; python canopen \
and CANFestival call float() on the text and read None for `0x3FC00000`. Both notations are in \
wide use, so no choice suits every reader.

It is only a hint: CiA 306 V1.3 does not specify how REAL values are written, so neither notation \
is wrong.

Fix: pick the notation your tool chain reads and use it throughout the file.",
        fixable: false,
    },
    CheckInfo {
        code: "P059",
        slug: "invalid-octets",
        severity: Severity::Error,
        group: Group::Values,
        title: "OCTET_STRING and DOMAIN data are an even number of hex digits",
        reference: &[48],
        spec: "CiA 306 V1.3 §4.3",
        explanation: "\
An OCTET_STRING value (or a DOMAIN ParameterValue) is not a sequence of hex digit pairs: it has \
an odd number of digits or characters that are not hex digits. canopener tolerates white space \
between the pairs and a `0x` prefix.

python canopen reads it with bytes.fromhex and fails; lely's hex lexer stops at the first \
character that is not a hex digit and keeps fewer bytes, so the device gets other data than the \
author wrote.

It is an error because CiA 306 writes octet strings as hex bytes without `0x`, two digits per byte \
with the leading 0 kept (`01a1053c`).

Fix: write two hex digits per byte, without prefix or separators.",
        fixable: false,
    },
    CheckInfo {
        code: "P060",
        slug: "invalid-boolean",
        severity: Severity::Error,
        group: Group::Values,
        title: "BOOLEAN values are 0 or 1",
        reference: &[48],
        spec: "CiA 306 V1.3 §4.2, CiA 301",
        explanation: "\
A value of a BOOLEAN entry is neither 0 nor 1 (seen: `3`, `0xFFFF` as HighLimit).

lely reports such a value as out of range; readers that accept it store a boolean the device \
cannot hold, and whether it means true depends on the tool.

It is an error because BOOLEAN has exactly the values 0 and 1 (CiA 301).

Fix: write 0 or 1, or correct the DataType if the entry is not a boolean.",
        fixable: false,
    },
    CheckInfo {
        code: "P061",
        slug: "invalid-value",
        severity: Severity::Error,
        group: Group::Values,
        title: "every value is valid for its data type",
        reference: &[45],
        spec: "CiA 306 V1.3 §4.2, §4.6.3.2",
        explanation: "\
A DefaultValue, LowLimit, HighLimit or ParameterValue of a REAL or time type cannot be read as \
its data type: `0.0f` (C syntax) on REAL32, text on a TIME_OF_DAY. (Integers, booleans and octet \
strings have their own codes: P050, P060, P059.)

Readers substitute 0 or None without telling (python canopen's float() fails, lely rejects the \
value), so the device default is unknown.

It is an error because the value has no meaning for the data type the section declares.

Fix: write the value in the syntax of its type, or correct the DataType.",
        fixable: false,
    },
    CheckInfo {
        code: "P062",
        slug: "nodeid-spelling",
        severity: Severity::Info,
        group: Group::Values,
        title: "`$NODEID+offset` is written in capitals without spaces",
        reference: &[47],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A `$NODEID` formula has the right form but is written with spaces or in other letter case \
(`$NodeID+0x80`, `$NODEID + 0x180`). canopener reads it normally.

python canopen upper-cases and removes spaces, lely and CANopenEditor (since its issue #57) accept \
both, and Vector's checker accepts them too; a strict hand-written parser comparing the literal \
text `$NODEID+` does not.

It is only a hint: the meaning is unambiguous and every reader surveyed accepts it.

Fix: write `$NODEID+0x180`.",
        fixable: false,
    },
    CheckInfo {
        code: "P070",
        slug: "unknown-object-type",
        severity: Severity::Error,
        group: Group::Objects,
        title: "ObjectType is one of the codes CiA 306 defines",
        reference: &[29],
        spec: "CiA 306 V1.3 §4.6.3.2",
        explanation: "\
ObjectType is not one of 0x0 (NULL), 0x2 (DOMAIN), 0x5 (DEFTYPE), 0x6 (DEFSTRUCT), 0x7 (VAR), \
0x8 (ARRAY) or 0x9 (RECORD), or is not a number.

The object code decides which keys apply and whether sub-objects exist; with an unknown code lely \
rejects the object and python canopen leaves it out of the object dictionary without a word.

It is an error because CiA 306 §4.6.3.2 defines exactly these codes.

Fix: write the object code of the object (0x7 for a single value, 0x8 for an array, 0x9 for a \
record).",
        fixable: false,
    },
    CheckInfo {
        code: "P071",
        slug: "unknown-data-type",
        severity: Severity::Error,
        group: Group::Objects,
        title: "DataType is a CiA 301 type or defined in the file",
        reference: &[31],
        spec: "CiA 306 V1.3 §4.6.3.2, CiA 301",
        explanation: "\
DataType is not a number, or names an index that is neither a CiA 301 data type nor defined by a \
DEFTYPE or DEFSTRUCT section of the file (for example 0x0040, a manufacturer-specific type, \
without its definition).

Without the type nobody knows the size or encoding of the value: SDO transfers, PDO mapping \
lengths and value checks all depend on it. python canopen falls back to DOMAIN with a warning.

It is an error because CiA 306 §4.6.3.2 makes DataType the index of a data type of the object \
dictionary.

Fix: use the index of a CiA 301 type (0x0007 for UNSIGNED32), or add the type's definition.",
        fixable: false,
    },
    CheckInfo {
        code: "P072",
        slug: "unknown-access-type",
        severity: Severity::Error,
        group: Group::Objects,
        title: "AccessType is ro, wo, rw, rwr, rww or const",
        reference: &[32],
        spec: "CiA 306 V1.3 §4.6.3.2",
        explanation: "\
AccessType is not one of the six tokens CiA 306 defines (seen: `UNKNOWN`, `readwrite`).

The access type decides whether a master may read or write the entry and in which PDO direction \
it can be mapped. python canopen keeps the text verbatim, lely and canopen-host report it, and \
CANopenEditor leaves the access empty.

It is an error because CiA 306 §4.6.3.2 defines exactly ro, wo, rw, rwr, rww and const.

Fix: write the access type of the entry.",
        fixable: false,
    },
    CheckInfo {
        code: "P073",
        slug: "missing-key",
        severity: Severity::Error,
        group: Group::Objects,
        title: "object sections carry the keys their object type requires",
        reference: &[28, 30],
        spec: "CiA 306 V1.3 §4.6.3.2",
        explanation: "\
An object or sub-object section lacks a key the CiA 306 key table requires for its object type: \
ParameterName always; DataType and AccessType for a VAR (and for an ARRAY or RECORD with \
CompactSubObj); SubNumber for an ARRAY or RECORD without CompactSubObj.

python canopen aborts with NoOptionError on a VAR without AccessType, lely's dcfchk crashes with \
KeyError, and CANopenEditor silently drops the object.

It is an error because CiA 306 §4.6.3.2 marks these keys mandatory.

Fix: add the key.",
        fixable: false,
    },
    CheckInfo {
        code: "P074",
        slug: "invalid-compact-sub-obj",
        severity: Severity::Error,
        group: Group::Objects,
        title: "CompactSubObj is a number up to 254 on an ARRAY or RECORD without SubNumber",
        reference: &[41],
        spec: "CiA 306 V1.3 §4.6.3.4.2",
        explanation: "\
CompactSubObj cannot be applied as written: it is not a number, it exceeds 254, it sits on a VAR \
or DOMAIN (which have no sub-objects), or it is given together with a non-zero SubNumber.

lely rejects an object with both SubNumber and CompactSubObj; CANopenEditor clips values above \
254; on a VAR the key is meaningless and the sub-objects the author intended do not exist (often \
the ObjectType should be 0x8).

It is an error because CiA 306 §4.6.3.4.2 defines CompactSubObj as an UNSIGNED8 count of \
sub-objects 1..254 for arrays and records described without sub-object sections, and requires \
SubNumber to be 0 or absent with it.

Fix: correct CompactSubObj, or the ObjectType, or remove SubNumber.",
        fixable: false,
    },
    CheckInfo {
        code: "P080",
        slug: "pdo-pair-incomplete",
        severity: Severity::Error,
        group: Group::Cia301,
        title: "every PDO has both its communication and its mapping object",
        reference: &[54],
        spec: "CiA 301-§7.5.2.38",
        explanation: "\
A PDO communication object (1400h-15FFh, 1800h-19FFh) exists without its mapping object \
(1600h-17FFh, 1A00h-1BFFh), or the reverse.

A PDO needs both: the communication object says when and with which COB-ID it is sent, the \
mapping object what it carries. lely's dcfchk crashes with KeyError on a TPDO without its mapping; \
masters cannot configure the PDO.

It is an error because CiA 301 defines each PDO by the pair of objects.

Fix: add the missing object (with CompactPDO, remove the explicit half and let the compact form \
describe both).",
        fixable: false,
    },
    CheckInfo {
        code: "P090",
        slug: "unlisted-module",
        severity: Severity::Error,
        group: Group::Modules,
        title: "module sections use module numbers [SupportedModules] declares",
        reference: &[62],
        spec: "CiA 306 V1.3 §6",
        explanation: "\
A module section `[M<x>...]` uses a module number x that is 0 or larger than \
[SupportedModules] NrOfEntries, or the file has no [SupportedModules] at all.

Tools that configure modular devices enumerate modules 1..NrOfEntries, so the module is never \
offered; EdsDcfNet reports it as INI_UNLISTED_MODULE_SECTION.

It is an error because CiA 306 §6 numbers module descriptions 1..NrOfEntries of \
[SupportedModules].

Fix: raise NrOfEntries, renumber the module sections, or delete them.",
        fixable: false,
    },
];

/// Turns the loading diagnostics into findings, marking those the fix engine corrects.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    for diagnostic in cx.diagnostics {
        let code = diagnostic.code.as_str();
        let fixable = CHECKS.iter().any(|c| c.code == code && c.fixable);
        out.push(Finding::from_diagnostic(diagnostic, fixable));
    }
}

#[cfg(test)]
mod tests {
    use canopener_eds::diag::Code;

    use super::*;

    #[test]
    fn every_loading_code_has_exactly_one_entry_with_the_same_slug_and_severity() {
        let table: Vec<(&str, &str, Severity)> =
            CHECKS.iter().map(|c| (c.code, c.slug, c.severity)).collect();
        let loader: Vec<(&str, &str, Severity)> = Code::ALL
            .iter()
            .map(|c| (c.as_str(), c.slug(), c.severity()))
            .collect();
        assert_eq!(table, loader);
    }

    #[test]
    fn exactly_the_codes_the_fix_engine_corrects_are_fixable() {
        let fixable: Vec<&str> = CHECKS.iter().filter(|c| c.fixable).map(|c| c.code).collect();
        assert_eq!(fixable, ["P031", "P032", "P042", "P043", "P044", "P045"]);
        let engine: Vec<&str> = crate::fix::BUILTIN_FIXES
            .iter()
            .copied()
            .filter(|c| c.starts_with('P'))
            .collect();
        assert_eq!(fixable, engine);
    }

    #[test]
    fn references_are_checks_of_section_10_and_explanations_are_pages() {
        for c in CHECKS {
            assert!(c.reference.iter().all(|&r| (1..=65).contains(&r)), "{}", c.code);
            assert!(c.spec.starts_with("CiA "), "{}", c.code);
            let paragraphs = c.explanation.split("\n\n").count();
            assert!(
                (2..=4).contains(&paragraphs),
                "{}: {paragraphs} paragraphs",
                c.code
            );
            assert!(
                c.explanation.lines().all(|l| !l.starts_with('#')),
                "{}: no headings",
                c.code
            );
        }
    }

    #[test]
    fn diagnostics_become_findings_with_their_fixability() {
        let loaded = canopener_eds::load(b"[FileInfo]\nFileName=x.eds\nFileName=y.eds\n[1000sub01]\nA=1\n");
        let cx = Context::new(&loaded, Some("x.eds"));
        let mut out = Vec::new();
        run(&cx, &mut out);
        assert_eq!(out.len(), loaded.diagnostics.len());
        let duplicate = out.iter().find(|f| f.diagnostic.code == "P021");
        assert!(duplicate.is_some_and(|f| !f.fixable && f.diagnostic.severity == Severity::Error));
        let spelling = out.iter().find(|f| f.diagnostic.code == "P031");
        assert!(spelling.is_some_and(|f| f.fixable && f.diagnostic.section.as_deref() == Some("1000sub01")));
    }
}
