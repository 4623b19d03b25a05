//! The `udp-multicast://GROUP:PORT` backend: python-can's serverless `udp_multicast` bus.
//!
//! Every endpoint joins one multicast group; every datagram on it is one frame in the format of
//! [`crate::multicast_wire`]. There is no server, no ordering guarantee and no flow control: a
//! receiver that falls behind loses datagrams in the kernel (the interop reference §1 measured
//! 15–45 % loss for unpaced bursts of 1000 frames and none for paced traffic up to 20 k frames/s,
//! which is twice the rate of a saturated 1 Mbit/s bus).

use std::io;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, UdpSocket};
use std::time::Duration;

use canopener_can::CanFrame;
use socket2::{Domain, Protocol, Socket, Type};

use crate::clock::WallClock;
use crate::error::TransportError;
use crate::multicast_wire::{self, MAX_DATAGRAM_LEN};
use crate::spec::BusSpec;
use crate::{CanBus, Received};

/// python-can's default group for `interface="udp_multicast"` (IPv4).
pub const DEFAULT_GROUP: Ipv4Addr = Ipv4Addr::new(239, 74, 163, 2);
/// python-can's default port for `interface="udp_multicast"`.
pub const DEFAULT_PORT: u16 = 43113;

/// The receive buffer we ask the kernel for. The default (`net.core.rmem_default`, about 200 kB
/// or 300–500 datagrams) loses frames in bursts; the kernel caps the request at
/// `net.core.rmem_max`, so this is best effort.
const RECEIVE_BUFFER_BYTES: usize = 4 << 20;

const HINT_GROUP: &str = "the host needs a multicast route, e.g. `ip route add 224.0.0.0/4 dev lo` \
                          for a bus on this machine only";
const HINT_RETRY: &str = "check the network configuration and try again";

/// An endpoint on a python-can-compatible UDP multicast bus.
///
/// Frames are sent from a socket of their own and received on a socket bound to the group's port,
/// as python-can's own sockets are. Datagrams that cannot be decoded, error frames and CAN FD
/// frames are skipped and counted (see [`UdpMulticastBus::skipped_datagrams`]).
#[derive(Debug)]
pub struct UdpMulticastBus {
    spec: BusSpec,
    endpoint: String,
    receiver: UdpSocket,
    sender: UdpSocket,
    /// The source address our own datagrams arrive with; see [`UdpMulticastBus::open`].
    own_source: SocketAddr,
    receiver_nonblocking: bool,
    skipped: u64,
    buffer: Vec<u8>,
}

impl UdpMulticastBus {
    /// Joins `group` on `port`.
    ///
    /// The receiving socket mirrors python-can: address and port reuse, bound to the wildcard
    /// address on `port`, membership on the interface the kernel routes the group to, TTL
    /// (hop limit) 1, multicast loopback on so other processes on this host see our frames.
    ///
    /// python-can peers receive their own frames because every process sends from its bound port,
    /// so all local senders share one source address and cannot tell each other apart. We send
    /// from a separate socket with an ephemeral port instead, and drop datagrams whose source is
    /// that socket: that removes exactly our own frames and nobody else's. Turning multicast
    /// loopback off instead would also hide our frames from the other processes on this host.
    pub fn open(group: IpAddr, port: u16) -> Result<UdpMulticastBus, TransportError> {
        let spec = BusSpec::UdpMulticast { group, port };
        let endpoint = spec.to_string();
        if !group.is_multicast() {
            return Err(TransportError::io(
                endpoint,
                "joining the multicast group",
                "use a multicast group address such as 239.74.163.2 (224.0.0.0/4 or ff00::/8)",
                io::Error::new(
                    io::ErrorKind::InvalidInput,
                    format!("{group} is not a multicast address"),
                ),
            ));
        }
        let receiver = bind_receiver(group, port).map_err(|source| {
            TransportError::io(
                &endpoint,
                "binding and joining the multicast group",
                HINT_GROUP,
                source,
            )
        })?;
        let sender = connect_sender(group, port).map_err(|source| {
            TransportError::io(&endpoint, "opening the multicast send socket", HINT_GROUP, source)
        })?;
        let own_source = sender.local_addr().map_err(|source| {
            TransportError::io(&endpoint, "reading the send address", HINT_RETRY, source)
        })?;
        Ok(UdpMulticastBus {
            spec,
            endpoint,
            receiver,
            sender,
            own_source,
            receiver_nonblocking: false,
            skipped: 0,
            buffer: vec![0; MAX_DATAGRAM_LEN],
        })
    }

    /// How many datagrams were skipped so far: undecodable ones, error frames and CAN FD frames.
    pub fn skipped_datagrams(&self) -> u64 {
        self.skipped
    }

    /// The source address of the datagrams this endpoint sends.
    pub fn send_address(&self) -> SocketAddr {
        self.own_source
    }

    fn set_receiver_nonblocking(&mut self, nonblocking: bool) -> io::Result<()> {
        if self.receiver_nonblocking != nonblocking {
            self.receiver.set_nonblocking(nonblocking)?;
            self.receiver_nonblocking = nonblocking;
        }
        Ok(())
    }

