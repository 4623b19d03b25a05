//! The real-time bit-accurate virtual bus keeps a saturated 1 Mbit/s bus at its exact theoretical
//! frame rate, both on the simulated timeline (receive timestamps) and in wall-clock time.
//!
//! This is its own test binary so that no other test competes for the two CPU cores while it runs.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread;
use std::time::Duration;

use canopener_can::bits::frame_bits;
use canopener_can::{Bitrate, CanFrame, StandardId};
use canopener_transport::{CanBus, VirtualBus, VirtualOptions, WallClock};

const WARM_UP: Duration = Duration::from_millis(200);
const MEASURE: Duration = Duration::from_millis(1500);

#[test]
fn saturated_1_mbit_bus_delivers_the_theoretical_frame_rate() {
    let bitrate = Bitrate::M1;
    // A DLC-8 TPDO as CANopen devices send them; its stuffed length is exact, not an estimate.
    let frame = CanFrame::new(
        StandardId::new(0x181).unwrap(),
        &[0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0xDE, 0xF0],
    )
    .unwrap();
    let bits = frame_bits(&frame).total;
    let theoretical = f64::from(bitrate.bits_per_second()) / f64::from(bits);

    // 1024 queued frames are 115 ms of bus time: a sender thread descheduled for less than that
    // on a busy machine still keeps the bus saturated.
    let options = VirtualOptions {
        tx_queue_len: 1024,
        ..VirtualOptions::default()
    };
    let mut sender = VirtualBus::open_with("saturation", Some(bitrate), options).unwrap();
    let mut receiver = VirtualBus::open("saturation", Some(bitrate)).unwrap();
    let stop = Arc::new(AtomicBool::new(false));
    let sender_stop = Arc::clone(&stop);
    let sender_thread = thread::spawn(move || {
        let mut sent = 0u64;
        // `send` blocks while the transmit queue is full, so this keeps the bus saturated without
        // spinning.
        while !sender_stop.load(Ordering::Relaxed) {
            sender.send(&frame).unwrap();
            sent += 1;
        }
        sent
    });

    let started = std::time::Instant::now();
    let mut window = Vec::new();
    while started.elapsed() < WARM_UP + MEASURE {
        let received = receiver
            .recv(Duration::from_secs(1))
            .unwrap()
            .expect("the bus stalled");
        assert_eq!(received.frame, frame);
        if started.elapsed() >= WARM_UP {
            window.push((received.timestamp, WallClock::now()));
        }
    }
    stop.store(true, Ordering::Relaxed);
    let sent = sender_thread.join().unwrap();

    let (first, last) = (window[0], window[window.len() - 1]);
    let intervals = (window.len() - 1) as f64;
    let bus_rate = intervals / (last.0 - first.0).as_secs_f64();
    let wall_rate = intervals / (last.1 - first.1).as_secs_f64();
    println!(
        "{bits}-bit frames at {bitrate}: theoretical {theoretical:.1} frames/s, on the bus timeline \
         {bus_rate:.1} frames/s, received in wall-clock time {wall_rate:.1} frames/s ({} frames measured, \
         {sent} sent)",
        window.len()
    );
    // Every frame follows the previous one after exactly its own length: no idle gaps.
    for pair in window.windows(2) {
        assert_eq!(pair[1].0 - pair[0].0, bitrate.frame_duration(&frame));
    }
    assert!(
        (bus_rate / theoretical - 1.0).abs() < 0.01,
        "bus timeline rate {bus_rate} vs {theoretical}"
    );
    assert!(
        (wall_rate / theoretical - 1.0).abs() < 0.01,
        "wall-clock rate {wall_rate} vs {theoretical}"
    );
}
