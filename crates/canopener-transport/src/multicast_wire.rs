//! python-can's `udp_multicast` datagram format, without sockets.
//!
//! The format is defined only by python-can's `can/interfaces/udp_multicast/utils.py`
//! (`pack_message` / `unpack_message`): one UDP datagram carries one CAN message as one msgpack map
//! with eleven keys, written in a fixed order. python-can decodes with `Message(check=True, **map)`,
//! so a peer dies on unknown keys, on `dlc != len(data)` and on a missing `is_extended_id` (which
//! defaults to extended). We therefore always write all eleven keys exactly as python-can does, and
//! decode leniently, skipping (never panicking on) anything python-can would reject.

use canopener_can::{CanFrame, CanId, Instant};
use serde::{Deserialize, Deserializer, Serialize};

/// The largest datagram python-can reads; ours are at most 170 bytes.
pub const MAX_DATAGRAM_LEN: usize = 4096;

/// The message map in python-can's key order. Field order is the wire order.
#[derive(Serialize)]
struct OutgoingMessage<'a> {
    timestamp: f64,
    arbitration_id: u32,
    is_extended_id: bool,
    is_remote_frame: bool,
    is_error_frame: bool,
    channel: Option<&'a str>,
    dlc: u8,
    #[serde(with = "serde_bytes")]
    data: &'a [u8],
    is_fd: bool,
    bitrate_switch: bool,
    error_state_indicator: bool,
}

/// The keys we act on. Unknown keys, `timestamp` and `channel` are ignored; missing keys take
/// python-can's `Message` defaults.
#[derive(Deserialize)]
#[serde(default)]
struct IncomingMessage {
    arbitration_id: u64,
    #[serde(deserialize_with = "truthy")]
    is_extended_id: bool,
    #[serde(deserialize_with = "truthy")]
    is_remote_frame: bool,
    #[serde(deserialize_with = "truthy")]
    is_error_frame: bool,
    dlc: Option<u64>,
    #[serde(deserialize_with = "payload")]
    data: Option<Vec<u8>>,
    #[serde(deserialize_with = "truthy")]
    is_fd: bool,
}

impl Default for IncomingMessage {
    fn default() -> IncomingMessage {
        IncomingMessage {
            arbitration_id: 0,
            // python-can's `Message.__init__` default, which is why senders must always write it.
            is_extended_id: true,
            is_remote_frame: false,
            is_error_frame: false,
            dlc: None,
            data: None,
            is_fd: false,
        }
    }
}

/// Why a datagram did not yield a classical CAN frame.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    /// The datagram is not a msgpack map of the expected shape.
    #[error("not a python-can udp_multicast message: {0}")]
    Malformed(String),
    /// The message is an error frame, which carries no CAN frame.
    #[error("error frame (not a data or remote frame)")]
    ErrorFrame,
    /// The message is a CAN FD frame; canopener transports classical frames only.
    #[error("CAN FD frame (only classical CAN frames are supported)")]
    FdFrame,
    /// The identifier does not fit its format.
    #[error("arbitration id {id:#X} does not fit a {format} identifier")]
    BadId {
        /// The raw identifier.
        id: u64,
        /// `standard` or `extended`.
        format: &'static str,
    },
    /// The DLC or the data length is invalid for a classical frame.
    #[error("dlc {dlc} with {data_len} data bytes is not a valid classical CAN frame")]
    BadLength {
        /// The DLC field (or the data length when it was missing).
        dlc: u64,
        /// The number of data bytes.
        data_len: usize,
    },
}

/// Encodes `frame` as python-can does, with `timestamp` as the sender's time.
///
/// The result is a msgpack map with eleven keys; `dlc == len(data)` for data frames, remote
/// frames carry empty data and `dlc` = the requested length.
pub fn encode(frame: &CanFrame, timestamp: Instant) -> Vec<u8> {
    let message = OutgoingMessage {
        timestamp: instant_as_secs_f64(timestamp),
        arbitration_id: frame.id().as_raw(),
        is_extended_id: frame.id().is_extended(),
        is_remote_frame: frame.is_remote(),
        is_error_frame: false,
        channel: None,
        dlc: frame.dlc(),
        data: frame.data(),
        is_fd: false,
        bitrate_switch: false,
        error_state_indicator: false,
    };
    // Serialising a struct of plain numbers, bools and bytes into a Vec cannot fail: rmp-serde
    // only errors on IO failure (a Vec never fails) or on types msgpack cannot express.
    rmp_serde::to_vec_named(&message).unwrap_or_default()
}

