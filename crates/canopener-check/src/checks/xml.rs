//! The `X` series: what the CiA 311 XDD/XDC reader found (`canopener_xdd::XddCode`, `X0xx`), and
//! the checks only an XML file needs (`X1xx`). Findings of this series are made by the check
//! pipeline of `canopener-description`, which has the XML; this module gives each code its
//! registry entry (title, clause, explanation), so selection, `eds explain` and the reports know it.
//!
//! Code, slug and severity of the `X0xx` entries are written out here and tested against
//! `canopener_xdd::XddCode::ALL` in `canopener-description` (this crate does not depend on the
//! reader), so the registry and the reader cannot drift apart.

use canopener_eds::Severity;

use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;

/// The XML codes, in code order.
pub(crate) const CHECKS: &[CheckInfo] = &[
    CheckInfo {
        code: "X001",
        slug: "no-namespace",
        severity: Severity::Warning,
        group: Group::Xml,
        title: "the root element is in a CiA 311 namespace",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A (xdd-format.md §2)",
        explanation: "\
The root ISO15745ProfileContainer element is in no namespace. CiA 311 files are in `http://www.canopen.org/xml/1.0` or `.../1.1`; EdsDcfNet writes files without one. canopener matches elements by local name and reads the file anyway.

A warning because the file is not schema-valid: a validating reader (CANeds, an XML editor with the CiA 311 schema) rejects it, while CANopenEditor and canopener read it.

Fix: add `xmlns=\"http://www.canopen.org/xml/1.1\"` to the root element.",
        fixable: false,
    },
    CheckInfo {
        code: "X002",
        slug: "project-wrapper",
        severity: Severity::Info,
        group: Group::Xml,
        title: "the file is a plain XDD/XDC, not a CANopenEditor project",
        reference: &[],
        spec: "CiA 311 V1.1 (xdd-format.md §1.1)",
        explanation: "\
The file is a CANopenEditor project (`CanOpenProject_1_1` or `OpenEDSProject`) holding one device; canopener checked that device.

Only a hint: other CiA 311 readers expect an ISO15745ProfileContainer root and do not read project files.

Fix: export the device as XDD from CANopenEditor when it goes to other tools.",
        fixable: false,
    },
    CheckInfo {
        code: "X003",
        slug: "missing-part",
        severity: Severity::Error,
        group: Group::Xml,
        title: "the profiles, the object list and required elements are present",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3, A.1.4",
        explanation: "\
A part the CiA 311 schema requires is missing: the communication network profile, its ApplicationLayers/CANopenObjectList, CANopenGeneralFeatures inside NetworkManagement, or its required `granularity`. What depends on it is missing from the model (no object dictionary without the object list).

An error because the schema requires the part and every reader loses the information.

Fix: add the element; CANopenEditor writes it when the device is saved again.",
        fixable: false,
    },
    CheckInfo {
        code: "X004",
        slug: "profile-type",
        severity: Severity::Warning,
        group: Group::Xml,
        title: "every ProfileBody names its CANopen xsi:type",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3, A.1.4 (xdd-format.md §3)",
        explanation: "\
A ProfileBody has no `xsi:type` of `ProfileBody_Device_CANopen` or `ProfileBody_CommunicationNetwork_CANopen`; canopener took its role from its content.

A warning because readers that tell the profiles apart by type (CANopenEditor, validating readers) may not find the object dictionary.

Fix: write the xsi:type on both ProfileBody elements.",
        fixable: false,
    },
    CheckInfo {
        code: "X005",
        slug: "duplicate-unique-id",
        severity: Severity::Error,
        group: Group::Xml,
        title: "every uniqueID is unique in the document",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A (xsd:ID)",
        explanation: "\
Two elements carry the same `uniqueID`. CiA 311 types it as xsd:ID, unique in the document; canopener uses the first element and reports the second.

An error because the file is not schema-valid and readers resolve the references to different elements, so the object dictionary differs between tools.

Fix: give every parameter, array, struct and template its own uniqueID.",
        fixable: false,
    },
    CheckInfo {
        code: "X006",
        slug: "unresolved-reference",
        severity: Severity::Error,
        group: Group::Xml,
        title: "every uniqueIDRef and dataTypeIDRef names an element of the right kind",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (CANopenObject@uniqueIDRef)",
        explanation: "\
A `uniqueIDRef` (object to parameter) or `dataTypeIDRef` (parameter to data type) names no element, or one of the wrong kind. When an object references a parameter, CiA 311 says its data type, access, default and limits \"shall be defined by the referenced element\", so they are missing from the model.

An error because the file is not schema-valid (IDREF) and the object is incomplete in every reader.

Fix: correct the reference or add the parameter it names.",
        fixable: false,
    },
    CheckInfo {
        code: "X010",
        slug: "invalid-index",
        severity: Severity::Error,
        group: Group::Xml,
        title: "every index and subIndex is a hex number in range",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (index: four hex digits, subIndex: two)",
        explanation: "\
An `index` or `subIndex` attribute is missing or is not a hexBinary number up to FFFF (index) or FF (sub-index); the entry is skipped.

An error because the attribute is required and the entry cannot be placed in the object dictionary.

Fix: write the index as four hex digits (`1018`) and the sub-index as two (`01`), without `0x`.",
        fixable: false,
    },
    CheckInfo {
        code: "X011",
        slug: "duplicate-entry",
        severity: Severity::Error,
        group: Group::Xml,
        title: "every index, and every sub-index within its object, appears once",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4; CiA 301 V4.2 §7.4.1",
        explanation: "\
An object index, or a sub-index within one object, appears twice; the first is used and the second ignored.

An error because an object dictionary has one entry per index and sub-index (CiA 301 §7.4.1), and readers keep different copies.

Fix: remove or renumber the duplicate.",
        fixable: false,
    },
    CheckInfo {
        code: "X012",
        slug: "hex-notation",
        severity: Severity::Info,
        group: Group::Xml,
        title: "hexBinary values have the width CiA 311 writes",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (hexBinary)",
        explanation: "\
A hexBinary value (index, subIndex, dataType, objFlags) is valid xsd:hexBinary but not of the width CiA 311's annotations give: `0000` for a subIndex (old libedssharp), eight digits for objFlags (Faulhaber). canopener read the number.

Only a hint: the schema type is xsd:hexBinary, which any even number of digits satisfies; only readers that insist on the width (CANopenEditor reads a subIndex of exactly one byte) differ. A `0x` prefix or an odd number of digits is not xsd:hexBinary at all: that is X016.

Fix: write the index with four digits (`1018`), the sub-index and an inline dataType with two (`01`, `07`), objFlags with four (`0001`).",
        fixable: false,
    },
    CheckInfo {
        code: "X013",
        slug: "xml-sub-number-mismatch",
        severity: Severity::Warning,
        group: Group::Xml,
        title: "subNumber equals the number of CANopenSubObject elements",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (subNumber)",
        explanation: "\
`subNumber` says a different number of sub-objects than the object has CANopenSubObject children (or is not a number); canopener counts the children.

A warning because readers that trust subNumber (CiA 306 SubNumber) allocate the wrong number of sub-objects.

Fix: make subNumber the number of sub-objects, or drop the attribute.",
        fixable: false,
    },
    CheckInfo {
        code: "X014",
        slug: "missing-name",
        severity: Severity::Warning,
        group: Group::Xml,
        title: "every object and sub-object has a name",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (name: required)",
        explanation: "\
A CANopenObject or CANopenSubObject has no `name`, which CiA 311 requires; canopener uses the referenced parameter's label when there is one.

A warning because the file is not schema-valid and tools show the entry unnamed.

Fix: give every object and sub-object a name.",
        fixable: false,
    },
    CheckInfo {
        code: "X015",
        slug: "invalid-object-type",
        severity: Severity::Error,
        group: Group::Xml,
        title: "every object and sub-object has a decimal objectType",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (objectType: required unsignedByte)",
        explanation: "\
An object or sub-object has no `objectType` or one that is not a number; ObjectType is left out of the model.

An error because the attribute is required and the object code decides how the entry is read (VAR, ARRAY, RECORD).

Fix: write the CiA 301 object code in decimal: 7 VAR, 8 ARRAY, 9 RECORD.",
        fixable: false,
    },
    CheckInfo {
        code: "X016",
        slug: "schema-type",
        severity: Severity::Error,
        group: Group::Xml,
        title: "numbers, hexBinary values and IDs have their CiA 311 schema type",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.2-A.1.4 (xsd:hexBinary, xsd:unsignedByte/Short/Long, xsd:ID)",
        explanation: "\
An attribute the reader interprets holds a value that is not of its CiA 311 schema type: an `index`, `subIndex`, `dataType` or `objFlags` that is not xsd:hexBinary (`0x2000` with a prefix, `201` with an odd number of digits, or no hex number at all for objFlags); an `objectType`, `subNumber`, `granularity`, `dynamicChannels` (xsd:unsignedByte), `nrOfRxPDO`/`nrOfTxPDO` (xsd:unsignedShort) or `networkNumber` (xsd:unsignedLong) written in hex, out of range or not a number; a commissioning `nodeID` written in hex; a `uniqueID` that is no xsd:ID (NCName). The message names the element and the attribute.

An error because the file is not valid against the CiA 311 schema, and tools read it differently: CANopenEditor's reader, which deserialises against the schema, refuses the whole file on an odd-length hexBinary, and others guess (`201` is 0201h to one reader and skipped by another). canopener never guesses: when the number is clear (`0x2000`, `201`) it is read and the message says as what; when it is not, the key is left out of the model. No schema default ever stands in for a value that is there but unreadable.

Fix: write hexBinary without prefix and with an even number of digits (`2000`, `0201`), unsigned numbers in decimal within their type's range, IDs as names (`UID_OBJ_2000`).",
        fixable: false,
    },
    CheckInfo {
        code: "X020",
        slug: "invalid-data-type",
        severity: Severity::Error,
        group: Group::Xml,
        title: "every entry has a readable data type",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (dataType hexBinary); A.1.3 (parameter types)",
        explanation: "\
A `dataType` is not a hex data type index, or an object's data type cannot be determined from its own attributes nor from the parameter it references.

An error because a value without a data type cannot be read or written over SDO.

Fix: write `dataType` as the CiA 301 type index (`0007`), or reference a parameter with an IEC type element.",
        fixable: false,
    },
    CheckInfo {
        code: "X021",
        slug: "conflicting-values",
        severity: Severity::Warning,
        group: Group::Xml,
        title: "an object's attributes agree with its parameter (data type, access, values)",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (uniqueIDRef annotation)",
        explanation: "\
The object states a data type, access type or value inline and the parameter it references says something else; canopener uses the object's attribute. This is also the check of an object's `dataType` against its parameter's type.

A warning because readers that follow the reference (CANopenEditor, python canopen PR #614) and readers that take the inline value build different dictionaries.

Fix: make both say the same, or state the value in one place only.",
        fixable: false,
    },
    CheckInfo {
        code: "X022",
        slug: "no-access",
        severity: Severity::Info,
        group: Group::Xml,
        title: "every entry has an access type CiA 306 can express",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3 (parameter@access)",
        explanation: "\
A parameter has `access=\"noAccess\"`, which has no CiA 306 AccessType; the model has none.

Only a hint: the value is legal CiA 311, but an EDS exported from the file has no access type for the entry.

Fix: nothing, unless the file will be converted to EDS.",
        fixable: false,
    },
    CheckInfo {
        code: "X023",
        slug: "unknown-token",
        severity: Severity::Error,
        group: Group::Xml,
        title: "enumerated attributes and booleans use CiA 311's tokens (accessType, access, PDOmapping, booleans, baud rates)",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3, A.1.4 (enumerations, xsd:boolean)",
        explanation: "\
An enumerated attribute holds a token outside its CiA 311 vocabulary: a CANopenObject accessType other than ro, wo, rw, const; a parameter access other than const, read, write, readWrite, readWriteInput, readWriteOutput, noAccess; a PDOmapping other than no, default, optional, TPDO, RPDO; a boolean other than true, false, 1, 0; a baud rate or dynamic channel spelt otherwise. The message names the element and the attribute.

An error because the file is not valid against the CiA 311 schema and tools disagree on the meaning: CANopenEditor refuses the file, others fall back to a default. canopener reads a token whose meaning is clear and says as what (`rwr` as an accessType, `rw` as the parameter access readWrite, `TRUE`); any other token leaves its key out of the model. It never falls back to the schema default: a parameter with `access=\"rw\"` is not read-only, and `PDOmapping=\"yes\"` is neither mapped nor unmapped.

Fix: use the exact CiA 311 token (`readWrite`, `optional`, `250 Kbps`, `true`).",
        fixable: false,
    },
    CheckInfo {
        code: "X024",
        slug: "ambiguous-bitstring",
        severity: Severity::Info,
        group: Group::Xml,
        title: "BITSTRING parameters state their CANopen data type",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3 (IEC 61131 types)",
        explanation: "\
A parameter of IEC type BITSTRING has no inline `dataType`: canopener reads it as OCTET_STRING, or DOMAIN when it has no default (CANopenEditor's convention).

Only a hint: the convention is CANopenEditor's, not CiA 311's.

Fix: add `dataType` on the object (`000A` OCTET_STRING, `000F` DOMAIN).",
        fixable: false,
    },
    CheckInfo {
        code: "X025",
        slug: "parent-values-ignored",
        severity: Severity::Info,
        group: Group::Xml,
        title: "ARRAY and RECORD objects carry no data type, access or values of their own",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4; CiA 306 V1.3 §4.6.3",
        explanation: "\
An ARRAY or RECORD object states a data type, access, default, limits or PDO mapping on itself. CiA 306 gives these keys to sub-objects only, so they are not carried into the model.

Only a hint: the values have no effect on the device.

Fix: state them on the sub-objects.",
        fixable: false,
    },
    CheckInfo {
        code: "X026",
        slug: "spaced-octets",
        severity: Severity::Info,
        group: Group::Xml,
        title: "OCTET_STRING and DOMAIN values are written without spaces",
        reference: &[],
        spec: "CiA 311 V1.1 (xdd-format.md §15); CiA 306 V1.3 §4.6.3.2",
        explanation: "\
An OCTET_STRING or DOMAIN value is written as space-separated bytes (`C8 3D BB`); canopener joins them (`C83DBB`).

Only a hint: the intent is clear, but an EDS reader would not accept the spaces.

Fix: write the bytes without spaces.",
        fixable: false,
    },
    CheckInfo {
        code: "X030",
        slug: "date-time-notation",
        severity: Severity::Error,
        group: Group::Xml,
        title: "file dates and times are xsd:date and xsd:time",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.2 (ag_formatAndFile)",
        explanation: "\
fileCreationDate/Time or fileModificationDate/Time are not xsd:date (`2024-03-01`) or xsd:time (`13:05:00`).

An error, as every value outside its CiA 311 schema type is (X016, X023): the file is not schema-valid, a validating reader refuses it and other tools show no or a wrong date. A time whose meaning is clear (`9:48:42 PM`) is read as that time; anything else is kept as written, never replaced by another date.

Fix: write the dates and times in XML Schema notation.",
        fixable: false,
    },
    CheckInfo {
        code: "X031",
        slug: "id-notation",
        severity: Severity::Warning,
        group: Group::Xml,
        title: "vendor and product IDs are written unambiguously and agree between profiles",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3 (DeviceIdentity); CiA 306 V1.3 §4.5",
        explanation: "\
A vendor or product ID is bare hex with letters (no `0x`), or ApplicationLayers/identity says a different ID than DeviceIdentity; DeviceIdentity is used.

A warning because tools read the ID differently and the identity is what a master matches against 1018h.

Fix: write `0x` and eight hex digits, the same in both places.",
        fixable: false,
    },
    CheckInfo {
        code: "X032",
        slug: "baud-rate-without-key",
        severity: Severity::Info,
        group: Group::Xml,
        title: "every supported baud rate has a CiA 306 key",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (supportedBaudRate)",
        explanation: "\
The file lists `100 Kbps` or `auto-baudRate`, which CiA 306 has no BaudRate_ key for; they are not in the model.

Only a hint: legal CiA 311, lost in an EDS export.

Fix: nothing, unless the file will be converted to EDS.",
        fixable: false,
    },
    CheckInfo {
        code: "X034",
        slug: "non-standard-attribute",
        severity: Severity::Info,
        group: Group::Xml,
        title: "only attributes CiA 311 defines are used",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A",
        explanation: "\
An element carries attributes CiA 311 does not define (CANopenEditor's `ngSlave`, `ngMaster`, `NrOfNG_MonitoredNodes`, `NodeID` on deviceCommissioning, and the like).

Only a hint: readers other than the writing tool ignore them.

Fix: none needed; a strict schema validation fails on them.",
        fixable: false,
    },
    CheckInfo {
        code: "X035",
        slug: "commissioning",
        severity: Severity::Warning,
        group: Group::Xml,
        title: "deviceCommissioning holds a usable node-ID and bit rate",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (deviceCommissioning); CiA 301 V4.2 §7.3.2",
        explanation: "\
deviceCommissioning holds a node-ID outside 1..127 or an actualBaudRate that is not a bit rate; the value is kept as written.

A warning because a configuration tool cannot commission the device with it (CiA 301 §7.3.2 allows node-IDs 1..127).

Fix: write the node-ID and bit rate the device runs with.",
        fixable: false,
    },
    CheckInfo {
        code: "X036",
        slug: "invalid-dummy",
        severity: Severity::Error,
        group: Group::Xml,
        title: "dummyUsage entries are Dummy0001..Dummy0007",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.4 (dummyUsage enumeration)",
        explanation: "\
A `dummy@entry` is not one of the 14 strings `Dummy0001=0` ... `Dummy0007=1` the schema allows.

An error, as every value outside its CiA 311 schema type is (X023): a validating reader refuses the file, and readers that are not strict disagree on the entry.

Fix: use the schema's spelling.",
        fixable: false,
    },
    CheckInfo {
        code: "X037",
        slug: "packed-description",
        severity: Severity::Info,
        group: Group::Xml,
        title: "productText holds a description, not packed EDS keys",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3 (productText)",
        explanation: "\
productText holds `key=value|...` pairs (Faulhaber's and libedssharp's way of carrying EDS FileInfo through XDD); canopener unpacked them into the model.

Only a hint: other readers show the packed text as the description.

Fix: none needed.",
        fixable: false,
    },
    CheckInfo {
        code: "X038",
        slug: "line-breaks",
        severity: Severity::Info,
        group: Group::Xml,
        title: "texts that become EDS values have no line breaks",
        reference: &[],
        spec: "CiA 306 V1.3 §4.2",
        explanation: "\
A text that becomes an EDS value (name, description) has line breaks; they were replaced by spaces.

Only a hint: CiA 306 values are one line.

Fix: none needed unless the file is converted to EDS.",
        fixable: false,
    },
    CheckInfo {
        code: "X039",
        slug: "unmapped-properties",
        severity: Severity::Info,
        group: Group::Xml,
        title: "properties have a CiA 306 counterpart",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3 (property)",
        explanation: "\
`property` elements (CANopenNode's `CO_*` and others) have no CiA 306 key; they are not in the model.

Only a hint: they configure the CANopenNode code generator, not the device description.

Fix: none needed.",
        fixable: false,
    },
    CheckInfo {
        code: "X040",
        slug: "disabled-object",
        severity: Severity::Info,
        group: Group::Xml,
        title: "no object is marked CO_disabled",
        reference: &[],
        spec: "CiA 311 V1.1 (xdd-format.md §12.2)",
        explanation: "\
An object is marked CANopenNode `CO_disabled`: CANopenEditor leaves it out of the device and its EDS export; canopener keeps it, as CiA 311 describes it, and checks it.

Only a hint: what the device implements depends on the tool.

Fix: remove the object from the XDD if the device does not implement it.",
        fixable: false,
    },
    CheckInfo {
        code: "X041",
        slug: "side-channel",
        severity: Severity::Warning,
        group: Group::Xml,
        title: "canopener's EDS:* properties apply",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3 (property)",
        explanation: "\
A canopener side-channel property (`EDS:*`, written by `canopener eds convert`) could not be applied.

A warning because content of the original EDS is lost.

Fix: convert the EDS again; do not edit EDS:* properties by hand.",
        fixable: false,
    },
    CheckInfo {
        code: "X101",
        slug: "value-not-allowed",
        severity: Severity::Error,
        group: Group::Xml,
        title: "default and actual values lie within the parameter's allowedValues",
        reference: &[],
        spec: "CiA 311 V1.1 Annex A.1.3 (allowedValues)",
        explanation: "\
A default or actual value is not one of the parameter's `allowedValues`: not in its `value` list and outside every `range`. Only parameters whose allowedValues hold a value list or more than one range are checked here: a single range becomes LowLimit/HighLimit and C602 checks it.

An error for the same reason as C602: CiA 311 allowedValues restrict what the parameter may hold, so a device with that value violates its own description.

Fix: correct the value, or the allowedValues.",
        fixable: false,
    },
    CheckInfo {
        code: "X102",
        slug: "xml-readers",
        severity: Severity::Info,
        group: Group::Xml,
        title: "what other tools do with a CiA 311 file",
        reference: &[],
        spec: "CiA 311 V1.1; canopen-tools-survey.md §1b",
        explanation: "\
How the file fares in other tools (from canopen-tools-survey.md): python canopen cannot read XDD or XDC at all (request #568 and PR #614 are open); Lely's dcf tools read EDS/DCF only; CANopenEditor reads XDD v1.0 and v1.1 and XDC v1.1 (it reads CO_disabled objects as absent, X040); EdsDcfNet 1.12 ignored uniqueIDRef, so reference-style objects came out without data types. CiA 306 checks that concern only EDS text (syntax, key spelling, DeviceInfo keys with no CiA 311 counterpart) are not run on XML.

Only a hint, reported once per file.

Fix: give python canopen and Lely an EDS or DCF: `canopener eds convert FILE --to eds`.",
        fixable: false,
    },
];

/// Nothing to do on the CiA 306 model: the XML findings are made where the XML is.
pub(crate) fn run(_cx: &Context<'_>, _out: &mut Vec<Finding>) {}
