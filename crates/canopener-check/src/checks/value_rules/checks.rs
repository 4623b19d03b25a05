//! The descriptions of the codes the rule table reports (C870-C899). Each code groups rows of one
//! meaning and one severity; the rows themselves are in [`super::table`].

use canopener_eds::Severity;

use crate::check_info::{CheckInfo, Group};

pub(crate) const COUNTER_OVERFLOW: CheckInfo = CheckInfo {
    code: "C870",
    slug: "sync-counter-overflow-reserved",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "1019h (synchronous counter overflow value) is 0 or 2..240",
    reference: &[],
    spec: "CiA 301 object 1019h",
    explanation: "\
1019h says whether SYNC messages carry a counter: 0 means no counter (the SYNC has no data), 2..240 \
is the value at which the counter wraps back to 1. The values 1 and 241..255 are reserved. This \
check reports a 1019h value in a reserved range.

Devices refuse reserved values with SDO abort 0609 0030h (CANopenNode, lely), and the CiA \
conformance test (Sync 05) writes them expecting that refusal, so the file's default cannot be \
restored and a master that configures the network from it fails.

It is an error: the value has no meaning in CiA 301.

Fix: write 0 for SYNC without a counter, or the overflow value 2..240.",
    fixable: false,
};

pub(crate) const START_VALUE_RESERVED: CheckInfo = CheckInfo {
    code: "C871",
    slug: "sync-start-value-reserved",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "TPDO SYNC start values (sub 6) are 0..240",
    reference: &[],
    spec: "CiA 301 TPDO communication parameter (1800h-19FFh) sub 6",
    explanation: "\
Sub 6 of a TPDO communication parameter is the SYNC start value: 0 means the SYNC counter is \
ignored, 1..240 names the counter value of the first SYNC that counts for a cyclic TPDO. 241..255 \
are reserved, since the counter never exceeds 240. This check reports a start value above 240.

Devices refuse it with 0609 0030h, so the default cannot be downloaded, and the TPDO would never \
start if it were accepted.

It is an error: the value is reserved.

Fix: write 0, or the counter value 1..240 at which the TPDO starts.",
    fixable: false,
};

pub(crate) const SYNC_OBJECT_MISSING: CheckInfo = CheckInfo {
    code: "C872",
    slug: "sync-object-missing",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "SYNC users (synchronous PDOs, 1007h, 1019h) have 1005h, and a SYNC producer has 1006h",
    reference: &[],
    spec: "CiA 301 objects 1005h, 1006h (conditional on SYNC)",
    explanation: "\
1005h (COB-ID SYNC) is mandatory for a device that consumes or produces SYNC; 1006h (communication \
cycle period) for a device that produces it. This check reports a synchronous PDO (RPDO transmission \
type 0..240, TPDO 0..240 or 252), a synchronous window 1007h or a counter overflow value 1019h in a \
file without 1005h, and a 1005h with bit 30 set (this device produces SYNC) without 1006h.

Without 1005h a master cannot tell or configure which CAN-ID the device synchronises on, and a \
synchronous PDO never moves; without 1006h a SYNC producer has no period to send at. The CiA \
conformance test reads 1005h on every device whose EDS describes synchronous PDOs.

It is an error: CiA 301 makes these objects mandatory for the function the file describes.

Fix: describe 1005h (UNSIGNED32, rw, default 0x80) and, for a SYNC producer, 1006h (UNSIGNED32, rw, \
µs); or use event-driven transmission types (254/255) if the device has no SYNC.",
    fixable: false,
};

pub(crate) const RTR_ONLY_WITHOUT_RTR: CheckInfo = CheckInfo {
    code: "C873",
    slug: "rtr-only-tpdo-without-rtr",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "RTR-only TPDOs (transmission type 252/253) allow RTR (COB-ID bit 30 = 0)",
    reference: &[],
    spec: "CiA 301 TPDO communication parameter (1800h-19FFh) sub 1, sub 2",
    explanation: "\
Transmission types 252 and 253 make a TPDO answer remote transmission requests only. Bit 30 of the \
TPDO's COB-ID (sub 1) set to 1 says that the TPDO may not be requested by RTR. This check reports a \
TPDO whose transmission type is 252 or 253 while its COB-ID sets bit 30.

Such a TPDO can never be sent. lely refuses the transmission type in that case (0609 0030h), so the \
defaults cannot be applied either.

It is an error: the two values contradict each other.

Fix: clear bit 30 of sub 1, or use an event-driven (254/255) or synchronous transmission type.",
    fixable: false,
};

