//! Misbehaving clients never disturb good ones: garbage, half elements, over-long elements, floods
//! and clients that stop reading, plus reconnect storms while the bus is flooded.

#[path = "support/test_client.rs"]
mod test_client;

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::{self, JoinHandle};
use std::time::Duration;

use canopener_can::{CanFrame, CanId};
use socket2::{Domain, Socket, Type};
use test_client::{TestClient, handshake, numbered, recv_once, send_all, sequence_of, start_hub, wait_until};

/// CAN ids of the two well-behaved clients; everything else on the bus is noise to them.
const GOOD_A: u16 = 0x181;
const GOOD_B: u16 = 0x201;
const FLOOD_ID: u16 = 0x7FE;

/// A raw client whose receive buffer is tiny, so that not reading fills the hub's queue quickly.
fn connect_with_small_receive_buffer(addr: SocketAddr, bus: &str) -> TcpStream {
    let socket = Socket::new(Domain::IPV4, Type::STREAM, None).unwrap();
    socket.set_recv_buffer_size(4096).unwrap();
    socket.connect(&addr.into()).unwrap();
    let mut stream: TcpStream = socket.into();
    stream.set_read_timeout(Some(test_client::READ_TIMEOUT)).unwrap();
    assert_eq!(recv_once(&mut stream).unwrap(), "< hi >");
    stream.write_all(format!("< open {bus} >").as_bytes()).unwrap();
    assert_eq!(recv_once(&mut stream).unwrap(), "< ok >");
    stream.write_all(b"< rawmode >").unwrap();
    assert_eq!(recv_once(&mut stream).unwrap(), "< ok >");
    stream
}

/// Deterministic noise: an xorshift generator, with extra `<`, `>` and spaces so the framer works.
fn noise(len: usize, seed: u64) -> Vec<u8> {
    let mut state = seed | 1;
    (0..len)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            match state % 16 {
                0 => b'<',
                1 => b'>',
                2 => b' ',
                _ => (state >> 8) as u8,
            }
        })
        .collect()
}

/// Reads until `count` frames with `id` arrived, skipping everyone else's traffic.
fn read_from(client: &mut TestClient, id: u16, count: usize) -> Vec<u32> {
    let wanted = CanId::standard(id).unwrap();
    let mut sequences = Vec::with_capacity(count);
    // Other clients' traffic keeps arriving, so a read timeout alone would never fire if the frames
    // we wait for stopped: bound the whole wait instead.
    let deadline = std::time::Instant::now() + Duration::from_secs(120);
    while sequences.len() < count {
        assert!(
            std::time::Instant::now() < deadline,
            "only {} of {count} frames from {id:03X} arrived within 120 s",
            sequences.len()
        );
        for (frame, _) in client.read_frames(1) {
            if frame.id() == wanted {
                sequences.push(sequence_of(&frame));
            }
        }
    }
    sequences
}

/// Runs `body` in a loop on a thread until `stop` is set.
fn until_stopped(stop: &Arc<AtomicBool>, mut body: impl FnMut() -> bool + Send + 'static) -> JoinHandle<()> {
    let stop = Arc::clone(stop);
    thread::spawn(move || {
        while !stop.load(Ordering::Relaxed) {
            if !body() {
                break;
            }
        }
    })
}

