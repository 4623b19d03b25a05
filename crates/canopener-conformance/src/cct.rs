//! The 127 cases of the CiA CANopen Conformance Test Tool 3.0.3.10 and how canopener covers each:
//! the one table `docs/conformance.md`, `scripts/cct_coverage.py` and the CI test that runs the
//! catalogue on clean simulated devices read.
//!
//! A case is [`Coverage::Covered`] when a test (or a named step of one) does what the case's name
//! says, [`Coverage::Partial`] when it checks a named part of it, and [`Coverage::Different`] when
//! canopener deliberately reads the case another way; the row's `reading` says which part, or
//! which reading and why. The CCT's procedures are not public beyond the case names and the log of
//! one run (CANopenNode's demo device, `CANopenDemo test/test_report_CCT.md`), which is where the
//! readings below come from. Each test records the cases it performed
//! ([`Ctx::performed`](crate::context::Ctx::performed)); `tests/simulated.rs` checks that every
//! covered and partial case is performed on at least one clean simulated device.

use crate::catalogue::TestDef;

/// How a test covers a CCT case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coverage {
    /// The test does what the case says.
    Covered,
    /// The test checks a named part of the case.
    Partial,
    /// canopener reads the case another way, for a reason the table gives.
    Different,
}

impl Coverage {
    /// `covered`, `partial` or `different`.
    pub fn as_str(self) -> &'static str {
        match self {
            Covered => "covered",
            Partial => "partial",
            Different => "different",
        }
    }
}

/// One CCT case and the tests that perform it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Case {
    /// The case's name in the CCT's list (`SDO 19`, `Testing other 09`).
    pub name: &'static str,
    /// How canopener covers it.
    pub coverage: Coverage,
    /// The tests that perform it (each records the case when the step has run).
    pub tests: &'static [&'static str],
    /// What the test does for the case: for a partial case the part, for a different one the
    /// reading and why; for a covered case a note where the name leaves the procedure open.
    pub reading: &'static str,
}

const fn case(
    name: &'static str,
    coverage: Coverage,
    tests: &'static [&'static str],
    reading: &'static str,
) -> Case {
    Case {
        name,
        coverage,
        tests,
        reading,
    }
}

use Coverage::{Covered, Different, Partial};

