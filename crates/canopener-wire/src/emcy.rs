//! Emergency messages (CiA 301 §7.2.7 EMCY), their error codes and the error register (1001h).
//!
//! Frame layout (CiA 301 §7.2.7.3.1): D0..D1 error code (little-endian), D2 error register, D3..D7
//! manufacturer-specific error field. An EMCY with code 0000h ("error reset") reports that an error
//! went away.

/// The EMCY error codes with a specific CiA 301 text, and the CiA 401 codes that generic I/O devices
/// send, in ascending order of code.
pub const EMCY_CODES: &[(u16, &str)] = &[
    (0x0000, "error reset or no error"),
    (0x2310, "output current too high, overload"),
    (0x2320, "output short circuit"),
    (0x2330, "output load dump"),
    (0x3110, "input voltage too high"),
    (0x3120, "input voltage too low"),
    (0x3210, "internal voltage too high"),
    (0x3220, "internal voltage too low"),
    (0x3310, "output voltage too high"),
    (0x3320, "output voltage too low"),
    (0x8110, "CAN overrun (objects lost)"),
    (0x8120, "CAN in error-passive mode"),
    (0x8130, "life guard error or heartbeat error"),
    (0x8140, "recovered from bus-off"),
    (0x8150, "CAN-ID collision"),
    (0x8210, "PDO not processed due to length error"),
    (0x8220, "PDO length exceeded"),
    (0x8230, "DAM-MPDO not processed, destination object not available"),
    (0x8240, "unexpected SYNC data length"),
    (0x8250, "RPDO timeout"),
];

/// The error-code classes of CiA 301 by upper byte (`code & 0xFF00`), in ascending order.
const EMCY_CLASSES: &[(u16, &str)] = &[
    (0x0000, "error reset or no error"),
    (0x1000, "generic error"),
    (0x2000, "current, generic"),
    (0x2100, "current, device input side"),
    (0x2200, "current inside the device"),
    (0x2300, "current, device output side"),
    (0x3000, "voltage, generic"),
    (0x3100, "mains voltage"),
    (0x3200, "voltage inside the device"),
    (0x3300, "output voltage"),
    (0x4000, "temperature, generic"),
    (0x4100, "ambient temperature"),
    (0x4200, "device temperature"),
    (0x5000, "device hardware"),
    (0x6000, "device software, generic"),
    (0x6100, "internal software"),
    (0x6200, "user software"),
    (0x6300, "data set"),
    (0x7000, "additional modules"),
    (0x8000, "monitoring, generic"),
    (0x8100, "communication, generic"),
    (0x8200, "protocol error, generic"),
    (0x9000, "external error"),
    (0xF000, "additional functions"),
    (0xFF00, "device-specific"),
];

/// The text of an EMCY error code.
///
/// A code with its own entry (such as 8130h) gets that text; otherwise the class of its upper byte
/// (81xxh "communication, generic"), then the class of its upper nibble (2Fxxh "current, generic").
/// Codes in no class (Axxxh to Exxxh) are "reserved error code".
pub fn emcy_code_text(code: u16) -> &'static str {
    lookup(EMCY_CODES, code)
        .or_else(|| lookup(EMCY_CLASSES, code & 0xFF00))
        .or_else(|| lookup(EMCY_CLASSES, code & 0xF000))
        .unwrap_or("reserved error code")
}