    /// One receive attempt waiting at most `wait` (`None`: forever, zero: do not wait).
    fn receive_datagram(&mut self, wait: Option<Duration>) -> io::Result<Option<(usize, SocketAddr)>> {
        match wait {
            Some(Duration::ZERO) => self.set_receiver_nonblocking(true)?,
            wait => {
                self.set_receiver_nonblocking(false)?;
                self.receiver.set_read_timeout(wait)?;
            }
        }
        match self.receiver.recv_from(&mut self.buffer) {
            Ok(received) => Ok(Some(received)),
            Err(err) if matches!(err.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => Ok(None),
            Err(err) if err.kind() == io::ErrorKind::Interrupted => Ok(None),
            Err(err) => Err(err),
        }
    }
}

impl CanBus for UdpMulticastBus {
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        let datagram = multicast_wire::encode(frame, WallClock::now());
        self.sender.send(&datagram).map_err(|source| {
            TransportError::io(&self.endpoint, "sending a multicast datagram", HINT_GROUP, source)
        })?;
        Ok(())
    }

    fn recv(&mut self, timeout: Duration) -> Result<Option<Received>, TransportError> {
        let deadline = std::time::Instant::now().checked_add(timeout);
        loop {
            let wait = deadline.map(|d| d.saturating_duration_since(std::time::Instant::now()));
            let received = self.receive_datagram(wait).map_err(|source| {
                TransportError::io(
                    &self.endpoint,
                    "receiving a multicast datagram",
                    HINT_RETRY,
                    source,
                )
            })?;
            let Some((len, source)) = received else {
                if wait == Some(Duration::ZERO) || deadline.is_some_and(|d| std::time::Instant::now() >= d) {
                    return Ok(None);
                }
                continue;
            };
            // python-can stamps with the kernel receive time (SO_TIMESTAMPNS); reading the clock
            // right after recvfrom returns differs from that by the wake-up latency only.
            let timestamp = WallClock::now();
            // IP and port only: an IPv6 source may carry a scope id that `local_addr` lacks.
            if source.ip() == self.own_source.ip() && source.port() == self.own_source.port() {
                continue;
            }
            // `len` is at most the buffer length: recv_from never reports more than it copied.
            let datagram = self.buffer.get(..len).unwrap_or_default();
            match multicast_wire::decode(datagram) {
                Ok(frame) => return Ok(Some(Received { frame, timestamp })),
                Err(err) => {
                    self.skipped += 1;
                    tracing::debug!(endpoint = %self.endpoint, %source, "skipping datagram: {err}");
                }
            }
        }
    }

    fn spec(&self) -> &BusSpec {
        &self.spec
    }
}

fn bind_receiver(group: IpAddr, port: u16) -> io::Result<UdpSocket> {
    let socket = Socket::new(
        Domain::for_address(SocketAddr::new(group, port)),
        Type::DGRAM,
        Some(Protocol::UDP),
    )?;
    socket.set_reuse_address(true)?;
    #[cfg(unix)]
    socket.set_reuse_port(true)?;
    // Best effort: a smaller buffer than asked for still works, it only loses bursts sooner.
    let _ = socket.set_recv_buffer_size(RECEIVE_BUFFER_BYTES);
    match group {
        IpAddr::V4(group) => {
            socket.bind(&SocketAddr::new(Ipv4Addr::UNSPECIFIED.into(), port).into())?;
            socket.join_multicast_v4(&group, &Ipv4Addr::UNSPECIFIED)?;
            socket.set_multicast_ttl_v4(1)?;
            socket.set_multicast_loop_v4(true)?;
        }
        IpAddr::V6(group) => {
            socket.set_only_v6(true)?;
            socket.bind(&SocketAddr::new(Ipv6Addr::UNSPECIFIED.into(), port).into())?;
            socket.join_multicast_v6(&group, 0)?;
            socket.set_multicast_hops_v6(1)?;
            socket.set_multicast_loop_v6(true)?;
        }
    }
    Ok(socket.into())
}

/// A socket connected to the group: `local_addr` then reports the exact source address (route's
/// interface address and ephemeral port) that our datagrams carry.
fn connect_sender(group: IpAddr, port: u16) -> io::Result<UdpSocket> {
    let destination = SocketAddr::new(group, port);
    let socket = Socket::new(Domain::for_address(destination), Type::DGRAM, Some(Protocol::UDP))?;
    match group {
        IpAddr::V4(_) => {
            socket.set_multicast_ttl_v4(1)?;
            socket.set_multicast_loop_v4(true)?;
        }
        IpAddr::V6(_) => {
            socket.set_multicast_hops_v6(1)?;
            socket.set_multicast_loop_v6(true)?;
        }
    }
    socket.connect(&destination.into())?;
    Ok(socket.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unicast_group_is_rejected_with_a_hint() {
        let err = UdpMulticastBus::open(IpAddr::V4(Ipv4Addr::new(10, 0, 0, 1)), 43113).unwrap_err();
        let message = err.to_string();
        assert!(message.contains("udp-multicast://10.0.0.1:43113"), "{message}");
        assert!(message.contains("not a multicast address"), "{message}");
        assert!(message.contains("239.74.163.2"), "{message}");
    }
}
