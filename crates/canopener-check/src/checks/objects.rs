//! Group F of the check catalogue (`docs/check-catalogue.md`): object and sub-object sections (checks 28-44).
//!
//! The loader already reports a missing `ParameterName` or other mandatory key (P073), unknown
//! object, data and access types (P070-P072), a `SubNumber` that disagrees with the sub-sections
//! (P045), orphan sub-sections and companion sections (P040, P041), leading zeros in section names
//! (P031), sub-indices above FFh (P030), every `CompactSubObj` problem (P074) and companion entries
//! outside 1..=CompactSubObj (P046). The checks here add the rest: the key obligation matrix's "not
//! supported" keys, `PDOMapping` values and mappability, sub-index 0, ARRAY and standard structure
//! sub-types, companion counts, object links and `ObjFlags`.
//!
//! Checks about how a file is written look only at sections that are written (`Origin::Explicit`);
//! sub-objects generated from `CompactSubObj` or `CompactPDO` are not in the file.

use std::collections::BTreeMap;

use canopener_eds::model::{Attributes, Object, Properties, int_of};
use canopener_eds::section_name::{Companion, SectionKind};
use canopener_eds::{AccessType, DataType, ObjectType, Origin, Severity, TypeKind};

use crate::check_info::{CheckInfo, Group};
use crate::context::{Context, object_kind};
use crate::finding::Finding;

const PARAMETER_NAME_TOO_LONG: CheckInfo = CheckInfo {
    code: "C501",
    slug: "parameter-name-too-long",
    severity: Severity::Warning,
    group: Group::Objects,
    title: "ParameterName is at most 241 characters",
    reference: &[28],
    spec: "CiA 306 V1.3 §4.6.3.2",
    explanation: "\
CiA 306 §4.6.3.2 limits ParameterName to 241 characters, so that `ParameterName=` plus the name \
fits the 255-character line limit of §4.2 with room to spare. This check reports longer names.

Tools that size their buffers by the specification truncate the name (the CiA conformance tool \
reports it), and a name that long no longer fits a configuration tool's tree or a generated C \
identifier.

It is a warning: the object is still read correctly; only the name suffers.

Fix: shorten the name; put the long description in the device manual or a [Comments] line.",
    fixable: false,
};

const KEY_NOT_SUPPORTED: CheckInfo = CheckInfo {
    code: "C502",
    slug: "key-not-supported-for-object-type",
    severity: Severity::Warning,
    group: Group::Objects,
    title: "no key the obligation table marks \"not supported\" for the object type",
    reference: &[30],
    spec: "CiA 306 V1.3 §4.6.3.2 (table of keys per object type)",
    explanation: "\
The table in CiA 306 §4.6.3.2 says which keys each object type takes. Keys it marks \"not \
supported\" are: SubNumber and CompactSubObj on a VAR or DEFTYPE; DataType, AccessType, \
DefaultValue, PDOMapping, LowLimit and HighLimit on an ARRAY, RECORD or DEFSTRUCT without \
CompactSubObj (those belong on the sub-objects); PDOMapping, SubNumber, LowLimit, HighLimit and \
CompactSubObj on a DOMAIN. This check reports such a key with a non-empty value. (A non-zero \
CompactSubObj on a VAR or DOMAIN, or next to a SubNumber, is reported as P074.)

Readers ignore the key, so whatever it says has no effect: an AccessType on a RECORD does not make \
its sub-objects writable, a DefaultValue on an ARRAY does not fill its entries. lely's dcfchk \
rejects AccessType on a RECORD; EdsDcfNet reports INI_OBJECT_KEY_NOT_SUPPORTED.

It is a warning, not an error: CiA 306 allows extra keys for future extensions (§4.2) and its own \
DCF example carries SubNumber=0 on a VAR, and no tool misreads the object because of it.

Fix: delete the key, or move it to the sub-objects it was meant for.",
    fixable: false,
};

const ACCESS_TYPE_CASE: CheckInfo = CheckInfo {
    code: "C503",
    slug: "access-type-not-lowercase",
    severity: Severity::Info,
    group: Group::Objects,
    title: "AccessType is written in lower case",
    reference: &[32],
    spec: "CiA 306 V1.3 §4.6.3.2",
    explanation: "\
CiA 306 §4.6.3.2 spells the access types ro, wo, rw, rwr, rww and const. This check reports a \
valid access type written in other letter case (RW, Ro, CONST).

python canopen, lely, CANopenEditor and CANFestival's objdictgen all compare the token without \
regard to case, so the file is read correctly; hand-written parsers and scripts that compare \
strings literally are the ones that trip.

It is only information: the meaning is unambiguous.

Fix: write the token in lower case.",
    fixable: false,
};

const PDO_MAPPING_NOT_BOOLEAN: CheckInfo = CheckInfo {
    code: "C504",
    slug: "pdo-mapping-not-boolean",
    severity: Severity::Error,
    group: Group::Objects,
    title: "PDOMapping is 0 or 1",
    reference: &[33],
    spec: "CiA 306 V1.3 §4.6.3.2",
    explanation: "\
PDOMapping is a Boolean (CiA 306 §4.6.3.2): 0 means the object cannot be mapped into a PDO, 1 that \
it can. This check reports any other value (2, yes, TRUE, text).

Tools disagree on what such a value means: python canopen raises on a value int() cannot read, \
CANopenEditor treats anything but 1 as not mappable, so the same file gives a mappable object in \
one tool and an unmappable one in another.

It is an error because the value is not a Boolean as CiA 306 defines it.

Fix: write PDOMapping=1 if the object may be mapped, PDOMapping=0 otherwise.",
    fixable: false,
};