pub(crate) const START_VALUE_WITHOUT_COUNTER: CheckInfo = CheckInfo {
    code: "C874",
    slug: "sync-start-value-without-counter",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "A TPDO SYNC start value goes with a SYNC counter (1019h) that reaches it",
    reference: &[],
    spec: "CiA 301 objects 1019h, 1800h-19FFh sub 6",
    explanation: "\
A SYNC start value other than 0 is compared with the counter that SYNC messages carry, and SYNC \
carries a counter only when 1019h (synchronous counter overflow value) is not 0; the counter runs \
1..1019h. This check reports a TPDO with a start value other than 0 when 1019h is not described, is \
0, or is below the start value.

The start value then never matches: depending on the stack the TPDO ignores it or never starts, and \
a master cannot tell which from the file.

It is a warning: CiA 301 defines the start value as meaningful only with a counter; the file may \
rely on the network's SYNC producer having one, which the file cannot show.

Fix: describe 1019h with an overflow value at least the start value, or set the start value to 0.",
    fixable: false,
};

pub(crate) const START_VALUE_NOT_CYCLIC: CheckInfo = CheckInfo {
    code: "C875",
    slug: "sync-start-value-not-cyclic",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "A TPDO SYNC start value goes with a cyclic synchronous transmission type (1..240)",
    reference: &[],
    spec: "CiA 301 TPDO communication parameter (1800h-19FFh) sub 2, sub 6",
    explanation: "\
The SYNC start value names the SYNC at which a cyclic synchronous TPDO (transmission type 1..240) \
starts counting. This check reports a start value other than 0 on a TPDO with another transmission \
type (acyclic 0, RTR-only 252/253, event-driven 254/255).

The start value then has no effect, which usually means the transmission type or the start value \
is not what the author meant.

It is a warning: nothing is refused, but the value is ignored.

Fix: set the start value to 0, or use a transmission type 1..240.",
    fixable: false,
};

pub(crate) const EMCY_RESERVED_BIT: CheckInfo = CheckInfo {
    code: "C876",
    slug: "emcy-cob-id-reserved-bit",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "1014h (COB-ID EMCY) keeps the reserved bit 30 zero",
    reference: &[],
    spec: "CiA 301 object 1014h",
    explanation: "\
The COB-ID EMCY holds the valid flag in bit 31, the frame type in bit 29 and the CAN-ID in bits \
0-28; bit 30 is reserved and 0 (unlike PDO COB-IDs, where bit 30 is the RTR flag). This check \
reports a 1014h value with bit 30 set, including a $NODEID formula whose offset sets it.

Devices refuse or mask the value, so the file does not say what the device does; usually a PDO \
COB-ID pattern such as 0x40000080 was copied.

It is an error: reserved bits must be 0.

Fix: write $NODEID+0x80 (EMCY valid) or $NODEID+0x80000080 (not valid).",
    fixable: false,
};

pub(crate) const EMCY_INHIBIT_ALONE: CheckInfo = CheckInfo {
    code: "C877",
    slug: "emcy-inhibit-without-emcy",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "1015h (inhibit time EMCY) goes with 1014h (COB-ID EMCY)",
    reference: &[],
    spec: "CiA 301 objects 1014h, 1015h",
    explanation: "\
1015h sets the minimum time between two EMCY messages of the device; EMCY messages need their \
COB-ID, 1014h. This check reports a file that describes 1015h but not 1014h.

Tools that set up EMCY consumers from the file find an inhibit time for a message whose CAN-ID they \
cannot learn.

It is a warning: the inhibit time alone does no harm, but the file is incomplete about EMCY.

Fix: describe 1014h ($NODEID+0x80) or remove 1015h.",
    fixable: false,
};

