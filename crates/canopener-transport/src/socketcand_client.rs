//! The `socketcand://HOST:PORT/BUS` backend: a client of a socketcand server in raw mode.
//!
//! The protocol follows linux-can/socketcand `doc/protocol.md` as python-can speaks it (interop
//! reference §3): the server greets with `< hi >`, the client sends `< open BUS >` and
//! `< rawmode >`, each answered by `< ok >`; then frames travel as `< send … >` /
//! `< sendrtr … >` from the client and `< frame … >` / `< rtr … >` from the server. The codec is
//! `canopener_socketcand`; this module only moves its bytes over TCP.

use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::Duration;

use canopener_can::CanFrame;
use canopener_socketcand::{
    DEFAULT_MAX_ELEMENT_LEN, ElementReader, ServerMessage, parse_server_message, write_open, write_rawmode,
    write_send,
};

use crate::error::TransportError;
use crate::spec::{self, BusSpec, SpecError};
use crate::{CanBus, Received};

/// How long one TCP connection attempt may take.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(2);
/// How many times the connection is attempted before giving up, e.g. while a hub is starting.
pub const CONNECT_ATTEMPTS: u32 = 3;
/// The pause between connection attempts.
const CONNECT_RETRY_PAUSE: Duration = Duration::from_millis(300);
/// How long each handshake reply may take.
const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(5);
/// How long a send may wait for the server to accept bytes before reporting a timeout.
const SEND_TIMEOUT: Duration = Duration::from_secs(5);
/// Bytes read from the socket at once: about 70 frame elements.
const READ_CHUNK: usize = 4096;

const HINT_SERVER: &str = "check that the socketcand server is running and reachable";

/// An endpoint on a bus of a socketcand server (for example `canopener bus serve`).
///
/// Receives every frame the server forwards: all frames other clients and the server's interface
/// put on the bus, not this client's own. Error frames and elements this client does not
/// interpret are skipped (logged at debug level). The timestamps are the server's.
#[derive(Debug)]
pub struct SocketcandBus {
    spec: BusSpec,
    endpoint: String,
    stream: TcpStream,
    reader: ElementReader,
    /// Bytes of an earlier send that the server had not accepted when that send timed out; they
    /// go out before anything else so the stream never carries half an element.
    unsent: VecDeque<u8>,
    out: Vec<u8>,
    read_buf: Vec<u8>,
    nonblocking: bool,
    skipped: u64,
}

impl SocketcandBus {
    /// Connects to `host:port` (retrying [`CONNECT_ATTEMPTS`] times), opens `bus` and switches to
    /// raw mode.
    pub fn connect(host: &str, port: u16, bus: &str) -> Result<SocketcandBus, TransportError> {
        let spec = BusSpec::Socketcand {
            host: host.to_owned(),
            port,
            bus: bus.to_owned(),
        };
        let endpoint = spec.to_string();
        // The name goes into `< open NAME >`: a space or `>` in it would break the element.
        spec::validate_bus_name(bus).map_err(|problem| SpecError {
            spec: endpoint.clone(),
            problem,
        })?;
        let stream =
            connect_with_retries(host, port).map_err(|(attempts, source)| TransportError::Connect {
                endpoint: endpoint.clone(),
                attempts,
                source,
            })?;
        // Frames are small and latency matters more than packet count.
        stream
            .set_nodelay(true)
            .map_err(|source| TransportError::io(&endpoint, "setting TCP_NODELAY", HINT_SERVER, source))?;
        stream.set_write_timeout(Some(SEND_TIMEOUT)).map_err(|source| {
            TransportError::io(&endpoint, "setting the send timeout", HINT_SERVER, source)
        })?;
        let mut client = SocketcandBus {
            spec,
            endpoint,
            stream,
            reader: ElementReader::new(DEFAULT_MAX_ELEMENT_LEN),
            unsent: VecDeque::new(),
            out: Vec::new(),
            read_buf: vec![0; READ_CHUNK],
            nonblocking: false,
            skipped: 0,
        };
        client.handshake(bus)?;
        Ok(client)
    }

    /// How many elements were skipped so far: error frames, unknown or malformed elements.
    pub fn skipped_elements(&self) -> u64 {
        self.skipped
    }