const PDO_MAPPING_ON_DOMAIN: CheckInfo = CheckInfo {
    code: "C505",
    slug: "pdo-mapping-on-domain",
    severity: Severity::Error,
    group: Group::Objects,
    title: "no DOMAIN is marked PDO-mappable",
    reference: &[33],
    spec: "CiA 306 V1.3 §4.6.3.2, CiA 301",
    explanation: "\
A DOMAIN (object type 0x2, or data type 0x000F) is a block of data of any length, transferred by \
SDO. A PDO mapping entry gives a fixed length of at most 64 bits, so a DOMAIN cannot be mapped. \
This check reports PDOMapping=1 on a DOMAIN.

A configuration tool offers the object for mapping, and the mapping fails on the device (SDO abort \
0x06040041, object cannot be mapped to the PDO) or, worse, maps an arbitrary prefix of the data.

It is an error: the table of CiA 306 §4.6.3.2 marks PDOMapping \"not supported\" for DOMAIN objects, \
and CiA 301 mapping entries cannot describe a variable length.

Fix: set PDOMapping=0, or describe the mappable part as a VAR of a fixed-length type.",
    fixable: false,
};

const PDO_MAPPING_ON_STRING: CheckInfo = CheckInfo {
    code: "C506",
    slug: "pdo-mapping-on-string",
    severity: Severity::Warning,
    group: Group::Objects,
    title: "strings marked PDO-mappable",
    reference: &[33],
    spec: "CiA 301",
    explanation: "\
VISIBLE_STRING, OCTET_STRING and UNICODE_STRING objects have a length of their own. This check \
reports PDOMapping=1 on them.

A string can only be mapped with a fixed length that the mapping entry states (8 bits per \
character); the EDS does not say that length, so a configuration tool has to guess, and python \
canopen and CANopenEditor size the string from its DefaultValue. Several devices (CANopenNode's \
examples among them) do map short octet strings.

It is a warning, not an error: CiA 301 does not forbid mapping a fixed-length string, but the file \
cannot say which length is meant.

Fix: set PDOMapping=0, or map the data through fixed-size integer objects.",
    fixable: false,
};

const MAPPING_DIRECTION_UNCLEAR: CheckInfo = CheckInfo {
    code: "C518",
    slug: "mapping-direction-unclear",
    severity: Severity::Warning,
    group: Group::Objects,
    title: "PDO-mappable read/write entries say their direction (rww or rwr, not rw)",
    reference: &[33],
    spec: "CiA 306 V1.3 §4.6.3.2 (AccessType rwr, rww); CANchkEDS warning 4",
    explanation: "\
CiA 306 gives read/write entries three access types: rw, rwr (\"read/write on process input\", \
which a TPDO transmits) and rww (\"read/write on process output\", which an RPDO writes). This check \
reports an entry with AccessType=rw and PDOMapping=1: it may be mapped, but the file does not say \
whether it is process input or output. CiA's EDS checker CANchkEDS, which the conformance test runs \
as its first case, reports the same as warning 4 (\"Access type in section [6200sub1] has no clear \
mapping direction\"): on CANopenNode's demoDevice.eds it is 36 of its 43 warnings, and canopener \
reports the same 36 entries. In the corpus it fires on 1398 entries of 65 of the 148 EDS/DCF files \
(`tests/mapping_direction_corpus.rs` keeps the count per file), every one an rw entry with \
PDOMapping=1: servo drives' parameters (516 in one ASDA-A3 file), CANopenNode's outputs, test files.

Configuration tools that lay out process data from the EDS cannot tell whether to offer the entry \
for a TPDO or an RPDO, and a CiA 311 export loses the direction (CANopenEditor writes PDOmapping \
`optional`).

It is a warning, not an error: rw entries may be mapped in both directions (CiA 301), and a device \
is right to accept that; the file only leaves the direction unsaid.

Fix: write AccessType=rww for outputs an RPDO writes (6200h, 6411h), rwr for inputs a TPDO reads.",
    fixable: false,
};

const SUB_OF_SIMPLE_OBJECT: CheckInfo = CheckInfo {
    code: "C507",
    slug: "sub-object-of-simple-object",
    severity: Severity::Error,
    group: Group::Objects,
    title: "only ARRAY, RECORD and DEFSTRUCT objects have sub-object sections",
    reference: &[35],
    spec: "CiA 306 V1.3 §4.6.3.2, §4.6.3.3",
    explanation: "\
Sub-object sections [<index>sub<n>] describe the entries of an ARRAY, RECORD or DEFSTRUCT. This \
check reports a sub-object section whose object is a VAR, DOMAIN, DEFTYPE or NULL (a missing \
ObjectType means VAR).

Readers disagree on what the sub-objects mean: python canopen builds a VAR and drops them, lely \
rejects them, CANopenEditor attaches them to a VAR it then writes back without them. Either the \
ObjectType is wrong (the object is really a RECORD) or the sub-sections are left over.

It is an error because CiA 306 §4.6.3.2 gives a VAR no sub-objects (SubNumber is \"not supported\" \
for it).

Fix: set ObjectType=0x8 (ARRAY) or 0x9 (RECORD) with a SubNumber, or delete the sub-sections.",
    fixable: false,
};

const SUB0_MISSING: CheckInfo = CheckInfo {
    code: "C508",
    slug: "sub0-missing",
    severity: Severity::Error,
    group: Group::Objects,
    title: "ARRAY and RECORD objects describe sub-index 0",
    reference: &[36],
    spec: "CiA 306 V1.3 §4.6.3.2, CiA 301",
    explanation: "\
Sub-index 0 of an ARRAY or RECORD holds the highest sub-index supported (CiA 301), and a \
master reads it first to learn how many entries follow. This check reports an ARRAY, RECORD or \
DEFSTRUCT that describes sub-objects but no [<index>sub0].

lely warns that the object \"does not provide the highest sub-index\"; SDO clients that read sub 0 \
to size the object get an abort from the device or a wrong answer from a simulator built from the \
EDS.

It is an error because sub 0 is part of every ARRAY and RECORD in CiA 301.

Fix: add [<index>sub0] with ParameterName=Highest sub-index supported, DataType=0x0005, \
AccessType=ro (or const) and DefaultValue set to the highest sub-index described.",
    fixable: false,
};

const SUB0_NOT_UNSIGNED8: CheckInfo = CheckInfo {
    code: "C509",
    slug: "sub0-not-unsigned8",
    severity: Severity::Error,
    group: Group::Objects,
    title: "sub-index 0 is UNSIGNED8",
    reference: &[36],
    spec: "CiA 301",
    explanation: "\
Sub-index 0 of an ARRAY, RECORD or DEFSTRUCT is UNSIGNED8 (CiA 301): it holds the highest \
sub-index, at most 254. This check reports another DataType on [<index>sub0].

An SDO client expects one byte; a device or simulator built from the EDS answers with two or four, \
and lely's dcfchk rejects the file (\"sub0 must be UNSIGNED8\").

It is an error because the type of sub-index 0 is fixed by CiA 301.

Fix: set DataType=0x0005 on the sub 0 section.",
    fixable: false,
};

const SUB0_NOT_HIGHEST: CheckInfo = CheckInfo {
    code: "C537",
    slug: "sub0-not-highest-sub-index",
    severity: Severity::Error,
    group: Group::Objects,
    title: "sub-index 0 DefaultValue equals the highest sub-index described",
    reference: &[37],
    spec: "CiA 306 V1.3 §4.6.3.2, CiA 301",
    explanation: "\
The DefaultValue of sub-index 0 of an ARRAY or RECORD is the highest sub-index the object \
implements (CiA 306 §4.6.3.2: sub-objects need not be consecutive, so [1010] with sub 0 and sub 4 \
has sub 0 = 4). This check compares it with the highest [<index>sub<n>] section present (FFh \
excluded). Objects whose sub 0 counts the entries in use may legitimately be lower: the \
pre-defined error field 1003h and the PDO mapping objects 1600h-17FFh and 1A00h-1BFFh (number of \
mapped objects, 0 = disabled); for those the check only requires sub 0 not to exceed the highest \
sub-index described. Objects that modules extend (CiA 306 §6) are not checked, since their sub 0 \
depends on the modules connected.

A master that reads sub 0 and then walks the entries up to it hits sub-indices the device does not \
have (SDO abort 0x06090011), or never reads the last ones. Simulators and generated object \
dictionaries take the count from sub 0 and disagree with the sections.

It is an error because CiA 301 defines sub 0 as the highest sub-index supported.

Fix: `canopener eds fix` sets the DefaultValue to the highest sub-index described. For a PDO \
mapping object whose sub 0 is higher than the entries described, describe the missing entries \
instead; the fix does not change a mapping.",
    fixable: true,
};

const ARRAY_SUB_TYPES_DIFFER: CheckInfo = CheckInfo {
    code: "C510",
    slug: "array-sub-types-differ",
    severity: Severity::Error,
    group: Group::Objects,
    title: "the entries 1..n of an ARRAY share one DataType",
    reference: &[39],
    spec: "CiA 301",
    explanation: "\
An ARRAY (ObjectType 0x8) is a sequence of entries of one data type (CiA 301); only \
sub-index 0, the number of entries, differs. This check reports an ARRAY sub-object from sub 1 on \
whose DataType differs from that of the lowest entry.

Code generators (CANopenNode's exporter, CANopenEditor) emit an ARRAY as a C array of one type and \
refuse or silently convert differing entries; a device built that way answers with the wrong \
length for the odd entries.

It is an error because an ARRAY with entries of different types is not an ARRAY in CiA 301.

Fix: give every entry the same DataType, or make the object a RECORD (ObjectType=0x9).",
    fixable: false,
};

const STRUCTURE_SUB_TYPE: CheckInfo = CheckInfo {
    code: "C511",
    slug: "standard-structure-sub-type",
    severity: Severity::Error,
    group: Group::Objects,
    title: "standard structures (PDO, SDO, identity) use the CiA 301 sub-object types",
    reference: &[40],
    spec: "CiA 301 (data types 0020h-0023h), §7.5.2",
    explanation: "\
CiA 301 defines four record structures: PDO_COMMUNICATION_PARAMETER (0020h: sub 1 UNSIGNED32 \
COB-ID, sub 2 UNSIGNED8 transmission type, sub 3 UNSIGNED16 inhibit time, sub 4 UNSIGNED8 \
reserved, sub 5 UNSIGNED16 event timer, sub 6 UNSIGNED8 SYNC start value), PDO_MAPPING (0021h: \
subs 1-64 UNSIGNED32), SDO_PARAMETER (0022h: subs 1-2 UNSIGNED32 COB-IDs, sub 3 UNSIGNED8 node-ID) \
and IDENTITY (0023h: subs 1-4 UNSIGNED32). The objects 1018h, 1200h-12FFh, 1400h-15FFh, \
1600h-17FFh, 1800h-19FFh and 1A00h-1BFFh are of these types. This check reports a sub-object of \
such an object whose DataType differs (sub 0 is covered by C509).

Masters configure PDOs and SDO channels by writing these sub-objects with the CiA 301 sizes; an \
SDO download of 4 bytes to a sub-object the device believes is 2 bytes long is aborted (0x06070010, \
length mismatch), and tools that decode mapping entries read garbage.

It is an error because the structures are fixed by CiA 301.

Fix: set the DataType given in the message.",
    fixable: false,
};

const COMPANION_WITHOUT_COMPACT: CheckInfo = CheckInfo {
    code: "C512",
    slug: "companion-without-compact-sub-obj",
    severity: Severity::Error,
    group: Group::Objects,
    title: "[<index>Name], [<index>Value] and [<index>Denotation] belong to CompactSubObj objects",
    reference: &[42],
    spec: "CiA 306 V1.3 §4.6.3.4.2, §5.3.3",
    explanation: "\
The sections [<index>Name], [<index>Value] and [<index>Denotation] name, configure and denote the \
sub-objects that CompactSubObj generates (CiA 306 §4.6.3.4.2 and §5.3.3). This check reports such \
a section for an object without a non-zero CompactSubObj.

Every reader ignores the section for an object whose sub-objects are written out, so the names, \
configured values or denotations in it are silently lost: a DCF's [<index>Value] entries are never \
downloaded to the device.

It is an error because the sections have no meaning outside the compact form.

Fix: move the names, values or denotations into the [<index>sub<n>] sections (ParameterName, \
ParameterValue, Denotation), or describe the object with CompactSubObj.",
    fixable: false,
};

const COMPANION_COUNT: CheckInfo = CheckInfo {
    code: "C513",
    slug: "companion-entry-count",
    severity: Severity::Error,
    group: Group::Objects,
    title: "NrOfEntries of [<index>Name], [<index>Value], [<index>Denotation] matches the entries",
    reference: &[42],
    spec: "CiA 306 V1.3 §4.6.3.4.2, §5.3.3",
    explanation: "\
A [<index>Name], [<index>Value] or [<index>Denotation] section starts with NrOfEntries=<n>, the \
number of entries that follow (they may be sparse: 1, 2 and 15 with NrOfEntries=3). This check \
reports a missing NrOfEntries or one that differs from the number of entries.

Readers bound their loop by NrOfEntries: python canopen reads only that many names, lely's dcfchk \
rejects the section, so entries beyond the count are lost and a count above the entries makes \
python canopen fail.

It is an error because CiA 306 §4.6.3.4.2 defines NrOfEntries as the number of entries.

Fix: set NrOfEntries to the number of sub-index entries in the section.",
    fixable: false,
};

const OBJECT_LINKS_COUNT: CheckInfo = CheckInfo {
    code: "C514",
    slug: "object-links-count",
    severity: Severity::Error,
    group: Group::Objects,
    title: "ObjectLinks in [<index>ObjectLinks] matches the numbered links",
    reference: &[43],
    spec: "CiA 306 V1.3 §4.6.4",
    explanation: "\
An [<index>ObjectLinks] section groups objects that belong together: ObjectLinks=<n>, then \
1=<index> ... n=<index>, numbered in decimal from 1 (CiA 306 §4.6.4). This check reports a missing \
ObjectLinks count, a count that differs from the numbered entries, and entries that are not \
numbered 1..n.

Tools that show the grouping (the CiA conformance tool, configuration tools) walk the entries 1..n \
and miss the rest or stop at a gap.

It is an error because CiA 306 §4.6.4 defines the count and the numbering.

Fix: number the links 1..n and set ObjectLinks=n.",
    fixable: false,
};

const OBJECT_LINK_TARGET: CheckInfo = CheckInfo {
    code: "C515",
    slug: "object-link-target-missing",
    severity: Severity::Error,
    group: Group::Objects,
    title: "every object link names an object the file describes",
    reference: &[43],
    spec: "CiA 306 V1.3 §4.6.4",
    explanation: "\
Each entry of an [<index>ObjectLinks] section names an object index (CiA 306 §4.6.4). This check \
reports an entry that is not an index or names an object the file does not describe (CiA's \
certification checks that \"references point to existing entries\").

A tool that follows the link finds nothing; usually the linked object was renamed or removed and \
the link was forgotten.

It is an error because a link must point to an object of the device.

Fix: correct the index, describe the object, or delete the link and renumber.",
    fixable: false,
};

const OBJ_FLAGS_INVALID: CheckInfo = CheckInfo {
    code: "C516",
    slug: "obj-flags-invalid",
    severity: Severity::Error,
    group: Group::Objects,
    title: "ObjFlags is an Unsigned32",
    reference: &[44],
    spec: "CiA 306 V1.3 §4.6.3.2",
    explanation: "\
ObjFlags is an Unsigned32 bit field (CiA 306 §4.6.3.2; bit 0: refuse write on download, bit 1: \
refuse read on scan). This check reports a value that is not a number or does not fit 32 bits.

Configuration tools decide from ObjFlags whether to download or scan the object; a value they \
cannot read is taken as 0, so an object that must not be written is written.

It is an error because the value is not an Unsigned32.

Fix: write the flags as a number, e.g. ObjFlags=0x1; omit the key when it is 0.",
    fixable: false,
};

const OBJ_FLAGS_RESERVED: CheckInfo = CheckInfo {
    code: "C517",
    slug: "obj-flags-reserved-bits",
    severity: Severity::Warning,
    group: Group::Objects,
    title: "ObjFlags sets only bits 0 and 1",
    reference: &[44],
    spec: "CiA 306 V1.3 §4.6.3.2",
    explanation: "\
CiA 306 §4.6.3.2 defines ObjFlags bit 0 (refuse write on download) and bit 1 (refuse read on \
scan); bits 2-31 are reserved and must be 0. This check reports reserved bits that are set \
(EdsDcfNet: INI_OBJ_FLAGS_RESERVED_BITS).

Today's tools ignore the reserved bits, but a later edition may give them a meaning (CiA 311 \
already defines bit 2 for XDD files), and the file then says something its author did not mean.

It is a warning: the defined bits are still read correctly.

Fix: clear bits 2-31.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    PARAMETER_NAME_TOO_LONG,
    KEY_NOT_SUPPORTED,
    ACCESS_TYPE_CASE,
    PDO_MAPPING_NOT_BOOLEAN,
    PDO_MAPPING_ON_DOMAIN,
    PDO_MAPPING_ON_STRING,
    MAPPING_DIRECTION_UNCLEAR,
    SUB_OF_SIMPLE_OBJECT,
    SUB0_MISSING,
    SUB0_NOT_UNSIGNED8,
    SUB0_NOT_HIGHEST,
    ARRAY_SUB_TYPES_DIFFER,
    STRUCTURE_SUB_TYPE,
    COMPANION_WITHOUT_COMPACT,
    COMPANION_COUNT,
    OBJECT_LINKS_COUNT,
    OBJECT_LINK_TARGET,
    OBJ_FLAGS_INVALID,
    OBJ_FLAGS_RESERVED,
];

/// CiA 306 V1.3 §4.6.3.2: ParameterName has at most 241 characters.
const MAX_PARAMETER_NAME: usize = 241;

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    for (&index, object) in &cx.eds.objects {
        if object.origin == Origin::Explicit {
            check_section(cx, out, index, None, &object.attributes);
        }
        for (&sub, sub_object) in &object.subs {
            if sub_object.origin == Origin::Explicit {
                check_section(cx, out, index, Some(sub), &sub_object.attributes);
            }
        }
        if object.origin != Origin::Explicit {
            continue;
        }
        check_structure(cx, out, index, object);
        check_companions(cx, out, index, object);
    }
}

/// Checks of one written section's keys.
fn check_section(cx: &Context<'_>, out: &mut Vec<Finding>, index: u16, sub: Option<u8>, a: &Attributes) {
    let kind = object_kind(index, sub);
    if let Some(name) = a.parameter_name.as_deref() {
        let chars = name.chars().count();
        if chars > MAX_PARAMETER_NAME {
            out.push(
                cx.finding(
                    &PARAMETER_NAME_TOO_LONG,
                    kind,
                    Some("ParameterName"),
                    format!(
                        "ParameterName has {chars} characters, more than the {MAX_PARAMETER_NAME} \
                         CiA 306 allows"
                    ),
                )
                .with_help("shorten the name; put the long description in [Comments]"),
            );
        }
    }
    let object_type = a.object_type();
    let compact = a.compact_sub_obj() != 0;
    for key in unsupported_keys(object_type, compact, sub.is_some(), a) {
        let value = a.get(key).unwrap_or("");
        let section = cx.display_name(kind);
        let what = object_type.map_or_else(|| "an object".to_owned(), with_article);
        let qualifier = match object_type {
            Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct) => " without CompactSubObj",
            _ => "",
        };
        out.push(
            cx.finding(
                &KEY_NOT_SUPPORTED,
                kind,
                Some(key),
                format!("{key}={value} is not supported on {what}{qualifier}; readers ignore it"),
            )
            .with_help(match object_type {
                Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct) => {
                    format!("delete {key} from [{section}] or move it to the sub-objects")
                }
                _ => format!("delete {key} from [{section}]"),
            }),
        );
    }
    if let (Some(raw), Some(access)) = (a.access_type.as_deref(), a.access_type())
        && raw.trim() != access.as_str()
        && raw.trim().eq_ignore_ascii_case(access.as_str())
    {
        out.push(
            cx.finding(
                &ACCESS_TYPE_CASE,
                kind,
                Some("AccessType"),
                format!(
                    "AccessType={} is spelt `{}` in CiA 306",
                    raw.trim(),
                    access.as_str()
                ),
            )
            .with_help(format!("write AccessType={}", access.as_str())),
        );
    }
    check_pdo_mapping(cx, out, kind, a);
    check_obj_flags(cx, out, kind, a);
}