fn lookup(table: &[(u16, &'static str)], code: u16) -> Option<&'static str> {
    table
        .iter()
        .find(|(known, _)| *known == code)
        .map(|(_, text)| *text)
}

/// The bits of the error register (CiA 301 object 1001h), bit 0 first.
pub const ERROR_REGISTER_BITS: [&str; 8] = [
    "generic",
    "current",
    "voltage",
    "temperature",
    "communication",
    "device profile",
    "reserved bit 6",
    "manufacturer",
];

/// Error register bit 0: set whenever any error is present.
pub const ERROR_REGISTER_GENERIC: u8 = 0x01;
/// Error register bit 6: reserved, always 0.
pub const ERROR_REGISTER_RESERVED: u8 = 0x40;

/// The names of the bits set in an error register, joined by ", ", e.g. "generic, communication";
/// empty for 0.
pub fn error_register_text(register: u8) -> String {
    ERROR_REGISTER_BITS
        .iter()
        .enumerate()
        .filter(|(bit, _)| register & (1 << bit) != 0)
        .map(|(_, name)| *name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// An emergency message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EmcyMessage {
    /// The error code; 0000h resets an error.
    pub code: u16,
    /// The error register 1001h at the time of the message.
    pub register: u8,
    /// The manufacturer-specific error field, D3..D7.
    pub vendor: [u8; 5],
}

/// Why bytes are not an emergency message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EmcyError {
    /// Fewer than the 3 bytes of error code and error register.
    #[error("an EMCY frame needs at least 3 bytes (error code and error register), got {0}")]
    TooShort(usize),
}

impl EmcyMessage {
    /// Reads an EMCY from frame data. CiA 301 sends 8 bytes; shorter data down to 3 bytes is read
    /// with the missing manufacturer bytes as 0, so a monitor can still show it.
    pub fn parse(data: &[u8]) -> Result<EmcyMessage, EmcyError> {
        let [code_lo, code_hi, register, rest @ ..] = data else {
            return Err(EmcyError::TooShort(data.len()));
        };
        let mut vendor = [0; 5];
        for (slot, byte) in vendor.iter_mut().zip(rest) {
            *slot = *byte;
        }
        Ok(EmcyMessage {
            code: u16::from_le_bytes([*code_lo, *code_hi]),
            register: *register,
            vendor,
        })
    }

    /// The 8 data bytes of the frame.
    pub fn encode(&self) -> [u8; 8] {
        let [code_lo, code_hi] = self.code.to_le_bytes();
        let [v0, v1, v2, v3, v4] = self.vendor;
        [code_lo, code_hi, self.register, v0, v1, v2, v3, v4]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specific_codes_win_over_classes() {
        assert_eq!(emcy_code_text(0x8130), "life guard error or heartbeat error");
        assert_eq!(emcy_code_text(0x2310), "output current too high, overload");
        assert_eq!(emcy_code_text(0x8131), "communication, generic");
        assert_eq!(emcy_code_text(0x2345), "current, device output side");
        assert_eq!(emcy_code_text(0x2F00), "current, generic");
        assert_eq!(emcy_code_text(0x0012), "error reset or no error");
        assert_eq!(emcy_code_text(0xFF42), "device-specific");
        assert_eq!(emcy_code_text(0xF042), "additional functions");
        assert_eq!(emcy_code_text(0xA000), "reserved error code");
        assert_eq!(emcy_code_text(0x5530), "device hardware");
    }

    #[test]
    fn tables_are_sorted() {
        assert!(EMCY_CODES.windows(2).all(|pair| pair[0].0 < pair[1].0));
        assert!(EMCY_CLASSES.windows(2).all(|pair| pair[0].0 < pair[1].0));
    }

    #[test]
    fn error_register_names() {
        assert_eq!(error_register_text(0x11), "generic, communication");
        assert_eq!(error_register_text(0x00), "");
        assert_eq!(error_register_text(0x81), "generic, manufacturer");
    }

    #[test]
    fn parse_and_encode() {
        let data = [0x30, 0x81, 0x11, 1, 2, 3, 4, 5];
        let emcy = EmcyMessage::parse(&data).unwrap();
        assert_eq!(
            emcy,
            EmcyMessage {
                code: 0x8130,
                register: 0x11,
                vendor: [1, 2, 3, 4, 5]
            }
        );
        assert_eq!(emcy.encode(), data);
        assert_eq!(EmcyMessage::parse(&[0, 0]), Err(EmcyError::TooShort(2)));
        assert_eq!(EmcyMessage::parse(&[0x10, 0x82, 0x01]).unwrap().vendor, [0; 5]);
    }
}
