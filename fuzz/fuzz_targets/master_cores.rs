//! Arbitrary answers from a "device" to the master-side cores (`canopener-master`): an SDO client in
//! the middle of an upload or download (every protocol), an LSS master scanning for unconfigured
//! nodes, and a node monitor guarding a node. Whatever comes back, no core may panic, every transfer
//! must end (result, failure or timeout) within a bounded time, and no core may ask for a timer in
//! the past.
//!
//! Input: byte 0 picks the SDO transfer (upload/download × normal/expedited/segmented/block) and its
//! size; the rest is a sequence of operations: `op < 0xF0` sends one frame (CAN-ID from a table of
//! the IDs the cores listen to, DLC from the next byte, then the data) to all cores; `0xF0..` lets
//! virtual time pass (the next byte × 10 ms), running due timers.

#![no_main]

use canopener_can::Core;
use std::time::Duration;

use canopener_can::{CanFrame, Instant, StandardId};
use canopener_master::error_control::{ConsumerTime, GuardingConfig, NodeMonitor};
use canopener_master::lss_master::{KnownParts, LssConfig, LssMaster, ScanPlan, node_id_range};
use canopener_master::sdo_client::{DownloadMode, SdoClient, SdoClientEvent, UploadMode};
use canopener_wire::NodeId;
use libfuzzer_sys::fuzz_target;

const NODE: u8 = 5;
/// CAN-IDs the cores listen to: SDO response, LSS slave→master, error control, and a few others.
const IDS: [u16; 8] = [0x585, 0x585, 0x585, 0x7E4, 0x7E4, 0x705, 0x705, 0x085];
/// After the input ends, time enough for every core to give up: SDO 1 s timeout per phase, LSS
/// 100 ms per step (a full scan of 128 steps plus assignment), guarding life time.
const DRAIN: Duration = Duration::from_secs(120);

struct Cores {
    sdo: SdoClient,
    lss: LssMaster,
    monitor: NodeMonitor,
    now: Instant,
    sdo_done: bool,
}

impl Cores {
    fn frame(&mut self, frame: &CanFrame) {
        self.sdo.handle_frame(self.now, frame);
        self.lss.handle_frame(self.now, frame);
        self.monitor.handle_frame(self.now, frame);
        self.drain();
    }

    fn deadline(&self) -> Option<Instant> {
        [
            self.sdo.poll_timeout(),
            self.lss.poll_timeout(),
            self.monitor.poll_timeout(),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    fn advance(&mut self, by: Duration) {
        let until = self.now + by;
        let mut runs = 0u32;
        while let Some(due) = self.deadline() {
            if due > until {
                break;
            }
            assert!(due >= self.now, "a timer in the past: {due:?} < {:?}", self.now);
            self.now = due;
            self.sdo.handle_timeout(due);
            self.lss.handle_timeout(due);
            self.monitor.handle_timeout(due);
            self.drain();
            runs += 1;
            assert!(runs < 1_000_000, "timers without end");
        }
        self.now = until;
    }

    fn drain(&mut self) {
        for frame in std::iter::from_fn(|| self.sdo.poll_transmit()) {
            assert_eq!(
                frame.id().as_raw(),
                0x605,
                "the client only talks on its request COB-ID"
            );
            assert_eq!(frame.data().len(), 8, "SDO requests are 8 bytes");
        }
        while let Some(event) = self.sdo.poll_event() {
            if !matches!(event, SdoClientEvent::Progress { .. }) {
                assert!(!self.sdo_done, "two results for one transfer: {event:?}");
                self.sdo_done = true;
            }
        }
        while self.lss.poll_transmit().is_some() {}
        while self.lss.poll_event().is_some() {}
        while self.monitor.poll_transmit().is_some() {}
        while self.monitor.poll_event().is_some() {}
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&setup, rest)) = data.split_first() else {
        return;
    };
    let now = Instant::ZERO;
    let mut sdo = SdoClient::new(NODE).expect("node 5");
    let size = usize::from(setup >> 3) * 37;
    let payload: Vec<u8> = (0..size).map(|i| i as u8).collect();
    let started = match setup & 0x07 {
        0 => sdo.upload(now, 0x1018, 1, UploadMode::Normal),
        1 => sdo.upload(now, 0x2000, 0, UploadMode::Block),
        2 => sdo.download(now, 0x1017, 0, vec![0xE8, 0x03], DownloadMode::Expedited),
        3 => sdo.download(now, 0x2000, 0, payload, DownloadMode::Segmented),
        4 => sdo.download(now, 0x2000, 0, payload, DownloadMode::Block),
        5 => sdo.download(now, 0x2000, 0, payload, DownloadMode::Auto),
        6 => sdo.upload(now, 0x1008, 0, UploadMode::Block),
        _ => sdo.download(now, 0x2000, 0, Vec::new(), DownloadMode::Segmented),
    };
    let mut lss = LssMaster::new(LssConfig::DEFAULT);
    let first = NodeId::new(10).expect("node-ID");
    let last = NodeId::new(20).expect("node-ID");
    let plan = ScanPlan {
        node_ids: node_id_range(first, last),
        store: setup & 0x80 != 0,
        known: KnownParts::NONE,
    };
    lss.scan_all(now, plan).expect("idle master starts a scan");
    let mut monitor = NodeMonitor::new(ConsumerTime::Learn);
    let guarding = GuardingConfig {
        guard_time: Duration::from_millis(100),
        life_time_factor: 3,
    };
    monitor
        .start_guarding(now, NodeId::new(NODE).expect("node-ID"), guarding)
        .expect("valid guarding");
    let mut cores = Cores {
        sdo,
        lss,
        monitor,
        now,
        sdo_done: started.is_err(),
    };
    cores.drain();

    let mut input = rest.iter().copied();
    while let Some(op) = input.next() {
        if op >= 0xF0 {
            let steps = u64::from(input.next().unwrap_or(1));
            cores.advance(Duration::from_millis(steps * 10));
            continue;
        }
        let id = IDS[usize::from(op % 8)];
        let dlc = usize::from(input.next().unwrap_or(8) % 9);
        let bytes: Vec<u8> = input.by_ref().take(dlc).collect();
        let id = StandardId::new(id).expect("11-bit");
        let frame = if op & 0x80 != 0 && dlc == 0 {
            CanFrame::remote(id, 1)
        } else {
            CanFrame::new(id, &bytes)
        };
        if let Ok(frame) = frame {
            cores.frame(&frame);
        }
    }
    // Silence from now on: every transfer must end by itself.
    cores.advance(DRAIN);
    assert!(cores.sdo_done, "the SDO transfer never ended");
    assert!(
        !cores.sdo.is_busy(),
        "the SDO client is still busy after {DRAIN:?} of silence"
    );
    assert!(
        cores.lss.running().is_none(),
        "the LSS master is still busy after {DRAIN:?} of silence"
    );
});