/// The keys of a section that the obligation table of CiA 306 V1.3 §4.6.3.2 marks "not supported"
/// for its object type, among those written with a value. Cases P074 already reports (a non-zero
/// CompactSubObj on a VAR or DOMAIN, SubNumber next to CompactSubObj) and PDOMapping=1 on a
/// DOMAIN (C505) are left out.
fn unsupported_keys(
    object_type: Option<ObjectType>,
    compact: bool,
    is_sub: bool,
    a: &Attributes,
) -> Vec<&'static str> {
    let present = |key: &str| a.get(key).is_some_and(|v| !v.trim().is_empty());
    let candidates: &[&'static str] = match object_type {
        Some(ObjectType::Var) => {
            if compact {
                &["SubNumber"]
            } else {
                &["SubNumber", "CompactSubObj"]
            }
        }
        Some(ObjectType::DefType) => &["SubNumber", "CompactSubObj"],
        Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct) if !compact && !is_sub => &[
            "DataType",
            "AccessType",
            "DefaultValue",
            "PDOMapping",
            "LowLimit",
            "HighLimit",
        ],
        Some(ObjectType::Domain) => {
            if compact {
                &["SubNumber", "LowLimit", "HighLimit", "PDOMapping"]
            } else {
                &[
                    "SubNumber",
                    "LowLimit",
                    "HighLimit",
                    "PDOMapping",
                    "CompactSubObj",
                ]
            }
        }
        _ => &[],
    };
    candidates
        .iter()
        .copied()
        .filter(|&key| present(key))
        .filter(|&key| !(object_type == Some(ObjectType::Domain) && key == "PDOMapping" && a.pdo_mapping()))
        .collect()
}

