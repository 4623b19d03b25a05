//! Group H of the check catalogue (`docs/check-catalogue.md`): CiA 301 semantics (checks 51-58).
//!
//! What the loader already reports is not repeated: a PDO communication object without its mapping
//! object (check 54) is P080, and values that do not parse or do not fit their type are P050/P054.
//! The checks here read values as the device will use them: in a DCF the configured
//! `ParameterValue` when there is one, otherwise `DefaultValue`; `$NODEID` formulas are evaluated
//! for the DCF's node-ID, or for every node-ID 1..=127 in an EDS. Objects that `CompactPDO` implies
//! are real objects of the device and are checked like written ones; findings about them point at
//! `[DeviceInfo] CompactPDO`.
//!
//! Reading values and pointing findings at what is written are shared with group K, in
//! [`super::reading`].

use std::collections::BTreeMap;
use std::ops::RangeInclusive;

use canopener_eds::model::int_of;
use canopener_eds::section_name::SectionKind;
use canopener_eds::{
    AccessType, Attributes, DataType, ObjectListKind, ObjectType, Origin, Severity, TypeKind,
};

use super::reading::{Int, Reading, entry_name, live_object, object_finding, reading, type_name, written};
use crate::check_info::{CheckInfo, Group};
use crate::context::Context;
use crate::finding::Finding;

const MANDATORY_OBJECT: CheckInfo = CheckInfo {
    code: "C701",
    slug: "mandatory-object-attributes",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "1000h, 1001h and 1018h have the object type, data types and access CiA 301 gives them",
    reference: &[51],
    spec: "CiA 301 objects 1000h, 1001h, 1018h",
    explanation: "\
Every CANopen device has 1000h (device type: VAR, UNSIGNED32), 1001h (error register: VAR, \
UNSIGNED8) and 1018h (identity: RECORD with sub 0 UNSIGNED8 and subs 1-4 UNSIGNED32), all \
read-only. This check compares the ObjectType, DataType and AccessType written for them with those \
definitions; `const` counts as read-only.

Masters and configuration tools read these objects from every node before anything else, with the \
sizes CiA 301 fixes: a device type described as INTEGER32 or an error register as INTEGER16 makes \
an EDS-driven master decode the answer wrongly or refuse the SDO response length, and a writable \
identity invites tools to write it. The CiA conformance test reads 1000h and expects a refusal \
when writing it.

It is an error because the objects are defined once for all devices; no device profile may change \
them. An ARRAY instead of a RECORD for 1018h is only a warning: the sub-objects and their types are \
the same on the bus.

Fix: write the object type, data types and access exactly as above.",
    fixable: false,
};

const IDENTITY_SUBS: CheckInfo = CheckInfo {
    code: "C702",
    slug: "identity-sub-indices",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "1018h has sub 1 (Vendor-ID) and its highest sub-index is 1..4",
    reference: &[51],
    spec: "CiA 301 object 1018h",
    explanation: "\
The identity object 1018h has at most four entries: Vendor-ID (sub 1, mandatory), product code, \
revision number and serial number. Its sub 0 therefore holds 1..4. This check reports a sub 0 value \
outside 1..4, sub-objects above 4 and a missing sub 1. (A sub 0 that disagrees with the sub-objects \
present is check 37, group F.)

LSS (CiA 305) addresses a node by the 128 bits of 1018h sub 1..4, and masters identify devices by \
the Vendor-ID; tools that build the LSS address or compare identities from the EDS get it wrong when \
the layout differs.

It is an error: CiA 301 fixes the layout of 1018h for every device.

Fix: describe sub 0..4 only, with sub 0 = the highest sub-index present (4 when all are there).",
    fixable: false,
};

const ERROR_CONTROL: CheckInfo = CheckInfo {
    code: "C703",
    slug: "no-error-control",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "The device offers heartbeat (1017h) or node guarding (100Ch and 100Dh)",
    reference: &[52],
    spec: "CiA 301 objects 1017h, 100Ch, 100Dh",
    explanation: "\
CiA 301 requires every device to support an error-control protocol: the heartbeat producer (1017h, \
mandatory when node guarding is not supported) or node guarding (100Ch guard time and 100Dh life \
time factor, which only work together). This check reports a file that describes neither 1017h nor \
both of 100Ch and 100Dh. A device offering both is allowed; it must not run them at the same time, \
which is a matter of configuration, not of the description.

Without error control a master cannot notice that the node has dropped off the bus: the CiA \
conformance test's error-control group fails, and tools that set up heartbeat consumers from the \
EDS have nothing to configure.

It is an error for an ordinary device. It is a warning for an NMT master (SimpleBootUpMaster=1 or \
1F80h bit 0 set) that describes heartbeat consumption (1016h): such a file often describes only \
the monitoring side.

Fix: describe 1017h (UNSIGNED16, rw, default 0 or the producer time in ms), or both 100Ch and 100Dh.",
    fixable: false,
};

const HEARTBEAT_RESERVED: CheckInfo = CheckInfo {
    code: "C704",
    slug: "heartbeat-consumer-reserved-bits",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "1016h consumer heartbeat entries keep bits 24-31 zero",
    reference: &[53],
    spec: "CiA 301 object 1016h",
    explanation: "\
Each 1016h entry is bits 0-15 the consumer time in ms, bits 16-23 the node-ID to monitor and bits \
24-31 reserved (0). This check reports entries whose value sets any of bits 24-31.

A device that stores such a value either refuses it when a tool downloads the configuration (the \
write of the EDS default fails) or masks the bits silently, so the file does not say what the device \
does. Often the cause is a node-ID written one byte too high.

It is an error: reserved bits must be 0.

Fix: write the entry as node-ID << 16 | time in ms, e.g. 0x0005012C for node 5 and 300 ms.",
    fixable: false,
};

const HEARTBEAT_DUPLICATE: CheckInfo = CheckInfo {
    code: "C705",
    slug: "heartbeat-consumer-duplicate-node",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "No two active 1016h entries monitor the same node",
    reference: &[53],
    spec: "CiA 301 object 1016h",
    explanation: "\
An entry of 1016h is active when its node-ID is 1..127 and its time is not 0. This check reports a \
second active entry for a node-ID that an earlier entry already monitors.

Devices refuse such a configuration: CANopenNode answers the SDO write with 0604 0043h (general \
parameter incompatibility), and the CiA conformance test (Heartbeat 04) expects exactly that. A \
tool that downloads the defaults of this file therefore fails.

It is an error because the configuration cannot be applied to a conforming device.

Fix: keep one entry per monitored node; set the others to 0.",
    fixable: false,
};

const PDO_HIGHEST_SUB: CheckInfo = CheckInfo {
    code: "C706",
    slug: "pdo-comm-highest-sub",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "PDO communication parameters have sub 0 = 2..5 (RPDO) or 2..6 (TPDO)",
    reference: &[55],
    spec: "CiA 301 PDO communication parameter (1400h-15FFh, 1800h-19FFh)",
    explanation: "\
Sub 0 of an RPDO communication parameter (1400h-15FFh) is its highest sub-index: at least 2 (COB-ID \
and transmission type are mandatory) and at most 5 (event timer). A TPDO (1800h-19FFh) also has sub \
6, the SYNC start value, so its sub 0 is 2..6. This check reports values outside those ranges.

A value of 0 or 1 describes a PDO without a transmission type; 6 on an RPDO claims a SYNC start \
value RPDOs do not have. Masters that read sub 0 to decide which sub-indices to configure then write \
objects that do not exist or skip ones that do.

It is an error: CiA 301 defines these records.

Fix: set sub 0 to the highest sub-index the device implements, and describe only sub-indices that \
exist for the PDO direction.",
    fixable: false,
};

const TRANSMISSION_TYPE: CheckInfo = CheckInfo {
    code: "C707",
    slug: "pdo-transmission-type-reserved",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "PDO transmission types avoid the reserved values",
    reference: &[55],
    spec: "CiA 301 transmission types (table 72)",
    explanation: "\
Transmission types 0-240 are synchronous, 254 and 255 event-driven; 252 and 253 are the RTR-only \
types of TPDOs. 241-251 are reserved for both directions, and 252-253 are reserved for RPDOs. This \
check reports a transmission type (sub 2) in a reserved range.

Devices refuse reserved values with 0609 0030h (lely, CANopenNode), so downloading the file's \
defaults fails, and a master cannot tell how the PDO is meant to be triggered.

It is an error: the value has no meaning in CiA 301.

Fix: use 255 (event-driven, device profile) for RPDOs and event TPDOs, 254 for manufacturer-specific \
events, 1-240 for cyclic synchronous TPDOs, 0 for acyclic synchronous ones.",
    fixable: false,
};

