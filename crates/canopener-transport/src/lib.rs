//! CAN bus transports behind one small trait, [`CanBus`], selected by a bus spec string.
//!
//! Architecture invariant: this crate is where IO lives for CAN. It opens sockets, starts threads
//! and reads the wall clock; the protocol crates (frames, CANopen state machines, the simulator
//! engine, the socketcand codec) never depend on it and stay sans-IO. The hub is the only other
//! library crate that does IO.
//!
//! Backends, each selected by a [`BusSpec`] (see [`spec`] for the grammar):
//! - [`VirtualBus`], `virtual:NAME[?bitrate=RATE]`: an in-process bus; ideal (instant) or
//!   bit-accurate in real time, driven by `canopener_bus_engine::BusEngine`.
//! - [`SocketcandBus`], `socketcand://HOST:PORT/BUS`: a client of a socketcand server such as
//!   `canopener bus serve`.
//! - `SocketCanBus`, `socketcan:IFACE`: Linux SocketCAN with kernel receive timestamps (Linux only).
//! - [`UdpMulticastBus`], `udp-multicast://GROUP:PORT`: python-can's serverless `udp_multicast`.
//!
//! Every receive timestamp is an [`Instant`] on the Unix epoch, so timestamps from different
//! backends and processes can be compared and printed as candump times. Blocking calls wait on
//! sockets or condition variables, never by spinning, and every wait is bounded by the caller's
//! timeout.
//!
//! ```
//! use std::time::Duration;
//! use canopener_can::{CanFrame, StandardId};
//! use canopener_transport::{BusSpec, open};
//!
//! let spec: BusSpec = "virtual:doc-example".parse()?;
//! let mut master = open(&spec)?;
//! let mut device = open(&spec)?;
//! let sdo_request = CanFrame::new(StandardId::new(0x601).unwrap(), &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0])?;
//! master.send(&sdo_request)?;
//! let received = device.recv(Duration::from_secs(1))?.expect("a frame within a second");
//! assert_eq!(received.frame, sdo_request);
//! // The sender never receives its own frame.
//! assert!(master.recv(Duration::ZERO)?.is_none());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]
// A file or a frame must never panic this library: no unwrap, expect or unchecked index outside tests
// (as rustls does).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)
)]

mod clock;
mod error;
pub mod multicast_wire;
#[cfg(target_os = "linux")]
mod socketcan_bus;
mod socketcand_client;
pub mod spec;
mod udp_multicast;
mod virtual_bus;
mod virtual_engine;

use std::time::Duration;

use canopener_can::{CanFrame, Instant};

pub use clock::WallClock;
pub use error::TransportError;
#[cfg(target_os = "linux")]
pub use socketcan_bus::SocketCanBus;
pub use socketcand_client::{CONNECT_ATTEMPTS, CONNECT_TIMEOUT, SocketcandBus};
pub use spec::{BusSpec, SpecError, SpecProblem, spec_from_env_or};
pub use udp_multicast::{DEFAULT_GROUP, DEFAULT_PORT, UdpMulticastBus};
pub use virtual_bus::{VirtualBus, VirtualOptions};

/// A frame taken off the bus, with the time it was received.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Received {
    /// The frame.
    pub frame: CanFrame,
    /// When it was received, on the Unix epoch: the kernel's receive time (SocketCAN), the hub's
    /// (socketcand), the end of the frame on the simulated wire (bit-accurate virtual bus) or the
    /// local receive time (ideal virtual bus, udp-multicast).
    pub timestamp: Instant,
}

/// One endpoint on a CAN bus.
///
/// An endpoint receives every frame other endpoints put on the bus, never its own, in bus order.
/// Dropping it closes it cleanly.
pub trait CanBus: Send + std::fmt::Debug {
    /// Hands `frame` to the medium. Returns once the frame is queued for the bus; it does not wait
    /// for the frame to be transmitted or received.
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError>;

    /// The next frame, waiting at most `timeout`; `Ok(None)` when none arrived in time.
    /// `Duration::ZERO` only takes what is already there.
    ///
    /// [`TransportError::Overrun`] reports frames lost because this endpoint did not keep up; the
    /// endpoint stays usable. [`TransportError::Closed`] means the peer or server went away and
    /// the endpoint must be reopened.
    fn recv(&mut self, timeout: Duration) -> Result<Option<Received>, TransportError>;

    /// The spec this endpoint was opened with.
    fn spec(&self) -> &BusSpec;
}

/// Opens an endpoint on the bus `spec` names.
pub fn open(spec: &BusSpec) -> Result<Box<dyn CanBus>, TransportError> {
    Ok(match spec {
        BusSpec::Virtual { name, bitrate } => Box::new(VirtualBus::open(name, *bitrate)?),
        BusSpec::Socketcand { host, port, bus } => Box::new(SocketcandBus::connect(host, *port, bus)?),
        BusSpec::SocketCan { interface } => open_socketcan(spec, interface)?,
        BusSpec::UdpMulticast { group, port } => Box::new(UdpMulticastBus::open(*group, *port)?),
    })
}

#[cfg(target_os = "linux")]
fn open_socketcan(_spec: &BusSpec, interface: &str) -> Result<Box<dyn CanBus>, TransportError> {
    Ok(Box::new(SocketCanBus::open(interface)?))
}

#[cfg(not(target_os = "linux"))]
fn open_socketcan(spec: &BusSpec, _interface: &str) -> Result<Box<dyn CanBus>, TransportError> {
    Err(TransportError::Unsupported {
        endpoint: spec.to_string(),
        reason: "SocketCAN exists on Linux only; run `canopener bus serve` on a Linux machine with the \
                 interface and use --bus socketcand://HOST:29536/can0",
    })
}