#[test]
fn good_clients_get_every_frame_in_order_while_others_misbehave() {
    const COUNT: u32 = 20_000;
    // A stall timeout that outlasts a good reader's scheduling hiccups on a loaded 2-core machine;
    // the non-reader is still dropped well within the 20 s wait below.
    let hub = start_hub(|config| {
        config.stall_timeout = Duration::from_secs(3);
        config.client_queue = 1024;
    });
    let addr = hub.local_addr();
    let stop = Arc::new(AtomicBool::new(false));
    let mut background = Vec::new();

    // Never reads: must be dropped once its queue stays full.
    let non_reader = connect_with_small_receive_buffer(addr, "can0");

    // Garbage before any handshake, and garbage from a raw client, both without end.
    let mut seed = 1;
    let mut garbage_early = TcpStream::connect(addr).unwrap();
    background.push(until_stopped(&stop, move || {
        seed += 1;
        garbage_early.write_all(&noise(8192, seed)).is_ok()
    }));
    let mut garbage_raw = TestClient::connect(addr, "can0").sender();
    let mut drain = garbage_raw.try_clone().unwrap();
    background.push(thread::spawn(move || {
        while matches!(drain.read(&mut [0; 65536]), Ok(n) if n > 0) {}
    }));
    let mut raw_seed = 1000;
    background.push(until_stopped(&stop, move || {
        raw_seed += 1;
        garbage_raw.write_all(&noise(8192, raw_seed)).is_ok()
    }));

    // Over-long elements, each followed by a valid frame that must still get through.
    let mut over_long = TestClient::connect(addr, "can0").sender();
    let mut drain = over_long.try_clone().unwrap();
    background.push(thread::spawn(move || {
        while matches!(drain.read(&mut [0; 65536]), Ok(n) if n > 0) {}
    }));
    background.push(until_stopped(&stop, move || {
        let mut element = b"< send 123 8 ".to_vec();
        element.extend(std::iter::repeat_n(b'a', 10_000));
        element.extend_from_slice(b" >< send 7FD 0 >");
        over_long.write_all(&element).is_ok()
    }));

    // Half elements, then disconnect, over and over.
    background.push(until_stopped(&stop, move || {
        if let Ok(mut stream) = handshake(addr, "can0") {
            let _ = stream.write_all(b"< send 123 8 11 22 3");
        }
        true
    }));

    // A healthy client flooding the bus with valid frames as fast as the hub lets it.
    let mut flooder = TestClient::connect(addr, "can0").sender();
    let mut drain = flooder.try_clone().unwrap();
    background.push(thread::spawn(move || {
        while matches!(drain.read(&mut [0; 65536]), Ok(n) if n > 0) {}
    }));
    let mut flood_sequence = 0u32;
    background.push(until_stopped(&stop, move || {
        let mut out = Vec::new();
        for _ in 0..500 {
            canopener_socketcand::write_send(&mut out, &numbered(FLOOD_ID, flood_sequence));
            flood_sequence = flood_sequence.wrapping_add(1);
        }
        // Paced at about 100 000 frames/s: far more than a bus carries, yet leaving the good readers
        // headroom. Unpaced, the flood kept every queue full, so a reader starved of CPU for one stall
        // timeout on a loaded machine was rightly dropped and the test hung waiting for its frames.
        thread::sleep(Duration::from_millis(5));
        flooder.write_all(&out).is_ok()
    }));

    // The two good clients exchange their frames through all of that.
    let mut a = TestClient::connect(addr, "can0");
    let mut b = TestClient::connect(addr, "can0");
    let mut a_out = a.sender();
    let mut b_out = b.sender();
    // Every handle on A's socket is handed back and kept open until B has read all of A's frames:
    // closing a socket whose receive buffer still holds unread flood traffic makes the kernel send a
    // reset and discard what A had not sent yet, which is the test losing frames, not the hub.
    let a_sending = thread::spawn(move || {
        send_all(&mut a_out, (0..COUNT).map(|i| numbered(GOOD_A, i)));
        a_out
    });
    let b_sending = thread::spawn(move || {
        send_all(&mut b_out, (0..COUNT).map(|i| numbered(GOOD_B, i)));
        b_out
    });
    let a_reading = thread::spawn(move || (read_from(&mut a, GOOD_B, COUNT as usize), a));
    let b_got = read_from(&mut b, GOOD_A, COUNT as usize);
    let (a_got, _a) = a_reading.join().unwrap();
    let _a_out = a_sending.join().unwrap();
    let _b_out = b_sending.join().unwrap();
    assert_eq!(
        a_got,
        (0..COUNT).collect::<Vec<_>>(),
        "A got all of B's frames in order"
    );
    assert_eq!(
        b_got,
        (0..COUNT).collect::<Vec<_>>(),
        "B got all of A's frames in order"
    );

    assert!(
        wait_until(Duration::from_secs(20), || hub.stats().clients_dropped >= 1),
        "the non-reading client must be dropped: {:?}",
        hub.stats()
    );
    stop.store(true, Ordering::Relaxed);
    let stats = hub.stats();
    assert!(stats.garbage_elements > 0, "garbage was counted: {stats:?}");
    assert!(
        stats.discarded_bytes > 0,
        "bytes outside elements were counted: {stats:?}"
    );
    assert!(
        stats.frames_in > 2 * u64::from(COUNT),
        "the flood really flowed: {stats:?}"
    );

    // The non-reader's connection was closed by the hub: draining it ends in EOF or a reset.
    let mut non_reader = non_reader;
    let mut closed = false;
    for _ in 0..100_000 {
        match non_reader.read(&mut [0; 65536]) {
            Ok(0) | Err(_) => {
                closed = true;
                break;
            }
            Ok(_) => {}
        }
    }
    assert!(closed, "the dropped client's socket is closed");
    drop(hub);
    for handle in background {
        handle.join().unwrap();
    }
}