const RESTRICTED_COB_ID: CheckInfo = CheckInfo {
    code: "C710",
    slug: "restricted-cob-id",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "Valid PDO, SYNC, TIME, EMCY and additional SDO COB-IDs avoid the restricted CAN-IDs",
    reference: &[56],
    spec: "CiA 301 restricted CAN-IDs (pre-defined connection set)",
    explanation: "\
CiA 301 reserves CAN-IDs 000h (NMT), 001h-07Fh, 101h-180h, 581h-5FFh and 601h-67Fh (the default \
SDO channels), 6E0h-6FFh and 701h-7FFh (NMT error control, LSS) and forbids them for SYNC, TIME, \
EMCY, PDOs and additional SDO servers. This check evaluates the 11-bit CAN-ID of 1005h, 1012h (when \
TIME is produced or consumed), 1014h and of every valid PDO (bit 31 clear) and additional SDO server \
(1201h-127Fh). A $NODEID formula is evaluated for every node-ID 1..127 (for the node-ID of a DCF), \
and the finding names the node-IDs that land in a restricted range.

A frame on a restricted CAN-ID collides with network management, another node's SDO channel or \
heartbeat. The CiA conformance test writes every restricted ID into these objects and expects the \
device to refuse (0609 0030h), so a device whose defaults use one cannot even have them restored.

It is an error: the CAN-IDs are reserved by CiA 301 for every network.

Fix: use the pre-defined connection set ($NODEID+0x180 … $NODEID+0x500 for PDO1-4) or set bit 31 \
to disable the PDO.",
    fixable: false,
};

const COB_ID_29_BIT: CheckInfo = CheckInfo {
    code: "C711",
    slug: "cob-id-29-bit",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "Default COB-IDs of valid objects use 11-bit CAN-IDs",
    reference: &[56],
    spec: "CiA 301 COB-ID bit 29 (frame)",
    explanation: "\
Bit 29 of a COB-ID selects a 29-bit (extended) CAN-ID. CiA 301 devices need not support extended \
frames, and an EDS has no entry that says whether the device does. This check reports valid \
PDO, SYNC, TIME, EMCY and additional SDO COB-IDs with bit 29 set.

Many devices and stacks refuse 29-bit IDs (CANopenNode rejects them with 0609 0030h), and masters \
built on 11-bit-only controllers cannot receive the frames.

It is a warning, not an error: a device that supports extended frames may use them; the file cannot \
prove it does not.

Fix: use an 11-bit CAN-ID unless the whole network is designed for extended frames.",
    fixable: false,
};

const COB_ID_RESERVED_BITS: CheckInfo = CheckInfo {
    code: "C712",
    slug: "cob-id-reserved-bits",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "11-bit COB-IDs keep bits 11-28 zero",
    reference: &[56],
    spec: "CiA 301 COB-ID layout",
    explanation: "\
A COB-ID holds the CAN-ID in bits 0-10 for an 11-bit frame (bit 29 clear) and bits 0-28 for a 29-bit \
frame; bits 11-28 must be 0 for 11-bit frames. This check reports PDO, SYNC, TIME, EMCY and SDO \
server COB-IDs with bit 29 clear and any of bits 11-28 set, including $NODEID formulas whose sum \
carries into bit 11 for some node-IDs.

Devices refuse such values (CANopenNode: 0609 0030h), and tools disagree on what they mean: some \
mask the CAN-ID to 11 bits, others treat the value as an extended ID.

It is an error: the value is not a valid COB-ID.

Fix: write the CAN-ID in bits 0-10 with the flags in bits 29-31 only, e.g. $NODEID+0x80000200 for a \
disabled RPDO1.",
    fixable: false,
};

const NOT_PREDEFINED: CheckInfo = CheckInfo {
    code: "C713",
    slug: "pdo-cob-id-not-predefined",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "Valid PDO1-4 use the pre-defined connection set",
    reference: &[56],
    spec: "CiA 301 pre-defined connection set",
    explanation: "\
The pre-defined connection set gives RPDO1-4 the COB-IDs $NODEID+0x200, +0x300, +0x400, +0x500 \
and TPDO1-4 $NODEID+0x180, +0x280, +0x380, +0x480. This check reports a valid (bit 31 clear) PDO1-4 \
of an EDS whose default COB-ID differs, ignoring the valid and RTR flags (bits 31 and 30). A plain \
number that equals the default for one node-ID only (0x181) is reported too: the EDS describes \
every node of that type. DCFs, which hold a configuration, and NMT masters, whose PDOs listen to \
other nodes, are not checked.

Masters rely on the connection set to talk to a device without configuring it first; a device that \
departs from it needs a configured master, and two such devices can collide.

It is a warning: a manufacturer may choose other defaults, but should have a reason.

Fix: write $NODEID+0x180 … as above, or disable the PDO (bit 31) when it has no default use.",
    fixable: false,
};

const DUPLICATE_COB_ID: CheckInfo = CheckInfo {
    code: "C714",
    slug: "duplicate-pdo-cob-id",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "Valid PDOs of the device use distinct COB-IDs",
    reference: &[56],
    spec: "CiA 301 PDO COB-ID",
    explanation: "\
Each CAN-ID has one transmitter on a network. This check reports two valid PDOs of the same device \
whose COB-IDs select the same CAN-ID: always when both are $NODEID formulas with the same offset or \
both the same number, and for the one node-ID at which a formula and a number meet.

A TPDO sharing its CAN-ID with another TPDO puts two transmitters on one identifier (bus errors when \
they send at once); a TPDO sharing it with an RPDO makes the device consume its own data. These are \
errors. Two RPDOs on one CAN-ID and a clash at a single node-ID are warnings: the first is unusual \
but harmless on the bus, the second only matters if the device gets that node-ID.

Fix: give every valid PDO its own COB-ID, e.g. from the pre-defined connection set.",
    fixable: false,
};

const MAPPED_MISSING: CheckInfo = CheckInfo {
    code: "C720",
    slug: "mapped-object-missing",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "Default PDO mappings reference objects that exist or enabled dummies",
    reference: &[57],
    spec: "CiA 301 PDO mapping; CiA 306 V1.3 §4.6.2 (DummyUsage), §6",
    explanation: "\
For each mapping entry 1..n of 1600h-17FFh and 1A00h-1BFFh (n = sub 0), the mapped index and \
sub-index must be an object of the device, or a dummy (a data type index such as 0005h for \
UNSIGNED8) that [DummyUsage] enables. This check reports entries that reference neither, including \
entries of 0x00000000 counted by sub 0. Modular devices (CiA 306 §6) are exempt for objects not in \
the base file: their defaults may map objects that the modules create.

A device cannot accept a mapping to an object it does not have (0602 0000h or 0604 0041h), so the \
file's default mapping cannot be restored by a tool, and a master that lays out PDO data from the \
EDS has nothing to decode.

It is an error: the default mapping is invalid for the device.

Fix: describe the mapped object, enable the dummy in [DummyUsage], or lower sub 0 to the entries in use.",
    fixable: false,
};