fn check_pdo_mapping(cx: &Context<'_>, out: &mut Vec<Finding>, kind: SectionKind, a: &Attributes) {
    let Some(raw) = a.pdo_mapping.as_deref().map(str::trim) else {
        return;
    };
    if raw.is_empty() {
        return;
    }
    if !matches!(int_of(raw), Some(0 | 1)) {
        out.push(
            cx.finding(
                &PDO_MAPPING_NOT_BOOLEAN,
                kind,
                Some("PDOMapping"),
                format!("PDOMapping={raw} is not a Boolean 0 or 1"),
            )
            .with_help("write PDOMapping=1 if the object may be mapped into a PDO, PDOMapping=0 otherwise"),
        );
        return;
    }
    if !a.pdo_mapping() {
        return;
    }
    let object_type = a.object_type();
    let structured = matches!(
        object_type,
        Some(ObjectType::Array | ObjectType::Record | ObjectType::DefStruct)
    );
    if structured && a.compact_sub_obj() == 0 {
        // The key is "not supported" there (C502); it describes no value that could be mapped.
        return;
    }
    let data_type = a.data_type().map(|t| cx.eds.resolve_data_type(t));
    let kind_of = data_type.and_then(DataType::kind);
    let domain = object_type == Some(ObjectType::Domain) || kind_of == Some(TypeKind::Domain);
    if domain {
        out.push(
            cx.finding(
                &PDO_MAPPING_ON_DOMAIN,
                kind,
                Some("PDOMapping"),
                "PDOMapping=1 on a DOMAIN, which has no fixed length to map",
            )
            .with_help("set PDOMapping=0; DOMAIN data is transferred by SDO"),
        );
    } else if let (Some(t), Some(TypeKind::VisibleString | TypeKind::OctetString | TypeKind::UnicodeString)) =
        (data_type, kind_of)
    {
        out.push(
            cx.finding(
                &PDO_MAPPING_ON_STRING,
                kind,
                Some("PDOMapping"),
                format!("PDOMapping=1 on a {t}, whose mapped length the EDS cannot state"),
            )
            .with_help("set PDOMapping=0 unless the device maps a fixed length of this string"),
        );
    }
    // A DOMAIN cannot be mapped at all (C505): its direction is beside the point.
    if a.access_type() == Some(AccessType::Rw) && !domain {
        out.push(
            cx.finding(
                &MAPPING_DIRECTION_UNCLEAR,
                kind,
                Some("AccessType"),
                "AccessType=rw with PDOMapping=1 has no clear mapping direction: rww would say an RPDO \
                 writes it, rwr that a TPDO reads it",
            )
            .with_help("write AccessType=rww for an output, AccessType=rwr for an input"),
        );
    }
}