#[test]
fn a_client_that_never_reads_its_replies_is_dropped() {
    let hub = start_hub(|config| {
        config.stall_timeout = Duration::from_millis(300);
        config.client_queue = 16;
    });
    let mut stream = connect_with_small_receive_buffer(hub.local_addr(), "can0");
    let echoes = b"< echo >".repeat(2_000_000);
    // The hub stops reading from us while our replies pile up, so this write may fail or block;
    // either way the hub must drop us.
    let writer = thread::spawn(move || {
        let _ = stream.write_all(&echoes);
        stream
    });
    assert!(
        wait_until(Duration::from_secs(10), || hub.stats().clients_dropped == 1),
        "{:?}",
        hub.stats()
    );
    let _ = writer.join();
    assert!(wait_until(Duration::from_secs(5), || hub.stats().clients_active == 0));
}

#[test]
fn reconnect_loop_under_a_flood_has_zero_handshake_failures() {
    const RECONNECTS: usize = 100;
    let hub = start_hub(|_| {});
    let addr = hub.local_addr();
    let stop = Arc::new(AtomicBool::new(false));
    let flooded = Arc::new(AtomicU64::new(0));
    let mut flooder = TestClient::connect(addr, "can0").sender();
    let mut drain = flooder.try_clone().unwrap();
    let drainer = thread::spawn(move || while matches!(drain.read(&mut [0; 65536]), Ok(n) if n > 0) {});
    let flooded_count = Arc::clone(&flooded);
    let mut sequence = 0;
    let flood = until_stopped(&stop, move || {
        let mut out = Vec::new();
        for _ in 0..100 {
            canopener_socketcand::write_send(&mut out, &numbered(FLOOD_ID, sequence));
            sequence += 1;
        }
        flooded_count.fetch_add(100, Ordering::Relaxed);
        flooder.write_all(&out).is_ok()
    });
    assert!(wait_until(Duration::from_secs(5), || flooded
        .load(Ordering::Relaxed)
        > 1000));

    let mut failures = Vec::new();
    let mut saw_traffic = 0;
    for attempt in 0..RECONNECTS {
        match handshake(addr, "can0") {
            Ok(mut stream) => {
                // After the handshake the flood reaches the new client, proving it was flowing.
                if recv_once(&mut stream).is_ok_and(|text| text.starts_with("< frame ")) {
                    saw_traffic += 1;
                }
            }
            Err(reason) => failures.push(format!("attempt {attempt}: {reason}")),
        }
    }
    stop.store(true, Ordering::Relaxed);
    flood.join().unwrap();
    drop(hub);
    drainer.join().unwrap();
    assert!(
        failures.is_empty(),
        "{} handshake failures: {failures:?}",
        failures.len()
    );
    assert!(
        saw_traffic > RECONNECTS / 2,
        "the bus was flooded during the handshakes ({saw_traffic})"
    );
}

#[test]
fn a_frame_split_across_many_writes_still_arrives() {
    let hub = start_hub(|_| {});
    let mut a = TestClient::connect(hub.local_addr(), "can0");
    let mut b = TestClient::connect(hub.local_addr(), "can0");
    for byte in b"junk< send 601 8 40 0 10 0 0 0 0 0 >" {
        a.stream.write_all(&[*byte]).unwrap();
        thread::sleep(Duration::from_millis(1));
    }
    let (frame, _) = b.read_frames(1)[0];
    assert_eq!(
        frame,
        CanFrame::new(CanId::standard(0x601).unwrap(), &[0x40, 0, 0x10, 0, 0, 0, 0, 0]).unwrap()
    );
    assert_eq!(hub.stats().discarded_bytes, 4);
}
