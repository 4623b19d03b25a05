//! The hub speaks socketcand the way python-can expects: exact handshake bytes, lossless ordered
//! delivery to every other raw client on the bus, isolation between buses, and the raw-mode grace.

#[path = "support/test_client.rs"]
mod test_client;

use std::io::Write;
use std::thread;
use std::time::{Duration, Instant as StdInstant};

use canopener_can::{CanFrame, CanId};
use test_client::{TestClient, handshake, numbered, recv_once, send_all, sequence_of, start_hub, wait_until};

#[test]
fn handshake_replies_are_byte_exact_and_each_arrives_alone() {
    let hub = start_hub(|_| {});
    let mut stream = std::net::TcpStream::connect(hub.local_addr()).unwrap();
    stream.set_read_timeout(Some(test_client::READ_TIMEOUT)).unwrap();
    assert_eq!(recv_once(&mut stream).unwrap(), "< hi >");
    for (command, reply) in [
        ("< open can0 >", "< ok >"),
        ("< echo >", "< echo >"),
        ("< bcmmode >", "< ok >"),
        ("< controlmode >", "< ok >"),
        ("< isotpmode >", "< ok >"),
        ("< rawmode >", "< ok >"),
        ("< echo >", "< echo >"),
    ] {
        stream.write_all(command.as_bytes()).unwrap();
        assert_eq!(recv_once(&mut stream).unwrap(), reply, "reply to {command}");
    }
}

#[test]
fn an_invalid_bus_name_is_refused_and_the_connection_closed() {
    let hub = start_hub(|_| {});
    for name in ["this-name-is-far-too-long", "can/0"] {
        let mut stream = std::net::TcpStream::connect(hub.local_addr()).unwrap();
        stream.set_read_timeout(Some(test_client::READ_TIMEOUT)).unwrap();
        assert_eq!(recv_once(&mut stream).unwrap(), "< hi >");
        stream.write_all(format!("< open {name} >").as_bytes()).unwrap();
        assert_eq!(recv_once(&mut stream).unwrap(), "< error could not open bus >");
        assert_eq!(
            recv_once(&mut stream).unwrap(),
            "",
            "connection must be closed after the refusal"
        );
    }
}

#[test]
fn two_raw_clients_exchange_20000_frames_each_way_lossless_and_ordered() {
    const COUNT: u32 = 20_000;
    let hub = start_hub(|_| {});
    let mut a = TestClient::connect(hub.local_addr(), "can0");
    let mut b = TestClient::connect(hub.local_addr(), "can0");
    let mut a_out = a.sender();
    let mut b_out = b.sender();
    let a_sending = thread::spawn(move || send_all(&mut a_out, (0..COUNT).map(|i| numbered(0x100, i))));
    let b_sending = thread::spawn(move || send_all(&mut b_out, (0..COUNT).map(|i| numbered(0x200, i))));
    let a_reading = thread::spawn(move || a.read_frames(COUNT as usize));
    let b_received = b.read_frames(COUNT as usize);
    let a_received = a_reading.join().unwrap();
    a_sending.join().unwrap();
    b_sending.join().unwrap();
    for (received, id) in [(&a_received, 0x200), (&b_received, 0x100)] {
        for (expected, (frame, _)) in (0..COUNT).zip(received) {
            assert_eq!(
                frame.id(),
                CanId::standard(id).unwrap(),
                "only the other client's frames arrive"
            );
            assert_eq!(
                sequence_of(frame),
                expected,
                "frames arrive complete and in order"
            );
        }
    }
    assert!(
        a_received.windows(2).all(|w| w[0].1 <= w[1].1),
        "hub timestamps never go back"
    );
    let stats = hub.stats();
    assert_eq!(stats.frames_in, 2 * u64::from(COUNT));
    assert!(wait_until(Duration::from_secs(5), || hub.stats().frames_out
        == 2 * u64::from(COUNT)));
}

#[test]
fn a_tiny_client_queue_slows_senders_but_delivers_everything() {
    const COUNT: u32 = 5_000;
    let hub = start_hub(|config| config.client_queue = 1);
    let mut a = TestClient::connect(hub.local_addr(), "can0");
    let mut b = TestClient::connect(hub.local_addr(), "can0");
    let mut a_out = a.sender();
    let sending = thread::spawn(move || send_all(&mut a_out, (0..COUNT).map(|i| numbered(0x100, i))));
    let got: Vec<u32> = b
        .read_frames(COUNT as usize)
        .iter()
        .map(|(f, _)| sequence_of(f))
        .collect();
    sending.join().unwrap();
    assert_eq!(got, (0..COUNT).collect::<Vec<_>>());
    assert_eq!(hub.stats().clients_dropped, 0);
    assert!(a.read_for(Duration::from_millis(50)).is_empty());
}

