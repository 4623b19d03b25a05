//! The one error type every transport returns.
//!
//! Each message names the endpoint (the bus spec as the user wrote it, e.g.
//! `socketcand://127.0.0.1:29536/can0`), says what failed and how to fix it.

use std::io;
use std::time::Duration;

use crate::spec::SpecError;

/// Why opening, sending on or receiving from a bus failed.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// The bus spec string is malformed.
    #[error(transparent)]
    Spec(#[from] SpecError),

    /// Neither a `--bus` argument nor the `CANOPENER_BUS` environment variable names a bus.
    #[error(
        "no bus given: pass --bus SPEC or set the CANOPENER_BUS environment variable, \
         e.g. --bus socketcand://127.0.0.1:29536/can0, --bus virtual:demo or \
         --bus udp-multicast://239.74.163.2:43113"
    )]
    NoBusGiven,

    /// The `CANOPENER_BUS` environment variable holds a malformed bus spec.
    #[error("the CANOPENER_BUS environment variable is invalid: {0}")]
    EnvSpec(#[source] SpecError),

    /// The `CANOPENER_BUS` environment variable is not valid Unicode.
    #[error(
        "the CANOPENER_BUS environment variable is not valid UTF-8; set it to a bus spec such as \
         socketcand://127.0.0.1:29536/can0"
    )]
    EnvNotUnicode,

    /// A socket operation failed.
    #[error("{operation} failed for {endpoint}: {source}; {hint}")]
    Io {
        /// The bus spec of the endpoint.
        endpoint: String,
        /// What was being done, e.g. `joining multicast group`.
        operation: &'static str,
        /// What the user can check or change.
        hint: &'static str,
        /// The operating system's error.
        #[source]
        source: io::Error,
    },

    /// The TCP connection to a socketcand server could not be established.
    #[error(
        "could not connect to the socketcand server for {endpoint} after {attempts} attempts: {source}; \
         start one with `canopener bus serve` or check the host and port"
    )]
    Connect {
        /// The bus spec of the endpoint.
        endpoint: String,
        /// How many connection attempts were made.
        attempts: u32,
        /// The error of the last attempt.
        #[source]
        source: io::Error,
    },

    /// The socketcand server answered something unexpected during the handshake.
    #[error(
        "socketcand handshake with {endpoint} failed: expected {expected} but the server sent {got:?}; \
         check that the server speaks socketcand and offers this bus"
    )]
    Handshake {
        /// The bus spec of the endpoint.
        endpoint: String,
        /// The element the client waited for, e.g. `< hi >`.
        expected: &'static str,
        /// What arrived instead (at most a few hundred bytes, lossily decoded).
        got: String,
    },

    /// The socketcand server refused to open the bus.
    #[error(
        "the socketcand server for {endpoint} refused to open bus {bus}: {reason}; check the bus name \
         (a canopener hub opens any valid name, a real socketcand only its configured interfaces)"
    )]
    BusRefused {
        /// The bus spec of the endpoint.
        endpoint: String,
        /// The bus name that was asked for.
        bus: String,
        /// The server's error text.
        reason: String,
    },

    /// The peer closed the connection.
    #[error("the connection for {endpoint} was closed by the server; restart the server and reopen the bus")]
    Closed {
        /// The bus spec of the endpoint.
        endpoint: String,
    },

    /// This kernel has no SocketCAN support (`socket(AF_CAN)` fails).
    #[error(
        "{endpoint} cannot be opened: this kernel has no SocketCAN support (socket(AF_CAN) failed: \
         {source}); run `canopener bus serve` and use --bus socketcand://127.0.0.1:29536/can0, \
         or use --bus udp-multicast://239.74.163.2:43113"
    )]
    SocketCanUnavailable {
        /// The bus spec of the endpoint.
        endpoint: String,
        /// The operating system's error, usually EAFNOSUPPORT.
        #[source]
        source: io::Error,
    },

    /// SocketCAN exists but has no interface of that name.
    #[error("no CAN interface named {interface}; list interfaces with `ip link`")]
    NoSuchInterface {
        /// The interface name that was asked for.
        interface: String,
    },

    /// The receiver did not keep up: its bounded queue was full and frames were lost.
    ///
    /// Returned once per loss; the frames still queued are older than the lost ones.
    #[error(
        "{endpoint} lost {lost} frames because its receive queue was full; call recv more often \
         or read from a dedicated thread"
    )]
    Overrun {
        /// The bus spec of the endpoint.
        endpoint: String,
        /// How many frames were lost since the last report.
        lost: u64,
    },

    /// A frame could not be handed to the medium in time because the transmit queue stayed full.
    #[error(
        "sending on {endpoint} timed out after {waited:?} because the transmit queue stayed full; \
         the bus is saturated by frames with higher priority (lower id)"
    )]
    SendTimeout {
        /// The bus spec of the endpoint.
        endpoint: String,
        /// How long the sender waited.
        waited: Duration,
    },

    /// Two endpoints opened the same virtual bus name with different bitrates.
    #[error(
        "virtual bus {name:?} is already open with {existing} but {requested} was requested; \
         use the same spec for every endpoint of a bus or pick another name"
    )]
    VirtualBusMismatch {
        /// The bus name.
        name: String,
        /// The mode the bus runs in, e.g. `ideal timing` or `bitrate 500k`.
        existing: String,
        /// The mode the new endpoint asked for.
        requested: String,
    },

    /// The spec names a backend that this build or operating system does not provide.
    #[error("{endpoint} is not supported on this operating system: {reason}")]
    Unsupported {
        /// The bus spec of the endpoint.
        endpoint: String,
        /// Why, and what to use instead.
        reason: &'static str,
    },
}

impl TransportError {
    /// An [`TransportError::Io`] for `endpoint`.
    pub(crate) fn io(
        endpoint: impl Into<String>,
        operation: &'static str,
        hint: &'static str,
        source: io::Error,
    ) -> TransportError {
        TransportError::Io {
            endpoint: endpoint.into(),
            operation,
            hint,
            source,
        }
    }
}
