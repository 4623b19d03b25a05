//! The `socketcan:IFACE` backend: Linux SocketCAN raw sockets with kernel receive timestamps.
//!
//! Kernels built without CAN support (this project's CI machine among them) fail `socket(AF_CAN)`
//! with EAFNOSUPPORT; opening then reports [`TransportError::SocketCanUnavailable`] naming the
//! alternatives (the socketcand hub and udp-multicast) instead of a bare errno.

use std::io;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use canopener_can::{CanFrame, CanId, Instant};
use socketcan::{EmbeddedFrame, Socket, SocketOptions};

use crate::error::TransportError;
use crate::spec::BusSpec;
use crate::{CanBus, Received};

/// Linux `ENODEV`: `if_nametoindex` found no interface of that name.
const ENODEV: i32 = 19;
/// Linux `ENOBUFS`: the interface's transmit queue is full.
const ENOBUFS: i32 = 105;

/// How long `send` retries while the kernel's transmit queue is full.
const SEND_RETRY_LIMIT: Duration = Duration::from_secs(1);
/// The pause between those retries: about one DLC-8 frame at 1 Mbit/s.
const SEND_RETRY_PAUSE: Duration = Duration::from_micros(200);

const HINT_RETRY: &str = "check that the interface is up (`ip link set IFACE up`)";

/// An endpoint on a SocketCAN interface such as `can0` or `vcan0`.
///
/// The socket receives every frame on the interface except its own (the kernel's
/// `CAN_RAW_RECV_OWN_MSGS` default), including frames of other local sockets; error frames are
/// skipped. Timestamps are the kernel's `SO_TIMESTAMPNS` receive times.
#[derive(Debug)]
pub struct SocketCanBus {
    spec: BusSpec,
    endpoint: String,
    socket: socketcan::CanSocket,
    nonblocking: bool,
}

impl SocketCanBus {
    /// Opens `interface` and enables kernel receive timestamps.
    pub fn open(interface: &str) -> Result<SocketCanBus, TransportError> {
        let spec = BusSpec::SocketCan {
            interface: interface.to_owned(),
        };
        let endpoint = spec.to_string();
        // Probe AF_CAN before looking the interface up: on a kernel without CAN the interface
        // lookup fails first and would blame the name instead of the missing kernel support.
        probe_af_can().map_err(|source| TransportError::SocketCanUnavailable {
            endpoint: endpoint.clone(),
            source,
        })?;
        let socket = socketcan::CanSocket::open(interface).map_err(|source| {
            if source.raw_os_error() == Some(ENODEV) {
                TransportError::NoSuchInterface {
                    interface: interface.to_owned(),
                }
            } else {
                TransportError::io(&endpoint, "opening the CAN interface", HINT_RETRY, source)
            }
        })?;
        socket.set_recv_timestamp(true).map_err(|source| {
            TransportError::io(
                &endpoint,
                "enabling kernel receive timestamps",
                HINT_RETRY,
                source,
            )
        })?;
        Ok(SocketCanBus {
            spec,
            endpoint,
            socket,
            nonblocking: false,
        })
    }

    fn set_nonblocking(&mut self, nonblocking: bool) -> io::Result<()> {
        if self.nonblocking != nonblocking {
            self.socket.set_nonblocking(nonblocking)?;
            self.nonblocking = nonblocking;
        }
        Ok(())
    }

    fn read_one(&mut self, wait: Option<Duration>) -> io::Result<Option<(socketcan::CanFrame, SystemTime)>> {
        match wait {
            Some(Duration::ZERO) => self.set_nonblocking(true)?,
            wait => {
                self.set_nonblocking(false)?;
                self.socket.set_read_timeout(wait)?;
            }
        }
        match self.socket.read_frame_with_timestamp() {
            Ok(read) => Ok(Some(read)),
            Err(err)
                if matches!(
                    err.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
                ) =>
            {
                Ok(None)
            }
            Err(err) => Err(err),
        }
    }
}

impl CanBus for SocketCanBus {
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        let raw = to_socketcan(frame);
        let started = std::time::Instant::now();
        self.set_nonblocking(false)
            .map_err(|source| TransportError::io(&self.endpoint, "sending a frame", HINT_RETRY, source))?;
        loop {
            match self.socket.write_frame(&raw) {
                Ok(()) => return Ok(()),
                // A full qdisc reports ENOBUFS instead of blocking, and poll() does not signal
                // when it drains, so retrying after a short pause is the usual remedy.
                Err(err) if err.raw_os_error() == Some(ENOBUFS) => {
                    let waited = started.elapsed();
                    if waited >= SEND_RETRY_LIMIT {
                        return Err(TransportError::SendTimeout {
                            endpoint: self.endpoint.clone(),
                            waited,
                        });
                    }
                    std::thread::sleep(SEND_RETRY_PAUSE);
                }
                Err(err) if err.kind() == io::ErrorKind::Interrupted => {}
                Err(source) => {
                    return Err(TransportError::io(
                        &self.endpoint,
                        "sending a frame",
                        HINT_RETRY,
                        source,
                    ));
                }
            }
        }
    }

    fn recv(&mut self, timeout: Duration) -> Result<Option<Received>, TransportError> {
        let deadline = std::time::Instant::now().checked_add(timeout);
        loop {
            let wait = deadline.map(|d| d.saturating_duration_since(std::time::Instant::now()));
            let read = self.read_one(wait).map_err(|source| {
                TransportError::io(&self.endpoint, "receiving a frame", HINT_RETRY, source)
            })?;
            let Some((raw, received_at)) = read else {
                if wait == Some(Duration::ZERO) || deadline.is_some_and(|d| std::time::Instant::now() >= d) {
                    return Ok(None);
                }
                continue;
            };
            match from_socketcan(&raw) {
                Some(frame) => {
                    return Ok(Some(Received {
                        frame,
                        timestamp: system_time_to_instant(received_at),
                    }));
                }
                None => tracing::debug!(endpoint = %self.endpoint, ?raw, "skipping error frame"),
            }
        }
    }

    fn spec(&self) -> &BusSpec {
        &self.spec
    }
}