const NOT_MAPPABLE: CheckInfo = CheckInfo {
    code: "C721",
    slug: "mapped-object-not-mappable",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "Default PDO mappings only map objects with PDOMapping=1",
    reference: &[57],
    spec: "CiA 306 V1.3 §4.6.3.2 (PDOMapping); CiA 301 PDO mapping",
    explanation: "\
An object may be mapped into a PDO only when its description says PDOMapping=1 (a missing \
PDOMapping means 0). This check reports active default mapping entries whose object says otherwise.

The device would refuse this mapping (0604 0041h, \"object cannot be mapped\"), and configuration \
tools that honour PDOMapping will not offer the object, so the defaults and the description \
contradict each other.

It is an error: the file is inconsistent about its own objects.

Fix: set PDOMapping=1 on the mapped object, or map a different object.",
    fixable: false,
};

const MAPPING_DIRECTION: CheckInfo = CheckInfo {
    code: "C722",
    slug: "mapping-direction",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "RPDOs map writable objects and TPDOs readable ones",
    reference: &[57],
    spec: "CiA 306 V1.3 §4.6.3.2 (AccessType rwr/rww); CiA 301 PDO mapping",
    explanation: "\
An RPDO writes into the objects it maps, so they must be wo, rw or rww; a TPDO reads them, so they \
must be ro, rw, rwr or const. rwr (\"on process input\") marks objects for TPDOs only and rww (\"on \
process output\") for RPDOs only. This check reports active default mapping entries whose object's \
AccessType does not allow the PDO's direction.

The CiA conformance test maps rww/wo objects into a TPDO and rwr/ro objects into an RPDO and \
expects the device to refuse; a default mapping of that kind therefore cannot be restored, and \
libEDSsharp's VerifyPDOMapping reports it too.

It is an error: the direction contradicts the object's access type.

Fix: correct the AccessType (rww for outputs, rwr for inputs) or move the entry to a PDO of the \
other direction.",
    fixable: false,
};

const MAPPING_LENGTH: CheckInfo = CheckInfo {
    code: "C723",
    slug: "mapping-length",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "Mapping entry lengths equal the bit size of the mapped object's type",
    reference: &[57],
    spec: "CiA 301 PDO mapping entry (bits 0-7 = length in bits)",
    explanation: "\
Bits 0-7 of a mapping entry give the length in bits of the mapped object, which must equal the size \
of its data type (UNSIGNED16 = 16, BOOLEAN = 1); strings may be mapped with any whole number of \
bytes, UNICODE_STRING with whole characters. Dummy entries take the size of the dummy type. This \
check reports entries whose length differs.

A device refuses a length larger than the object (CANopenNode: 0604 0041h), and masters that unpack \
PDOs from the EDS read the wrong bits.

It is an error. A BOOLEAN mapped with 8 bits is a warning: CiA 301 gives BOOLEAN 1 bit, but many \
files map it with 8 because their stack stores it in a byte; whether a device accepts 1 or 8 depends \
on its stack.

Fix: write the type's size in bits 0-7 of the entry (e.g. 0x60000108 for an UNSIGNED8 at 6000sub1).",
    fixable: false,
};

const MAPPING_TOO_LONG: CheckInfo = CheckInfo {
    code: "C724",
    slug: "mapping-too-long",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "A default PDO mapping fits in 64 bits",
    reference: &[57],
    spec: "CiA 301 PDO (classical CAN: 8 data bytes)",
    explanation: "\
A PDO on classical CAN carries at most 8 bytes. This check adds the lengths of mapping entries 1..n \
(n = sub 0) of each mapping object and reports totals above 64 bits.

Devices refuse such a mapping (0604 0042h, \"would exceed the PDO length\"), so the default cannot be \
applied and the PDO stays unusable.

It is an error for classical CAN, which CiA 306 V1.3 files describe.

Fix: split the entries over two PDOs or map smaller objects.",
    fixable: false,
};

const MAPPING_GRANULARITY: CheckInfo = CheckInfo {
    code: "C725",
    slug: "mapping-granularity",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "Default mapping entry lengths are multiples of [DeviceInfo] Granularity",
    reference: &[57],
    spec: "CiA 306 V1.3 §4.5 (Granularity)",
    explanation: "\
Granularity in [DeviceInfo] is the mapping granularity the device allows, in bits (8 on most \
devices; 0 means the mapping cannot be changed). This check reports active default mapping entries \
whose length is not a multiple of it, e.g. 1-bit BOOLEAN entries on a device that says 8.

A configuration tool that honours Granularity cannot rebuild the default mapping, and the file \
contradicts itself about what the device can map.

It is a warning, not an error: CiA 306 states Granularity for mappings a tool configures and does \
not say in so many words that the manufacturer's defaults obey it. Real files disagree (Granularity=64 \
with 16-bit default entries is seen in vendor files); the safe reading is that one of the two is \
wrong.

Fix: correct Granularity to what the device supports (1 for bit-wise mapping), or the default mapping.",
    fixable: false,
};

const MAPPING_UNDESCRIBED: CheckInfo = CheckInfo {
    code: "C726",
    slug: "mapping-entry-undescribed",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "Every mapping entry that sub 0 counts is described",
    reference: &[57],
    spec: "CiA 301 PDO mapping; CiA 306 V1.3 §4.6.3.2",
    explanation: "\
Sub 0 of a mapping object counts the active entries 1..n. This check reports entries below the \
highest described sub-index that sub 0 counts but the file does not describe (a sub 0 above the \
highest sub-index is check 37 in group F).

Tools then do not know what the default mapping is, and each fills the gap its own way.

It is a warning: the file is incomplete rather than wrong about the device.

Fix: describe the missing [xxxxsubN] sections or lower sub 0.",
    fixable: false,
};

const MAPPED_DIRECTION_UNCLEAR: CheckInfo = CheckInfo {
    code: "C727",
    slug: "mapped-direction-unclear",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "Default PDO mappings map entries whose access says the direction",
    reference: &[57],
    spec: "CiA 306 V1.3 §4.6.3.2 (AccessType rwr, rww); CiA 301 PDO mapping; CANchkEDS warning 5",
    explanation: "\
An active default mapping entry (1..n of 1600h-17FFh or 1A00h-1BFFh, n = sub 0) maps an entry whose \
AccessType is rw: the PDO gives it a direction (an RPDO writes it, so it is an output and should be \
rww; a TPDO reads it, an input, rwr) that its own description does not state. CANchkEDS reports it \
as warning 5 (\"Access type in section [6411sub1] has no clear mapping direction concerning PDO \
section [1601sub1]\"), 6 times on CANopenNode's demoDevice.eds, the same 6 pairs canopener \
reports; the mapped entry itself is C518. In the corpus: 104 mapping entries in 28 of the 148 EDS/DCF \
files.

A tool that reads the direction from the access type (rwr/rww) and one that reads it from the \
default mapping describe the same object differently, and a CiA 311 export cannot say which PDO \
the object belongs to.

It is a warning: rw entries may be mapped in either direction, so the mapping is valid; the file \
only fails to say what its own default mapping shows.

Fix: give the mapped entry the access its PDO implies: rww for an RPDO, rwr for a TPDO.",
    fixable: false,
};

const SDO_SERVER: CheckInfo = CheckInfo {
    code: "C730",
    slug: "sdo-server-cob-id",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "1200h uses $NODEID+0x600 and $NODEID+0x580",
    reference: &[58],
    spec: "CiA 301 object 1200h (default SDO server), pre-defined connection set",
    explanation: "\
The default SDO server is fixed by the pre-defined connection set: sub 1 (client to server) is \
600h + node-ID and sub 2 (server to client) 580h + node-ID, always valid and read-only. This check \
reports other values. In an EDS a plain number that is right for one node-ID only (0x601) is a \
warning: the description is then valid for that node alone; write the formula.

Every master reaches a device's object dictionary through these two CAN-IDs; a different value in \
the EDS makes tools that read it talk to the wrong identifier, and a device that really used it \
would not be reachable by any other master.

It is an error: CiA 301 allows no other default SDO server COB-IDs.

Fix: write $NODEID+0x600 and $NODEID+0x580.",
    fixable: false,
};

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[
    MANDATORY_OBJECT,
    IDENTITY_SUBS,
    ERROR_CONTROL,
    HEARTBEAT_RESERVED,
    HEARTBEAT_DUPLICATE,
    PDO_HIGHEST_SUB,
    TRANSMISSION_TYPE,
    RESTRICTED_COB_ID,
    COB_ID_29_BIT,
    COB_ID_RESERVED_BITS,
    NOT_PREDEFINED,
    DUPLICATE_COB_ID,
    MAPPED_MISSING,
    NOT_MAPPABLE,
    MAPPING_DIRECTION,
    MAPPING_LENGTH,
    MAPPING_TOO_LONG,
    MAPPING_GRANULARITY,
    MAPPING_UNDESCRIBED,
    MAPPED_DIRECTION_UNCLEAR,
    SDO_SERVER,
];

/// Runs the checks of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    mandatory_var(cx, out, 0x1000, "the device type", DataType::UNSIGNED32);
    mandatory_var(cx, out, 0x1001, "the error register", DataType::UNSIGNED8);
    identity(cx, out);
    error_control(cx, out);
    heartbeat_consumer(cx, out);
    pdo_communication(cx, out);
    cob_ids(cx, out);
    mappings(cx, out);
    sdo_server(cx, out);
}

// ---- 51: 1000h, 1001h, 1018h --------------------------------------------------------------------

fn mandatory_var(cx: &Context<'_>, out: &mut Vec<Finding>, index: u16, what: &str, expected: DataType) {
    let Some(object) = live_object(cx, index) else {
        return;
    };
    let attributes = &object.attributes;
    match object.object_type() {
        Some(ObjectType::Var) | None => {}
        Some(other) => {
            out.push(
                object_finding(
                    cx,
                    &MANDATORY_OBJECT,
                    index,
                    None,
                    Some("ObjectType"),
                    format!(
                        "{index:X}h is written as {other} (ObjectType {}); CiA 301 defines {what} as a VAR",
                        written(attributes.object_type.as_deref())
                    ),
                )
                .with_help("write ObjectType=0x7 and describe the value on the object itself"),
            );
            return;
        }
    }
    data_type_is(cx, out, index, None, attributes, expected, what);
    read_only(cx, out, index, None, attributes, what);
}

fn identity(cx: &Context<'_>, out: &mut Vec<Finding>) {
    const INDEX: u16 = 0x1018;
    let Some(object) = live_object(cx, INDEX) else {
        return;
    };
    match object.object_type() {
        Some(ObjectType::Record) | None => {}
        Some(ObjectType::Array) => out.push(
            object_finding(
                cx,
                &MANDATORY_OBJECT,
                INDEX,
                None,
                Some("ObjectType"),
                format!(
                    "1018h is written as an ARRAY (ObjectType {}); CiA 301 defines the identity object as a RECORD",
                    written(object.attributes.object_type.as_deref())
                ),
            )
            .with_severity(Severity::Warning)
            .with_help("write ObjectType=0x9"),
        ),
        Some(other) => {
            out.push(
                object_finding(
                    cx,
                    &MANDATORY_OBJECT,
                    INDEX,
                    None,
                    Some("ObjectType"),
                    format!(
                        "1018h is written as {other} (ObjectType {}); CiA 301 defines the identity object as a RECORD",
                        written(object.attributes.object_type.as_deref())
                    ),
                )
                .with_help("write ObjectType=0x9 with sub-objects 0..4"),
            );
            return;
        }
    }
    for (&sub, sub_object) in &object.subs {
        if sub_object.origin == Origin::Orphan || sub == 0xFF {
            continue;
        }
        let attributes = &sub_object.attributes;
        if sub > 4 {
            out.push(
                object_finding(
                    cx,
                    &IDENTITY_SUBS,
                    INDEX,
                    Some(sub),
                    None,
                    format!("1018sub{sub:X} is not defined: the identity object ends at sub-index 4 (serial number)"),
                )
                .with_help("remove the sub-object; manufacturer data belongs in 2000h-5FFFh"),
            );
            continue;
        }
        let (expected, what) = match sub {
            0 => (DataType::UNSIGNED8, "1018h's highest sub-index"),
            1 => (DataType::UNSIGNED32, "the Vendor-ID"),
            2 => (DataType::UNSIGNED32, "the product code"),
            3 => (DataType::UNSIGNED32, "the revision number"),
            _ => (DataType::UNSIGNED32, "the serial number"),
        };
        data_type_is(cx, out, INDEX, Some(sub), attributes, expected, what);
        read_only(cx, out, INDEX, Some(sub), attributes, what);
    }
    if !object.subs.is_empty() && object.subs.get(&1).is_none_or(|s| s.origin == Origin::Orphan) {
        out.push(
            object_finding(
                cx,
                &IDENTITY_SUBS,
                INDEX,
                None,
                None,
                "1018h has no sub-index 1 (Vendor-ID), which CiA 301 makes mandatory",
            )
            .with_help("add [1018sub1] with DataType=0x0007, AccessType=ro and the CiA-assigned Vendor-ID"),
        );
    }
    if let Some(sub0) = object.subs.get(&0)
        && let Some(reading) = reading(cx, &sub0.attributes)
        && let Int::Literal(value) = reading.value
        && !(1..=4).contains(&value)
    {
        out.push(
            object_finding(
                cx,
                &IDENTITY_SUBS,
                INDEX,
                Some(0),
                Some(reading.key),
                format!("1018sub0 {} {} is outside 1..4", reading.key, reading.text),
            )
            .with_help("sub 0 of 1018h is the highest sub-index present: 1 to 4"),
        );
    }
}

fn data_type_is(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    index: u16,
    sub: Option<u8>,
    attributes: &Attributes,
    expected: DataType,
    what: &str,
) {
    let Some(declared) = attributes.data_type() else {
        return;
    };
    if cx.eds.resolve_data_type(declared) == expected {
        return;
    }
    out.push(
        object_finding(
            cx,
            &MANDATORY_OBJECT,
            index,
            sub,
            Some("DataType"),
            format!(
                "{} DataType {} is {}; CiA 301 defines {what} as {expected}",
                entry_name(index, sub),
                written(attributes.data_type.as_deref()),
                type_name(cx.eds.resolve_data_type(declared)),
            ),
        )
        .with_help(format!("write DataType=0x{:04X}", expected.0)),
    );
}

fn read_only(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    index: u16,
    sub: Option<u8>,
    attributes: &Attributes,
    what: &str,
) {
    let Some(access) = attributes.access_type() else {
        return;
    };
    if matches!(access, AccessType::Ro | AccessType::Const) {
        return;
    }
    out.push(
        object_finding(
            cx,
            &MANDATORY_OBJECT,
            index,
            sub,
            Some("AccessType"),
            format!(
                "{} AccessType {}: CiA 301 defines {what} read-only",
                entry_name(index, sub),
                written(attributes.access_type.as_deref())
            ),
        )
        .with_help("write AccessType=ro (or const)"),
    );
}

// ---- 52: heartbeat or node guarding ---------------------------------------------------------------

fn error_control(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let has = |index| live_object(cx, index).is_some();
    if has(0x1017) || (has(0x100C) && has(0x100D)) {
        return;
    }
    let guarding = match (has(0x100C), has(0x100D)) {
        (true, false) => "; 100Ch (guard time) is there but 100Dh (life time factor) is not",
        (false, true) => "; 100Dh (life time factor) is there but 100Ch (guard time) is not",
        _ => "",
    };
    let message = format!(
        "neither 1017h (producer heartbeat time) nor 100Ch and 100Dh (node guarding) are described{guarding}"
    );
    let list = SectionKind::ObjectList(ObjectListKind::Optional);
    let finding = if cx.has_section(list) {
        cx.finding(&ERROR_CONTROL, list, None, message)
    } else {
        cx.file_finding(&ERROR_CONTROL, message)
    };
    let finding = if is_master(cx) && has(0x1016) {
        finding.with_severity(Severity::Warning).with_help(
            "an NMT master with heartbeat consumption only; describe 1017h if the device also produces heartbeats",
        )
    } else {
        finding.with_help("describe 1017h (UNSIGNED16, rw, ms) or both 100Ch and 100Dh")
    };
    out.push(finding);
}

/// Whether the device says it is an NMT master (`SimpleBootUpMaster=1` or 1F80h bit 0).
fn is_master(cx: &Context<'_>) -> bool {
    let simple = cx
        .eds
        .device_info
        .simple_boot_up_master
        .as_deref()
        .and_then(int_of)
        == Some(1);
    let startup = live_object(cx, 0x1F80)
        .and_then(|o| reading(cx, &o.attributes))
        .is_some_and(|r| matches!(r.value, Int::Literal(v) if v & 1 == 1));
    simple || startup
}

// ---- 53: 1016h ----------------------------------------------------------------------------------

fn heartbeat_consumer(cx: &Context<'_>, out: &mut Vec<Finding>) {
    const INDEX: u16 = 0x1016;
    let Some(object) = live_object(cx, INDEX) else {
        return;
    };
    let mut monitored: BTreeMap<i128, u8> = BTreeMap::new();
    for (&sub, sub_object) in object.subs.range(1..0xFF) {
        if sub_object.origin == Origin::Orphan {
            continue;
        }
        let Some(reading) = reading(cx, &sub_object.attributes) else {
            continue;
        };
        let Int::Literal(value) = reading.value else {
            continue;
        };
        let reserved = (value >> 24) & 0xFF;
        if reserved != 0 {
            out.push(
                object_finding(
                    cx,
                    &HEARTBEAT_RESERVED,
                    INDEX,
                    Some(sub),
                    Some(reading.key),
                    format!(
                        "1016sub{sub:X} {} {} sets reserved bits 24-31 (0x{reserved:02X})",
                        reading.key, reading.text
                    ),
                )
                .with_help("an entry is node-ID << 16 | time in ms; bits 24-31 are 0"),
            );
            continue;
        }
        let node = (value >> 16) & 0xFF;
        let time = value & 0xFFFF;
        if !(1..=127).contains(&node) || time == 0 {
            continue;
        }
        match monitored.get(&node) {
            Some(&first) => out.push(
                object_finding(
                    cx,
                    &HEARTBEAT_DUPLICATE,
                    INDEX,
                    Some(sub),
                    Some(reading.key),
                    format!(
                        "1016sub{sub:X} {} {} monitors node {node} again (already 1016sub{first:X})",
                        reading.key, reading.text
                    ),
                )
                .with_help("keep one active entry per node; devices refuse duplicates with 0604 0043h"),
            ),
            None => {
                monitored.insert(node, sub);
            }
        }
    }
}

// ---- 55: PDO communication parameters -------------------------------------------------------------

fn pdo_communication(cx: &Context<'_>, out: &mut Vec<Finding>) {
    for direction in [Direction::Receive, Direction::Transmit] {
        let base = direction.communication_base();
        for (&index, object) in cx.eds.objects.range(base..=base + 0x1FF) {
            if object.origin == Origin::Orphan {
                continue;
            }
            let pdo = direction.name(index - base);
            let highest = direction.highest_sub();
            if let Some(sub0) = live_sub(object, 0)
                && let Some(reading) = reading(cx, &sub0.attributes)
                && let Int::Literal(value) = reading.value
                && !(2..=i128::from(highest)).contains(&value)
            {
                out.push(
                    object_finding(
                        cx,
                        &PDO_HIGHEST_SUB,
                        index,
                        Some(0),
                        Some(reading.key),
                        format!(
                            "{index:X}sub0 {} {} is outside 2..{highest}: {pdo}'s communication parameter has sub-indices 1 to {highest}",
                            reading.key, reading.text
                        ),
                    )
                    .with_help("sub 0 is the highest sub-index implemented; COB-ID (1) and transmission type (2) are mandatory"),
                );
            }
            if let Some(sub2) = live_sub(object, 2)
                && let Some(reading) = reading(cx, &sub2.attributes)
                && let Int::Literal(value) = reading.value
                && direction.reserved_transmission_types().contains(&value)
            {
                let range = direction.reserved_transmission_types();
                out.push(
                    object_finding(
                        cx,
                        &TRANSMISSION_TYPE,
                        index,
                        Some(2),
                        Some(reading.key),
                        format!(
                            "{index:X}sub2 {} {} is a reserved transmission type for {pdo} ({}..{} are reserved)",
                            reading.key,
                            reading.text,
                            range.start(),
                            range.end()
                        ),
                    )
                    .with_help(match direction {
                        Direction::Receive => "RPDOs use 0-240 (synchronous) or 254/255 (event-driven)",
                        Direction::Transmit => {
                            "TPDOs use 0-240 (synchronous), 252/253 (RTR only) or 254/255 (event-driven)"
                        }
                    }),
                );
            }
        }
    }
}

// ---- 56: COB-IDs --------------------------------------------------------------------------------

/// What a COB-ID entry configures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Service {
    Pdo(Direction, u16),
    Sync,
    Time,
    Emcy,
    SdoServer(u16),
}

