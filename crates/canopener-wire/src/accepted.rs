//! The one oracle for SDO answers: the abort codes a refusal may carry and the command specifiers
//! an answer may have, where CiA 301 leaves the server a choice. The conformance suites judge
//! through these sets, and the model-based tester's models name them (`accepted(no_object)` in a
//! pattern), so the two oracles cannot disagree.
//!
//! The abort sets follow one rule (written down in `docs/conformance.md`): where the CCT's accepted
//! codes are public (the CCT log quoted in `cia301-401-305-essentials.md` §1.3 and §3.4), exactly
//! that set; elsewhere the code CiA 301's table names for the condition, plus the general error
//! 0800 0000h, which CiA 301 allows for any refusal.

use crate::abort;

/// The abort codes a refusal may carry, and where that set comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Accepted {
    /// The name a model gives the set: `accepted(write_read_only)`.
    pub name: &'static str,
    /// The codes.
    pub codes: &'static [u32],
    /// Where the set comes from (a CCT case, or CiA 301's table).
    pub source: &'static str,
}

impl Accepted {
    /// Whether `code` is in the set.
    pub fn accepts(&self, code: u32) -> bool {
        self.codes.contains(&code)
    }

    /// `0601 0002h, 0601 0000h or 0800 0000h`.
    pub fn list(&self) -> String {
        let codes: Vec<String> = self.codes.iter().map(|c| code_text(*c)).collect();
        match codes.split_last() {
            Some((last, [])) => last.clone(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        }
    }
}

/// `0609 0031h`, as CiA 301 writes abort codes.
pub fn code_text(code: u32) -> String {
    format!("{:04X} {:04X}h", code >> 16, code & 0xFFFF)
}

/// `0609 0031h (value of parameter written too high)`.
pub fn code_meaning(code: u32) -> String {
    match abort::abort_code_text(code) {
        Some(text) => format!("{} ({text})", code_text(code)),
        None => code_text(code),
    }
}

const CCT_LOG: &str = "the CCT's accepted codes (cia301-401-305-essentials.md §1.3)";
const CCT_MAPPING: &str = "the CCT's accepted codes for PDO mapping (cia301-401-305-essentials.md §3.4)";
const CIA_TABLE: &str = "CiA 301's abort code for the condition, or the general error";

/// Writing a read-only entry (CCT SDO 03, OD 03).
pub const WRITE_READ_ONLY: Accepted = Accepted {
    name: "write_read_only",
    codes: &[
        abort::WRITE_READ_ONLY,
        abort::UNSUPPORTED_ACCESS,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// Reading a write-only entry (CCT OD 04).
pub const READ_WRITE_ONLY: Accepted = Accepted {
    name: "read_write_only",
    codes: &[
        abort::READ_WRITE_ONLY,
        abort::UNSUPPORTED_ACCESS,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// A sub-index that does not exist (CCT SDO 05).
pub const NO_SUB_INDEX: Accepted = Accepted {
    name: "no_sub_index",
    codes: &[abort::SUB_INDEX_DOES_NOT_EXIST, abort::GENERAL_ERROR],
    source: CCT_LOG,
};
/// An object that does not exist (CCT SDO 06, SDO 28–30).
pub const NO_OBJECT: Accepted = Accepted {
    name: "no_object",
    codes: &[abort::OBJECT_DOES_NOT_EXIST, abort::GENERAL_ERROR],
    source: CCT_LOG,
};
/// An unknown command specifier (CCT SDO 07).
pub const BAD_COMMAND: Accepted = Accepted {
    name: "bad_command",
    codes: &[abort::COMMAND_SPECIFIER_INVALID, abort::GENERAL_ERROR],
    source: CCT_LOG,
};
/// Too many bytes for the entry's type (CCT SDO 08).
pub const TOO_LONG: Accepted = Accepted {
    name: "too_long",
    codes: &[
        abort::LENGTH_MISMATCH,
        abort::LENGTH_TOO_HIGH,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// Too few bytes for the entry's type (CCT SDO 09).
pub const TOO_SHORT: Accepted = Accepted {
    name: "too_short",
    codes: &[
        abort::LENGTH_MISMATCH,
        abort::LENGTH_TOO_LOW,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// A value above HighLimit (CCT SDO 10, OD 06).
pub const TOO_HIGH: Accepted = Accepted {
    name: "too_high",
    codes: &[abort::VALUE_TOO_HIGH, abort::INVALID_VALUE, abort::GENERAL_ERROR],
    source: CCT_LOG,
};
/// A value below LowLimit (CCT SDO 11, OD 06): the CCT's set for SDO 10 mirrored to "too low".
pub const TOO_LOW: Accepted = Accepted {
    name: "too_low",
    codes: &[abort::VALUE_TOO_LOW, abort::INVALID_VALUE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// A segment whose toggle bit did not alternate (CCT SDO 17).
pub const TOGGLE: Accepted = Accepted {
    name: "toggle",
    codes: &[abort::TOGGLE_BIT_NOT_ALTERNATED, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// A server that gives up on a transfer its client stopped serving (CiA 301 sets no time for it).
pub const TIMED_OUT: Accepted = Accepted {
    name: "timed_out",
    codes: &[abort::PROTOCOL_TIMED_OUT, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// A block upload with a block size outside 1..127 (CCT SDO 26).
pub const BLOCK_SIZE: Accepted = Accepted {
    name: "block_size",
    codes: &[
        abort::COMMAND_SPECIFIER_INVALID,
        abort::INVALID_BLOCK_SIZE,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// A block acknowledge with an impossible sequence number (CCT SDO 27).
pub const SEQUENCE_NUMBER: Accepted = Accepted {
    name: "sequence_number",
    codes: &[
        abort::COMMAND_SPECIFIER_INVALID,
        abort::INVALID_SEQUENCE_NUMBER,
        abort::GENERAL_ERROR,
    ],
    source: CCT_LOG,
};
/// A block download whose end frame carries a CRC that does not match the data (CiA 301 block
/// download end, when client and server both support the CRC).
pub const CRC: Accepted = Accepted {
    name: "crc",
    codes: &[abort::CRC_ERROR, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// The answer of a device without block transfer to a block request (CCT SDO 19, 22).
pub const NO_BLOCK_TRANSFER: Accepted = Accepted {
    name: "no_block_transfer",
    codes: &[abort::COMMAND_SPECIFIER_INVALID],
    source: CCT_LOG,
};
/// Writing mapping entries outside the mapping procedure (CCT PDO 23, 24).
pub const MAPPING_SEQUENCE: Accepted = Accepted {
    name: "mapping_sequence",
    codes: &[
        abort::UNSUPPORTED_ACCESS,
        abort::OBJECT_NOT_MAPPABLE,
        abort::GENERAL_ERROR,
    ],
    source: CCT_MAPPING,
};
/// Enabling a mapping that is too long or has too many entries (CCT PDO 25, 26). 0609 0030h and
/// 0609 0031h are CiA 301's codes for a sub-index 0 above its range, which some stacks use.
pub const MAPPING_LENGTH: Accepted = Accepted {
    name: "mapping_length",
    codes: &[
        abort::PDO_LENGTH_EXCEEDED,
        abort::UNSUPPORTED_ACCESS,
        abort::OBJECT_NOT_MAPPABLE,
        abort::OBJECT_DOES_NOT_EXIST,
        abort::INVALID_VALUE,
        abort::VALUE_TOO_HIGH,
        abort::GENERAL_ERROR,
    ],
    source: CCT_MAPPING,
};
/// Mapping an object that may not be mapped, or in the wrong direction (CCT PDO 28, 29, 31, 32).
pub const NOT_MAPPABLE: Accepted = Accepted {
    name: "not_mappable",
    codes: &[abort::OBJECT_NOT_MAPPABLE, abort::OBJECT_DOES_NOT_EXIST],
    source: CCT_MAPPING,
};
/// A value CiA 301 does not allow for a parameter (reserved transmission types, restricted CAN-IDs,
/// a CAN-ID changed while valid, SYNC counter overflow 1 or above 240).
pub const INVALID_VALUE: Accepted = Accepted {
    name: "invalid_value",
    codes: &[abort::INVALID_VALUE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// A value out of range, with either of CiA 301's codes for it.
pub const OUT_OF_RANGE: Accepted = Accepted {
    name: "out_of_range",
    codes: &[
        abort::INVALID_VALUE,
        abort::VALUE_TOO_HIGH,
        abort::VALUE_TOO_LOW,
        abort::GENERAL_ERROR,
    ],
    source: CIA_TABLE,
};
/// 1019h written while 1006h is not 0 (CCT SYNC 09).
pub const DEVICE_STATE: Accepted = Accepted {
    name: "device_state",
    codes: &[abort::CANNOT_TRANSFER_DEVICE_STATE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// A wrong store or restore signature (CCT Other 01, 03).
pub const WRONG_SIGNATURE: Accepted = Accepted {
    name: "wrong_signature",
    codes: &[abort::CANNOT_TRANSFER, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// Reading 1003h above its number of errors (CCT Emergency 03; CiA 301 as quoted in CANopenNode
/// PR 253).
pub const NO_DATA: Accepted = Accepted {
    name: "no_data",
    codes: &[abort::NO_DATA_AVAILABLE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};
/// Two heartbeat consumer entries for one node (CCT Heartbeat 04).
pub const INCOMPATIBLE: Accepted = Accepted {
    name: "incompatible",
    codes: &[abort::PARAMETER_INCOMPATIBLE, abort::GENERAL_ERROR],
    source: CIA_TABLE,
};

/// Every abort set, by the name models give it.
pub const ABORT_SETS: &[Accepted] = &[
    WRITE_READ_ONLY,
    READ_WRITE_ONLY,
    NO_SUB_INDEX,
    NO_OBJECT,
    BAD_COMMAND,
    TOO_LONG,
    TOO_SHORT,
    TOO_HIGH,
    TOO_LOW,
    TOGGLE,
    TIMED_OUT,
    BLOCK_SIZE,
    SEQUENCE_NUMBER,
    CRC,
    NO_BLOCK_TRANSFER,
    MAPPING_SEQUENCE,
    MAPPING_LENGTH,
    NOT_MAPPABLE,
    INVALID_VALUE,
    OUT_OF_RANGE,
    DEVICE_STATE,
    WRONG_SIGNATURE,
    NO_DATA,
    INCOMPATIBLE,
];

/// The command specifiers of an expedited upload response (CiA 301 §7.2.4.3.6) for an entry of
/// `size` bytes (1..=4): with the size indicated (`s = 1`, `n = 4 - size`: 4Fh, 4Bh, 47h, 43h) or
/// without (`s = 0`: 42h, which CiA 301 allows for any expedited upload). `None` for other sizes.
pub fn expedited_upload_commands(size: usize) -> Option<[u8; 2]> {
    let n = 4usize.checked_sub(size).filter(|_| size >= 1)?;
    Some([0x43 | ((n as u8) << 2), EXPEDITED_UPLOAD_UNSIZED])
}

/// The expedited upload response without size indication (`e = 1, s = 0`).
pub const EXPEDITED_UPLOAD_UNSIZED: u8 = 0x42;

/// A set of answers a model names: `accepted(expedited_upload_4)` for the command byte of the
/// answer to an upload of a 4-byte entry, `accepted(no_object)` for an abort code.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NamedSet {
    /// The name in models.
    pub name: &'static str,
    /// The values.
    pub values: Vec<u32>,
    /// What the set is.
    pub meaning: String,
}

/// Every set a model may name: the abort sets, and `expedited_upload_1` .. `expedited_upload_4`
/// (the command specifiers of an expedited upload answer for an entry of that many bytes).
pub fn named_sets() -> Vec<NamedSet> {
    let mut sets: Vec<NamedSet> = ABORT_SETS
        .iter()
        .map(|a| NamedSet {
            name: a.name,
            values: a.codes.to_vec(),
            meaning: format!("abort codes {} ({})", a.list(), a.source),
        })
        .collect();
    const UPLOADS: [&str; 4] = [
        "expedited_upload_1",
        "expedited_upload_2",
        "expedited_upload_3",
        "expedited_upload_4",
    ];
    for (i, name) in UPLOADS.iter().enumerate() {
        let commands = expedited_upload_commands(i + 1).unwrap_or_default();
        sets.push(NamedSet {
            name,
            values: commands.iter().map(|c| u32::from(*c)).collect(),
            meaning: format!(
                "expedited upload answer of {} byte(s): {:02X}h (size indicated) or {:02X}h (size not indicated)",
                i + 1,
                commands[0],
                commands[1]
            ),
        });
    }
    sets
}

/// The set a model names `name`.
pub fn named_set(name: &str) -> Option<NamedSet> {
    named_sets().into_iter().find(|s| s.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_read_as_cia_301_writes_them() {
        assert_eq!(code_text(0x0609_0031), "0609 0031h");
        assert_eq!(TOO_HIGH.list(), "0609 0031h, 0609 0030h or 0800 0000h");
        assert!(NO_BLOCK_TRANSFER.accepts(0x0504_0001) && !NO_BLOCK_TRANSFER.accepts(0x0800_0000));
        assert!(code_meaning(0x0602_0000).contains("does not exist"));
    }

    #[test]
    fn every_set_has_a_unique_name_and_a_code_of_the_table() {
        let sets = named_sets();
        for (i, s) in sets.iter().enumerate() {
            assert!(sets[..i].iter().all(|o| o.name != s.name), "{} twice", s.name);
            assert!(!s.values.is_empty(), "{}", s.name);
        }
        for a in ABORT_SETS {
            for code in a.codes {
                assert!(
                    abort::abort_code_text(*code).is_some(),
                    "{} has {code:#X}",
                    a.name
                );
            }
        }
    }

    /// The two answers the issue found the model and the suite disagreeing on.
    #[test]
    fn a_write_to_a_read_only_entry_and_an_unsized_upload_are_accepted() {
        let write = named_set("write_read_only").unwrap();
        assert_eq!(write.values, [0x0601_0002, 0x0601_0000, 0x0800_0000]);
        assert_eq!(named_set("expedited_upload_4").unwrap().values, [0x43, 0x42]);
        assert_eq!(named_set("expedited_upload_1").unwrap().values, [0x4F, 0x42]);
        assert_eq!(expedited_upload_commands(2), Some([0x4B, 0x42]));
        assert_eq!(expedited_upload_commands(0), None);
        assert_eq!(expedited_upload_commands(5), None);
    }
}