/// Decodes one datagram into a classical CAN frame.
pub fn decode(datagram: &[u8]) -> Result<CanFrame, DecodeError> {
    let message: IncomingMessage =
        rmp_serde::from_slice(datagram).map_err(|err| DecodeError::Malformed(err.to_string()))?;
    if message.is_error_frame {
        return Err(DecodeError::ErrorFrame);
    }
    if message.is_fd {
        return Err(DecodeError::FdFrame);
    }
    let id = to_can_id(message.arbitration_id, message.is_extended_id)?;
    let data = message.data.unwrap_or_default();
    if message.is_remote_frame {
        // python-can: a remote frame has no data and `dlc` is the requested length; without
        // a `dlc` key `Message` uses `len(data)`, which is 0.
        let dlc = message.dlc.unwrap_or(0);
        let bad_length = DecodeError::BadLength {
            dlc,
            data_len: data.len(),
        };
        if !data.is_empty() {
            return Err(bad_length);
        }
        let dlc = u8::try_from(dlc).map_err(|_| bad_length.clone())?;
        return CanFrame::remote(id, dlc).map_err(|_| bad_length);
    }
    let data_len = data.len();
    let dlc = message.dlc.unwrap_or(data_len as u64);
    let bad_length = DecodeError::BadLength { dlc, data_len };
    if dlc != data_len as u64 {
        return Err(bad_length);
    }
    CanFrame::new(id, &data).map_err(|_| bad_length)
}

fn to_can_id(raw: u64, extended: bool) -> Result<CanId, DecodeError> {
    let format = if extended { "extended" } else { "standard" };
    let bad_id = DecodeError::BadId { id: raw, format };
    let raw = u32::try_from(raw).map_err(|_| bad_id.clone())?;
    if extended {
        CanId::extended(raw).map_err(|_| bad_id)
    } else {
        let raw = u16::try_from(raw).map_err(|_| bad_id.clone())?;
        CanId::standard(raw).map_err(|_| bad_id)
    }
}

fn instant_as_secs_f64(instant: Instant) -> f64 {
    instant.secs() as f64 + f64::from(instant.subsec_nanos()) / 1e9
}

/// Python truthiness for the flag fields: python-can passes them straight to `Message`, which
/// only tests them with `if`, so `1`, `0` and `None` work there and must work here.
fn truthy<'de, D: Deserializer<'de>>(deserializer: D) -> Result<bool, D::Error> {
    struct Truthy;
    impl serde::de::Visitor<'_> for Truthy {
        type Value = bool;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("a bool, an integer or nil")
        }
        fn visit_bool<E>(self, v: bool) -> Result<bool, E> {
            Ok(v)
        }
        fn visit_i64<E>(self, v: i64) -> Result<bool, E> {
            Ok(v != 0)
        }
        fn visit_u64<E>(self, v: u64) -> Result<bool, E> {
            Ok(v != 0)
        }
        fn visit_f64<E>(self, v: f64) -> Result<bool, E> {
            Ok(v != 0.0)
        }
        fn visit_unit<E>(self) -> Result<bool, E> {
            Ok(false)
        }
        fn visit_none<E>(self) -> Result<bool, E> {
            Ok(false)
        }
    }
    deserializer.deserialize_any(Truthy)
}