fn check_obj_flags(cx: &Context<'_>, out: &mut Vec<Finding>, kind: SectionKind, a: &Attributes) {
    let Some(raw) = a.obj_flags.as_deref().map(str::trim) else {
        return;
    };
    match a.obj_flags() {
        None => out.push(
            cx.finding(
                &OBJ_FLAGS_INVALID,
                kind,
                Some("ObjFlags"),
                format!("ObjFlags={raw} is not an Unsigned32"),
            )
            .with_help(
                "write the flags as a number: bit 0 refuse write on download, bit 1 refuse read on scan",
            ),
        ),
        Some(flags) if flags & !0x3 != 0 => out.push(
            cx.finding(
                &OBJ_FLAGS_RESERVED,
                kind,
                Some("ObjFlags"),
                format!("ObjFlags={raw} sets reserved bits 0x{:X}", flags & !0x3),
            )
            .with_help(format!(
                "write ObjFlags=0x{:X}, or omit the key when it is 0",
                flags & 0x3
            )),
        ),
        Some(_) => {}
    }
}

/// Checks of an object's sub-objects as a whole.
fn check_structure(cx: &Context<'_>, out: &mut Vec<Finding>, index: u16, object: &Object) {
    let Some(object_type) = object.object_type() else {
        return;
    };
    if !object_type.has_subs() {
        for (&sub, sub_object) in &object.subs {
            if sub_object.origin != Origin::Explicit {
                continue;
            }
            let kind = SectionKind::Sub(index, sub);
            out.push(
                cx.finding(
                    &SUB_OF_SIMPLE_OBJECT,
                    kind,
                    None,
                    format!(
                        "[{}] describes a sub-object of {index:04X}h, which is {}",
                        cx.display_name(kind),
                        with_article(object_type)
                    ),
                )
                .with_help(format!(
                    "set ObjectType=0x8 or 0x9 in [{}] if it has sub-objects, or delete this section",
                    cx.display_name(SectionKind::Object(index))
                )),
            );
        }
        return;
    }
    if object.subs.is_empty() {
        return;
    }
    let Some(sub0) = object.subs.get(&0) else {
        let first = object.subs.keys().next().copied().unwrap_or(1);
        out.push(
            cx.finding(
                &SUB0_MISSING,
                SectionKind::Object(index),
                None,
                format!(
                    "{object_type} {index:04X}h describes sub-objects from sub {first:X} on but no sub 0 \
                     (highest sub-index)"
                ),
            )
            .with_help(format!(
                "add [{index:X}sub0] with DataType=0x0005, AccessType=ro and the highest sub-index as \
                 DefaultValue"
            )),
        );
        return;
    };
    if sub0.origin == Origin::Explicit {
        check_sub0(cx, out, index, object, &sub0.attributes);
    }
    if object_type == ObjectType::Array {
        check_array_types(cx, out, index, object);
    }
    check_standard_structure(cx, out, index, object);
}

