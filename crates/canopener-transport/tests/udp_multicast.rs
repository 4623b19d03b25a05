//! Two Rust udp-multicast endpoints and a raw python-can-style peer on one multicast group.
//!
//! The test re-runs itself inside a fresh network namespace (`unshare --net`) whose only interface
//! is loopback with a multicast route (`ip route add 224.0.0.0/4 dev lo`, interop reference §1), so
//! no datagram leaves the machine and parallel runs cannot hear each other. Where the kernel or
//! the sandbox forbids creating a network namespace, the test says so and why, and does nothing,
//! unless `CANOPENER_REQUIRE_NETNS` is set (as CI does): then that is a failure.

// Says on the test output why a test could not run here (no network namespace).
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::net::{IpAddr, Ipv4Addr, SocketAddr, UdpSocket};
use std::process::Command;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

use canopener_can::{CanFrame, CanId, Instant, StandardId};
use canopener_transport::multicast_wire;
use canopener_transport::{BusSpec, CanBus, UdpMulticastBus, open};

const IN_NETNS: &str = "CANOPENER_TEST_IN_NETNS";
const REQUIRE_NETNS: &str = "CANOPENER_REQUIRE_NETNS";
const SETUP: &str = "ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec \"$0\" \"$@\"";

fn sid(raw: u16) -> CanId {
    StandardId::new(raw).unwrap().into()
}

/// Runs `test` inside a private network namespace, re-executing this test binary there.
fn in_private_netns(test_name: &str, test: fn()) {
    if std::env::var_os(IN_NETNS).is_some() {
        test();
        return;
    }
    let probe = Command::new("unshare").args(["--net", "true"]).output();
    let unavailable = match probe {
        Ok(output) if output.status.success() => None,
        Ok(output) => Some(format!(
            "cannot create a network namespace (unshare --net: {}); the test needs one so that \
             multicast stays on a private loopback",
            String::from_utf8_lossy(&output.stderr).trim()
        )),
        Err(err) => Some(format!(
            "`unshare` is not available ({err}); it comes with util-linux"
        )),
    };
    if let Some(reason) = unavailable {
        assert!(
            std::env::var_os(REQUIRE_NETNS).is_none(),
            "{test_name} must run ({REQUIRE_NETNS} is set): {reason}"
        );
        println!("skipping {test_name}: {reason}");
        return;
    }
    let exe = std::env::current_exe().unwrap();
    let output = Command::new("unshare")
        .args(["--net", "sh", "-c", SETUP])
        .arg(exe)
        .args(["--exact", test_name, "--nocapture", "--test-threads=1"])
        .env(IN_NETNS, "1")
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{test_name} failed inside the network namespace ({}):\n{}\n{}",
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
}

/// A group and port unlikely to be shared with a parallel run, even outside a namespace.
fn private_group_and_port() -> (IpAddr, u16) {
    let seed = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .subsec_nanos()
        ^ std::process::id();
    let [a, b, c, _] = seed.to_le_bytes();
    (
        IpAddr::V4(Ipv4Addr::new(239, 200, a, b.max(1))),
        40_000 + u16::from(c) * 64 % 20_000,
    )
}

/// A socket set up exactly as python-can's `UdpMulticastBus` sets up its only socket.
fn python_can_socket(group: IpAddr, port: u16) -> UdpSocket {
    use socket2::{Domain, Protocol, Socket, Type};
    let IpAddr::V4(group) = group else {
        unreachable!("the test uses IPv4 groups")
    };
    let socket = Socket::new(Domain::IPV4, Type::DGRAM, Some(Protocol::UDP)).unwrap();
    socket.set_reuse_address(true).unwrap();
    socket.set_reuse_port(true).unwrap();
    socket
        .bind(&SocketAddr::new(Ipv4Addr::UNSPECIFIED.into(), port).into())
        .unwrap();
    socket.join_multicast_v4(&group, &Ipv4Addr::UNSPECIFIED).unwrap();
    socket.set_multicast_ttl_v4(1).unwrap();
    socket.set_read_timeout(Some(Duration::from_millis(300))).unwrap();
    socket.into()
}