/// `data` as python-can accepts it: msgpack bin (what it writes) or an array of small integers
/// (what serde writes for a plain `Vec<u8>`). A string is rejected, as `bytearray(str)` fails there.
fn payload<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<Vec<u8>>, D::Error> {
    struct Payload;
    impl<'de> serde::de::Visitor<'de> for Payload {
        type Value = Option<Vec<u8>>;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("binary data or an array of byte values")
        }
        fn visit_bytes<E>(self, v: &[u8]) -> Result<Self::Value, E> {
            Ok(Some(v.to_vec()))
        }
        fn visit_byte_buf<E>(self, v: Vec<u8>) -> Result<Self::Value, E> {
            Ok(Some(v))
        }
        fn visit_unit<E>(self) -> Result<Self::Value, E> {
            Ok(None)
        }
        fn visit_none<E>(self) -> Result<Self::Value, E> {
            Ok(None)
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut bytes = Vec::new();
            // Bounded by the datagram: each element takes at least one byte of it.
            while let Some(byte) = seq.next_element::<u8>()? {
                bytes.push(byte);
            }
            Ok(Some(bytes))
        }
    }
    deserializer.deserialize_any(Payload)
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::strategy::any_frame;
    use canopener_can::{ExtendedId, StandardId};
    use proptest::prelude::*;
    use serde::Serialize;

    fn sid(raw: u16) -> StandardId {
        StandardId::new(raw).unwrap()
    }

    /// A msgpack value for hand-built test maps; untagged, so each variant encodes as its content.
    #[derive(Serialize, Clone)]
    #[serde(untagged)]
    enum V {
        Bool(bool),
        Int(i64),
        F32(f32),
        Str(&'static str),
        Bin(#[serde(with = "serde_bytes")] Vec<u8>),
        Array(Vec<u8>),
    }

    /// Builds msgpack maps for the tolerance tests from (key, value) pairs, in the given order.
    fn map(entries: &[(&str, V)]) -> Vec<u8> {
        struct Entries<'a>(&'a [(&'a str, V)]);
        impl Serialize for Entries<'_> {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.collect_map(self.0.iter().map(|(k, v)| (k, v)))
            }
        }
        rmp_serde::to_vec_named(&Entries(entries)).unwrap()
    }

    /// `needle` occurs in `haystack` as a contiguous byte string.
    fn contains(haystack: &[u8], needle: &[u8]) -> bool {
        haystack.windows(needle.len()).any(|w| w == needle)
    }

    /// The 162-byte example of the interop reference §2, produced by python-can 4.6.1.
    fn python_can_example() -> Vec<u8> {
        let mut expected = vec![0x8b];
        let mut key = |name: &str| {
            expected.push(0xa0 | name.len() as u8);
            expected.extend_from_slice(name.as_bytes());
        };
        key("timestamp");
        let mut tail: Vec<u8> = vec![0xcb, 0x41, 0xd9, 0x54, 0xfc, 0x40, 0x20, 0x00, 0x00];
        expected.append(&mut tail);
        let mut push = |name: &str, value: &[u8]| {
            expected.push(0xa0 | name.len() as u8);
            expected.extend_from_slice(name.as_bytes());
            expected.extend_from_slice(value);
        };
        push("arbitration_id", &[0xcd, 0x06, 0x01]);
        push("is_extended_id", &[0xc2]);
        push("is_remote_frame", &[0xc2]);
        push("is_error_frame", &[0xc2]);
        push("channel", &[0xc0]);
        push("dlc", &[0x08]);
        push(
            "data",
            &[0xc4, 0x08, 0x40, 0x00, 0x10, 0x00, 0x00, 0x00, 0x00, 0x00],
        );
        push("is_fd", &[0xc2]);
        push("bitrate_switch", &[0xc2]);
        push("error_state_indicator", &[0xc2]);
        expected
    }

    #[test]
    fn encoding_is_byte_identical_to_python_can() {
        let frame = CanFrame::new(sid(0x601), &[0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]).unwrap();
        let bytes = encode(&frame, Instant::from_millis(1_700_000_000_500));
        let expected = python_can_example();
        assert_eq!(expected.len(), 162);
        assert_eq!(bytes, expected);
    }

    #[test]
    fn remote_frame_has_empty_data_and_requested_dlc() {
        let frame = CanFrame::remote(sid(0x701), 1).unwrap();
        let bytes = encode(&frame, Instant::ZERO);
        assert!(contains(&bytes, b"\xafis_remote_frame\xc3"));
        assert!(contains(&bytes, b"\xa3dlc\x01\xa4data\xc4\x00"));
        assert_eq!(decode(&encode(&frame, Instant::ZERO)), Ok(frame));
    }

    #[test]
    fn extended_id_is_always_written() {
        let frame = CanFrame::new(ExtendedId::new(0x1AAA_AAAA).unwrap(), &[1, 0xF1]).unwrap();
        let bytes = encode(&frame, Instant::ZERO);
        assert!(contains(
            &bytes,
            b"\xaearbitration_id\xce\x1a\xaa\xaa\xaa\xaeis_extended_id\xc3"
        ));
        assert!(contains(&bytes, b"\xa3dlc\x02\xa4data\xc4\x02\x01\xf1"));
        let standard = encode(&CanFrame::new(sid(0x7FF), &[]).unwrap(), Instant::ZERO);
        assert!(contains(&standard, b"\xaeis_extended_id\xc2"));
        assert_eq!(decode(&encode(&frame, Instant::ZERO)), Ok(frame));
    }

    #[test]
    fn minimal_map_decodes_with_python_can_defaults() {
        let bytes = map(&[
            ("arbitration_id", V::Int(0x181)),
            ("is_extended_id", V::Bool(false)),
            ("data", V::Bin(vec![1, 2])),
        ]);
        assert_eq!(decode(&bytes), Ok(CanFrame::new(sid(0x181), &[1, 2]).unwrap()));
    }

    #[test]
    fn missing_is_extended_id_means_extended_like_python_can() {
        let bytes = map(&[("arbitration_id", V::Int(0x181)), ("data", V::Bin(vec![]))]);
        let frame = decode(&bytes).unwrap();
        assert_eq!(frame.id(), CanId::extended(0x181).unwrap());
    }

    #[test]
    fn data_as_array_of_ints_and_unknown_keys_are_accepted() {
        let bytes = map(&[
            ("arbitration_id", V::Int(0x601)),
            ("is_extended_id", V::Int(0)),
            ("data", V::Array(vec![0x40, 0x00, 0x10])),
            ("is_rx", V::Bool(true)),
            ("something_else", V::Str("x")),
            ("timestamp", V::F32(1.5)),
        ]);
        assert_eq!(
            decode(&bytes),
            Ok(CanFrame::new(sid(0x601), &[0x40, 0x00, 0x10]).unwrap())
        );
    }

    #[test]
    fn invalid_messages_are_rejected_not_panicked_on() {
        type Expectation = fn(&DecodeError) -> bool;
        let cases: Vec<(Vec<u8>, Expectation)> = vec![
            (vec![], |e| matches!(e, DecodeError::Malformed(_))),
            (vec![0xc1], |e| matches!(e, DecodeError::Malformed(_))),
            (b"hello".to_vec(), |e| matches!(e, DecodeError::Malformed(_))),
            (map(&[("data", V::Str("text"))]), |e| {
                matches!(e, DecodeError::Malformed(_))
            }),
            (
                map(&[
                    ("arbitration_id", V::Int(0x800)),
                    ("is_extended_id", V::Bool(false)),
                ]),
                |e| {
                    matches!(
                        e,
                        DecodeError::BadId {
                            id: 0x800,
                            format: "standard"
                        }
                    )
                },
            ),
            (map(&[("arbitration_id", V::Int(0x2000_0000))]), |e| {
                matches!(e, DecodeError::BadId { .. })
            }),
            (map(&[("arbitration_id", V::Int(-1))]), |e| {
                matches!(e, DecodeError::Malformed(_))
            }),
            (map(&[("dlc", V::Int(3)), ("data", V::Bin(vec![1]))]), |e| {
                matches!(e, DecodeError::BadLength { dlc: 3, data_len: 1 })
            }),
            (map(&[("data", V::Bin(vec![0; 9]))]), |e| {
                matches!(e, DecodeError::BadLength { .. })
            }),
            (
                map(&[("is_remote_frame", V::Bool(true)), ("dlc", V::Int(9))]),
                |e| matches!(e, DecodeError::BadLength { dlc: 9, .. }),
            ),
            (
                map(&[("is_remote_frame", V::Bool(true)), ("data", V::Bin(vec![1]))]),
                |e| matches!(e, DecodeError::BadLength { .. }),
            ),
            (map(&[("is_error_frame", V::Bool(true))]), |e| {
                *e == DecodeError::ErrorFrame
            }),
            (
                map(&[
                    ("is_fd", V::Bool(true)),
                    ("dlc", V::Int(12)),
                    ("data", V::Bin(vec![0; 12])),
                ]),
                |e| *e == DecodeError::FdFrame,
            ),
        ];
        for (bytes, expected) in cases {
            let result = decode(&bytes);
            assert!(
                matches!(&result, Err(e) if expected(e)),
                "{bytes:02x?} gave {result:?}"
            );
        }
    }

    #[test]
    fn serde_array_form_is_rejected() {
        #[derive(Serialize)]
        struct Positional {
            arbitration_id: u32,
            data: Vec<u8>,
        }
        let bytes = rmp_serde::to_vec(&Positional {
            arbitration_id: 1,
            data: vec![],
        })
        .unwrap();
        assert!(matches!(decode(&bytes), Err(DecodeError::Malformed(_))));
    }

    proptest! {
        #[test]
        fn encode_decode_round_trips(frame in any_frame(), nanos in any::<u64>()) {
            let bytes = encode(&frame, Instant::from_nanos(nanos));
            prop_assert!(bytes.len() <= MAX_DATAGRAM_LEN);
            prop_assert_eq!(decode(&bytes), Ok(frame));
        }

        #[test]
        fn decode_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
            let _ = decode(&bytes);
        }

        #[test]
        fn decode_never_panics_on_mutated_valid_messages(
            frame in any_frame(), flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..6)
        ) {
            let mut bytes = encode(&frame, Instant::ZERO);
            for (pos, value) in flips {
                let len = bytes.len();
                bytes[pos % len] = value;
            }
            if let Ok(decoded) = decode(&bytes) {
                prop_assert!(decoded.dlc() <= 8);
            }
        }
    }
}