    fn handshake(&mut self, bus: &str) -> Result<(), TransportError> {
        self.expect_reply("< hi >", |m| matches!(m, ServerMessage::Hi))?;
        self.out.clear();
        write_open(&mut self.out, bus);
        self.write_out()?;
        let reply = self.handshake_reply("< ok >")?;
        match reply {
            (ServerMessage::Ok, _) => {}
            (ServerMessage::Error { text }, _) => {
                return Err(TransportError::BusRefused {
                    endpoint: self.endpoint.clone(),
                    bus: bus.to_owned(),
                    reason: text,
                });
            }
            (_, element) => return Err(self.handshake_error("< ok >", element)),
        }
        self.out.clear();
        write_rawmode(&mut self.out);
        self.write_out()?;
        self.expect_reply("< ok >", |m| matches!(m, ServerMessage::Ok))
    }

    fn expect_reply(
        &mut self,
        expected: &'static str,
        accept: fn(&ServerMessage) -> bool,
    ) -> Result<(), TransportError> {
        let (message, element) = self.handshake_reply(expected)?;
        if accept(&message) {
            Ok(())
        } else {
            Err(self.handshake_error(expected, element))
        }
    }

    /// The next element during the handshake, parsed, with its text for error messages.
    fn handshake_reply(&mut self, expected: &'static str) -> Result<(ServerMessage, String), TransportError> {
        let deadline = std::time::Instant::now() + HANDSHAKE_TIMEOUT;
        loop {
            if let Some(element) = self.reader.next_element() {
                let element = element.map_err(|err| self.handshake_error(expected, err.to_string()))?;
                let message = parse_server_message(&element)
                    .map_err(|_| self.handshake_error(expected, element.clone()))?;
                return Ok((message, element));
            }
            let wait = deadline.saturating_duration_since(std::time::Instant::now());
            if wait.is_zero() {
                let timed_out = io::Error::new(
                    io::ErrorKind::TimedOut,
                    format!("no {expected} within {HANDSHAKE_TIMEOUT:?}"),
                );
                return Err(TransportError::io(
                    &self.endpoint,
                    "waiting for the socketcand handshake",
                    "check that the server speaks socketcand",
                    timed_out,
                ));
            }
            self.read_some(Some(wait))?;
        }
    }

    fn handshake_error(&self, expected: &'static str, got: String) -> TransportError {
        TransportError::Handshake {
            endpoint: self.endpoint.clone(),
            expected,
            got,
        }
    }

    fn set_nonblocking(&mut self, nonblocking: bool) -> Result<(), TransportError> {
        if self.nonblocking != nonblocking {
            self.stream.set_nonblocking(nonblocking).map_err(|source| {
                TransportError::io(&self.endpoint, "switching the socket mode", HINT_SERVER, source)
            })?;
            self.nonblocking = nonblocking;
        }
        Ok(())
    }

