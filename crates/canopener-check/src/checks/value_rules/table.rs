//! The rule table: one row per CiA 301 value range, reserved value or cross-object dependency of a
//! communication object, with its severity, its source and the check that reports it.
//!
//! Sources are the project's reference notes: `C§n` is `cia301-401-305-essentials.md` §n, `E§n`
//! `eds-format-and-checks.md` §n (both compile public CiA 301 excerpts, stack sources and a CCT
//! log). Severity follows the source: a value that the device must refuse (the stacks answer
//! 0609 0030h, the CCT expects the refusal) or that leaves an object unusable is an error; a value
//! without effect, or one a source only discourages, a warning; a value CiA 301 only calls "not
//! used", info.

use canopener_eds::Severity;

use super::checks::{
    COUNTER_OVERFLOW, EMCY_INHIBIT_ALONE, EMCY_RESERVED_BIT, EVENT_TIMER_NO_EFFECT, GUARDING_PAIR,
    HEARTBEAT_AND_GUARDING, HEARTBEAT_CONSUMER_COUNT, MAPPING_COUNT, NMT_STARTUP_RESERVED,
    RPDO_INHIBIT_UNUSED, RTR_ONLY_WITHOUT_RTR, SDO_CLIENT_SERVER_NODE, START_VALUE_NOT_CYCLIC,
    START_VALUE_RESERVED, START_VALUE_WITHOUT_COUNTER, STORE_RESTORE_RESERVED, SYNC_OBJECT_MISSING,
};
use crate::check_info::CheckInfo;

/// One rule.
#[derive(Debug)]
pub(crate) struct Rule {
    /// The first object index the rule applies to.
    pub(crate) first: u16,
    /// The last object index (equal to `first` for one object).
    pub(crate) last: u16,
    /// Which entries of each object.
    pub(crate) subs: Subs,
    /// What kind of rule it is, for the published table.
    pub(crate) kind: Kind,
    /// Conditions (all must hold) under which the rule applies; empty: always.
    pub(crate) when: &'static [Cond],
    /// What must then hold; empty for rows that are only documented here.
    pub(crate) then: &'static [Cond],
    /// The rule in words; ends the finding's message.
    pub(crate) text: &'static str,
    /// How to fix a finding.
    pub(crate) help: &'static str,
    /// The severity the source gives it.
    pub(crate) severity: Severity,
    /// Where the rule comes from.
    pub(crate) source: &'static str,
    /// The check that reports it.
    pub(crate) check: Check,
}

/// The entries of an object a rule is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Subs {
    /// The object's own value (a VAR).
    Object,
    /// One sub-index.
    One(u8),
    /// Every described sub-index in this range (FFh excluded).
    Range(u8, u8),
}

/// The kind of a rule, as the published table names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// The value lies in a range.
    Range,
    /// The value avoids reserved values.
    Reserved,
    /// Reserved bits are 0.
    ReservedBits,
    /// Another object must exist or hold a value.
    Dependency,
    /// Two values contradict each other.
    Contradiction,
}

impl Kind {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Self::Range => "range",
            Self::Reserved => "reserved values",
            Self::ReservedBits => "reserved bits",
            Self::Dependency => "dependency",
            Self::Contradiction => "contradiction",
        }
    }
}

/// Who reports a rule.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Check {
    /// A check of this group, evaluated from the row.
    New(&'static CheckInfo),
    /// Checks that existed before the table; the row documents that they cover it.
    Existing(&'static [&'static str]),
    /// Not checked, for this reason.
    NotChecked(&'static str),
}

/// A condition on one entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Cond {
    /// The entry tested.
    pub(crate) entry: Entry,
    /// The test.
    pub(crate) test: Test,
}

/// An entry, relative to the one the rule is evaluated for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Entry {
    /// The entry itself.
    This,
    /// Another sub-index of the same object.
    Sub(u8),
    /// A fixed object's value (`None`) or sub-index.
    Fixed(u16, Option<u8>),
}

impl Entry {
    /// The index and sub-index this entry names for the subject `(index, sub)`.
    pub(crate) fn locate(self, index: u16, sub: Option<u8>) -> (u16, Option<u8>) {
        match self {
            Self::This => (index, sub),
            Self::Sub(s) => (index, Some(s)),
            Self::Fixed(i, s) => (i, s),
        }
    }