fn probe_af_can() -> io::Result<()> {
    let domain = socket2::Domain::from(socketcan::addr::AF_CAN);
    let protocol = socket2::Protocol::from(socketcan::addr::CAN_RAW);
    socket2::Socket::new(domain, socket2::Type::RAW, Some(protocol)).map(drop)
}

#[allow(
    clippy::expect_used,
    reason = "CanId guarantees 11 or 29 bits and CanFrame a DLC and data length of 0 to 8, exactly what the socketcan constructors accept: no expect here depends on input"
)]
fn to_socketcan(frame: &CanFrame) -> socketcan::CanFrame {
    let id: socketcan::Id = match frame.id() {
        CanId::Standard(id) => socketcan::StandardId::new(id.as_raw()).expect("11-bit id").into(),
        CanId::Extended(id) => socketcan::ExtendedId::new(id.as_raw()).expect("29-bit id").into(),
    };
    if frame.is_remote() {
        socketcan::CanFrame::new_remote(id, usize::from(frame.dlc())).expect("remote DLC 0 to 8")
    } else {
        socketcan::CanFrame::new(id, frame.data()).expect("0 to 8 data bytes")
    }
}

/// `None` for error frames (and for anything a classical frame cannot represent).
fn from_socketcan(frame: &socketcan::CanFrame) -> Option<CanFrame> {
    let id = match frame.id() {
        socketcan::Id::Standard(id) => CanId::standard(id.as_raw()).ok()?,
        socketcan::Id::Extended(id) => CanId::extended(id.as_raw()).ok()?,
    };
    match frame {
        socketcan::CanFrame::Data(data) => CanFrame::new(id, data.data()).ok(),
        socketcan::CanFrame::Remote(remote) => CanFrame::remote(id, u8::try_from(remote.dlc()).ok()?).ok(),
        socketcan::CanFrame::Error(_) => None,
    }
}

fn system_time_to_instant(time: SystemTime) -> Instant {
    // A receive time before 1970 means a broken clock; the epoch keeps the frame usable.
    let since_epoch = time.duration_since(UNIX_EPOCH).unwrap_or_default();
    Instant::from_nanos(u64::try_from(since_epoch.as_nanos()).unwrap_or(u64::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::strategy::any_frame;
    use proptest::prelude::*;

    #[test]
    fn missing_af_can_or_interface_gives_an_actionable_error() {
        let err = SocketCanBus::open("cnpnr-none0").unwrap_err();
        let message = err.to_string();
        if probe_af_can().is_err() {
            assert!(
                matches!(err, TransportError::SocketCanUnavailable { .. }),
                "{err:?}"
            );
            assert!(message.contains("socketcan:cnpnr-none0"), "{message}");
            assert!(message.contains("canopener bus serve"), "{message}");
            assert!(
                message.contains("--bus socketcand://127.0.0.1:29536/can0"),
                "{message}"
            );
            assert!(
                message.contains("--bus udp-multicast://239.74.163.2:43113"),
                "{message}"
            );
        } else {
            assert!(matches!(err, TransportError::NoSuchInterface { .. }), "{err:?}");
            assert_eq!(
                message,
                "no CAN interface named cnpnr-none0; list interfaces with `ip link`"
            );
        }
    }

    #[test]
    fn error_frames_are_skipped() {
        let error = socketcan::CanErrorFrame::new_error(0x004, &[0, 0x08, 0, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!(from_socketcan(&socketcan::CanFrame::Error(error)), None);
    }

    #[test]
    fn kernel_timestamps_become_unix_epoch_instants() {
        let time = UNIX_EPOCH + Duration::new(1_436_509_052, 249_713_000);
        assert_eq!(system_time_to_instant(time).to_string(), "1436509052.249713");
    }

    proptest! {
        #[test]
        fn frames_map_both_ways(frame in any_frame()) {
            let raw = to_socketcan(&frame);
            prop_assert_eq!(raw.is_extended(), frame.id().is_extended());
            prop_assert_eq!(raw.is_remote_frame(), frame.is_remote());
            prop_assert_eq!(raw.dlc(), usize::from(frame.dlc()));
            prop_assert_eq!(from_socketcan(&raw), Some(frame));
        }
    }
}