    /// Reads once, waiting at most `wait` (`None`: forever, zero: not at all); `false` when
    /// nothing arrived in time.
    fn read_some(&mut self, wait: Option<Duration>) -> Result<bool, TransportError> {
        match wait {
            Some(Duration::ZERO) => self.set_nonblocking(true)?,
            wait => {
                self.set_nonblocking(false)?;
                self.stream.set_read_timeout(wait).map_err(|source| {
                    TransportError::io(&self.endpoint, "setting the receive timeout", HINT_SERVER, source)
                })?;
            }
        }
        match self.stream.read(&mut self.read_buf) {
            Ok(0) => Err(TransportError::Closed {
                endpoint: self.endpoint.clone(),
            }),
            Ok(len) => {
                // `read` never reports more bytes than the buffer holds.
                self.reader.push(self.read_buf.get(..len).unwrap_or_default());
                Ok(true)
            }
            Err(err) if matches!(err.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => {
                Ok(false)
            }
            Err(err) if err.kind() == io::ErrorKind::Interrupted => Ok(false),
            Err(err) if is_disconnect(&err) => Err(TransportError::Closed {
                endpoint: self.endpoint.clone(),
            }),
            Err(source) => Err(TransportError::io(
                &self.endpoint,
                "receiving from the server",
                HINT_SERVER,
                source,
            )),
        }
    }

    /// Writes `self.unsent` and then `self.out`, keeping whatever the server did not accept in
    /// time in `self.unsent`.
    fn write_out(&mut self) -> Result<(), TransportError> {
        self.set_nonblocking(false)?;
        self.unsent.extend(self.out.drain(..));
        while !self.unsent.is_empty() {
            let (head, _) = self.unsent.as_slices();
            match self.stream.write(head) {
                Ok(0) => {
                    return Err(TransportError::Closed {
                        endpoint: self.endpoint.clone(),
                    });
                }
                Ok(written) => drop(self.unsent.drain(..written)),
                Err(err) if err.kind() == io::ErrorKind::Interrupted => {}
                Err(err) if matches!(err.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => {
                    return Err(TransportError::SendTimeout {
                        endpoint: self.endpoint.clone(),
                        waited: SEND_TIMEOUT,
                    });
                }
                Err(err) if is_disconnect(&err) => {
                    return Err(TransportError::Closed {
                        endpoint: self.endpoint.clone(),
                    });
                }
                Err(source) => {
                    return Err(TransportError::io(
                        &self.endpoint,
                        "sending to the server",
                        HINT_SERVER,
                        source,
                    ));
                }
            }
        }
        Ok(())
    }

    /// The next frame already read and buffered, skipping everything that is not a frame.
    fn next_buffered_frame(&mut self) -> Option<Received> {
        while let Some(element) = self.reader.next_element() {
            let element = match element {
                Ok(element) => element,
                Err(err) => {
                    self.skip(format_args!("{err}"));
                    continue;
                }
            };
            match parse_server_message(&element) {
                Ok(ServerMessage::Frame { frame, timestamp }) => return Some(Received { frame, timestamp }),
                Ok(ServerMessage::ErrorFrame { class, timestamp }) => {
                    self.skip(format_args!("error frame class {class:#X} at {timestamp}"));
                }
                Ok(other) => self.skip(format_args!("{other:?}")),
                Err(err) => self.skip(format_args!("{err}")),
            }
        }
        None
    }

    fn skip(&mut self, what: std::fmt::Arguments<'_>) {
        self.skipped += 1;
        tracing::debug!(endpoint = %self.endpoint, "skipping socketcand element: {what}");
    }
}

/// How long closing waits for the server to close its side after ours (our hub answers a
/// half-close at once; a server that does not is waited for no longer than this).
const CLOSE_LINGER: Duration = Duration::from_millis(200);

impl Drop for SocketcandBus {
    /// Closes gracefully. A socket closed while the server's traffic still sits unread in its
    /// receive buffer makes the kernel reset the connection and throw away what was not delivered
    /// yet: the last frames a one-shot command sent (an NMT command, `bus send`) could be lost.
    /// So: half-close (the server gets everything we sent, then end of stream), and read until the
    /// server closes too, for at most 200 ms (`CLOSE_LINGER`).
    fn drop(&mut self) {
        if self.write_out().is_err() || self.stream.shutdown(std::net::Shutdown::Write).is_err() {
            return;
        }
        let _ = self.stream.set_nonblocking(false);
        let deadline = std::time::Instant::now() + CLOSE_LINGER;
        let mut sink = [0u8; 4096];
        while let Some(left) = deadline.checked_duration_since(std::time::Instant::now()) {
            if left.is_zero() || self.stream.set_read_timeout(Some(left)).is_err() {
                break;
            }
            match self.stream.read(&mut sink) {
                Ok(0) => break,
                Ok(_) => {}
                Err(err) if err.kind() == io::ErrorKind::Interrupted => {}
                Err(_) => break,
            }
        }
    }
}

impl CanBus for SocketcandBus {
    fn send(&mut self, frame: &CanFrame) -> Result<(), TransportError> {
        self.out.clear();
        write_send(&mut self.out, frame);
        self.write_out()
    }

    fn recv(&mut self, timeout: Duration) -> Result<Option<Received>, TransportError> {
        let deadline = std::time::Instant::now().checked_add(timeout);
        loop {
            if let Some(received) = self.next_buffered_frame() {
                return Ok(Some(received));
            }
            let wait = deadline.map(|d| d.saturating_duration_since(std::time::Instant::now()));
            let got_bytes = self.read_some(wait)?;
            if !got_bytes
                && (wait == Some(Duration::ZERO) || deadline.is_some_and(|d| std::time::Instant::now() >= d))
            {
                return Ok(None);
            }
        }
    }

    fn spec(&self) -> &BusSpec {
        &self.spec
    }
}

fn is_disconnect(err: &io::Error) -> bool {
    matches!(
        err.kind(),
        io::ErrorKind::BrokenPipe
            | io::ErrorKind::ConnectionReset
            | io::ErrorKind::ConnectionAborted
            | io::ErrorKind::UnexpectedEof
    )
}

/// Connects to the first reachable address of `host:port`, trying the whole list
/// [`CONNECT_ATTEMPTS`] times; on failure, the number of attempts and the last error.
fn connect_with_retries(host: &str, port: u16) -> Result<TcpStream, (u32, io::Error)> {
    let mut last_error = io::Error::new(io::ErrorKind::NotFound, format!("{host} has no address"));
    for attempt in 1..=CONNECT_ATTEMPTS {
        match (host, port).to_socket_addrs() {
            Ok(addresses) => {
                let addresses: Vec<SocketAddr> = addresses.collect();
                for address in addresses {
                    match TcpStream::connect_timeout(&address, CONNECT_TIMEOUT) {
                        Ok(stream) => return Ok(stream),
                        Err(err) => last_error = err,
                    }
                }
            }
            Err(err) => last_error = err,
        }
        if attempt < CONNECT_ATTEMPTS {
            std::thread::sleep(CONNECT_RETRY_PAUSE);
        }
    }
    Err((CONNECT_ATTEMPTS, last_error))
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_can::{CanId, Instant, StandardId};
    use std::net::TcpListener;
    use std::thread;

    /// A scripted server: greets, then answers `open` and `rawmode` with the given replies and
    /// then writes `after_handshake`; returns everything the client sent once it disconnects.
    fn scripted_server(
        greeting: &'static [u8],
        open_reply: &'static [u8],
        after_handshake: &'static [u8],
    ) -> (u16, thread::JoinHandle<Vec<u8>>) {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let handle = thread::spawn(move || {
            let (mut stream, _) = listener.accept().unwrap();
            stream.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
            let mut received = Vec::new();
            stream.write_all(greeting).unwrap();
            read_until(&mut stream, &mut received, b"< open can0 >");
            stream.write_all(open_reply).unwrap();
            if open_reply != b"< ok >" {
                return received;
            }
            read_until(&mut stream, &mut received, b"< rawmode >");
            stream.write_all(b"< ok >").unwrap();
            stream.write_all(after_handshake).unwrap();
            let mut buf = [0; 1024];
            while let Ok(n @ 1..) = stream.read(&mut buf) {
                received.extend_from_slice(&buf[..n]);
            }
            received
        });
        (port, handle)
    }

    fn read_until(stream: &mut TcpStream, received: &mut Vec<u8>, needle: &[u8]) {
        let mut buf = [0; 256];
        while !received.windows(needle.len()).any(|w| w == needle) {
            let n = stream.read(&mut buf).unwrap();
            assert!(
                n > 0,
                "client closed before sending {:?}",
                String::from_utf8_lossy(needle)
            );
            received.extend_from_slice(&buf[..n]);
        }
    }

    fn sid(raw: u16) -> CanId {
        StandardId::new(raw).unwrap().into()
    }

    #[test]
    fn receives_frames_and_remote_frames_with_server_timestamps_skipping_the_rest() {
        let (port, server) = scripted_server(
            b"< hi >",
            b"< ok >",
            b"< frame 181 1700000000.250000 0102 >junk< error 004 1700000000.300000 >< fdframe 1 0 1.0 00 >\
              < echo >< frame 12 1.0 >< rtr 701 1700000000.500000 1 >< frame 1AAAAAAA 1700000001.000001  >",
        );
        let mut bus = SocketcandBus::connect("127.0.0.1", port, "can0").unwrap();
        let first = bus.recv(Duration::from_secs(5)).unwrap().unwrap();
        assert_eq!(first.frame, CanFrame::new(sid(0x181), &[1, 2]).unwrap());
        assert_eq!(first.timestamp, Instant::from_millis(1_700_000_000_250));
        let second = bus.recv(Duration::from_secs(5)).unwrap().unwrap();
        assert_eq!(second.frame, CanFrame::remote(sid(0x701), 1).unwrap());
        assert_eq!(second.timestamp, Instant::from_millis(1_700_000_000_500));
        let third = bus.recv(Duration::from_secs(5)).unwrap().unwrap();
        assert_eq!(
            third.frame,
            CanFrame::new(CanId::extended(0x1AAA_AAAA).unwrap(), &[]).unwrap()
        );
        assert_eq!(third.timestamp, Instant::from_micros(1_700_000_001_000_001));
        // Error frame, fdframe, echo and the 2-digit id frame were skipped.
        assert_eq!(bus.skipped_elements(), 4);
        drop(bus);
        server.join().unwrap();
    }

    #[test]
    fn sends_socketcand_send_and_sendrtr_elements() {
        let (port, server) = scripted_server(b"< hi >", b"< ok >", b"");
        let mut bus = SocketcandBus::connect("127.0.0.1", port, "can0").unwrap();
        bus.send(&CanFrame::new(sid(0x601), &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).unwrap())
            .unwrap();
        bus.send(&CanFrame::remote(sid(0x701), 1).unwrap()).unwrap();
        bus.send(&CanFrame::new(CanId::extended(0x1AAA_AAAA).unwrap(), &[0x01, 0xF1]).unwrap())
            .unwrap();
        assert_eq!(bus.recv(Duration::ZERO).unwrap(), None);
        drop(bus);
        let sent = String::from_utf8(server.join().unwrap()).unwrap();
        assert_eq!(
            sent,
            "< open can0 >< rawmode >< send 601 8 40 00 10 00 00 00 00 00 >< sendrtr 701 1 >\
             < send 1AAAAAAA 2 01 F1 >"
        );
    }

    #[test]
    fn refused_bus_names_the_bus_and_the_reason() {
        let (port, server) = scripted_server(b"< hi >", b"< error could not open bus >", b"");
        let err = SocketcandBus::connect("127.0.0.1", port, "can0").unwrap_err();
        assert!(
            matches!(&err, TransportError::BusRefused { bus, reason, .. } if bus == "can0" && reason == "could not open bus"),
            "{err:?}"
        );
        let message = err.to_string();
        assert!(
            message.contains(&format!("socketcand://127.0.0.1:{port}/can0")),
            "{message}"
        );
        server.join().unwrap();
    }

    #[test]
    fn wrong_greeting_is_a_handshake_error() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let server = thread::spawn(move || {
            let (mut stream, _) = listener.accept().unwrap();
            stream.write_all(b"SSH-2.0-OpenSSH_9.6 < welcome >").unwrap();
            let mut buf = [0; 64];
            let _ = stream.read(&mut buf);
        });
        let err = SocketcandBus::connect("127.0.0.1", port, "can0").unwrap_err();
        assert!(
            matches!(&err, TransportError::Handshake { expected: "< hi >", got, .. } if got == "< welcome >"),
            "{err:?}"
        );
        server.join().unwrap();
    }

    #[test]
    fn server_closing_is_an_error_not_a_hang() {
        let (port, server) = scripted_server(b"< hi >", b"< ok >", b"< frame 181 1.000000 01 >");
        let mut bus = SocketcandBus::connect("127.0.0.1", port, "can0").unwrap();
        assert!(bus.recv(Duration::from_secs(5)).unwrap().is_some());
        // The scripted server closes its side once ours is half-closed.
        bus.stream.shutdown(std::net::Shutdown::Write).unwrap();
        server.join().unwrap();
        let err = bus.recv(Duration::from_secs(5)).unwrap_err();
        assert!(matches!(err, TransportError::Closed { .. }), "{err:?}");
        assert!(
            err.to_string()
                .contains(&format!("socketcand://127.0.0.1:{port}/can0")),
            "{err}"
        );
    }

    #[test]
    fn recv_times_out_with_none() {
        let (port, server) = scripted_server(b"< hi >", b"< ok >", b"< frame 181 1.000000 01");
        let mut bus = SocketcandBus::connect("127.0.0.1", port, "can0").unwrap();
        let started = std::time::Instant::now();
        // Half an element: no frame yet.
        assert_eq!(bus.recv(Duration::from_millis(100)).unwrap(), None);
        let waited = started.elapsed();
        assert!(
            waited >= Duration::from_millis(100) && waited < Duration::from_secs(3),
            "{waited:?}"
        );
        assert_eq!(bus.recv(Duration::ZERO).unwrap(), None);
        drop(bus);
        server.join().unwrap();
    }

    #[test]
    fn bus_names_that_would_break_the_element_are_refused_before_connecting() {
        for bad in ["", "can 0", "can0>", "a-name-longer-than-16"] {
            let err = SocketcandBus::connect("127.0.0.1", 1, bad).unwrap_err();
            assert!(matches!(err, TransportError::Spec(_)), "{bad:?}: {err:?}");
        }
    }

    #[test]
    fn nothing_listening_reports_the_attempts() {
        let port = {
            let listener = TcpListener::bind("127.0.0.1:0").unwrap();
            listener.local_addr().unwrap().port()
        };
        let err = SocketcandBus::connect("127.0.0.1", port, "can0").unwrap_err();
        assert!(
            matches!(
                err,
                TransportError::Connect {
                    attempts: CONNECT_ATTEMPTS,
                    ..
                }
            ),
            "{err:?}"
        );
        assert!(err.to_string().contains("canopener bus serve"), "{err}");
    }
}