impl Service {
    fn name(self) -> String {
        match self {
            Self::Pdo(direction, n) => direction.name(n),
            Self::Sync => "SYNC".to_owned(),
            Self::Time => "TIME".to_owned(),
            Self::Emcy => "EMCY".to_owned(),
            Self::SdoServer(n) => format!("SDO server {}", n + 1),
        }
    }

    /// Whether the object uses its CAN-ID with this value.
    fn in_use(self, value: u32) -> bool {
        match self {
            // 1005h bit 31 is "do not care": a SYNC consumer always listens on the CAN-ID.
            Self::Sync => true,
            // 1012h bit 31 = consumes TIME, bit 30 = produces it; with neither the CAN-ID is unused.
            Self::Time => value & 0xC000_0000 != 0,
            Self::Pdo(..) | Self::Emcy | Self::SdoServer(_) => value & VALID_BIT == 0,
        }
    }
}

const VALID_BIT: u32 = 0x8000_0000;
const FRAME_BIT: u32 = 0x2000_0000;
const EXTENDED_BITS: u32 = 0x1FFF_F800;

/// One COB-ID entry of the file with its effective value.
struct CobEntry<'a> {
    service: Service,
    index: u16,
    sub: Option<u8>,
    reading: Reading<'a>,
}

impl CobEntry<'_> {
    fn at(&self, node: u8) -> Option<u32> {
        u32::try_from(self.reading.value.at(node)).ok()
    }

    fn name(&self) -> String {
        entry_name(self.index, self.sub)
    }
}