fn check_sub0(cx: &Context<'_>, out: &mut Vec<Finding>, index: u16, object: &Object, a: &Attributes) {
    let kind = SectionKind::Sub(index, 0);
    if let Some(t) = a.data_type()
        && t != DataType::UNSIGNED8
    {
        let raw = a.data_type.as_deref().unwrap_or("").trim();
        out.push(
            cx.finding(
                &SUB0_NOT_UNSIGNED8,
                kind,
                Some("DataType"),
                format!("sub 0 of {index:04X}h has DataType={raw} ({t}); it is UNSIGNED8 in CiA 301"),
            )
            .with_help("set DataType=0x0005"),
        );
    }
    if extended_by_modules(cx, index) {
        return;
    }
    let Some(raw) = a.default_value.as_deref().map(str::trim) else {
        return;
    };
    if raw.is_empty() || canopener_eds::value::mentions_nodeid(raw) {
        return;
    }
    let Some(value) = int_of(raw) else {
        return;
    };
    let highest = object
        .subs
        .keys()
        .copied()
        .filter(|&s| s != 0xFF)
        .max()
        .unwrap_or(0);
    let counts_entries = counts_entries_in_use(index);
    let wrong = if counts_entries {
        // CiA 301: FEh and FFh in sub 0 of a mapping object select SAM-MPDO and DAM-MPDO.
        let mpdo = matches!(index, 0x1600..=0x17FF | 0x1A00..=0x1BFF) && matches!(value, 0xFE | 0xFF);
        !mpdo && (value > i128::from(highest) || value < 0)
    } else {
        value != i128::from(highest)
    };
    let highest_text = if raw.starts_with("0x") || raw.starts_with("0X") {
        format!("0x{highest:X}")
    } else {
        highest.to_string()
    };
    if !wrong {
        return;
    }
    let finding =
        if counts_entries {
            cx.finding(
            &SUB0_NOT_HIGHEST,
            kind,
            Some("DefaultValue"),
            format!(
                "sub 0 of {index:04X}h says {raw} entries are in use, but the highest sub-index described \
                 is {highest:X}h"
            ),
        )
        .with_help(format!("describe the entries up to sub {raw}, or lower sub 0 to {highest_text} or less"))
        // Lowering the number of mapped objects changes what the device does; not a safe fix.
        .with_fixable(false)
        } else {
            cx.finding(
                &SUB0_NOT_HIGHEST,
                kind,
                Some("DefaultValue"),
                format!(
                    "sub 0 of {index:04X}h has DefaultValue {raw}, but the highest sub-index described is \
                 {highest:X}h"
                ),
            )
            .with_help(format!(
                "set DefaultValue={highest_text} in [{}]",
                cx.display_name(kind)
            ))
            // Raising sub 0 to the sub-indices described is safe; lowering it would hide entries the
            // device may have but the file leaves out, so the fix engine refuses that direction.
            .with_fixable(value < i128::from(highest))
        };
    out.push(finding);
}