#[test]
fn a_third_client_sniffs_both_directions_in_the_bus_order() {
    const COUNT: u32 = 3_000;
    let hub = start_hub(|_| {});
    let mut a = TestClient::connect(hub.local_addr(), "can0");
    let mut b = TestClient::connect(hub.local_addr(), "can0");
    let mut sniffer = TestClient::connect(hub.local_addr(), "can0");
    let mut a_out = a.sender();
    let mut b_out = b.sender();
    let a_sending = thread::spawn(move || send_all(&mut a_out, (0..COUNT).map(|i| numbered(0x181, i))));
    let b_sending = thread::spawn(move || send_all(&mut b_out, (0..COUNT).map(|i| numbered(0x201, i))));
    let a_reading = thread::spawn(move || a.read_frames(COUNT as usize));
    let b_reading = thread::spawn(move || b.read_frames(COUNT as usize));
    let seen = sniffer.read_frames(2 * COUNT as usize);
    let a_received = a_reading.join().unwrap();
    let b_received = b_reading.join().unwrap();
    a_sending.join().unwrap();
    b_sending.join().unwrap();
    for id in [0x181u16, 0x201] {
        let from_one: Vec<u32> = seen
            .iter()
            .filter(|(f, _)| f.id() == CanId::standard(id).unwrap())
            .map(|(f, _)| sequence_of(f))
            .collect();
        assert_eq!(
            from_one,
            (0..COUNT).collect::<Vec<_>>(),
            "sniffer sees every frame of {id:X} in order"
        );
    }
    // One total order per bus: what A and B received appears in the sniffer's stream in the same order.
    let sniffer_order: Vec<CanFrame> = seen.iter().map(|(f, _)| *f).collect();
    let a_order: Vec<CanFrame> = a_received.iter().map(|(f, _)| *f).collect();
    let b_order: Vec<CanFrame> = b_received.iter().map(|(f, _)| *f).collect();
    assert_eq!(
        sniffer_order
            .iter()
            .filter(|f| f.id().as_raw() == 0x201)
            .copied()
            .collect::<Vec<_>>(),
        a_order
    );
    assert_eq!(
        sniffer_order
            .iter()
            .filter(|f| f.id().as_raw() == 0x181)
            .copied()
            .collect::<Vec<_>>(),
        b_order
    );
}

#[test]
fn buses_are_isolated_by_name_and_senders_do_not_hear_themselves() {
    let hub = start_hub(|_| {});
    let mut can0_a = TestClient::connect(hub.local_addr(), "can0");
    let mut can0_b = TestClient::connect(hub.local_addr(), "can0");
    let mut can1 = TestClient::connect(hub.local_addr(), "can1");
    send_all(&mut can0_a.stream, (0..10).map(|i| numbered(0x10, i)));
    send_all(&mut can1.stream, (0..5).map(|i| numbered(0x11, i)));
    let on_can0: Vec<u32> = can0_b
        .read_frames(10)
        .iter()
        .map(|(f, _)| sequence_of(f))
        .collect();
    assert_eq!(on_can0, (0..10).collect::<Vec<_>>());
    let window = Duration::from_millis(300);
    let can1_heard = can1.read_for(window);
    assert!(
        can1_heard.is_empty(),
        "can1 must not see can0 traffic or its own: {can1_heard:?}"
    );
    let can0_a_heard = can0_a.read_for(window);
    assert!(
        can0_a_heard.is_empty(),
        "no self-delivery and no can1 traffic: {can0_a_heard:?}"
    );
    assert!(can0_b.read_for(window).is_empty(), "can1 traffic stays on can1");
}

#[test]
fn echo_mode_returns_frames_to_their_sender() {
    let hub = start_hub(|config| config.echo = true);
    let mut a = TestClient::connect(hub.local_addr(), "can0");
    send_all(&mut a.stream, (0..3).map(|i| numbered(0x55, i)));
    let own: Vec<u32> = a.read_frames(3).iter().map(|(f, _)| sequence_of(f)).collect();
    assert_eq!(own, [0, 1, 2]);
}

