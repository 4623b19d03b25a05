//! The socketcand client against canopener's own hub (`canopener_hub::spawn`) on loopback.

use std::thread;
use std::time::Duration;

use canopener_can::{CanFrame, CanId, StandardId};
use canopener_hub::HubConfig;
use canopener_transport::{BusSpec, CanBus, SocketcandBus, TransportError, WallClock, open};

fn sid(raw: u16) -> CanId {
    StandardId::new(raw).unwrap().into()
}

fn start_hub() -> canopener_hub::HubHandle {
    canopener_hub::spawn(HubConfig::new("127.0.0.1:0".parse().unwrap())).unwrap()
}

fn connect(hub: &canopener_hub::HubHandle, bus: &str) -> Box<dyn CanBus> {
    let spec: BusSpec = format!("socketcand://127.0.0.1:{}/{bus}", hub.local_addr().port())
        .parse()
        .unwrap();
    open(&spec).unwrap()
}

fn recv_frame(bus: &mut dyn CanBus) -> CanFrame {
    bus.recv(Duration::from_secs(5))
        .unwrap()
        .expect("a frame within 5 s")
        .frame
}

#[test]
fn two_clients_exchange_every_frame_kind_with_hub_timestamps() {
    let hub = start_hub();
    let mut a = connect(&hub, "can0");
    let mut b = connect(&hub, "can0");
    let frames = [
        CanFrame::new(sid(0x601), &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).unwrap(),
        CanFrame::new(sid(0x080), &[]).unwrap(),
        CanFrame::remote(sid(0x701), 1).unwrap(),
        CanFrame::new(CanId::extended(0x1AAA_AAAA).unwrap(), &[0x01, 0xF1]).unwrap(),
        CanFrame::remote(CanId::extended(0x0000_0001).unwrap(), 0).unwrap(),
    ];
    // The hub may hold traffic back briefly after rawmode; timestamps are whole microseconds.
    let before = WallClock::now() - Duration::from_micros(1);
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
            received.timestamp >= before && received.timestamp <= WallClock::now(),
            "{received:?}"
        );
    }
    // The hub never echoes a frame to its sender.
    assert_eq!(a.recv(Duration::from_millis(100)).unwrap(), None);
    b.send(&frames[0]).unwrap();
    assert_eq!(recv_frame(a.as_mut()), frames[0]);
    hub.shutdown();
}

#[test]
fn buses_of_different_names_are_separate() {
    let hub = start_hub();
    let mut can0 = connect(&hub, "can0");
    let mut can1 = connect(&hub, "can1");
    let mut can1_peer = connect(&hub, "can1");
    can0.send(&CanFrame::new(sid(0x123), &[1]).unwrap()).unwrap();
    can1_peer.send(&CanFrame::new(sid(0x456), &[2]).unwrap()).unwrap();
    assert_eq!(
        recv_frame(can1.as_mut()),
        CanFrame::new(sid(0x456), &[2]).unwrap()
    );
    assert_eq!(can1.recv(Duration::from_millis(100)).unwrap(), None);
    hub.shutdown();
}

#[test]
fn ten_thousand_frames_arrive_complete_and_in_order() {
    const COUNT: u32 = 10_000;
    let hub = start_hub();
    let mut sender = connect(&hub, "flood");
    let mut receiver = connect(&hub, "flood");
    let sending = thread::spawn(move || {
        for n in 0..COUNT {
            sender
                .send(&CanFrame::new(sid(0x181), &n.to_le_bytes()).unwrap())
                .unwrap();
        }
        sender
    });
    for n in 0..COUNT {
        let frame = recv_frame(receiver.as_mut());
        assert_eq!(frame.data(), n.to_le_bytes(), "frame {n} out of order or lost");
    }
    let _sender = sending.join().unwrap();
    assert_eq!(receiver.recv(Duration::from_millis(50)).unwrap(), None);
    hub.shutdown();
}

#[test]
fn hub_shutdown_is_reported_not_a_hang() {
    let hub = start_hub();
    let port = hub.local_addr().port();
    let mut client = SocketcandBus::connect("127.0.0.1", port, "can0").unwrap();
    hub.shutdown();
    let started = std::time::Instant::now();
    let err = match client.recv(Duration::from_secs(5)) {
        Err(err) => err,
        Ok(None) => panic!("no error within 5 s after the hub stopped"),
        Ok(Some(received)) => panic!("unexpected frame {received:?}"),
    };
    assert!(started.elapsed() < Duration::from_secs(5));
    assert!(matches!(err, TransportError::Closed { .. }), "{err:?}");
    assert!(
        err.to_string()
            .contains(&format!("socketcand://127.0.0.1:{port}/can0")),
        "{err}"
    );
}

#[test]
fn frames_sent_just_before_closing_arrive_although_traffic_was_left_unread() {
    // A small queue and a long stall timeout: while the watcher does not read, the hub holds the
    // sender back, so the one-shot client's last frames are still in its socket when it closes.
    let mut config = HubConfig::new("127.0.0.1:0".parse().unwrap());
    config.client_queue = 64;
    config.stall_timeout = Duration::from_secs(30);
    let hub = canopener_hub::spawn(config).unwrap();
    let mut watcher = connect(&hub, "can0");
    let mut one_shot = connect(&hub, "can0");
    let mut chatter = connect(&hub, "can0");
    // Traffic the one-shot client never reads sits in its receive buffer when it closes.
    for _ in 0..50 {
        chatter
            .send(&CanFrame::new(sid(0x700), &[0x05]).unwrap())
            .unwrap();
    }
    thread::sleep(Duration::from_millis(100));
    const COUNT: u16 = 2000;
    let sender = thread::spawn(move || {
        for n in 0..COUNT {
            one_shot
                .send(&CanFrame::new(sid(0x100), &n.to_le_bytes()).unwrap())
                .unwrap();
        }
        // Closing must still deliver every frame it sent.
        drop(one_shot);
    });
    thread::sleep(Duration::from_millis(300));
    let mut next = 0u16;
    while next < COUNT {
        let frame = recv_frame(&mut *watcher);
        if frame.id() == sid(0x100) {
            assert_eq!(frame.data(), next.to_le_bytes(), "frames in order, none lost");
            next += 1;
        }
    }
    sender.join().unwrap();
}
