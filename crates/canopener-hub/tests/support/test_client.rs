//! A small blocking socketcand client for the hub tests, reading the way python-can does: the
//! handshake replies with one `recv` each that must be exactly the expected element.

// Each test binary includes this file and uses a different subset of it, so `expect` would fail
// in some of them; `pub` items are only reachable from the including test.
#![allow(dead_code, unreachable_pub)]

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant as StdInstant};

use canopener_can::{CanFrame, CanId, Instant};
use canopener_hub::{HubConfig, HubHandle};
use canopener_socketcand::{ElementReader, ServerMessage, parse_server_message, write_send};

/// How long any single test read may block before the test fails instead of hanging.
pub const READ_TIMEOUT: Duration = Duration::from_secs(20);

/// A hub on a free loopback port with test-friendly settings.
pub fn start_hub(adjust: impl FnOnce(&mut HubConfig)) -> HubHandle {
    let mut config = HubConfig::new(SocketAddr::from(([127, 0, 0, 1], 0)));
    adjust(&mut config);
    canopener_hub::spawn(config).expect("hub starts on a free port")
}

/// One `recv(256)` as python-can does it, as text.
pub fn recv_once(stream: &mut TcpStream) -> io::Result<String> {
    let mut buf = [0u8; 256];
    let n = stream.read(&mut buf)?;
    Ok(String::from_utf8_lossy(&buf[..n]).into_owned())
}

/// python-can's handshake, step by step; `Err` says which reply was wrong.
pub fn handshake(addr: SocketAddr, bus: &str) -> Result<TcpStream, String> {
    let mut stream = TcpStream::connect(addr).map_err(|e| format!("connect: {e}"))?;
    stream
        .set_read_timeout(Some(READ_TIMEOUT))
        .map_err(|e| e.to_string())?;
    stream.set_nodelay(true).map_err(|e| e.to_string())?;
    expect_reply(&mut stream, "< hi >")?;
    stream
        .write_all(format!("< open {bus} >").as_bytes())
        .map_err(|e| e.to_string())?;
    expect_reply(&mut stream, "< ok >")?;
    stream.write_all(b"< rawmode >").map_err(|e| e.to_string())?;
    expect_reply(&mut stream, "< ok >")?;
    Ok(stream)
}

fn expect_reply(stream: &mut TcpStream, expected: &str) -> Result<(), String> {
    let got = recv_once(stream).map_err(|e| format!("reading {expected}: {e}"))?;
    if got == expected {
        Ok(())
    } else {
        Err(format!("expected {expected:?}, got {got:?}"))
    }
}

/// A raw-mode client.
pub struct TestClient {
    pub stream: TcpStream,
    reader: ElementReader,
    buf: Vec<u8>,
}

impl TestClient {
    /// Connects and completes the python-can handshake, panicking with the reason if it fails.
    pub fn connect(addr: SocketAddr, bus: &str) -> TestClient {
        let stream = handshake(addr, bus).unwrap_or_else(|e| panic!("handshake on {bus}: {e}"));
        TestClient::from_stream(stream)
    }

    pub fn from_stream(stream: TcpStream) -> TestClient {
        TestClient {
            stream,
            reader: ElementReader::new(256),
            buf: vec![0; 64 * 1024],
        }
    }

    /// A second handle on the same socket, for sending from another thread.
    pub fn sender(&self) -> TcpStream {
        self.stream.try_clone().expect("clone socket")
    }

    /// Reads until `count` frames arrived; panics on timeout, EOF or a non-frame message.
    pub fn read_frames(&mut self, count: usize) -> Vec<(CanFrame, Instant)> {
        let mut frames = Vec::with_capacity(count);
        while frames.len() < count {
            while frames.len() < count {
                let Some(element) = self.reader.next_element() else {
                    break;
                };
                let element = element.expect("hub sends well-framed elements");
                match parse_server_message(&element) {
                    Ok(ServerMessage::Frame { frame, timestamp }) => frames.push((frame, timestamp)),
                    other => panic!("expected a frame, got {other:?} from {element:?}"),
                }
            }
            if frames.len() == count {
                break;
            }
            let n = self
                .stream
                .read(&mut self.buf)
                .unwrap_or_else(|e| panic!("reading frame {} of {count}: {e}", frames.len() + 1));
            assert!(
                n > 0,
                "hub closed the connection after {} of {count} frames",
                frames.len()
            );
            self.reader.push(&self.buf[..n]);
        }
        frames
    }

    /// Reads for `window` and returns every frame that arrived.
    pub fn read_for(&mut self, window: Duration) -> Vec<CanFrame> {
        let deadline = StdInstant::now() + window;
        let mut frames = Vec::new();
        loop {
            while let Some(element) = self.reader.next_element() {
                if let Ok(ServerMessage::Frame { frame, .. }) = parse_server_message(&element.unwrap()) {
                    frames.push(frame);
                }
            }
            let left = deadline.saturating_duration_since(StdInstant::now());
            if left.is_zero() {
                return frames;
            }
            self.stream
                .set_read_timeout(Some(left.max(Duration::from_millis(1))))
                .unwrap();
            match self.stream.read(&mut self.buf) {
                Ok(0) => return frames,
                Ok(n) => self.reader.push(&self.buf[..n]),
                Err(e) if matches!(e.kind(), io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut) => {}
                Err(e) => panic!("read failed: {e}"),
            }
            self.stream.set_read_timeout(Some(READ_TIMEOUT)).unwrap();
        }
    }
}

/// A data frame carrying `sequence` in its first four bytes, so order and loss can be checked.
pub fn numbered(id: u16, sequence: u32) -> CanFrame {
    let mut data = [0u8; 8];
    data[..4].copy_from_slice(&sequence.to_le_bytes());
    data[4] = (id & 0xFF) as u8;
    CanFrame::new(CanId::standard(id).unwrap(), &data).unwrap()
}

/// The sequence number written by [`numbered`].
pub fn sequence_of(frame: &CanFrame) -> u32 {
    u32::from_le_bytes(frame.data()[..4].try_into().unwrap())
}

/// Sends `frames` as `< send … >` elements, several per write like a busy client.
pub fn send_all(stream: &mut impl Write, frames: impl IntoIterator<Item = CanFrame>) {
    let mut out = Vec::with_capacity(64 * 1024);
    for frame in frames {
        write_send(&mut out, &frame);
        if out.len() > 60 * 1024 {
            stream.write_all(&out).expect("send frames");
            out.clear();
        }
    }
    stream.write_all(&out).expect("send frames");
}

/// Polls `condition` until it holds or `limit` passes; returns whether it held.
pub fn wait_until(limit: Duration, mut condition: impl FnMut() -> bool) -> bool {
    let deadline = StdInstant::now() + limit;
    while StdInstant::now() < deadline {
        if condition() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    condition()
}