    pub(crate) fn describe(self) -> String {
        match self {
            Self::This => "the value".to_owned(),
            Self::Sub(s) => format!("sub {s}"),
            Self::Fixed(i, None) => format!("{i:04X}h"),
            Self::Fixed(i, Some(s)) => format!("{i:04X}h sub {s}"),
        }
    }
}

/// A test of an entry's value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Test {
    /// The entry is described (exists).
    Described,
    /// The value lies in one of these inclusive ranges.
    In(&'static [(i128, i128)]),
    /// The value lies in none of these inclusive ranges.
    NotIn(&'static [(i128, i128)]),
    /// These bits are 0.
    BitsClear(u32),
    /// These bits are 1.
    BitsSet(u32),
    /// The value is not above that entry's value.
    NotAbove(Entry),
}

impl Test {
    /// Whether `value` passes; `other` is the compared entry's value for [`Test::NotAbove`].
    pub(crate) fn holds(self, value: i128, other: Option<i128>) -> bool {
        let within = |ranges: &[(i128, i128)]| ranges.iter().any(|&(a, b)| (a..=b).contains(&value));
        match self {
            Self::Described => true,
            Self::In(ranges) => within(ranges),
            Self::NotIn(ranges) => !within(ranges),
            Self::BitsClear(mask) => value & i128::from(mask) == 0,
            Self::BitsSet(mask) => value & i128::from(mask) == i128::from(mask),
            Self::NotAbove(_) => other.is_none_or(|o| value <= o),
        }
    }

    pub(crate) fn describe(self) -> String {
        let ranges = |rs: &[(i128, i128)]| {
            rs.iter()
                .map(|&(a, b)| {
                    if a == b {
                        a.to_string()
                    } else {
                        format!("{a}..{b}")
                    }
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        match self {
            Self::Described => "is described".to_owned(),
            Self::In(rs) => format!("is {}", ranges(rs)),
            Self::NotIn(rs) => format!("is not {}", ranges(rs)),
            Self::BitsClear(mask) => format!("has {} = 0", bits(mask)),
            Self::BitsSet(mask) => format!("has {} = 1", bits(mask)),
            Self::NotAbove(entry) => format!("is not above {}", entry.describe()),
        }
    }
}

/// `bit 30` or `bits 7-31` (a mask is one contiguous run in this table).
fn bits(mask: u32) -> String {
    let low = mask.trailing_zeros();
    let high = 31 - mask.leading_zeros();
    if low == high {
        format!("bit {low}")
    } else {
        format!("bits {low}-{high}")
    }
}

const fn when(entry: Entry, test: Test) -> Cond {
    Cond { entry, test }
}

const THIS: Entry = Entry::This;
const SYNC_COB_ID: Entry = Entry::Fixed(0x1005, None);
const COUNTER: Entry = Entry::Fixed(0x1019, None);
const NONZERO: Test = Test::NotIn(&[(0, 0)]);
const ZERO: Test = Test::In(&[(0, 0)]);
const SYNCHRONOUS_TPDO: Test = Test::In(&[(0, 240), (252, 252)]);
const SYNCHRONOUS_RPDO: Test = Test::In(&[(0, 240)]);
const BIT_31: u32 = 1 << 31;
const BIT_30: u32 = 1 << 30;

/// A documented-only row (covered elsewhere or not checked).
const fn doc(
    (first, last): (u16, u16),
    subs: Subs,
    kind: Kind,
    text: &'static str,
    severity: Severity,
    source: &'static str,
    check: Check,
) -> Rule {
    Rule {
        first,
        last,
        subs,
        kind,
        when: &[],
        then: &[],
        text,
        help: "",
        severity,
        source,
        check,
    }
}

/// Every rule, in object order.
pub(crate) const RULES: &[Rule] = &[
    doc(
        (0x1000, 0x1001),
        Subs::Object,
        Kind::Range,
        "VAR of UNSIGNED32 (1000h) / UNSIGNED8 (1001h), read-only",
        Severity::Error,
        "CiA 301 1000h, 1001h; E§9.1",
        Check::Existing(&["C701"]),
    ),
    doc(
        (0x1000, 0x1FFF),
        Subs::Range(0, 0xFE),
        Kind::Range,
        "object type, data type, access, PDO mapping and sub-indices as the CiA 301 profile data defines them",
        Severity::Error,
        "crates/canopener-check/data/cia301.toml (E§9, C§1-§6)",
        Check::Existing(&["C901", "C902", "C903", "C904", "C905", "C906", "C907", "C908"]),
    ),
    doc(
        (0x1000, 0x1FFF),
        Subs::One(0),
        Kind::Range,
        "sub 0 of a structured object equals its highest sub-index",
        Severity::Error,
        "E§10 check 37",
        Check::Existing(&["C537"]),
    ),
    Rule {
        first: 0x1003,
        last: 0x1003,
        subs: Subs::One(0),
        kind: Kind::Range,
        when: &[],
        then: &[when(THIS, ZERO)],
        text: "only 0 can be written to the number of errors in the pre-defined error field (it clears the history); any other value is refused",
        help: "",
        severity: Severity::Error,
        source: "CiA 301 1003h; C§4.3 (writing 0 to sub0 clears the list; any other value → 0609 0030h; CCT SDO 10 writes FFh and expects the refusal)",
        check: Check::NotChecked(
            "a rule on values written to the device, which the device test cia301.sdo.9 checks; a file's sub 0 holds the errors present at power-on, and the corpus has files that give it the number of entries (3 or 8), not reported until reviewed",
        ),
    },
    Rule {
        first: 0x1005,
        last: 0x1005,
        subs: Subs::Object,
        kind: Kind::Dependency,
        when: &[when(THIS, Test::BitsSet(BIT_30))],
        then: &[when(Entry::Fixed(0x1006, None), Test::Described)],
        text: "a SYNC producer (1005h bit 30 = 1) needs 1006h, the communication cycle period that paces it",
        help: "describe 1006h (UNSIGNED32, rw, µs, 0 = no SYNC) or clear bit 30 of 1005h",
        severity: Severity::Error,
        source: "CiA 301 1005h, 1006h; C§4.1 (bit 30 = produces SYNC; 1006h = SYNC interval); E§9.2",
        check: Check::New(&SYNC_OBJECT_MISSING),
    },
    doc(
        (0x1005, 0x1005),
        Subs::Object,
        Kind::Reserved,
        "a valid CAN-ID outside the restricted CAN-IDs; bits 11-28 = 0 for 11-bit IDs; 29-bit IDs warned",
        Severity::Error,
        "C§6; C§4.1",
        Check::Existing(&["C710", "C711", "C712"]),
    ),
    Rule {
        first: 0x1007,
        last: 0x1007,
        subs: Subs::Object,
        kind: Kind::Dependency,
        when: &[],
        then: &[when(SYNC_COB_ID, Test::Described)],
        text: "the synchronous window 1007h belongs to SYNC, which needs the COB-ID SYNC 1005h",
        help: "describe 1005h (UNSIGNED32, default 0x80) or remove 1007h",
        severity: Severity::Error,
        source: "CiA 301 1005h, 1007h; C§4.1; E§9.2 (1005h-1007h, 1019h conditional on SYNC)",
        check: Check::New(&SYNC_OBJECT_MISSING),
    },
    doc(
        (0x100C, 0x100D),
        Subs::Object,
        Kind::Dependency,
        "heartbeat (1017h) or node guarding (100Ch and 100Dh) is offered",
        Severity::Error,
        "CiA 301 1017h, 100Ch, 100Dh; E§9.2",
        Check::Existing(&["C703"]),
    ),
    Rule {
        first: 0x100C,
        last: 0x100C,
        subs: Subs::Object,
        kind: Kind::Dependency,
        when: &[],
        then: &[when(Entry::Fixed(0x100D, None), Test::Described)],
        text: "the guard time 100Ch works only with the life time factor 100Dh (node life time = 100Ch × 100Dh)",
        help: "describe 100Dh (UNSIGNED8) too, or remove 100Ch if the device has no node guarding",
        severity: Severity::Warning,
        source: "CiA 301 100Ch, 100Dh; C§2.6; E§9.2",
        check: Check::New(&GUARDING_PAIR),
    },
    Rule {
        first: 0x100D,
        last: 0x100D,
        subs: Subs::Object,
        kind: Kind::Dependency,
        when: &[],
        then: &[when(Entry::Fixed(0x100C, None), Test::Described)],
        text: "the life time factor 100Dh works only with the guard time 100Ch (node life time = 100Ch × 100Dh)",
        help: "describe 100Ch (UNSIGNED16, ms) too, or remove 100Dh if the device has no node guarding",
        severity: Severity::Warning,
        source: "CiA 301 100Ch, 100Dh; C§2.6; E§9.2",
        check: Check::New(&GUARDING_PAIR),
    },
    Rule {
        first: 0x1010,
        last: 0x1010,
        subs: Subs::Range(1, 0x7F),
        kind: Kind::ReservedBits,
        when: &[],
        then: &[when(THIS, Test::BitsClear(0xFFFF_FFFC))],
        text: "a store-parameters entry reads back bit 0 (saves on command) and bit 1 (saves autonomously); bits 2-31 are reserved (0)",
        help: "write 1 (store on command), 2 (autonomous) or 0; the \"save\" signature is written by the master, not a default",
        severity: Severity::Error,
        source: "CiA 301 1010h; C§5 (read-back: bits 0, 1; other bits 0)",
        check: Check::New(&STORE_RESTORE_RESERVED),
    },
    Rule {
        first: 0x1011,
        last: 0x1011,
        subs: Subs::Range(1, 0x7F),
        kind: Kind::ReservedBits,
        when: &[],
        then: &[when(THIS, Test::BitsClear(0xFFFF_FFFE))],
        text: "a restore-defaults entry reads back bit 0 (can restore defaults); bits 1-31 are reserved (0)",
        help: "write 1 (restores defaults) or 0; the \"load\" signature is written by the master, not a default",
        severity: Severity::Error,
        source: "CiA 301 1011h; C§5 (read-back: bit 0)",
        check: Check::New(&STORE_RESTORE_RESERVED),
    },
    doc(
        (0x1012, 0x1012),
        Subs::Object,
        Kind::Reserved,
        "a TIME COB-ID that is produced or consumed avoids the restricted CAN-IDs; bits 11-28 = 0 for 11-bit IDs",
        Severity::Error,
        "C§4.2; C§6",
        Check::Existing(&["C710", "C711", "C712"]),
    ),
    Rule {
        first: 0x1014,
        last: 0x1014,
        subs: Subs::Object,
        kind: Kind::ReservedBits,
        when: &[],
        then: &[when(THIS, Test::BitsClear(BIT_30))],
        text: "bit 30 of the COB-ID EMCY is reserved (0)",
        help: "clear bit 30: write $NODEID+0x80 (valid) or $NODEID+0x80000080 (not valid)",
        severity: Severity::Error,
        source: "CiA 301 1014h; C§4.3 (bit 30 reserved (0))",
        check: Check::New(&EMCY_RESERVED_BIT),
    },
    doc(
        (0x1014, 0x1014),
        Subs::Object,
        Kind::Reserved,
        "a valid EMCY COB-ID avoids the restricted CAN-IDs; bits 11-28 = 0 for 11-bit IDs",
        Severity::Error,
        "C§4.3; C§6",
        Check::Existing(&["C710", "C711", "C712"]),
    ),
    Rule {
        first: 0x1015,
        last: 0x1015,
        subs: Subs::Object,
        kind: Kind::Dependency,
        when: &[],
        then: &[when(Entry::Fixed(0x1014, None), Test::Described)],
        text: "the EMCY inhibit time 1015h paces EMCY messages, which need the COB-ID EMCY 1014h",
        help: "describe 1014h ($NODEID+0x80) or remove 1015h",
        severity: Severity::Warning,
        source: "CiA 301 1014h, 1015h; C§4.3; E§9.2 (1014h, 1015h when EMCY is produced)",
        check: Check::New(&EMCY_INHIBIT_ALONE),
    },
    Rule {
        first: 0x1016,
        last: 0x1016,
        subs: Subs::One(0),
        kind: Kind::Range,
        when: &[],
        then: &[when(THIS, Test::In(&[(1, 127)]))],
        text: "the number of consumer heartbeat entries is 1..127",
        help: "set sub 0 to the number of entries (1..127), or remove 1016h if the device consumes no heartbeats",
        severity: Severity::Error,
        source: "CiA 301 1016h; E§9.2 (sub 0 = number of entries (1..127))",
        check: Check::New(&HEARTBEAT_CONSUMER_COUNT),
    },
    doc(
        (0x1016, 0x1016),
        Subs::Range(1, 0x7F),
        Kind::ReservedBits,
        "consumer heartbeat entries keep bits 24-31 = 0",
        Severity::Error,
        "C§2.5; E§9.2",
        Check::Existing(&["C704"]),
    ),
    doc(
        (0x1016, 0x1016),
        Subs::Range(1, 0x7F),
        Kind::Contradiction,
        "no two active entries monitor the same node-ID (devices answer 0604 0043h)",
        Severity::Error,
        "C§2.5 (CCT Heartbeat 04)",
        Check::Existing(&["C705"]),
    ),
    doc(
        (0x1016, 0x1016),
        Subs::Range(1, 0x7F),
        Kind::Dependency,
        "the consumer time exceeds the monitored node's producer time",
        Severity::Warning,
        "C§2.5",
        Check::NotChecked("depends on another device's 1017h; a network check, not a file check"),
    ),
    Rule {
        first: 0x1017,
        last: 0x1017,
        subs: Subs::Object,
        kind: Kind::Contradiction,
        when: &[when(THIS, NONZERO), when(Entry::Fixed(0x100C, None), NONZERO)],
        then: &[when(Entry::Fixed(0x100D, None), ZERO)],
        text: "heartbeat and node guarding are both enabled; a device must not run both, and uses heartbeat when 1017h is not 0",
        help: "set 1017h or 100Ch/100Dh to 0 so that one error-control protocol is configured",
        severity: Severity::Warning,
        source: "CiA 301 1017h, 100Ch, 100Dh; E§9.2 (not both at the same time); C§2.6 (heartbeat wins)",
        check: Check::New(&HEARTBEAT_AND_GUARDING),
    },
    doc(
        (0x1018, 0x1018),
        Subs::One(0),
        Kind::Range,
        "sub 0 is 1..4, sub 1 (Vendor-ID) exists",
        Severity::Error,
        "CiA 301 1018h",
        Check::Existing(&["C702"]),
    ),
    Rule {
        first: 0x1019,
        last: 0x1019,
        subs: Subs::Object,
        kind: Kind::Reserved,
        when: &[],
        then: &[when(THIS, Test::NotIn(&[(1, 1), (241, 255)]))],
        text: "the synchronous counter overflow value is 0 (no counter) or 2..240; 1 and 241..255 are reserved",
        help: "write 0 for SYNC without a counter, or the counter's overflow value 2..240",
        severity: Severity::Error,
        source: "CiA 301 1019h; C§4.1 (1, 241..255 reserved; devices refuse them with 0609 0030h, CCT Sync 05); E§9.2",
        check: Check::New(&COUNTER_OVERFLOW),
    },
    Rule {
        first: 0x1019,
        last: 0x1019,
        subs: Subs::Object,
        kind: Kind::Dependency,
        when: &[],
        then: &[when(SYNC_COB_ID, Test::Described)],
        text: "the synchronous counter overflow value 1019h belongs to SYNC, which needs the COB-ID SYNC 1005h",
        help: "describe 1005h (UNSIGNED32, default 0x80) or remove 1019h",
        severity: Severity::Error,
        source: "CiA 301 1005h, 1019h; C§4.1; E§9.2 (1005h-1007h, 1019h conditional on SYNC)",
        check: Check::New(&SYNC_OBJECT_MISSING),
    },
    doc(
        (0x1028, 0x1028),
        Subs::Range(1, 0x7F),
        Kind::ReservedBits,
        "emergency consumer COB-IDs",
        Severity::Error,
        "–",
        Check::NotChecked("the reference notes do not describe 1028h; no rule without a source"),
    ),
    doc(
        (0x1029, 0x1029),
        Subs::Range(1, 0xFE),
        Kind::Reserved,
        "error behaviour 0 (pre-operational), 1 (no change), 2 (stopped); 3..127 reserved, 128..255 manufacturer-specific",
        Severity::Error,
        "C§2.8",
        Check::NotChecked("C§2.8 marks the values other than 0..2 UNCONFIRMED"),
    ),
    doc(
        (0x1200, 0x1200),
        Subs::One(0),
        Kind::Range,
        "sub 0 of the default SDO server is 2 (sub-indices 1 and 2 only)",
        Severity::Error,
        "C§1.6; E§9.2",
        Check::Existing(&["C537", "C908"]),
    ),
    doc(
        (0x1201, 0x127F),
        Subs::One(0),
        Kind::Range,
        "sub 0 of an additional SDO server is 3 (sub 3 = the client's node-ID)",
        Severity::Error,
        "C§1.6; E§9.2",
        Check::Existing(&["C537", "C908"]),
    ),
    doc(
        (0x1200, 0x1200),
        Subs::Range(1, 2),
        Kind::Range,
        "the default SDO server uses $NODEID+0x600 and $NODEID+0x580",
        Severity::Error,
        "C§1.6; C§6",
        Check::Existing(&["C730"]),
    ),
    doc(
        (0x1201, 0x127F),
        Subs::Range(1, 2),
        Kind::Reserved,
        "valid additional SDO server COB-IDs avoid the restricted CAN-IDs; bits 11-28 = 0 for 11-bit IDs",
        Severity::Error,
        "C§1.6; C§6",
        Check::Existing(&["C710", "C711", "C712"]),
    ),
    doc(
        (0x1280, 0x12FF),
        Subs::Range(1, 2),
        Kind::ReservedBits,
        "SDO client COB-ID bit 30",
        Severity::Error,
        "C§1.6",
        Check::NotChecked(
            "C§1.6: CiA 301 calls bit 30 \"dynamic\", an older DS301 guide \"reserved\"; the sources disagree",
        ),
    ),
    Rule {
        first: 0x1280,
        last: 0x12FF,
        subs: Subs::One(3),
        kind: Kind::Range,
        when: &[
            when(Entry::Sub(1), Test::BitsClear(BIT_31)),
            when(Entry::Sub(1), NONZERO),
            when(Entry::Sub(2), Test::BitsClear(BIT_31)),
            when(Entry::Sub(2), NONZERO),
        ],
        then: &[when(THIS, Test::In(&[(1, 127)]))],
        text: "a valid SDO client (both COB-IDs with bit 31 = 0 and a CAN-ID) names its server's node-ID 1..127",
        help: "write the server's node-ID (1..127) in sub 3, or set bit 31 of sub 1/2 while the client is unused",
        severity: Severity::Error,
        source: "CiA 301 1280h-12FFh; C§1.6 (sub 3 node-ID of the SDO server (1..127); active only when both COB-IDs are valid; a COB-ID of 0, CAN-ID 000h = NMT, is CANopenNode's \"not configured\"); E§9.2",
        check: Check::New(&SDO_CLIENT_SERVER_NODE),
    },
    doc(
        (0x1400, 0x15FF),
        Subs::One(0),
        Kind::Range,
        "sub 0 is 2..5",
        Severity::Error,
        "C§3.1; E§9.3",
        Check::Existing(&["C706"]),
    ),
    doc(
        (0x1400, 0x15FF),
        Subs::One(2),
        Kind::Reserved,
        "transmission types 241..253 are reserved for RPDOs",
        Severity::Error,
        "C§3.2; E§9.3",
        Check::Existing(&["C707"]),
    ),
    doc(
        (0x1400, 0x19FF),
        Subs::One(1),
        Kind::Reserved,
        "a valid PDO's COB-ID avoids the restricted CAN-IDs; bits 11-28 = 0 for 11-bit IDs; PDO1-4 use the pre-defined connection set; no two valid PDOs share a CAN-ID",
        Severity::Error,
        "C§3.1; C§6",
        Check::Existing(&["C710", "C711", "C712", "C713", "C714"]),
    ),
    Rule {
        first: 0x1400,
        last: 0x15FF,
        subs: Subs::One(2),
        kind: Kind::Dependency,
        when: &[when(THIS, SYNCHRONOUS_RPDO)],
        then: &[when(SYNC_COB_ID, Test::Described)],
        text: "a synchronous RPDO (transmission type 0..240) acts on SYNC, which needs the COB-ID SYNC 1005h",
        help: "describe 1005h (UNSIGNED32, default 0x80), or use transmission type 254/255",
        severity: Severity::Error,
        source: "CiA 301 1005h, 1400h; C§3.2 (0..240 applied at the next SYNC); E§9.2",
        check: Check::New(&SYNC_OBJECT_MISSING),
    },
    Rule {
        first: 0x1400,
        last: 0x15FF,
        subs: Subs::One(3),
        kind: Kind::Range,
        when: &[],
        then: &[when(THIS, ZERO)],
        text: "an RPDO does not use an inhibit time (sub 3), so a value other than 0 has no effect",
        help: "write 0, or remove sub 3 and lower sub 0 if no higher sub-index is needed",
        severity: Severity::Info,
        source: "CiA 301 1400h; C§3.1 (not meaningful for RPDO); E§9.3 (not used for RPDO)",
        check: Check::New(&RPDO_INHIBIT_UNUSED),
    },
    doc(
        (0x1600, 0x17FF),
        Subs::Range(1, 0x40),
        Kind::Dependency,
        "mapped objects exist (or are enabled dummies), are mappable and writable, entry lengths match their types and Granularity, the total fits 64 bits, counted entries are described",
        Severity::Error,
        "C§3.4; C§3.5",
        Check::Existing(&["C720", "C721", "C722", "C723", "C724", "C725", "C726"]),
    ),
    Rule {
        first: 0x1600,
        last: 0x17FF,
        subs: Subs::One(0),
        kind: Kind::Reserved,
        when: &[],
        then: &[when(THIS, Test::NotIn(&[(0x41, 0xFD)]))],
        text: "the number of mapped objects is 0..64, or FEh/FFh for MPDOs; 65..253 are reserved",
        help: "map at most 64 objects (sub 0 = 0..0x40)",
        severity: Severity::Error,
        source: "CiA 301 1600h; C§3.4 (0 = disabled, up to 40h; FEh SAM-MPDO, FFh DAM-MPDO); E§9.3",
        check: Check::New(&MAPPING_COUNT),
    },
    doc(
        (0x1800, 0x19FF),
        Subs::One(0),
        Kind::Range,
        "sub 0 is 2..6",
        Severity::Error,
        "C§3.1; E§9.3",
        Check::Existing(&["C706"]),
    ),
    doc(
        (0x1800, 0x19FF),
        Subs::One(2),
        Kind::Reserved,
        "transmission types 241..251 are reserved for TPDOs",
        Severity::Error,
        "C§3.2; E§9.3",
        Check::Existing(&["C707"]),
    ),
    Rule {
        first: 0x1800,
        last: 0x19FF,
        subs: Subs::One(2),
        kind: Kind::Dependency,
        when: &[when(THIS, SYNCHRONOUS_TPDO)],
        then: &[when(SYNC_COB_ID, Test::Described)],
        text: "a synchronous TPDO (transmission type 0..240 or 252) is sent on SYNC, which needs the COB-ID SYNC 1005h",
        help: "describe 1005h (UNSIGNED32, default 0x80), or use transmission type 254/255",
        severity: Severity::Error,
        source: "CiA 301 1005h, 1800h; C§3.2 (0..240 and 252 sent at SYNC); E§9.2",
        check: Check::New(&SYNC_OBJECT_MISSING),
    },
    Rule {
        first: 0x1800,
        last: 0x19FF,
        subs: Subs::One(2),
        kind: Kind::Contradiction,
        when: &[when(THIS, Test::In(&[(252, 253)]))],
        then: &[when(Entry::Sub(1), Test::BitsClear(BIT_30))],
        text: "an RTR-only TPDO (transmission type 252/253) is only ever sent on a remote request, which COB-ID bit 30 = 1 forbids",
        help: "clear bit 30 of sub 1 (RTR allowed) or use transmission type 254/255",
        severity: Severity::Error,
        source: "CiA 301 1800h; C§3.1 (bit 30 = 1: RTR not allowed; lely refuses 252/253 with bit 30 set); C§3.2",
        check: Check::New(&RTR_ONLY_WITHOUT_RTR),
    },
    Rule {
        first: 0x1800,
        last: 0x19FF,
        subs: Subs::One(5),
        kind: Kind::Contradiction,
        when: &[when(THIS, NONZERO)],
        then: &[when(Entry::Sub(2), Test::In(&[(254, 255)]))],
        text: "the TPDO event timer triggers event-driven TPDOs (transmission type 254/255) only, so it has no effect here",
        help: "set the event timer to 0, or use transmission type 254/255",
        severity: Severity::Warning,
        source: "CiA 301 1800h; C§3.3 (for 254/255 the TPDO is sent when the event timer expires)",
        check: Check::New(&EVENT_TIMER_NO_EFFECT),
    },
    Rule {
        first: 0x1800,
        last: 0x19FF,
        subs: Subs::One(6),
        kind: Kind::Reserved,
        when: &[],
        then: &[when(THIS, Test::NotIn(&[(241, 255)]))],
        text: "the SYNC start value is 0 (not used) or 1..240; 241..255 are reserved",
        help: "write 0, or the SYNC counter value (1..240) at which the TPDO starts",
        severity: Severity::Error,
        source: "CiA 301 1800h; C§3.1, C§3.3 (0 or 1..240; above 240 refused with 0609 0030h); E§9.3",
        check: Check::New(&START_VALUE_RESERVED),
    },
    Rule {
        first: 0x1800,
        last: 0x19FF,
        subs: Subs::One(6),
        kind: Kind::Dependency,
        when: &[when(THIS, NONZERO)],
        then: &[
            when(COUNTER, Test::Described),
            when(COUNTER, NONZERO),
            when(THIS, Test::NotAbove(COUNTER)),
        ],
        text: "a SYNC start value is compared with the SYNC counter, which needs 1019h not 0 and not below the start value",
        help: "describe 1019h with an overflow value at least the start value, or set the start value to 0",
        severity: Severity::Warning,
        source: "CiA 301 1019h, 1800h; C§3.3 (only meaningful when 1019h > 0); C§4.1 (counter counts 1..1019h)",
        check: Check::New(&START_VALUE_WITHOUT_COUNTER),
    },
    Rule {
        first: 0x1800,
        last: 0x19FF,
        subs: Subs::One(6),
        kind: Kind::Contradiction,
        when: &[when(THIS, NONZERO)],
        then: &[when(Entry::Sub(2), Test::In(&[(1, 240)]))],
        text: "a SYNC start value applies to cyclic synchronous TPDOs (transmission type 1..240) only, so it has no effect here",
        help: "set the SYNC start value to 0, or use a cyclic synchronous transmission type",
        severity: Severity::Warning,
        source: "CiA 301 1800h; C§3.3 (the start value marks the first SYNC for cyclic types)",
        check: Check::New(&START_VALUE_NOT_CYCLIC),
    },
    doc(
        (0x1A00, 0x1BFF),
        Subs::Range(1, 0x40),
        Kind::Dependency,
        "mapped objects exist (or are enabled dummies), are mappable and readable, entry lengths match their types and Granularity, the total fits 64 bits, counted entries are described",
        Severity::Error,
        "C§3.4; C§3.5",
        Check::Existing(&["C720", "C721", "C722", "C723", "C724", "C725", "C726"]),
    ),
    Rule {
        first: 0x1A00,
        last: 0x1BFF,
        subs: Subs::One(0),
        kind: Kind::Reserved,
        when: &[],
        then: &[when(THIS, Test::NotIn(&[(0x41, 0xFD)]))],
        text: "the number of mapped objects is 0..64, or FEh/FFh for MPDOs; 65..253 are reserved",
        help: "map at most 64 objects (sub 0 = 0..0x40)",
        severity: Severity::Error,
        source: "CiA 301 1A00h; C§3.4 (0 = disabled, up to 40h; FEh SAM-MPDO, FFh DAM-MPDO); E§9.3",
        check: Check::New(&MAPPING_COUNT),
    },
    doc(
        (0x1400, 0x19FF),
        Subs::One(1),
        Kind::Dependency,
        "a valid PDO has at least one mapped object",
        Severity::Warning,
        "C§3.1",
        Check::NotChecked("C§3.1: only CANopenNode refuses it; the CiA text was not seen"),
    ),
    Rule {
        first: 0x1F80,
        last: 0x1F80,
        subs: Subs::Object,
        kind: Kind::ReservedBits,
        when: &[],
        then: &[when(THIS, Test::BitsClear(0xFFFF_FF80))],
        text: "bits 7-31 of the NMT start-up value are reserved (0)",
        help: "clear bits 7-31; only bits 0-6 have a meaning",
        severity: Severity::Error,
        source: "CiA 302-2 1F80h; C§2.7 (bits 7..31 reserved; devices refuse unsupported bits with 0609 0030h)",
        check: Check::New(&NMT_STARTUP_RESERVED),
    },
    doc(
        (0x1F80, 0x1F80),
        Subs::Object,
        Kind::ReservedBits,
        "bit 5 (flying master)",
        Severity::Error,
        "C§2.7",
        Check::NotChecked("C§2.7 marks bit 5 UNCONFIRMED"),
    ),
];
