//! The CRC of SDO block transfers (CiA 301 §7.2.4.3.16).
//!
//! CRC-16-CCITT as CiA 301 uses it: polynomial x^16 + x^12 + x^5 + 1 (1021h), initial value 0,
//! most significant bit first, no final XOR (the variant also known as CRC-16/XMODEM). It covers the
//! payload bytes only, not the padding of the last segment.

/// The CRC of `data`.
pub fn crc16_ccitt(data: &[u8]) -> u16 {
    crc16_ccitt_update(0, data)
}

/// Continues a CRC over more data: `crc16_ccitt_update(crc16_ccitt(a), b) == crc16_ccitt(a ++ b)`.
pub fn crc16_ccitt_update(mut crc: u16, data: &[u8]) -> u16 {
    for &byte in data {
        crc ^= u16::from(byte) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn check_value_of_the_cia_variant() {
        assert_eq!(crc16_ccitt(b"123456789"), 0x31C3);
        assert_eq!(crc16_ccitt(b""), 0);
    }

    #[test]
    fn matches_a_conformance_test_block_upload() {
        // CiA CCT "SDO 23": block upload of 1008h "CANopenDemoPIC32" ends with CRC 43F3h.
        assert_eq!(crc16_ccitt(b"CANopenDemoPIC32"), 0x43F3);
    }

    proptest! {
        #[test]
        fn update_is_concatenation(a: Vec<u8>, b: Vec<u8>) {
            let joined: Vec<u8> = a.iter().chain(&b).copied().collect();
            prop_assert_eq!(crc16_ccitt_update(crc16_ccitt(&a), &b), crc16_ccitt(&joined));
        }
    }
}