fn recv_frame(bus: &mut dyn CanBus) -> CanFrame {
    bus.recv(Duration::from_secs(5))
        .unwrap()
        .expect("a frame within 5 s")
        .frame
}

#[test]
fn two_endpoints_and_a_python_can_style_peer_exchange_frames() {
    in_private_netns(
        "two_endpoints_and_a_python_can_style_peer_exchange_frames",
        || {
            let (group, port) = private_group_and_port();
            let spec = BusSpec::UdpMulticast { group, port };
            let mut a = open(&spec).unwrap();
            let mut b = UdpMulticastBus::open(group, port).unwrap();

            let frames = [
                CanFrame::new(sid(0x601), &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).unwrap(),
                CanFrame::remote(sid(0x701), 1).unwrap(),
                CanFrame::new(CanId::extended(0x1AAA_AAAA).unwrap(), &[0x01, 0xF1]).unwrap(),
                CanFrame::new(sid(0x000), &[]).unwrap(),
            ];
            let before = canopener_transport::WallClock::now();
            for frame in &frames {
                a.send(frame).unwrap();
            }
            for frame in &frames {
                let received = b
                    .recv(Duration::from_secs(5))
                    .unwrap()
                    .expect("a frame within 5 s");
                assert_eq!(&received.frame, frame);
                assert!(
                    received.timestamp >= before,
                    "{:?} < {before:?}",
                    received.timestamp
                );
            }
            // The sender does not hear itself, although multicast loopback delivered the datagrams.
            assert_eq!(a.recv(Duration::from_millis(100)).unwrap(), None);
            b.send(&frames[0]).unwrap();
            assert_eq!(recv_frame(a.as_mut()), frames[0]);
            assert_eq!(b.recv(Duration::from_millis(100)).unwrap(), None);

            // A python-can peer: one socket bound to the group port, used for sending and receiving.
            let peer = python_can_socket(group, port);
            let destination = SocketAddr::new(group, port);
            let python_frame = CanFrame::new(sid(0x181), &[1, 2, 3]).unwrap();
            peer.send_to(b"\xc1 not msgpack", destination).unwrap();
            peer.send_to(&multicast_wire::encode(&python_frame, Instant::ZERO), destination)
                .unwrap();
            assert_eq!(recv_frame(a.as_mut()), python_frame);
            assert_eq!(recv_frame(&mut b), python_frame);
            assert_eq!(b.skipped_datagrams(), 1);
            assert_eq!(a.recv(Duration::ZERO).unwrap(), None);
            // The peer hears our frames (and, like python-can, its own).
            b.send(&frames[2]).unwrap();
            let mut heard = Vec::new();
            let mut buf = [0; 4096];
            while let Ok((len, _)) = peer.recv_from(&mut buf) {
                heard.push(multicast_wire::decode(&buf[..len]));
            }
            assert!(heard.contains(&Ok(frames[2])), "{heard:?}");
            assert!(heard.contains(&Ok(python_frame)), "{heard:?}");
        },
    );
}

#[test]
fn a_burst_within_the_socket_buffer_arrives_complete_and_in_order() {
    in_private_netns(
        "a_burst_within_the_socket_buffer_arrives_complete_and_in_order",
        || {
            let (group, port) = private_group_and_port();
            let mut a = UdpMulticastBus::open(group, port).unwrap();
            let mut b = UdpMulticastBus::open(group, port).unwrap();
            for n in 0..300u16 {
                a.send(&CanFrame::new(sid(0x200), &n.to_be_bytes()).unwrap())
                    .unwrap();
            }
            for n in 0..300u16 {
                assert_eq!(recv_frame(&mut b).data(), n.to_be_bytes());
            }
            assert_eq!(b.recv(Duration::from_millis(50)).unwrap(), None);
        },
    );
}