fn cob_entries<'a>(cx: &Context<'a>) -> Vec<CobEntry<'a>> {
    let mut entries = Vec::new();
    let mut push = |service, index: u16, sub: Option<u8>| {
        let Some(object) = live_object(cx, index) else {
            return;
        };
        let attributes = match sub {
            None if object.subs.is_empty() => &object.attributes,
            None => return,
            Some(s) => match live_sub(object, s) {
                Some(sub_object) => &sub_object.attributes,
                None => return,
            },
        };
        if let Some(reading) = reading(cx, attributes) {
            entries.push(CobEntry {
                service,
                index,
                sub,
                reading,
            });
        }
    };
    push(Service::Sync, 0x1005, None);
    push(Service::Time, 0x1012, None);
    push(Service::Emcy, 0x1014, None);
    for n in 0..0x7F {
        if live_object(cx, 0x1201 + n).is_some() {
            push(Service::SdoServer(n + 1), 0x1201 + n, Some(1));
            push(Service::SdoServer(n + 1), 0x1201 + n, Some(2));
        }
    }
    for direction in [Direction::Receive, Direction::Transmit] {
        let base = direction.communication_base();
        let numbers: Vec<u16> = cx
            .eds
            .objects
            .range(base..=base + 0x1FF)
            .map(|(&i, _)| i - base)
            .collect();
        for n in numbers {
            push(Service::Pdo(direction, n), base + n, Some(1));
        }
    }
    entries
}