pub(crate) const MAPPING_COUNT: CheckInfo = CheckInfo {
    code: "C878",
    slug: "mapping-count-reserved",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "PDO mapping sub 0 is 0..64, or FEh/FFh for MPDOs",
    reference: &[],
    spec: "CiA 301 PDO mapping parameter (1600h-17FFh, 1A00h-1BFFh) sub 0",
    explanation: "\
Sub 0 of a PDO mapping parameter is the number of mapped objects: 0 disables the mapping, 1..64 \
(40h) are the entries in use; FEh and FFh select the multiplexed PDO kinds (SAM-MPDO, DAM-MPDO). \
65..253 are reserved. This check reports a sub 0 in the reserved range.

Devices refuse the value (0604 0042h or 0609 0030h), so the default mapping cannot be enabled.

It is an error: the value is reserved.

Fix: map at most 64 objects.",
    fixable: false,
};

pub(crate) const STORE_RESTORE_RESERVED: CheckInfo = CheckInfo {
    code: "C879",
    slug: "store-restore-reserved-bits",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "1010h/1011h entries read back only their defined bits",
    reference: &[],
    spec: "CiA 301 objects 1010h, 1011h",
    explanation: "\
Reading an entry of 1010h (store parameters) returns bit 0 = the device stores on command and bit 1 \
= it stores autonomously; reading 1011h (restore default parameters) returns bit 0 = it can restore \
defaults. The other bits are reserved (0). The signatures \"save\" (0x65766173) and \"load\" \
(0x64616F6C) are what a master writes, not what the entry holds. This check reports values with \
reserved bits set.

A tool that reads the file's default to learn whether the device can store or restore misreads a \
signature as capabilities, and a device cannot hold the value.

It is an error: reserved bits must be 0.

Fix: write 1 (on command), 2 (autonomously), 3 or 0 for 1010h; 1 or 0 for 1011h.",
    fixable: false,
};

pub(crate) const NMT_STARTUP_RESERVED: CheckInfo = CheckInfo {
    code: "C880",
    slug: "nmt-startup-reserved-bits",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "1F80h (NMT start-up) keeps the reserved bits 7-31 zero",
    reference: &[],
    spec: "CiA 302-2 object 1F80h",
    explanation: "\
1F80h configures how a device starts: bit 0 NMT master, bits 1-6 start-up and error options; bits \
7-31 are reserved. This check reports a value with any of bits 7-31 set.

Devices refuse unsupported bits with 0609 0030h, so the configuration cannot be applied.

It is an error: reserved bits must be 0.

Fix: clear bits 7-31.",
    fixable: false,
};

pub(crate) const SDO_CLIENT_SERVER_NODE: CheckInfo = CheckInfo {
    code: "C881",
    slug: "sdo-client-server-node-id",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "A valid SDO client (1280h-12FFh) names its server's node-ID 1..127",
    reference: &[],
    spec: "CiA 301 SDO client parameter (1280h-12FFh) sub 3",
    explanation: "\
An SDO client channel is active when both its COB-IDs (sub 1 and 2) have bit 31 = 0; sub 3 then \
names the node-ID of the server it talks to, 1..127. This check reports an active client whose sub \
3 is outside 1..127. COB-IDs of 0 (CAN-ID 000h belongs to NMT, so no channel can use it) are how \
CANopenNode files mark a client that the application configures at run time; they are not \
reported.

A master configured from the file opens a channel to a node that cannot exist.

It is an error: the value is outside the node-ID range.

Fix: write the server's node-ID, or set bit 31 of the COB-IDs while the client is unused.",
    fixable: false,
};

pub(crate) const HEARTBEAT_AND_GUARDING: CheckInfo = CheckInfo {
    code: "C882",
    slug: "heartbeat-and-guarding-enabled",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "Heartbeat (1017h) and node guarding (100Ch, 100Dh) are not both enabled",
    reference: &[],
    spec: "CiA 301 objects 1017h, 100Ch, 100Dh",
    explanation: "\
A device must not run heartbeat and node guarding at the same time. This check reports a file whose \
values enable both: 1017h (producer heartbeat time) not 0 and 100Ch (guard time) and 100Dh (life \
time factor) not 0.

Devices then use heartbeat and ignore guarding (lely, vendor manuals), so a master that guards the \
node from this configuration sees guarding errors.

It is a warning: the device resolves the conflict; the configuration is still not what it says.

Fix: set 1017h to 0, or 100Ch/100Dh to 0.",
    fixable: false,
};

