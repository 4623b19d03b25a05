//! Access types of object dictionary entries (CiA 306-1 §4.6.3.2 `AccessType`).
//!
//! The PDO direction rules follow lely-core's access bit model (`CO_ACCESS_*` in `co/obj.h`):
//! `rwr` is read/write "on process input", mappable into a TPDO only; `rww` is read/write "on
//! process output", mappable into an RPDO only.

use std::fmt;
use std::str::FromStr;

/// Who may read and write an entry, and in which PDO direction it may be mapped.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Access {
    /// Read only (`ro`); the device itself may still change the value.
    Ro,
    /// Write only (`wo`).
    Wo,
    /// Read and write (`rw`).
    Rw,
    /// Read and write, on process input (`rwr`): the value flows from the device to the bus.
    Rwr,
    /// Read and write, on process output (`rww`): the value flows from the bus to the device.
    Rww,
    /// Read only and constant (`const`): the value never changes.
    Const,
}

/// A string that is not one of the six CiA 306 access type tokens.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("access type `{text}` is not one of ro, wo, rw, rwr, rww, const (CiA 306-1 §4.6.3.2)")]
pub struct ParseAccessError {
    /// The text that was given.
    pub text: String,
}

impl Access {
    /// All six access types, in the order CiA 306 lists them.
    pub const ALL: [Access; 6] = [
        Access::Ro,
        Access::Wo,
        Access::Rw,
        Access::Rwr,
        Access::Rww,
        Access::Const,
    ];

    /// Whether an SDO upload may read the entry.
    pub const fn readable(self) -> bool {
        !matches!(self, Access::Wo)
    }

    /// Whether an SDO download may write the entry.
    pub const fn writable(self) -> bool {
        matches!(self, Access::Wo | Access::Rw | Access::Rwr | Access::Rww)
    }

    /// Whether the access type allows mapping into a transmit PDO (if the entry's `PDOMapping` is set).
    pub const fn tpdo_mappable(self) -> bool {
        matches!(self, Access::Ro | Access::Rw | Access::Rwr | Access::Const)
    }

    /// Whether the access type allows mapping into a receive PDO (if the entry's `PDOMapping` is set).
    pub const fn rpdo_mappable(self) -> bool {
        matches!(self, Access::Wo | Access::Rw | Access::Rww)
    }

    /// The lowercase token an EDS writes, e.g. `"rwr"`.
    pub const fn as_str(self) -> &'static str {
        match self {
            Access::Ro => "ro",
            Access::Wo => "wo",
            Access::Rw => "rw",
            Access::Rwr => "rwr",
            Access::Rww => "rww",
            Access::Const => "const",
        }
    }
}

impl fmt::Display for Access {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Access {
    /// Reads a CiA 306 token case-insensitively; `None` for anything else.
    pub fn parse(text: &str) -> Option<Access> {
        text.parse().ok()
    }
}

impl FromStr for Access {
    type Err = ParseAccessError;

    /// Reads a token case-insensitively, since real EDS files write `RO`, `Rw` and `CONST` too.
    fn from_str(text: &str) -> Result<Access, ParseAccessError> {
        Access::ALL
            .into_iter()
            .find(|access| access.as_str().eq_ignore_ascii_case(text))
            .ok_or_else(|| ParseAccessError {
                text: text.to_owned(),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_and_write_permissions() {
        let readable: Vec<_> = Access::ALL.into_iter().filter(|a| a.readable()).collect();
        let writable: Vec<_> = Access::ALL.into_iter().filter(|a| a.writable()).collect();
        assert_eq!(
            readable,
            [Access::Ro, Access::Rw, Access::Rwr, Access::Rww, Access::Const]
        );
        assert_eq!(writable, [Access::Wo, Access::Rw, Access::Rwr, Access::Rww]);
    }

    #[test]
    fn pdo_directions_follow_the_lely_bit_model() {
        let tpdo: Vec<_> = Access::ALL.into_iter().filter(|a| a.tpdo_mappable()).collect();
        let rpdo: Vec<_> = Access::ALL.into_iter().filter(|a| a.rpdo_mappable()).collect();
        assert_eq!(tpdo, [Access::Ro, Access::Rw, Access::Rwr, Access::Const]);
        assert_eq!(rpdo, [Access::Wo, Access::Rw, Access::Rww]);
    }

    #[test]
    fn parses_tokens_in_any_case_and_round_trips_display() {
        for access in Access::ALL {
            assert_eq!(access.to_string().parse::<Access>(), Ok(access));
            assert_eq!(access.as_str().to_uppercase().parse::<Access>(), Ok(access));
        }
        assert_eq!("Const".parse::<Access>(), Ok(Access::Const));
    }

    #[test]
    fn rejects_unknown_tokens_with_the_text() {
        let err = "r/w".parse::<Access>().unwrap_err();
        assert_eq!(err.text, "r/w");
        assert!(err.to_string().contains("`r/w`"), "{err}");
        assert!(" ro".parse::<Access>().is_err());
        assert!("".parse::<Access>().is_err());
    }
}