fn cob_ids(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let entries = cob_entries(cx);
    for entry in &entries {
        // A plain number is the same for every node-ID: evaluate it once.
        let nodes = match entry.reading.value {
            Int::Literal(_) => 1..=1,
            Int::NodeRelative(_) => node_ids(cx),
        };
        let mut restricted: Vec<(u8, u32, &'static str)> = Vec::new();
        let mut carries: Vec<u8> = Vec::new();
        let mut extended = false;
        for node in nodes {
            let Some(value) = entry.at(node) else { continue };
            if value & FRAME_BIT == 0 && value & EXTENDED_BITS != 0 {
                carries.push(node);
                continue;
            }
            if !entry.service.in_use(value) {
                continue;
            }
            if value & FRAME_BIT != 0 {
                extended = true;
                continue;
            }
            if let Some(reason) = restricted_reason(value & 0x7FF) {
                restricted.push((node, value & 0x7FF, reason));
            }
        }
        let service = entry.service.name();
        let reading = &entry.reading;
        if !carries.is_empty() {
            let scope = node_scope(&entry.reading, &carries);
            out.push(
                object_finding(
                    cx,
                    &COB_ID_RESERVED_BITS,
                    entry.index,
                    entry.sub,
                    Some(reading.key),
                    format!(
                        "{} {} {} ({service}) sets bits 11-28 without bit 29 (29-bit frame){scope}",
                        entry.name(),
                        reading.key,
                        reading.shown()
                    ),
                )
                .with_help("an 11-bit COB-ID has the CAN-ID in bits 0-10 and flags in bits 29-31 only"),
            );
        }
        if extended {
            out.push(
                object_finding(
                    cx,
                    &COB_ID_29_BIT,
                    entry.index,
                    entry.sub,
                    Some(reading.key),
                    format!(
                        "{} {} {} ({service}) sets bit 29: a 29-bit CAN-ID, which many devices and masters do not support",
                        entry.name(),
                        reading.key,
                        reading.shown()
                    ),
                )
                .with_help("use an 11-bit CAN-ID unless the network is built for extended frames"),
            );
        }
        if !restricted.is_empty() {
            let node_list: Vec<u8> = restricted.iter().map(|&(n, _, _)| n).collect();
            let (low, high) = restricted
                .iter()
                .fold((u32::MAX, 0), |(lo, hi), &(_, id, _)| (lo.min(id), hi.max(id)));
            let mut reasons: Vec<&str> = restricted.iter().map(|&(_, _, r)| r).collect();
            reasons.dedup();
            let ids = if low == high {
                format!("CAN-ID 0x{low:03X}")
            } else {
                format!("CAN-IDs 0x{low:03X}..0x{high:03X}")
            };
            let scope = node_scope(reading, &node_list);
            out.push(
                object_finding(
                    cx,
                    &RESTRICTED_COB_ID,
                    entry.index,
                    entry.sub,
                    Some(reading.key),
                    format!(
                        "{} {} {} gives {service} {ids}{scope}, which CiA 301 restricts ({})",
                        entry.name(),
                        reading.key,
                        reading.shown(),
                        reasons.join(", ")
                    ),
                )
                .with_help("use the pre-defined connection set or set bit 31 to disable the object"),
            );
        }
    }
    predefined_pdos(cx, out, &entries);
    duplicate_pdos(cx, out, &entries);
}

/// Why CiA 301 restricts an 11-bit CAN-ID, if it does.
fn restricted_reason(can_id: u32) -> Option<&'static str> {
    match can_id {
        0x000 => Some("NMT"),
        0x001..=0x07F | 0x101..=0x180 | 0x6E0..=0x6FF => Some("reserved"),
        0x581..=0x5FF => Some("default SDO server to client"),
        0x601..=0x67F => Some("default SDO client to server"),
        0x701..=0x77F => Some("NMT error control"),
        0x780..=0x7FF => Some("reserved, LSS"),
        _ => None,
    }
}

fn predefined_pdos(cx: &Context<'_>, out: &mut Vec<Finding>, entries: &[CobEntry<'_>]) {
    // A DCF holds a configuration and a master's PDOs listen to other nodes: both legitimately
    // depart from the connection set.
    if cx.is_dcf() || is_master(cx) {
        return;
    }
    for entry in entries {
        let Service::Pdo(direction, n) = entry.service else {
            continue;
        };
        if n > 3 {
            continue;
        }
        let expected = direction.predefined_base() + 0x100 * u32::from(n);
        let pdo = direction.name(n);
        let reading = &entry.reading;
        let message = match reading.value {
            Int::NodeRelative(offset) => {
                let Ok(offset) = u32::try_from(offset) else {
                    continue;
                };
                if offset & VALID_BIT != 0 || offset & !0xC000_0000 == expected {
                    continue;
                }
                format!(
                    "{} {} {} is not {pdo}'s pre-defined COB-ID $NODEID+0x{expected:X}",
                    entry.name(),
                    reading.key,
                    reading.shown()
                )
            }
            Int::Literal(value) => {
                let Ok(value) = u32::try_from(value) else { continue };
                if value & VALID_BIT != 0 {
                    continue;
                }
                let id = value & !0xC000_0000;
                match id.checked_sub(expected) {
                    Some(node @ 1..=127) => format!(
                        "{} {} {} is {pdo}'s pre-defined COB-ID only for node-ID {node}; an EDS describes every node-ID",
                        entry.name(),
                        reading.key,
                        reading.shown()
                    ),
                    _ => format!(
                        "{} {} {} is not {pdo}'s pre-defined COB-ID $NODEID+0x{expected:X}",
                        entry.name(),
                        reading.key,
                        reading.shown()
                    ),
                }
            }
        };
        out.push(
            object_finding(
                cx,
                &NOT_PREDEFINED,
                entry.index,
                entry.sub,
                Some(reading.key),
                message,
            )
            .with_help(format!(
                "write $NODEID+0x{expected:X}, or set bit 31 if the PDO is off by default"
            )),
        );
    }
}

fn duplicate_pdos(cx: &Context<'_>, out: &mut Vec<Finding>, entries: &[CobEntry<'_>]) {
    let node = if cx.is_dcf() { cx.eds.node_id() } else { None };
    let pdos: Vec<&CobEntry<'_>> = entries
        .iter()
        .filter(|e| matches!(e.service, Service::Pdo(..)))
        .collect();
    // The identifier part of a COB-ID: CAN-ID and frame bit, without the valid and RTR flags.
    let id = |v: i128| v & 0x3FFF_FFFF;
    // Each PDO is reported once, against the first earlier PDO it clashes with.
    for (later, b) in pdos.iter().enumerate() {
        let Some(at_b) = b.at(1) else { continue };
        // Validity is a flag bit the node-ID never reaches, so node 1 tells for all node-IDs.
        if !b.service.in_use(at_b) {
            continue;
        }
        let clash = pdos.iter().take(later).find_map(|a| {
            let at_a = a.at(1)?;
            if !a.service.in_use(at_a) {
                return None;
            }
            let only_node: Option<u8> = match (node, a.reading.value, b.reading.value) {
                (Some(n), x, y) => (id(x.at(n)) == id(y.at(n))).then_some(None)?,
                (None, Int::NodeRelative(x), Int::NodeRelative(y))
                | (None, Int::Literal(x), Int::Literal(y)) => (id(x) == id(y)).then_some(None)?,
                (None, Int::NodeRelative(offset), Int::Literal(value))
                | (None, Int::Literal(value), Int::NodeRelative(offset)) => Some(
                    u8::try_from(id(value) - id(offset))
                        .ok()
                        .filter(|n| (1..=127).contains(n))?,
                ),
            };
            Some((a, only_node))
        });
        let Some((a, only_node)) = clash else { continue };
        let receive_only = matches!(
            (a.service, b.service),
            (
                Service::Pdo(Direction::Receive, _),
                Service::Pdo(Direction::Receive, _)
            )
        );
        let scope = only_node.map_or(String::new(), |n| format!(" when the node-ID is {n}"));
        let finding = object_finding(
            cx,
            &DUPLICATE_COB_ID,
            b.index,
            b.sub,
            Some(b.reading.key),
            format!(
                "{} COB-ID {} equals {}'s ({} {}){scope}",
                b.service.name(),
                b.reading.shown(),
                a.service.name(),
                a.name(),
                a.reading.shown()
            ),
        )
        .with_help("give every valid PDO its own CAN-ID");
        out.push(if receive_only || only_node.is_some() {
            finding.with_severity(Severity::Warning)
        } else {
            finding
        });
    }
}

// ---- 57: mapping --------------------------------------------------------------------------------

fn mappings(cx: &Context<'_>, out: &mut Vec<Finding>) {
    let granularity = cx
        .eds
        .device_info
        .granularity
        .as_deref()
        .and_then(int_of)
        .filter(|g| (1..=64).contains(g));
    for direction in [Direction::Receive, Direction::Transmit] {
        let base = direction.mapping_base();
        for (&index, object) in cx.eds.objects.range(base..=base + 0x1FF) {
            if object.origin == Origin::Orphan {
                continue;
            }
            let Some(sub0) = live_sub(object, 0) else { continue };
            let Some(count) = reading(cx, &sub0.attributes) else {
                continue;
            };
            let Int::Literal(count_value) = count.value else {
                continue;
            };
            // FEh and FFh switch the PDO to SAM-/DAM-MPDO, which has no mapping entries.
            let Ok(n @ 1..=0xFD) = u8::try_from(count_value) else {
                continue;
            };
            let highest = object.highest_sub().unwrap_or(0);
            let pdo = direction.name(index - base);
            let mut total: i128 = 0;
            for k in 1..=n {
                let Some(entry) = live_sub(object, k) else {
                    if k < highest {
                        out.push(
                            object_finding(
                                cx,
                                &MAPPING_UNDESCRIBED,
                                index,
                                Some(0),
                                Some(count.key),
                                format!(
                                    "{index:X}sub0 {} {} counts mapping entry {k}, but [{index:X}sub{k:X}] is not described",
                                    count.key, count.text
                                ),
                            )
                            .with_help("describe the entry or lower sub 0"),
                        );
                    }
                    continue;
                };
                let Some(mapped) = reading(cx, &entry.attributes) else {
                    continue;
                };
                let Int::Literal(raw) = mapped.value else { continue };
                let Ok(raw) = u32::try_from(raw) else { continue };
                let length = raw & 0xFF;
                total += i128::from(length);
                let cx_entry = EntryAt {
                    cx,
                    index,
                    sub: k,
                    reading: &mapped,
                };
                check_mapping_entry(&cx_entry, out, direction, raw);
                if let Some(g) = granularity
                    && i128::from(length) % g != 0
                {
                    out.push(cx_entry.finding(
                        &MAPPING_GRANULARITY,
                        format!("maps {length} bits, not a multiple of [DeviceInfo] Granularity={g}"),
                        "correct Granularity or the default mapping",
                    ));
                }
            }
            if total > 64 {
                out.push(
                    object_finding(
                        cx,
                        &MAPPING_TOO_LONG,
                        index,
                        Some(0),
                        Some(count.key),
                        format!(
                            "{pdo} maps {total} bits in entries 1..{n}, more than the 64 bits of a CAN frame"
                        ),
                    )
                    .with_help("move entries to another PDO"),
                );
            }
        }
    }
}