/// Objects whose sub 0 counts the entries in use rather than naming the highest sub-index: the
/// pre-defined error field (CiA 301) and the PDO mapping parameters (§7.5.2.36, §7.5.2.38).
fn counts_entries_in_use(index: u16) -> bool {
    matches!(index, 0x1003 | 0x1600..=0x17FF | 0x1A00..=0x1BFF)
}

/// Whether a module of a modular device adds sub-indices to this object (CiA 306 §6.2): its sub 0
/// then depends on the modules connected.
fn extended_by_modules(cx: &Context<'_>, index: u16) -> bool {
    cx.eds.modules.values().any(|m| {
        m.sub_ext.contains_key(&index)
            || m.sub_extends
                .as_ref()
                .is_some_and(|p| p.numbered().any(|(_, v)| int_of(v) == Some(i128::from(index))))
    })
}

fn check_array_types(cx: &Context<'_>, out: &mut Vec<Finding>, index: u16, object: &Object) {
    // Streamed rather than collected: the first typed entry is the reference for the rest.
    let mut entries = object
        .subs
        .iter()
        .filter(|&(&s, _)| s != 0 && s != 0xFF)
        .filter_map(|(&s, so)| Some((s, so, so.attributes.data_type()?)));
    let Some((first_sub, _, first_type)) = entries.next() else {
        return;
    };
    for (sub, so, t) in entries {
        if t == first_type || so.origin != Origin::Explicit {
            continue;
        }
        out.push(
            cx.finding(
                &ARRAY_SUB_TYPES_DIFFER,
                SectionKind::Sub(index, sub),
                Some("DataType"),
                format!("ARRAY {index:04X}h sub {sub:X} is {t}, but sub {first_sub:X} is {first_type}"),
            )
            .with_help(format!(
                "give every entry the same DataType, or make {index:04X}h a RECORD (ObjectType=0x9)"
            )),
        );
    }
}

/// The CiA 301 structure an object is an instance of, by its index or a written structure DataType.
fn standard_structure(index: u16, object: &Object) -> Option<DataType> {
    let by_index = match index {
        0x1018 => Some(DataType::IDENTITY),
        0x1200..=0x12FF => Some(DataType::SDO_PARAMETER),
        0x1400..=0x15FF | 0x1800..=0x19FF => Some(DataType::PDO_COMMUNICATION_PARAMETER),
        0x1600..=0x17FF | 0x1A00..=0x1BFF => Some(DataType::PDO_MAPPING),
        _ => None,
    };
    by_index.or_else(|| {
        object
            .attributes
            .data_type()
            .filter(|t| (0x0020..=0x0023).contains(&t.0))
    })
}

/// The CiA 301 name of a standard structure type.
fn structure_name(structure: DataType) -> &'static str {
    match structure {
        DataType::PDO_COMMUNICATION_PARAMETER => "PDO_COMMUNICATION_PARAMETER",
        DataType::PDO_MAPPING => "PDO_MAPPING",
        DataType::SDO_PARAMETER => "SDO_PARAMETER",
        _ => "IDENTITY",
    }
}

/// An object type with its indefinite article, for messages.
fn with_article(object_type: ObjectType) -> String {
    match object_type {
        ObjectType::Array => "an ARRAY".to_owned(),
        other => format!("a {other}"),
    }
}

/// The type CiA 301 gives sub-index `sub` (1 and up) of a standard structure.
fn structure_sub_type(structure: DataType, sub: u8) -> Option<DataType> {
    Some(match (structure, sub) {
        (DataType::PDO_COMMUNICATION_PARAMETER, 1) => DataType::UNSIGNED32,
        (DataType::PDO_COMMUNICATION_PARAMETER, 2 | 4 | 6) => DataType::UNSIGNED8,
        (DataType::PDO_COMMUNICATION_PARAMETER, 3 | 5) => DataType::UNSIGNED16,
        (DataType::PDO_MAPPING, 1..=64) => DataType::UNSIGNED32,
        (DataType::SDO_PARAMETER, 1 | 2) => DataType::UNSIGNED32,
        (DataType::SDO_PARAMETER, 3) => DataType::UNSIGNED8,
        (DataType::IDENTITY, 1..=4) => DataType::UNSIGNED32,
        _ => return None,
    })
}

fn check_standard_structure(cx: &Context<'_>, out: &mut Vec<Finding>, index: u16, object: &Object) {
    let Some(structure) = standard_structure(index, object) else {
        return;
    };
    for (&sub, so) in &object.subs {
        if sub == 0 || so.origin != Origin::Explicit {
            continue;
        }
        let (Some(expected), Some(t)) = (structure_sub_type(structure, sub), so.attributes.data_type())
        else {
            continue;
        };
        if t == expected {
            continue;
        }
        out.push(
            cx.finding(
                &STRUCTURE_SUB_TYPE,
                SectionKind::Sub(index, sub),
                Some("DataType"),
                format!(
                    "{index:04X}h sub {sub:X} is {t}, but sub {sub:X} of the CiA 301 {} structure is \
                     {expected}",
                    structure_name(structure)
                ),
            )
            .with_help(format!("set DataType=0x{:04X}", expected.0)),
        );
    }
}

fn check_companions(cx: &Context<'_>, out: &mut Vec<Finding>, index: u16, object: &Object) {
    let compact = object.attributes.compact_sub_obj() != 0;
    for (companion, props) in [
        (Companion::Name, &object.names),
        (Companion::Value, &object.values),
        (Companion::Denotation, &object.denotations),
    ] {
        let Some(props) = props else { continue };
        let kind = SectionKind::Companion(index, companion);
        let name = cx.display_name(kind);
        if !compact {
            out.push(
                cx.finding(
                    &COMPANION_WITHOUT_COMPACT,
                    kind,
                    None,
                    format!(
                        "[{name}] belongs to {index:04X}h, which has no CompactSubObj; readers ignore it"
                    ),
                )
                .with_help(format!(
                    "move the entries into the [{index:X}sub<n>] sections, or give [{index:X}] a \
                     CompactSubObj"
                )),
            );
            continue;
        }
        check_count(cx, out, &COMPANION_COUNT, kind, props, "NrOfEntries");
    }
    if let Some(links) = &object.object_links {
        let kind = SectionKind::Companion(index, Companion::ObjectLinks);
        check_count(cx, out, &OBJECT_LINKS_COUNT, kind, links, "ObjectLinks");
        for (n, value) in links.numbered() {
            let target = int_of(value).and_then(|v| u16::try_from(v).ok());
            let described =
                target.is_some_and(|t| cx.eds.objects.get(&t).is_some_and(|o| o.origin != Origin::Orphan));
            if described {
                continue;
            }
            let key = n.to_string();
            let message = match target {
                Some(t) => {
                    format!("link {n}={value} names object {t:04X}h, which the file does not describe")
                }
                None => format!("link {n}={value} is not an object index"),
            };
            out.push(
                cx.finding(&OBJECT_LINK_TARGET, kind, Some(&key), message)
                    .with_help("correct the index, describe the object, or delete the link and renumber"),
            );
        }
    }
}

