//! A sans-IO codec for the socketcand protocol, byte-exact with what python-can speaks.
//!
//! socketcand (linux-can/socketcand, `doc/protocol.md`) carries CAN frames over TCP as ASCII
//! elements such as `< send 601 8 40 00 10 00 00 00 00 00 >` and `< frame 581 1.000000 4300 >`.
//! This crate splits a byte stream into elements, parses client commands and server messages, and
//! writes both directions. It performs no IO, spawns nothing and reads no clock: timestamps are
//! passed in. The socketcand client transport and the canopener hub drive it.
//!
//! Main items:
//! - [`ElementReader`]: bytes in, complete `< … >` elements out, with a length limit and resync.
//! - [`parse_client_command`] → [`ClientCommand`] and [`parse_server_message`] → [`ServerMessage`].
//! - Writers: [`write_send`], [`write_open`], [`write_rawmode`], … for clients; [`write_hi`],
//!   [`write_ok`], [`write_frame`], … for servers.
//!
//! The python-can traps this codec is built around (interop reference §3): server frame ids are
//! always 3 or 8 digits, frame data is contiguous uppercase hex, an empty frame keeps the space
//! before `>`, and python-can's remote frames arrive as `< send ID n  >` with no bytes.
//!
//! A client's receive loop:
//!
//! ```
//! use canopener_socketcand::{ElementReader, ServerMessage, parse_server_message, write_rawmode};
//!
//! let mut reader = ElementReader::new(canopener_socketcand::DEFAULT_MAX_ELEMENT_LEN);
//! let mut received = Vec::new();
//! // Bytes as a TCP read might return them: an element split across two reads.
//! for chunk in [&b"< ok >< frame 181 1700000000.000"[..], &b"100 0102 >"[..]] {
//!     reader.push(chunk);
//!     while let Some(element) = reader.next_element() {
//!         match parse_server_message(&element?)? {
//!             ServerMessage::Frame { frame, timestamp } => received.push((frame, timestamp)),
//!             other => println!("control message {other:?}"),
//!         }
//!     }
//! }
//! assert_eq!(received.len(), 1);
//! assert_eq!(received[0].0.data(), &[1, 2]);
//!
//! let mut out = Vec::new();
//! write_rawmode(&mut out);
//! assert_eq!(out, b"< rawmode >");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does); each exception names, where it stands, why it cannot fail.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod client;
mod element;
mod error;
mod fields;
mod server;

pub use client::{
    ClientCommand, parse_client_command, write_bcmmode, write_client_command, write_controlmode, write_echo,
    write_isotpmode, write_open, write_rawmode, write_send,
};
pub use element::{DEFAULT_MAX_ELEMENT_LEN, ElementReader, FramingError, MIN_ELEMENT_LEN};
pub use error::CommandError;
pub use fields::is_valid_bus_name;
pub use server::{
    ServerMessage, parse_server_message, write_error, write_error_frame, write_frame, write_hi, write_ok,
    write_server_message,
};

/// The TCP port socketcand and python-can use by default.
pub const DEFAULT_PORT: u16 = 29536;