pub(crate) const RPDO_INHIBIT_UNUSED: CheckInfo = CheckInfo {
    code: "C883",
    slug: "rpdo-inhibit-time-unused",
    severity: Severity::Info,
    group: Group::Cia301,
    title: "RPDO inhibit times (sub 3) are 0",
    reference: &[],
    spec: "CiA 301 RPDO communication parameter (1400h-15FFh) sub 3",
    explanation: "\
An RPDO has no inhibit time: sub 3 exists in the record for symmetry with TPDOs and is not used. \
This check reports an RPDO sub 3 other than 0.

The value has no effect; a reader may expect it to throttle incoming PDOs.

It is information only: CiA 301 calls the entry not used, not forbidden.

Fix: write 0.",
    fixable: false,
};

pub(crate) const EVENT_TIMER_NO_EFFECT: CheckInfo = CheckInfo {
    code: "C884",
    slug: "tpdo-event-timer-no-effect",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "A TPDO event timer goes with an event-driven transmission type (254/255)",
    reference: &[],
    spec: "CiA 301 TPDO communication parameter (1800h-19FFh) sub 2, sub 5",
    explanation: "\
The event timer of a TPDO (sub 5, ms) sends an event-driven TPDO (transmission type 254 or 255) when \
it expires. This check reports a TPDO with an event timer other than 0 and another transmission \
type.

The timer has no effect, so a user expecting a cyclic TPDO gets none: usually the transmission type \
or the timer is not what the author meant.

It is a warning: nothing is refused, but the value is ignored.

Fix: set the event timer to 0, or use transmission type 254/255.",
    fixable: false,
};

pub(crate) const GUARDING_PAIR: CheckInfo = CheckInfo {
    code: "C885",
    slug: "node-guarding-half",
    severity: Severity::Warning,
    group: Group::Cia301,
    title: "Node guarding objects 100Ch and 100Dh come together",
    reference: &[],
    spec: "CiA 301 objects 100Ch, 100Dh",
    explanation: "\
Node guarding needs both the guard time (100Ch) and the life time factor (100Dh): the node life time \
is their product. This check reports a file that describes one of them without the other. (A file \
with neither and no heartbeat is C703.)

A master that sets up guarding from the file cannot compute the life time.

It is a warning: the device still has heartbeat if 1017h is there; the guarding half is useless.

Fix: describe both objects, or neither.",
    fixable: false,
};

pub(crate) const HEARTBEAT_CONSUMER_COUNT: CheckInfo = CheckInfo {
    code: "C886",
    slug: "heartbeat-consumer-count",
    severity: Severity::Error,
    group: Group::Cia301,
    title: "1016h sub 0 (number of consumer heartbeat entries) is 1..127",
    reference: &[],
    spec: "CiA 301 object 1016h",
    explanation: "\
Sub 0 of 1016h (consumer heartbeat time) is the number of entries, one per monitored node: 1..127. \
This check reports a sub 0 of 0 or above 127.

An object with no entries offers nothing to configure, and more than 127 entries exceed the nodes a \
network can have; tools size their heartbeat tables from it.

It is an error: the value is outside the range CiA 301 defines.

Fix: set sub 0 to the number of entries, or remove 1016h.",
    fixable: false,
};

/// The checks of this group, in code order.
pub(crate) const CHECKS: &[CheckInfo] = &[
    COUNTER_OVERFLOW,
    START_VALUE_RESERVED,
    SYNC_OBJECT_MISSING,
    RTR_ONLY_WITHOUT_RTR,
    START_VALUE_WITHOUT_COUNTER,
    START_VALUE_NOT_CYCLIC,
    EMCY_RESERVED_BIT,
    EMCY_INHIBIT_ALONE,
    MAPPING_COUNT,
    STORE_RESTORE_RESERVED,
    NMT_STARTUP_RESERVED,
    SDO_CLIENT_SERVER_NODE,
    HEARTBEAT_AND_GUARDING,
    RPDO_INHIBIT_UNUSED,
    EVENT_TIMER_NO_EFFECT,
    GUARDING_PAIR,
    HEARTBEAT_CONSUMER_COUNT,
];