/// A section of `<count key>=n` followed by entries `1..` in decimal: the count must be present and
/// equal the number of numbered entries. For object links the entries must also run 1..=n (for the
/// companion sections of CompactSubObj they are sub-indices and may be sparse; P046 checks them).
fn check_count(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    info: &CheckInfo,
    kind: SectionKind,
    props: &Properties,
    count_key: &str,
) {
    let name = cx.display_name(kind);
    let numbered: BTreeMap<u32, &str> = props.numbered().collect();
    let count = numbered.len();
    match props.get(count_key).map(str::trim) {
        None | Some("") => out.push(
            cx.finding(
                info,
                kind,
                None,
                format!("[{name}] has no {count_key} count for its {}", entries(count)),
            )
            .with_help(format!("add {count_key}={count}")),
        ),
        Some(raw) => match int_of(raw) {
            Some(declared) if declared == count as i128 => {
                if count_key == "ObjectLinks"
                    && let Some(&outside) = numbered.keys().find(|&&n| n == 0 || n as usize > count)
                {
                    let key = outside.to_string();
                    out.push(
                        cx.finding(
                            info,
                            kind,
                            Some(&key),
                            format!("link {outside} is outside 1..={count} (ObjectLinks={raw})"),
                        )
                        .with_help("number the links 1, 2, ... up to ObjectLinks"),
                    );
                }
            }
            Some(_) | None => out.push(
                cx.finding(
                    info,
                    kind,
                    Some(count_key),
                    format!("{count_key}={raw} but [{name}] has {}", entries(count)),
                )
                .with_help(format!("set {count_key}={count}")),
            ),
        },
    }
}

/// "1 numbered entry", "3 numbered entries".
fn entries(count: usize) -> String {
    if count == 1 {
        "1 numbered entry".to_owned()
    } else {
        format!("{count} numbered entries")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::findings_with_code as findings;

    fn mapping(index: &str, sub0: &str) -> String {
        format!(
            "[{index}]\nParameterName=Mapping\nObjectType=0x9\nSubNumber=2\n\
             [{index}sub0]\nParameterName=Count\nDataType=0x0005\nAccessType=rw\nDefaultValue={sub0}\n\
             [{index}sub1]\nParameterName=Entry\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x60000108\n"
        )
    }

    #[test]
    fn mapping_sub0_counts_entries_and_may_select_mpdo() {
        assert!(findings(&mapping("1A00", "0"), "C537").is_empty());
        assert!(findings(&mapping("1A00", "0xFE"), "C537").is_empty());
        assert!(findings(&mapping("1600", "0xFF"), "C537").is_empty());
        let too_many = findings(&mapping("1A00", "3"), "C537");
        assert_eq!(too_many.len(), 1);
        // Lowering the number of mapped objects changes the mapping, so it is not offered as a fix.
        assert!(!too_many[0].fixable);
        // Any other record must name its highest sub-index exactly, and that is fixable.
        let record = findings(&mapping("2000", "0"), "C537");
        assert_eq!(record.len(), 1);
        assert!(record[0].fixable);
        assert_eq!(record[0].diagnostic.key.as_deref(), Some("DefaultValue"));
        assert_eq!(record[0].diagnostic.section.as_deref(), Some("2000sub0"));
    }

    #[test]
    fn objects_extended_by_modules_keep_their_sub0() {
        let text = "[2000]\nParameterName=Inputs\nObjectType=0x8\nSubNumber=1\n\
             [2000sub0]\nParameterName=Count\nDataType=0x0005\nAccessType=ro\nDefaultValue=8\n";
        assert_eq!(findings(text, "C537").len(), 1);
        let modular = format!(
            "{text}[SupportedModules]\nNrOfEntries=1\n[M1ModuleInfo]\nProductName=8 DI\n\
             [M1SubExtends]\nNrOfEntries=1\n1=0x2000\n[M1SubExt2000]\nParameterName=Input\n\
             DataType=0x0005\nAccessType=ro\nCount=1\n"
        );
        assert!(findings(&modular, "C537").is_empty());
    }

    #[test]
    fn generated_sub_objects_are_not_checked_as_written() {
        // CompactSubObj generates sub 0 and subs 1..=3; none of them is in the file.
        let text = "[2000]\nParameterName=Compact\nObjectType=0x8\nDataType=0x0006\nAccessType=rw\n\
             DefaultValue=0\nPDOMapping=1\nCompactSubObj=3\n";
        for code in ["C502", "C508", "C509", "C510", "C537"] {
            assert!(findings(text, code).is_empty(), "{code}");
        }
    }

    #[test]
    fn standard_structure_types() {
        assert_eq!(
            structure_sub_type(DataType::PDO_COMMUNICATION_PARAMETER, 3),
            Some(DataType::UNSIGNED16)
        );
        assert_eq!(
            structure_sub_type(DataType::PDO_MAPPING, 64),
            Some(DataType::UNSIGNED32)
        );
        assert_eq!(structure_sub_type(DataType::PDO_MAPPING, 65), None);
        assert_eq!(
            structure_sub_type(DataType::SDO_PARAMETER, 3),
            Some(DataType::UNSIGNED8)
        );
        assert_eq!(structure_sub_type(DataType::IDENTITY, 5), None);
    }
}