#[test]
fn bcm_mode_clients_receive_nothing_but_may_send() {
    let hub = start_hub(|_| {});
    let mut raw = TestClient::connect(hub.local_addr(), "can0");
    let mut bcm = std::net::TcpStream::connect(hub.local_addr()).unwrap();
    bcm.set_read_timeout(Some(Duration::from_millis(300))).unwrap();
    assert_eq!(recv_once(&mut bcm).unwrap(), "< hi >");
    bcm.write_all(b"< open can0 >").unwrap();
    assert_eq!(recv_once(&mut bcm).unwrap(), "< ok >");
    send_all(&mut raw.sender(), [numbered(0x1, 1)]);
    bcm.write_all(b"< send 002 1 ff >").unwrap();
    let got = raw.read_frames(1);
    assert_eq!(
        got[0].0,
        CanFrame::new(CanId::standard(2).unwrap(), &[0xFF]).unwrap()
    );
    let leaked = recv_once(&mut bcm);
    assert!(
        leaked.is_err(),
        "a BCM-mode client gets no frames, got {leaked:?}"
    );
}

#[test]
fn frames_sent_during_the_raw_grace_are_held_back_then_all_delivered_in_order() {
    let grace = Duration::from_millis(300);
    let hub = start_hub(|config| config.raw_grace = grace);
    let mut sender = TestClient::connect(hub.local_addr(), "can0");
    let mut stream = std::net::TcpStream::connect(hub.local_addr()).unwrap();
    stream.set_read_timeout(Some(test_client::READ_TIMEOUT)).unwrap();
    assert_eq!(recv_once(&mut stream).unwrap(), "< hi >");
    stream.write_all(b"< open can0 >").unwrap();
    assert_eq!(recv_once(&mut stream).unwrap(), "< ok >");
    stream.write_all(b"< rawmode >").unwrap();
    assert_eq!(
        recv_once(&mut stream).unwrap(),
        "< ok >",
        "the raw-mode reply arrives alone"
    );
    let ok_at = StdInstant::now();
    // The hub subscribed the receiver before it wrote `< ok >`, so all of these are for it.
    send_all(&mut sender.stream, (0..500).map(|i| numbered(0x42, i)));
    let mut receiver = TestClient::from_stream(stream);
    let frames = receiver.read_frames(500);
    let first_after = ok_at.elapsed();
    assert!(
        first_after >= grace - Duration::from_millis(50),
        "frames must wait for the grace ({grace:?}), first arrived after {first_after:?}"
    );
    let sequence: Vec<u32> = frames.iter().map(|(f, _)| sequence_of(f)).collect();
    assert_eq!(sequence, (0..500).collect::<Vec<_>>());
    assert!(sender.read_for(Duration::from_millis(50)).is_empty());
}

#[test]
fn remote_frames_travel_as_rtr_and_python_can_remote_shape_is_understood() {
    let hub = start_hub(|_| {});
    let mut a = TestClient::connect(hub.local_addr(), "can0");
    let mut b = TestClient::connect(hub.local_addr(), "can0");
    a.stream
        .write_all(b"< send 701 1  >< sendrtr 12345678 0 >")
        .unwrap();
    let got: Vec<CanFrame> = b.read_frames(2).into_iter().map(|(f, _)| f).collect();
    assert_eq!(
        got,
        [
            CanFrame::remote(CanId::standard(0x701).unwrap(), 1).unwrap(),
            CanFrame::remote(CanId::extended(0x1234_5678).unwrap(), 0).unwrap()
        ]
    );
}

#[test]
fn disconnected_clients_are_cleaned_up() {
    let hub = start_hub(|_| {});
    let mut survivor = TestClient::connect(hub.local_addr(), "can0");
    for _ in 0..20 {
        let mut client = TestClient::connect(hub.local_addr(), "can0");
        client.stream.write_all(b"< send 123 0 >< send 12").unwrap();
    }
    let mut half_open = std::net::TcpStream::connect(hub.local_addr()).unwrap();
    half_open.write_all(b"< open ca").unwrap();
    drop(half_open);
    // The half-open client may close before the hub has even accepted it, so wait for the hub to
    // have seen all 22 connections, not only for the active count to drop.
    assert!(
        wait_until(Duration::from_secs(5), || {
            let stats = hub.stats();
            stats.clients_connected == 22 && stats.clients_active == 1
        }),
        "all 22 clients seen, only the survivor stays connected: {:?}",
        hub.stats()
    );
    assert_eq!(hub.stats().clients_dropped, 0, "leaving is not being dropped");
    assert_eq!(survivor.read_frames(20).len(), 20);
}

#[test]
fn hub_handle_shutdown_closes_clients_and_returns() {
    let hub = start_hub(|_| {});
    let addr = hub.local_addr();
    let mut client = TestClient::connect(addr, "can0");
    let started = StdInstant::now();
    hub.shutdown();
    assert!(
        started.elapsed() < Duration::from_secs(3),
        "shutdown must not hang"
    );
    assert_eq!(
        recv_once(&mut client.stream).unwrap_or_default(),
        "",
        "open connections are closed"
    );
    assert!(handshake(addr, "can0").is_err(), "nothing listens after shutdown");
}
