//! Arbitrary frames and time steps fed to a simulated device (`canopener-device`, CiA 401 I/O on the
//! checker's base EDS): the device must never panic, every timer it asks for must move time forward
//! (no busy loop), what it sends must be valid CAN frames, and afterwards it must still be a working
//! node: an NMT reset node brings the boot-up message and an SDO upload of 1018h:01 is answered.
//!
//! Input: a sequence of operations. Byte `op`:
//! - `op < 0xE0`: a data frame; the CAN-ID comes from a table of the COB-IDs the device listens to
//!   (indexed by `op % 16`, plus the next byte as low bits), the DLC from the next byte, then the data.
//! - `0xE0..=0xEF`: a remote frame on an error-control or TPDO CAN-ID.
//! - `0xF0..=0xFF`: advance time by the next two bytes in milliseconds, running every due timer.

#![no_main]

use canopener_can::Core;
use canopener_can::{CanFrame, CanId, Instant, StandardId};
use canopener_device::cia401::{Cia401Io, install_objects};
use canopener_device::device::Device;
use canopener_device::od_build::build_od;
use libfuzzer_sys::fuzz_target;

const EDS: &[u8] = include_bytes!("../../crates/canopener-check/test_data/checks/base.eds");
const NODE: u8 = 5;
/// Timers one advance may run: far more than any legitimate schedule needs in 65 s (the fastest
/// periodic service, a 1 ms heartbeat or event timer, would need 65 536 runs per service).
const MAX_TIMERS_PER_ADVANCE: usize = 1_000_000;

/// CAN-ID bases the device's cores listen to; the low bits come from the input.
const BASES: [u16; 16] = [
    0x000, 0x080, 0x100, 0x200, 0x300, 0x400, 0x500, 0x600, 0x700, 0x7E5, 0x7E4, 0x180, 0x580, 0x080, 0x600,
    0x000,
];

fn device() -> Device {
    let eds = canopener_eds::load(EDS).eds;
    let mut built = build_od(&eds, NODE).expect("base.eds builds");
    install_objects(&mut built.od, NODE).expect("CiA 401 objects install");
    let mut device = Device::new(built.od, NODE, Box::new(Cia401Io::new())).expect("device");
    device.boot(Instant::ZERO);
    device
}

struct Run {
    device: Device,
    now: Instant,
    sent: Vec<CanFrame>,
}

impl Run {
    fn drain(&mut self) {
        while let Some(frame) = self.device.poll_transmit() {
            assert!(frame.data().len() <= 8, "{frame}");
            self.sent.push(frame);
        }
        while self.device.poll_event().is_some() {}
        if self.sent.len() > 100_000 {
            self.sent.clear();
        }
    }

    fn advance(&mut self, ms: u64) {
        let until = self.now + std::time::Duration::from_millis(ms);
        let mut runs = 0;
        while let Some(due) = self.device.poll_timeout() {
            if due > until {
                break;
            }
            let at = due.max(self.now);
            self.now = at;
            self.device.handle_timeout(at);
            self.drain();
            runs += 1;
            assert!(
                runs < MAX_TIMERS_PER_ADVANCE,
                "the device asks for timers without end at {at:?}"
            );
        }
        self.now = until;
    }

    fn frame(&mut self, frame: &CanFrame) {
        self.device.handle_frame(self.now, frame);
        self.drain();
    }
}

fuzz_target!(|data: &[u8]| {
    let mut run = Run {
        device: device(),
        now: Instant::ZERO,
        sent: Vec::new(),
    };
    run.drain();
    let mut input = data.iter().copied();
    while let Some(op) = input.next() {
        match op {
            0x00..=0xDF => {
                let low = u16::from(input.next().unwrap_or(NODE));
                let id = (BASES[usize::from(op % 16)] + (low & 0x7F)).min(0x7FF);
                let dlc = usize::from(input.next().unwrap_or(8) % 9);
                let bytes: Vec<u8> = input.by_ref().take(dlc).collect();
                let Some(id) = StandardId::new(id) else { continue };
                if let Ok(frame) = CanFrame::new(id, &bytes) {
                    run.frame(&frame);
                }
            }
            0xE0..=0xEF => {
                let base = if op & 1 == 0 { 0x700 } else { 0x180 };
                let id = base + u16::from(input.next().unwrap_or(NODE) & 0x7F);
                if let Some(frame) =
                    StandardId::new(id).and_then(|id| CanFrame::remote(CanId::from(id), 0).ok())
                {
                    run.frame(&frame);
                }
            }
            0xF0..=0xFF => {
                let ms = u16::from_le_bytes([input.next().unwrap_or(1), input.next().unwrap_or(0)]);
                run.advance(u64::from(ms));
            }
        }
    }

    // Still a working node? Reset node (to all nodes) must bring it back, with the node-ID LSS may
    // have made pending; unless LSS took the node-ID away.
    run.advance(1);
    if run.device.lss().is_some_and(|lss| lss.is_silent()) {
        // Switching bit rate (CiA 305 activate bit timing): silent by design until the delay ends.
        return;
    }
    run.sent.clear();
    run.frame(&CanFrame::new(StandardId::new(0).unwrap(), &[0x81, 0]).unwrap());
    if !run.device.is_configured() {
        return;
    }
    let node = run.device.node_id().get();
    let boot_up = 0x700 + u32::from(node);
    assert!(
        run.sent
            .iter()
            .any(|f| f.id().as_raw() == boot_up && f.data() == [0]),
        "no boot-up of node {node} after reset node: {:?}",
        run.sent.iter().map(ToString::to_string).collect::<Vec<_>>()
    );
    run.sent.clear();
    let request = StandardId::new(0x600 + u16::from(node)).unwrap();
    run.frame(&CanFrame::new(request, &[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]).unwrap());
    assert!(
        run.sent
            .iter()
            .any(|f| f.id().as_raw() == 0x580 + u32::from(node) && f.data().first() == Some(&0x43)),
        "1018h:01 not answered by node {node} after reset: {:?}",
        run.sent.iter().map(ToString::to_string).collect::<Vec<_>>()
    );
});
