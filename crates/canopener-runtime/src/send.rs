//! Sending a fixed list of frames, repeated, with a pause between any two of them.

use std::time::{Duration, Instant};

use canopener_can::CanFrame;
use canopener_transport::{CanBus, TransportError};

use crate::pacing::sleep_until;
use canopener_link::cancel::Cancel;

/// Sends `frames` in order, the whole list `repeat` times, pausing `gap` between any two frames (also
/// from the last frame of one round to the first of the next). The gap is measured from the previous
/// send, as a person spacing frames by hand would. Returns how many frames were sent before the end or
/// a cancel.
pub fn send_frames(
    bus: &mut dyn CanBus,
    frames: &[CanFrame],
    repeat: u64,
    gap: Duration,
    cancel: &Cancel,
) -> Result<u64, TransportError> {
    let mut sent = 0u64;
    for _ in 0..repeat {
        for frame in frames {
            if cancel.is_cancelled() {
                return Ok(sent);
            }
            if sent > 0 && !gap.is_zero() && !sleep_until(Instant::now().checked_add(gap), cancel) {
                return Ok(sent);
            }
            bus.send(frame)?;
            sent += 1;
        }
    }
    Ok(sent)
}

#[cfg(test)]
mod tests {
    use canopener_can::candump::parse_compact_frame;

    use super::*;
    use crate::test_support::virtual_pair;

    fn received(bus: &mut dyn CanBus) -> Vec<(String, canopener_can::Instant)> {
        let mut seen = Vec::new();
        while let Some(received) = bus.recv(Duration::ZERO).unwrap() {
            seen.push((received.frame.to_string(), received.timestamp));
        }
        seen
    }

    #[test]
    fn repeats_the_list_with_gaps_between_every_two_frames() {
        let (mut sender, mut receiver) = virtual_pair("send-repeat");
        let frames = [
            parse_compact_frame("000#0105").unwrap(),
            parse_compact_frame("701#R").unwrap(),
        ];
        let gap = Duration::from_millis(20);
        let sent = send_frames(&mut *sender, &frames, 2, gap, &Cancel::new()).unwrap();
        assert_eq!(sent, 4);
        let seen = received(&mut *receiver);
        let texts: Vec<&str> = seen.iter().map(|(text, _)| text.as_str()).collect();
        assert_eq!(texts, ["000#0105", "701#R", "000#0105", "701#R"]);
        for pair in seen.windows(2) {
            assert!(pair[1].1.saturating_duration_since(pair[0].1) >= gap, "{seen:?}");
        }
    }

    #[test]
    fn a_cancel_during_a_gap_stops_before_the_next_frame() {
        let (mut sender, mut receiver) = virtual_pair("send-cancel");
        let frames = [parse_compact_frame("123#01").unwrap()];
        let cancel = Cancel::new();
        let canceller = cancel.clone();
        let stopper = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(50));
            canceller.cancel();
        });
        let started = Instant::now();
        let sent = send_frames(&mut *sender, &frames, 5, Duration::from_secs(3600), &cancel).unwrap();
        stopper.join().unwrap();
        assert_eq!(sent, 1);
        assert!(started.elapsed() < Duration::from_secs(5));
        assert_eq!(received(&mut *receiver).len(), 1);
    }
}