/// Every case of the CCT 3.0.3.10 list, in its order.
pub const CASES: &[Case] = &[
    case(
        "EDS checker",
        Covered,
        &["cia301.eds.1"],
        "canopener's own EDS checks (CiA 306), where the CCT runs CANchkEDS",
    ),
    case("SDO 01", Covered, &["cia301.sdo.1"], ""),
    case(
        "SDO 02",
        Covered,
        &["cia301.od.8"],
        "every rw entry of 1000h-1FFFh (and beyond) is read and its value written back, where the CCT picks one",
    ),
    case("SDO 03", Covered, &["cia301.sdo.2"], ""),
    case("SDO 04", Covered, &["cia301.sdo.3"], ""),
    case("SDO 05", Covered, &["cia301.sdo.4"], ""),
    case("SDO 06", Covered, &["cia301.sdo.5"], ""),
    case("SDO 07", Covered, &["cia301.sdo.6"], ""),
    case("SDO 08", Covered, &["cia301.sdo.7"], ""),
    case("SDO 09", Covered, &["cia301.sdo.8"], ""),
    case(
        "SDO 10",
        Covered,
        &["cia301.sdo.9"],
        "the limits come from CiA 301's value rules (canopener-check's table: 1003h:00 takes only 0, the CCT's own case) and from the EDS's HighLimit",
    ),
    case("SDO 11", Covered, &["cia301.sdo.10"], ""),
    case("SDO 12", Covered, &["cia301.sdo.11"], ""),
    case(
        "SDO 13",
        Different,
        &["cia301.sdo.1"],
        "the server, not the client, chooses expedited or segmented for a 4-byte value (CiA 301 §7.2.4.3.6), and the CCT's log passes SDO 13 on an expedited answer: 1000h:00 is read with a client ready for either answer, and whichever the server sends must indicate 4 bytes and carry the value SDO 01 read",
    ),
    case("SDO 14", Covered, &["cia301.sdo.19"], ""),
    case("SDO 15", Covered, &["cia301.sdo.19"], ""),
    case(
        "SDO 16",
        Covered,
        &["cia301.sdo.12"],
        "the segmented upload is checked frame by frame: size indicated, toggles alternating, the last segment's unused bytes",
    ),
    case("SDO 17", Covered, &["cia301.sdo.13"], ""),
    case(
        "SDO 18",
        Covered,
        &["cia301.sdo.12"],
        "the CCT's SDO 18 repeats SDO 16's read (its log shows the same frames)",
    ),
    case("SDO 19", Covered, &["cia301.sdo.15"], ""),
    case("SDO 20", Covered, &["cia301.sdo.16"], ""),
    case("SDO 21", Covered, &["cia301.sdo.16"], ""),
    case(
        "SDO 22",
        Covered,
        &["cia301.sdo.15"],
        "without CRC, as the CCT's log asks for it",
    ),
    case("SDO 23", Covered, &["cia301.sdo.15"], ""),
    case("SDO 24", Covered, &["cia301.sdo.16"], ""),
    case("SDO 25", Covered, &["cia301.sdo.16"], ""),
    case("SDO 26", Covered, &["cia301.sdo.18"], ""),
    case(
        "SDO 27",
        Covered,
        &["cia301.sdo.21"],
        "block size 4, then a block acknowledge with ackseq 128",
    ),
    case(
        "SDO 28",
        Covered,
        &["cia301.sdo.20"],
        "every entry of 1201h-12FFh the EDS describes reads with its type",
    ),
    case(
        "SDO 29",
        Covered,
        &["cia301.sdo.20"],
        "after changing a node-ID (sub-index 3) or making a valid COB-ID invalid, a reset communication brings every EDS default back",
    ),
    case(
        "SDO 30",
        Covered,
        &["cia301.other.4"],
        "that change saved with 1010h:01 survives a reset communication; \"load\" and a reset node bring the default back",
    ),
    case("PDO 01", Covered, &["cia301.pdo.1"], ""),
    case("PDO 02", Covered, &["cia301.pdo.1"], ""),
    case("PDO 03", Covered, &["cia301.pdo.3"], ""),
    case(
        "PDO 04",
        Covered,
        &["cia301.pdo.12"],
        "operational; type FFh with an event timer (10 ms) shorter than the inhibit time (50 ms): TPDOs keep coming, never two within the inhibit time",
    ),
    case("PDO 05", Covered, &["cia301.pdo.6"], "operational"),
    case("PDO 06", Covered, &["cia301.pdo.7"], "operational"),
    case(
        "PDO 07",
        Covered,
        &["cia301.pdo.13"],
        "operational; type 0 sends only right after a SYNC, at most once per SYNC; whether an event occurs is the application's, so no TPDO at all passes",
    ),
    case(
        "PDO 08",
        Covered,
        &["cia301.pdo.14"],
        "operational; 1019h = 10, type 2, start value 5, SYNCs with counters; the SYNC whose counter equals the start value \"is regarded as the first received SYNC\": CANopenNode transmits at it, others count it as the first of n, both pass",
    ),
    case(
        "PDO 09",
        Covered,
        &["cia301.pdo.15"],
        "a TPDO that answers RTR in operational does not in stopped",
    ),
    case(
        "PDO 10",
        Covered,
        &["cia301.pdo.12"],
        "the CCT's log runs PDO 10-14 in stopped: the same TPDO, set up as for PDO 04, sends nothing in stopped",
    ),
    case(
        "PDO 11",
        Covered,
        &["cia301.pdo.6"],
        "stopped: the TPDO of PDO 05 sends nothing",
    ),
    case(
        "PDO 12",
        Covered,
        &["cia301.pdo.7"],
        "stopped: the TPDO of PDO 06 sends nothing on SYNC",
    ),
    case(
        "PDO 13",
        Covered,
        &["cia301.pdo.13"],
        "stopped: the TPDO of PDO 07 sends nothing on SYNC",
    ),
    case(
        "PDO 14",
        Covered,
        &["cia301.pdo.14"],
        "stopped: the TPDO of PDO 08 sends nothing on SYNCs with counters",
    ),
    case(
        "PDO 15",
        Different,
        &["cia301.pdo.15"],
        "read as the pre-operational counterpart of PDO 03 (operational) and PDO 09 (stopped): the CCT's log runs PDO 04-08 in operational, 10-14 in stopped and 16-20 in pre-operational, and skipped PDO 15 on a device without RTR, so its state is inferred; a TPDO that answers RTR in operational does not in pre-operational",
    ),
    case(
        "PDO 16",
        Covered,
        &["cia301.pdo.12"],
        "the CCT's log runs PDO 16-20 in pre-operational: the TPDO of PDO 04 sends nothing there",
    ),
    case(
        "PDO 17",
        Covered,
        &["cia301.pdo.6"],
        "pre-operational: the TPDO of PDO 05 sends nothing",
    ),
    case(
        "PDO 18",
        Covered,
        &["cia301.pdo.7"],
        "pre-operational: the TPDO of PDO 06 sends nothing on SYNC",
    ),
    case(
        "PDO 19",
        Covered,
        &["cia301.pdo.13"],
        "pre-operational: the TPDO of PDO 07 sends nothing on SYNC",
    ),
    case(
        "PDO 20",
        Covered,
        &["cia301.pdo.14"],
        "pre-operational: the TPDO of PDO 08 sends nothing on SYNCs with counters",
    ),
    case("PDO 21", Covered, &["cia301.pdo.2"], ""),
    case("PDO 22", Covered, &["cia301.pdo.8"], ""),
    case(
        "PDO 23",
        Covered,
        &["cia301.pdo.9"],
        "the PDO made invalid, sub-index 0 left as it is: writing a mapping entry is refused",
    ),
    case(
        "PDO 24",
        Covered,
        &["cia301.pdo.9"],
        "the PDO left valid: writing 0 to sub-index 0, then a mapping entry, is refused at the first of them",
    ),
    case(
        "PDO 25",
        Covered,
        &["cia301.pdo.10"],
        "8-bit objects in every entry, then sub-index 0 set to one more than the mapping has entries",
    ),
    case(
        "PDO 26",
        Covered,
        &["cia301.pdo.10"],
        "entries whose lengths add up to more than 64 bits",
    ),
    case("PDO 27", Covered, &["cia301.pdo.19"], ""),
    case("PDO 28", Covered, &["cia301.pdo.11"], ""),
    case(
        "PDO 29",
        Covered,
        &["cia301.pdo.5"],
        "a writable object with PDOMapping=0 (1017h where the EDS has it writable) into an RPDO, as the CCT maps 1401h:05",
    ),
    case("PDO 30", Covered, &["cia301.pdo.16"], ""),
    case(
        "PDO 31",
        Different,
        &["cia301.pdo.17"],
        "only wo objects are tried: an rww object is readable and CiA 301 does not forbid it in a TPDO",
    ),
    case(
        "PDO 32",
        Covered,
        &["cia301.pdo.5"],
        "1000h:00 into a TPDO, as the CCT",
    ),
    case(
        "PDO 33",
        Covered,
        &["cia301.pdo.18"],
        "a dummy entry enabled by [DummyUsage] (0002h-0007h) in an RPDO mapping",
    ),
    case(
        "OD 01",
        Covered,
        &["cia301.od.1", "cia301.od.8"],
        "every readable entry is read (od.1) and every rw entry's value written back (od.8), as the CCT's log does",
    ),
    case("OD 02", Covered, &["cia301.od.2"], ""),
    case("OD 03", Covered, &["cia301.od.3"], ""),
    case("OD 04", Covered, &["cia301.od.4"], ""),
    case(
        "OD 05",
        Covered,
        &["cia301.od.9"],
        "sub-index FFh of every object is read; where the device has it, its object code and data type are compared with the EDS",
    ),
    case("OD 06", Covered, &["cia301.od.5"], ""),
    case(
        "OD 07",
        Covered,
        &["cia301.od.1", "cia301.od.8"],
        "as OD 01, over every object",
    ),
    case(
        "OD 08",
        Covered,
        &["cia301.od.2"],
        "ObjFlags bit 1 entries are left out of the walk",
    ),
    case(
        "OD 09",
        Covered,
        &["cia301.od.8"],
        "ObjFlags bit 0 entries are not written",
    ),
    case("Emergency 01", Covered, &["cia301.emcy.1"], ""),
    case("Emergency 02", Covered, &["cia301.emcy.2"], ""),
    case("Emergency 03", Covered, &["cia301.emcy.5"], ""),
    case("Emergency 04", Covered, &["cia301.emcy.3", "cia301.emcy.4"], ""),
    case(
        "Emergency 05",
        Covered,
        &["cia301.emcy.3", "cia301.emcy.6"],
        "1001h is read again after the EMCY 8210h while the error is present (emcy.3); emcy.6 also reads it during a heartbeat consumer or guarding error",
    ),
    case(
        "Emergency 06",
        Different,
        &["cia301.emcy.5"],
        "1003h:01 is compared with the EMCY's error code (bits 0-15); the CCT also compares the additional information, whose expected form the references cannot confirm (CANopenNode fails it)",
    ),
    case("Synchronization 01", Covered, &["cia301.sync.1"], ""),
    case("Synchronization 02", Covered, &["cia301.sync.4"], ""),
    case(
        "Synchronization 03",
        Covered,
        &["cia301.sync.5"],
        "up to 8 TPDOs on type 1 each follow every SYNC once",
    ),
    case(
        "Synchronization 04",
        Covered,
        &["cia301.sync.5"],
        "the device made a SYNC consumer (1005h bit 30 clear, 1006h = 0) where the EDS makes them writable",
    ),
    case("Synchronization 05", Covered, &["cia301.sync.2"], ""),
    case("Synchronization 06", Covered, &["cia301.sync.2"], ""),
    case("Synchronization 07", Covered, &["cia301.sync.4"], ""),
    case(
        "Synchronization 08",
        Covered,
        &["cia301.other.3"],
        "1019h (while 1006h = 0) and 1007h saved, kept across a reset node, defaults back after \"load\"",
    ),
    case("Synchronization 09", Covered, &["cia301.sync.3"], ""),
    case(
        "Synchronization 10",
        Covered,
        &["cia301.other.3"],
        "as Synchronization 08",
    ),
    case("Guarding 01", Covered, &["cia301.ec.4"], ""),
    case("Guarding 02", Covered, &["cia301.ec.4"], ""),
    case("Guarding 03", Covered, &["cia301.ec.4"], ""),
    case(
        "Guarding 04",
        Covered,
        &["cia301.ec.9"],
        "remote frames on 700h + other node-IDs (0, 1, the neighbours, 127) are not answered, 700h + node-ID is",
    ),
    case("Guarding 05", Covered, &["cia301.ec.7"], ""),
    case("Guarding 06", Covered, &["cia301.ec.7"], ""),
    case("Heartbeat 01", Covered, &["cia301.ec.1"], ""),
    case("Heartbeat 02", Covered, &["cia301.ec.1"], ""),
    case("Heartbeat 03", Covered, &["cia301.ec.2"], ""),
    case("Heartbeat 04", Covered, &["cia301.ec.5"], ""),
    case("Heartbeat 05", Covered, &["cia301.ec.6"], ""),
    case("Heartbeat 06", Covered, &["cia301.ec.6"], ""),
    case(
        "Heartbeat 07",
        Covered,
        &["cia301.ec.10"],
        "1016h:01 back at its default after a reset node; re-armed, no heartbeat event before the first heartbeat",
    ),
    case(
        "Heartbeat versus guarding 01",
        Covered,
        &["cia301.ec.8"],
        "1017h/100Ch/100Dh read as 2/2/1 bytes",
    ),
    case("Heartbeat versus guarding 02", Covered, &["cia301.ec.2"], ""),
    case("Heartbeat versus guarding 03", Covered, &["cia301.ec.4"], ""),
    case(
        "Heartbeat versus guarding 04",
        Covered,
        &["cia301.ec.8"],
        "heartbeats at 1017h with 100Ch = 0",
    ),
    case("Heartbeat versus guarding 05", Covered, &["cia301.ec.3"], ""),
    case(
        "Heartbeat versus guarding 06",
        Covered,
        &["cia301.ec.8"],
        "heartbeats at 1017h with 100Ch/100Dh set",
    ),
    case("Heartbeat versus guarding 07", Covered, &["cia301.ec.3"], ""),
    case(
        "Testing other 01",
        Covered,
        &["cia301.other.1"],
        "'wron' as the CCT sends it: the UNSIGNED32 77726F6Eh, bytes 6E 6F 72 77, to 1010h:01",
    ),
    case(
        "Testing other 02",
        Covered,
        &["cia301.other.2"],
        "'evas' is how the CCT prints the UNSIGNED32 65766173h, bytes 73 61 76 65 = \"save\", to 1010h:01",
    ),
    case(
        "Testing other 03",
        Covered,
        &["cia301.other.1"],
        "'wron' (bytes 6E 6F 72 77) to 1011h:01",
    ),
    case(
        "Testing other 04",
        Covered,
        &["cia301.other.2"],
        "'daol' is the UNSIGNED32 64616F6Ch, bytes 6C 6F 61 64 = \"load\", to 1011h:01, then a reset node",
    ),
    case(
        "Testing other 05",
        Covered,
        &["cia301.other.1"],
        "'wron' (bytes 6E 6F 72 77) to 1010h:02",
    ),
    case(
        "Testing other 06",
        Covered,
        &["cia301.other.5"],
        "\"save\" to 1010h:02 (communication parameters), a reset node, the value kept",
    ),
    case(
        "Testing other 07",
        Covered,
        &["cia301.other.1"],
        "'wron' (bytes 6E 6F 72 77) to 1011h:02",
    ),
    case(
        "Testing other 08",
        Covered,
        &["cia301.other.5"],
        "\"load\" to 1011h:02, a reset node, the default back",
    ),
    case(
        "Testing other 09",
        Covered,
        &["cia301.other.6"],
        "a date and time written to 1020h and saved with 1010h:01 survive a reset node; \"load\" and a reset node bring 1020h's defaults back",
    ),
    case(
        "Testing other 10",
        Partial,
        &["cia301.pdo.4"],
        "one restricted CAN-ID (701h) as a TPDO COB-ID; the CCT writes every restricted CAN-ID to 1005h, 1012h, 1014h, 1400h:01 and 1800h:01",
    ),
    case(
        "State 01",
        Covered,
        &["cia301.nmt.1", "cia301.nmt.11"],
        "the boot-up after a reset (nmt.1); changed communication and application entries back at their DefaultValue after reset node (nmt.11)",
    ),
    case(
        "State 02",
        Covered,
        &["cia301.nmt.1", "cia301.nmt.5", "cia301.nmt.6", "cia301.nmt.8"],
        "",
    ),
    case(
        "State 03",
        Covered,
        &["cia301.nmt.2", "cia301.nmt.5", "cia301.nmt.6", "cia301.nmt.9"],
        "operational is entered and reported (nmt.2); TPDOs, RPDOs and the SYNC producer run there (nmt.5, nmt.6, nmt.9)",
    ),
    case(
        "State 04",
        Covered,
        &[
            "cia301.nmt.2",
            "cia301.nmt.4",
            "cia301.nmt.5",
            "cia301.nmt.6",
            "cia301.nmt.8",
            "cia301.nmt.9",
        ],
        "",
    ),
    case(
        "Transition 01",
        Covered,
        &["cia301.nmt.1", "cia301.nmt.10", "cia301.nmt.11"],
        "",
    ),
    case("Transition 02", Covered, &["cia301.nmt.2"], ""),
    case("Transition 03", Covered, &["cia301.nmt.2"], ""),
    case("Transition 04", Covered, &["cia301.nmt.2"], ""),
];