/// One mapping entry being checked, for findings that all point at it.
struct EntryAt<'c, 'a> {
    cx: &'c Context<'a>,
    index: u16,
    sub: u8,
    reading: &'c Reading<'c>,
}

impl EntryAt<'_, '_> {
    fn finding(&self, info: &CheckInfo, what: String, help: &str) -> Finding {
        object_finding(
            self.cx,
            info,
            self.index,
            Some(self.sub),
            Some(self.reading.key),
            format!(
                "{:X}sub{:X} {} {} {what}",
                self.index,
                self.sub,
                self.reading.key,
                self.reading.shown()
            ),
        )
        .with_help(help.to_owned())
    }
}

fn check_mapping_entry(at: &EntryAt<'_, '_>, out: &mut Vec<Finding>, direction: Direction, raw: u32) {
    let cx = at.cx;
    let (target, target_sub, length) = ((raw >> 16) as u16, ((raw >> 8) & 0xFF) as u8, raw & 0xFF);
    if raw == 0 {
        out.push(at.finding(
            &MAPPED_MISSING,
            "maps nothing, but sub 0 counts it as an active entry".to_owned(),
            "lower sub 0 to the number of entries in use",
        ));
        return;
    }
    // Indices below 1000h are data types: as mapping entries they are dummies (CiA 306 §4.6.2).
    if target < 0x1000 {
        let key = format!("Dummy{target:04X}");
        let enabled = cx
            .eds
            .dummy_usage
            .as_ref()
            .and_then(|d| d.get(&key))
            .and_then(int_of)
            == Some(1);
        if !enabled {
            out.push(at.finding(
                &MAPPED_MISSING,
                format!("maps dummy {target:04X}h, which [DummyUsage] does not enable ({key}=1)"),
                "enable the dummy in [DummyUsage] or map a real object",
            ));
        } else if let Some(bits) = DataType(target).bit_size()
            && bits != length
        {
            out.push(at.finding(
                &MAPPING_LENGTH,
                format!(
                    "maps dummy {target:04X}h with {length} bits; {} has {bits}",
                    type_name(DataType(target))
                ),
                "a dummy entry's length is the size of its type",
            ));
        }
        return;
    }
    let name = if target_sub == 0 && cx.eds.object(target).is_some_and(|o| o.subs.is_empty()) {
        format!("{target:X}h")
    } else {
        format!("{target:X}sub{target_sub:X}")
    };
    let Some(attributes) = mapped_attributes(cx, target, target_sub) else {
        // A modular device's defaults may map objects and sub-indices its modules create (CiA 306 §6).
        let from_module = cx
            .eds
            .modules
            .values()
            .any(|m| m.fixed.contains_key(&target) || m.sub_ext.contains_key(&target));
        if !from_module {
            let what = if live_object(cx, target).is_some() {
                format!("maps {name}, but {target:X}h has no sub-index {target_sub:X}")
            } else {
                format!("maps {name}, but object {target:X}h is not described")
            };
            out.push(at.finding(
                &MAPPED_MISSING,
                what,
                "describe the mapped object or correct the entry",
            ));
        }
        return;
    };
    if !attributes.pdo_mapping() {
        out.push(at.finding(
            &NOT_MAPPABLE,
            format!(
                "maps {name}, whose PDOMapping is {}",
                attributes.pdo_mapping.as_deref().map_or("missing (0)", str::trim)
            ),
            "set PDOMapping=1 on the mapped object, or map another object",
        ));
    }
    if let Some(access) = attributes.access_type() {
        let allowed = match direction {
            Direction::Receive => access.rpdo_mappable(),
            Direction::Transmit => access.tpdo_mappable(),
        };
        if !allowed {
            out.push(at.finding(
                &MAPPING_DIRECTION,
                format!(
                    "maps {name} (AccessType {}) into {}, which {}",
                    written(attributes.access_type.as_deref()),
                    direction.kind(),
                    match direction {
                        Direction::Receive => "writes it: it needs wo, rw or rww",
                        Direction::Transmit => "reads it: it needs ro, rw, rwr or const",
                    }
                ),
                "correct the AccessType or map the object into a PDO of the other direction",
            ));
        }
        if access == AccessType::Rw && attributes.pdo_mapping() {
            let (meant, role) = match direction {
                Direction::Receive => ("rww", "an output: an RPDO writes it"),
                Direction::Transmit => ("rwr", "an input: a TPDO reads it"),
            };
            out.push(at.finding(
                &MAPPED_DIRECTION_UNCLEAR,
                format!(
                    "maps {name}, whose AccessType rw has no clear mapping direction; this PDO makes it \
                     {role} ({meant})"
                ),
                &format!("write AccessType={meant} in [{}]", name.trim_end_matches('h')),
            ));
        }
    }
    let Some(declared) = attributes.data_type() else {
        return;
    };
    let data_type = cx.eds.resolve_data_type(declared);
    let type_text = type_name(data_type);
    let mismatch = match data_type.kind() {
        Some(TypeKind::VisibleString | TypeKind::OctetString) => (length == 0 || length % 8 != 0)
            .then(|| format!("not a whole number of bytes of its {type_text}")),
        Some(TypeKind::UnicodeString) => (length == 0 || length % 16 != 0)
            .then(|| format!("not a whole number of 16-bit characters of its {type_text}")),
        Some(TypeKind::Domain) | None => None,
        Some(_) => data_type
            .bit_size()
            .filter(|&bits| bits != length)
            .map(|bits| format!("but its type {type_text} has {bits}")),
    };
    if let Some(why) = mismatch {
        let finding = at.finding(
            &MAPPING_LENGTH,
            format!("maps {name} with {length} bits, {why}"),
            "write the type's size in bits 0-7 of the entry",
        );
        out.push(if data_type == DataType::BOOLEAN && length == 8 {
            finding.with_severity(Severity::Warning)
        } else {
            finding
        });
    }
}

/// The attributes of a mapped object or sub-object, if the device has it.
fn mapped_attributes<'a>(cx: &Context<'a>, index: u16, sub: u8) -> Option<&'a Attributes> {
    let object = live_object(cx, index)?;
    if object.subs.is_empty() {
        return (sub == 0).then_some(&object.attributes);
    }
    live_sub(object, sub).map(|s| &s.attributes)
}

// ---- 58: 1200h ----------------------------------------------------------------------------------

