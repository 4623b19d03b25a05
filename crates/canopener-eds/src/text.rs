//! Byte ↔ text decoding that can be undone exactly.
//!
//! CiA 306 §4.2 requires ISO 646 (ASCII), but real files carry UTF-8 (with and without a byte order
//! mark) and Windows-1252 bytes such as `°`. We decode UTF-8 when the bytes are valid UTF-8 and fall
//! back to Windows-1252 otherwise. The five bytes Windows-1252 leaves undefined (0x81, 0x8D, 0x8F,
//! 0x90, 0x9D) map to the C1 control characters of the same value, as the WHATWG encoding standard
//! does, so every byte sequence decodes and encodes back to the identical bytes.

use serde::{Deserialize, Serialize};

/// How the bytes of a file were turned into text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Encoding {
    /// UTF-8 without a byte order mark (plain ASCII files are reported as this).
    Utf8,
    /// UTF-8 starting with the byte order mark EF BB BF.
    Utf8Bom,
    /// Not valid UTF-8; decoded as Windows-1252 (a superset of ISO 8859-1 for printable bytes).
    Windows1252,
}

/// The characters Windows-1252 assigns to bytes 0x80..=0x9F (undefined bytes map to C1 controls).
const CP1252_HIGH: [char; 32] = [
    '\u{20AC}', '\u{0081}', '\u{201A}', '\u{0192}', '\u{201E}', '\u{2026}', '\u{2020}', '\u{2021}',
    '\u{02C6}', '\u{2030}', '\u{0160}', '\u{2039}', '\u{0152}', '\u{008D}', '\u{017D}', '\u{008F}',
    '\u{0090}', '\u{2018}', '\u{2019}', '\u{201C}', '\u{201D}', '\u{2022}', '\u{2013}', '\u{2014}',
    '\u{02DC}', '\u{2122}', '\u{0161}', '\u{203A}', '\u{0153}', '\u{009D}', '\u{017E}', '\u{0178}',
];

const BOM: &[u8] = b"\xEF\xBB\xBF";

/// Decodes file bytes, returning the text (without a byte order mark) and the encoding used.
pub fn decode(bytes: &[u8]) -> (String, Encoding) {
    let (body, bom) = match bytes.strip_prefix(BOM) {
        Some(rest) => (rest, true),
        None => (bytes, false),
    };
    match std::str::from_utf8(body) {
        Ok(text) => (
            text.to_owned(),
            if bom { Encoding::Utf8Bom } else { Encoding::Utf8 },
        ),
        // A BOM followed by invalid UTF-8 is not UTF-8 at all: decode every byte, BOM included.
        Err(_) => (
            bytes.iter().map(|&b| cp1252_char(b)).collect(),
            Encoding::Windows1252,
        ),
    }
}

/// Encodes text back into bytes in `encoding`.
///
/// Fails with the first character Windows-1252 cannot represent (only possible after an edit).
pub fn encode(text: &str, encoding: Encoding) -> Result<Vec<u8>, Unencodable> {
    match encoding {
        Encoding::Utf8 => Ok(text.as_bytes().to_vec()),
        Encoding::Utf8Bom => {
            let mut out = Vec::with_capacity(text.len() + BOM.len());
            out.extend_from_slice(BOM);
            out.extend_from_slice(text.as_bytes());
            Ok(out)
        }
        Encoding::Windows1252 => text
            .chars()
            .map(|c| cp1252_byte(c).ok_or(Unencodable { character: c }))
            .collect(),
    }
}

/// A character that the file's encoding cannot hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error(
    "character {character:?} (U+{:04X}) cannot be written in Windows-1252; convert the file to UTF-8 first",
    u32::from(*character)
)]
pub struct Unencodable {
    /// The offending character.
    pub character: char,
}

fn cp1252_char(byte: u8) -> char {
    match byte {
        #[allow(
            clippy::indexing_slicing,
            reason = "0x80..=0x9F less 0x80 indexes the table's 32 entries"
        )]
        0x80..=0x9F => CP1252_HIGH[usize::from(byte - 0x80)],
        _ => char::from(byte),
    }
}

fn cp1252_byte(c: char) -> Option<u8> {
    let code = u32::from(c);
    if code < 0x80 || (0xA0..=0xFF).contains(&code) {
        return u8::try_from(code).ok();
    }
    CP1252_HIGH
        .iter()
        .position(|&h| h == c)
        .and_then(|i| u8::try_from(0x80 + i).ok())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn utf8_with_and_without_bom() {
        assert_eq!(decode(b"[a]\n"), ("[a]\n".to_owned(), Encoding::Utf8));
        assert_eq!(
            decode(b"\xEF\xBB\xBF[a]\n"),
            ("[a]\n".to_owned(), Encoding::Utf8Bom)
        );
        assert_eq!(encode("[a]\n", Encoding::Utf8Bom).unwrap(), b"\xEF\xBB\xBF[a]\n");
    }

    #[test]
    fn latin1_degree_sign_and_euro() {
        let (text, enc) = decode(b"Unit=\xB0C \x80");
        assert_eq!(enc, Encoding::Windows1252);
        assert_eq!(text, "Unit=°C €");
        assert_eq!(encode(&text, enc).unwrap(), b"Unit=\xB0C \x80");
    }

    #[test]
    fn unencodable_character_is_reported() {
        let err = encode("ok 中", Encoding::Windows1252).unwrap_err();
        assert_eq!(err.character, '中');
        assert!(err.to_string().contains("U+4E2D"));
    }

    proptest! {
        #[test]
        fn every_byte_sequence_round_trips(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
            let (text, enc) = decode(&bytes);
            prop_assert_eq!(encode(&text, enc).unwrap(), bytes);
        }
    }
}