/// The case named `name`.
pub fn case_named(name: &str) -> Option<&'static Case> {
    CASES.iter().find(|c| c.name == name)
}

/// The cases `test` performs.
pub fn cases_of(test: &TestDef) -> impl Iterator<Item = &'static Case> + '_ {
    CASES.iter().filter(|c| c.tests.contains(&test.id))
}

/// The CCT cases `test`'s references name (`CCT SDO 19` → `SDO 19`).
pub fn referenced(test: &TestDef) -> impl Iterator<Item = &'static str> + '_ {
    test.references.iter().filter_map(|r| r.strip_prefix("CCT "))
}

#[cfg(test)]
mod tests {
    use std::collections::HashSet;

    use super::*;
    use crate::catalogue::catalogue;

    #[test]
    fn the_table_has_the_127_cases_once_each() {
        assert_eq!(CASES.len(), 127);
        let names: HashSet<&str> = CASES.iter().map(|c| c.name).collect();
        assert_eq!(names.len(), CASES.len());
        for case in CASES {
            assert!(!case.tests.is_empty(), "{} has no test", case.name);
            if case.coverage != Covered {
                assert!(
                    !case.reading.is_empty(),
                    "{}: a {} case says why",
                    case.name,
                    case.coverage.as_str()
                );
            }
        }
    }

    #[test]
    fn every_test_references_exactly_the_cases_the_table_gives_it() {
        let all = catalogue();
        for case in CASES {
            for id in case.tests {
                let test = all
                    .iter()
                    .find(|t| t.id == *id)
                    .unwrap_or_else(|| panic!("{}: no test {id}", case.name));
                assert!(
                    referenced(test).any(|r| r == case.name),
                    "{id} does not reference CCT {}",
                    case.name
                );
            }
        }
        for test in &all {
            for name in referenced(test) {
                let case = case_named(name).unwrap_or_else(|| panic!("{}: no CCT case {name}", test.id));
                assert!(
                    case.tests.contains(&test.id),
                    "{} references CCT {name}, which the table gives to {:?}",
                    test.id,
                    case.tests
                );
            }
        }
    }
}