fn sdo_server(cx: &Context<'_>, out: &mut Vec<Finding>) {
    const INDEX: u16 = 0x1200;
    let Some(object) = live_object(cx, INDEX) else {
        return;
    };
    for (sub, expected, what) in [
        (1u8, 0x600i128, "client to server"),
        (2, 0x580, "server to client"),
    ] {
        let Some(sub_object) = live_sub(object, sub) else {
            continue;
        };
        let Some(reading) = reading(cx, &sub_object.attributes) else {
            continue;
        };
        let node = if cx.is_dcf() { cx.eds.node_id() } else { None };
        let (correct, only_for) = match (reading.value, node) {
            (Int::NodeRelative(offset), _) => (offset == expected, None),
            (Int::Literal(value), Some(node)) => (value == expected + i128::from(node), None),
            (Int::Literal(value), None) => (
                false,
                u8::try_from(value - expected)
                    .ok()
                    .filter(|n| (1..=127).contains(n)),
            ),
        };
        if correct {
            continue;
        }
        let finding = object_finding(
            cx,
            &SDO_SERVER,
            INDEX,
            Some(sub),
            Some(reading.key),
            match only_for {
                Some(n) => format!(
                    "1200sub{sub} {} {} is the default SDO COB-ID ({what}) only for node-ID {n}",
                    reading.key,
                    reading.shown()
                ),
                None => format!(
                    "1200sub{sub} {} {} is not the default SDO COB-ID ({what}) $NODEID+0x{expected:X}",
                    reading.key,
                    reading.shown()
                ),
            },
        )
        .with_help(format!("write $NODEID+0x{expected:X}"));
        out.push(if only_for.is_some() {
            finding.with_severity(Severity::Warning)
        } else {
            finding
        });
    }
}

// ---- shared helpers -----------------------------------------------------------------------------

/// A PDO direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Direction {
    Receive,
    Transmit,
}

impl Direction {
    fn communication_base(self) -> u16 {
        match self {
            Self::Receive => 0x1400,
            Self::Transmit => 0x1800,
        }
    }

    fn mapping_base(self) -> u16 {
        match self {
            Self::Receive => 0x1600,
            Self::Transmit => 0x1A00,
        }
    }

    fn predefined_base(self) -> u32 {
        match self {
            Self::Receive => 0x200,
            Self::Transmit => 0x180,
        }
    }

    fn highest_sub(self) -> u8 {
        match self {
            Self::Receive => 5,
            Self::Transmit => 6,
        }
    }

    fn reserved_transmission_types(self) -> RangeInclusive<i128> {
        match self {
            Self::Receive => 241..=253,
            Self::Transmit => 241..=251,
        }
    }

    fn kind(self) -> &'static str {
        match self {
            Self::Receive => "an RPDO",
            Self::Transmit => "a TPDO",
        }
    }

    /// `RPDO1` for PDO number `n` counted from 0.
    fn name(self, n: u16) -> String {
        match self {
            Self::Receive => format!("RPDO{}", n + 1),
            Self::Transmit => format!("TPDO{}", n + 1),
        }
    }
}

/// The node-IDs a value must work for: the DCF's node-ID, or every node-ID an EDS may be used with.
fn node_ids(cx: &Context<'_>) -> RangeInclusive<u8> {
    match cx.eds.node_id() {
        Some(node) if cx.is_dcf() => node..=node,
        _ => 1..=127,
    }
}

/// " for node-IDs 1..31, 64..95" when a formula was evaluated; nothing for a plain number.
fn node_scope(reading: &Reading<'_>, nodes: &[u8]) -> String {
    if matches!(reading.value, Int::Literal(_)) {
        return String::new();
    }
    let mut ranges: Vec<(u8, u8)> = Vec::new();
    for &n in nodes {
        match ranges.last_mut() {
            Some((_, end)) if end.checked_add(1) == Some(n) => *end = n,
            _ => ranges.push((n, n)),
        }
    }
    let text: Vec<String> = ranges
        .iter()
        .map(|&(a, b)| {
            if a == b {
                a.to_string()
            } else {
                format!("{a}..{b}")
            }
        })
        .collect();
    let plural = if nodes.len() == 1 { "" } else { "s" };
    format!(" for node-ID{plural} {}", text.join(", "))
}

/// A sub-object of the device, not an orphan placeholder.
fn live_sub(object: &canopener_eds::Object, sub: u8) -> Option<&canopener_eds::SubObject> {
    object.subs.get(&sub).filter(|s| s.origin != Origin::Orphan)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn findings(text: &str) -> Vec<Finding> {
        let loaded = canopener_eds::load(text.as_bytes());
        let cx = Context::new(&loaded, None);
        let mut out = Vec::new();
        run(&cx, &mut out);
        out
    }

    fn with_code<'f>(found: &'f [Finding], code: &str) -> Vec<&'f Finding> {
        found.iter().filter(|f| f.diagnostic.code == code).collect()
    }

    #[test]
    fn restricted_ranges_end_where_cia_301_says() {
        let restricted = [
            0x000, 0x001, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x6FF, 0x701, 0x7E4, 0x7FF,
        ];
        let free = [0x080, 0x0FF, 0x100, 0x181, 0x580, 0x600, 0x680, 0x6DF, 0x700];
        for id in restricted {
            assert!(restricted_reason(id).is_some(), "0x{id:03X} should be restricted");
        }
        for id in free {
            assert_eq!(restricted_reason(id), None, "0x{id:03X} should be free");
        }
    }

    #[test]
    fn node_scope_names_ranges_of_node_ids() {
        let formula = Reading {
            key: "DefaultValue",
            text: "$NODEID+0x6A0",
            value: Int::NodeRelative(0x6A0),
        };
        let nodes: Vec<u8> = (64..=95).chain([100, 102, 103]).collect();
        assert_eq!(
            node_scope(&formula, &nodes),
            " for node-IDs 64..95, 100, 102..103"
        );
        assert_eq!(node_scope(&formula, &[5]), " for node-ID 5");
        let number = Reading {
            value: Int::Literal(0x6A5),
            text: "0x6A5",
            ..formula
        };
        assert_eq!(node_scope(&number, &[1]), "");
        assert_eq!(number.shown(), "0x6A5");
        assert_eq!(
            Reading {
                text: "1701",
                ..number
            }
            .shown(),
            "1701 (0x6A5)"
        );
    }

    const TPDO1: &str = "[1800]\nParameterName=TPDO1\nObjectType=0x9\nSubNumber=3\n\
[1800sub0]\nParameterName=n\nDataType=0x0005\nAccessType=ro\nDefaultValue=2\n\
[1800sub1]\nParameterName=COB-ID\nDataType=0x0007\nAccessType=rw\nDefaultValue=$NODEID+0x6A0\n\
[1800sub2]\nParameterName=type\nDataType=0x0005\nAccessType=rw\nDefaultValue=255\n";

    #[test]
    fn formulas_are_evaluated_for_every_node_id_of_an_eds_and_the_node_id_of_a_dcf() {
        let eds = findings(TPDO1);
        let restricted = with_code(&eds, "C710");
        assert_eq!(restricted.len(), 1, "{eds:?}");
        assert!(
            restricted
                .iter()
                .all(|f| f.diagnostic.message.contains("node-IDs 64..95")),
            "{restricted:?}"
        );
        let dcf = |node: u8| format!("[DeviceComissioning]\nNodeID={node}\n{TPDO1}");
        assert!(with_code(&findings(&dcf(5)), "C710").is_empty());
        assert_eq!(with_code(&findings(&dcf(64)), "C710").len(), 1);
    }

    #[test]
    fn implied_pdos_are_checked_and_point_at_compact_pdo() {
        // CompactPDO=0x01 implies only the COB-ID, so sub 0 of the implied RPDO1 is 1.
        let text = "[DeviceInfo]\nNrOfRXPDO=1\nNrOfTXPDO=0\nCompactPDO=0x01\n";
        let found = findings(text);
        let highest = with_code(&found, "C706");
        assert_eq!(highest.len(), 1, "{found:?}");
        assert!(
            highest
                .iter()
                .all(|f| f.diagnostic.span.line == 4 && f.diagnostic.key.as_deref() == Some("CompactPDO"))
        );
    }

    #[test]
    fn dcf_values_of_compact_arrays_point_at_their_value_entries() {
        let text = "[DeviceComissioning]\nNodeID=5\n\
[1016]\nParameterName=Consumer heartbeat time\nObjectType=0x8\nDataType=0x0007\nAccessType=rw\n\
DefaultValue=0\nCompactSubObj=2\n\
[1016Value]\nNrOfEntries=2\n1=0x00050064\n2=0x01060064\n";
        let found = findings(text);
        let reserved = with_code(&found, "C704");
        assert_eq!(reserved.len(), 1, "{found:?}");
        assert!(
            reserved
                .iter()
                .all(|f| f.diagnostic.section.as_deref() == Some("1016Value")
                    && f.diagnostic.key.as_deref() == Some("2")),
            "{reserved:?}"
        );
    }
}
