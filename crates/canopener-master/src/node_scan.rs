//! Which node-IDs answer, and who they are: the SDO clients of many nodes driven together as one
//! core, [`Fleet`]. Every node gets its own
//! client (CiA 301 §7.2.4: one transfer per channel at a time, but channels of different nodes are
//! independent), so asking 127 node-IDs takes about one SDO timeout instead of 127.
//!
//! Each node runs a short list of uploads in order: a first one (1000h, the device type every device
//! has), then, if anything answered it, the follow-ups (1018h sub 1..4). Only the node-IDs with a
//! running transfer count against the limit of requests in flight.

use std::collections::{HashMap, VecDeque};
use std::time::Duration;

use canopener_can::{CanFrame, CanId, Core, Instant};

use crate::node_info::unsigned;
use crate::sdo_client::{SdoClient, SdoClientError, SdoClientEvent, SdoTransferError, UploadMode};

/// The result of one upload of one node.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScanResult {
    /// The node-ID asked.
    pub node: u8,
    /// The object index read.
    pub index: u16,
    /// The sub-index read.
    pub sub: u8,
    /// The value, or the abort or timeout.
    pub outcome: Result<Vec<u8>, SdoTransferError>,
}

/// Many SDO clients as one sans-IO [`Core`].
#[derive(Debug)]
pub struct Fleet {
    nodes: Vec<NodeJobs>,
    by_response: HashMap<CanId, usize>,
    /// Nodes (positions in `nodes`) that have not started yet, in order.
    waiting: VecDeque<usize>,
    follow_ups: Vec<(u16, u8)>,
    parallel: usize,
    in_flight: usize,
    events: VecDeque<ScanResult>,
    started: bool,
}

#[derive(Debug)]
struct NodeJobs {
    node: u8,
    client: SdoClient,
    jobs: VecDeque<(u16, u8)>,
    /// Whether the first upload has ended (its follow-ups are queued if it was answered).
    first_done: bool,
}

impl Fleet {
    /// A fleet asking every node of `nodes` for `first`, then `follow_ups` of those that answered
    /// (an abort is an answer too), with at most `parallel` nodes busy at once.
    pub fn new(
        nodes: &[u8],
        first: (u16, u8),
        follow_ups: &[(u16, u8)],
        parallel: usize,
        timeout: Duration,
    ) -> Result<Fleet, SdoClientError> {
        let mut fleet = Fleet {
            nodes: Vec::with_capacity(nodes.len()),
            by_response: HashMap::new(),
            waiting: VecDeque::new(),
            follow_ups: follow_ups.to_vec(),
            parallel: parallel.max(1),
            in_flight: 0,
            events: VecDeque::new(),
            started: false,
        };
        for &node in nodes {
            let client = SdoClient::new(node)?.with_timeout(timeout);
            fleet.by_response.insert(client.response_id(), fleet.nodes.len());
            fleet.waiting.push_back(fleet.nodes.len());
            fleet.nodes.push(NodeJobs {
                node,
                client,
                jobs: VecDeque::from([first]),
                first_done: false,
            });
        }
        Ok(fleet)
    }

    /// Sends the first requests (up to the limit in flight).
    pub fn start(&mut self, now: Instant) {
        self.started = true;
        self.fill(now);
    }

    /// Whether every node has run all its uploads.
    pub fn finished(&self) -> bool {
        self.started && self.in_flight == 0 && self.waiting.is_empty()
    }

    /// Starts waiting nodes while fewer than `parallel` are busy.
    fn fill(&mut self, now: Instant) {
        while self.in_flight < self.parallel {
            let Some(slot) = self.waiting.pop_front() else {
                return;
            };
            if self.next_job(slot, now) {
                self.in_flight += 1;
            }
        }
    }

    /// Starts the next upload of a node; false when it has none left.
    fn next_job(&mut self, slot: usize, now: Instant) -> bool {
        let Some(jobs) = self.nodes.get_mut(slot) else {
            return false;
        };
        while let Some((index, sub)) = jobs.jobs.pop_front() {
            match jobs.client.upload(now, index, sub, UploadMode::Normal) {
                Ok(()) => return true,
                // Cannot happen for the indices the scan uses (the client is idle, the index not 0);
                // reported as a failed upload rather than lost.
                Err(err) => self.events.push_back(ScanResult {
                    node: jobs.node,
                    index,
                    sub,
                    outcome: Err(SdoTransferError::AbortedByClient {
                        code: canopener_wire::abort::GENERAL_ERROR,
                        reason: err.to_string(),
                    }),
                }),
            }
        }
        false
    }

    /// Collects what one node's client reported and moves that node on.
    fn collect(&mut self, slot: usize, now: Instant) {
        let mut done = false;
        let Some(jobs) = self.nodes.get_mut(slot) else {
            return;
        };
        while let Some(event) = jobs.client.poll_event() {
            let (index, sub, outcome) = match event {
                SdoClientEvent::Uploaded { index, sub, data, .. } => (index, sub, Ok(data)),
                SdoClientEvent::Failed { index, sub, error } => (index, sub, Err(error)),
                SdoClientEvent::Progress { .. } | SdoClientEvent::Downloaded { .. } => continue,
            };
            if !jobs.first_done {
                jobs.first_done = true;
                // Any answer, an abort too, means a device has this node-ID; silence means none.
                if !matches!(outcome, Err(SdoTransferError::TimedOut { .. })) {
                    jobs.jobs.extend(self.follow_ups.iter().copied());
                }
            }
            self.events.push_back(ScanResult {
                node: jobs.node,
                index,
                sub,
                outcome,
            });
            done = true;
        }
        if done
            && !self.nodes.get(slot).is_some_and(|jobs| jobs.client.is_busy())
            && !self.next_job(slot, now)
        {
            self.in_flight = self.in_flight.saturating_sub(1);
            self.fill(now);
        }
    }
}

impl Core for Fleet {
    type Event = ScanResult;

    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        if let Some(&slot) = self.by_response.get(&frame.id())
            && let Some(jobs) = self.nodes.get_mut(slot)
            && jobs.client.accept_frame(now, frame)
        {
            self.collect(slot, now);
        }
    }

    fn handle_timeout(&mut self, now: Instant) {
        for slot in 0..self.nodes.len() {
            let Some(jobs) = self.nodes.get_mut(slot) else {
                continue;
            };
            if jobs.client.poll_timeout().is_some_and(|due| due <= now) {
                jobs.client.handle_timeout(now);
                self.collect(slot, now);
            }
        }
    }

    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.nodes.iter_mut().find_map(|jobs| jobs.client.poll_transmit())
    }

    fn poll_event(&mut self) -> Option<ScanResult> {
        self.events.pop_front()
    }

    fn poll_timeout(&self) -> Option<Instant> {
        self.nodes
            .iter()
            .filter_map(|jobs| jobs.client.poll_timeout())
            .min()
    }
}

/// The identity 1018h sub 1 to 4 (vendor-ID, product code, revision, serial number, CiA 301
/// §7.5.2.24), the follow-ups of a scan by 1000h.
pub const IDENTITY: [(u16, u8); 4] = [(0x1018, 1), (0x1018, 2), (0x1018, 3), (0x1018, 4)];

/// One node that answered a scan for 1000h then [`IDENTITY`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScanRow {
    /// The node-ID.
    pub node: u8,
    /// 1000h, or why it is missing (an abort is an answer too).
    pub device_type: Result<u32, String>,
    /// 1018h sub 1..4, where read.
    pub identity: [Option<u32>; 4],
}

/// The nodes that gave any answer to 1000h, with what they said, by node-ID.
pub fn identify(results: &[ScanResult]) -> Vec<ScanRow> {
    let mut rows: Vec<ScanRow> = Vec::new();
    for result in results {
        let as_u32 = |data: &[u8]| unsigned(data, 4).ok().map(|v| v as u32);
        match (result.index, result.sub) {
            (0x1000, 0) => {
                let device_type = match &result.outcome {
                    Ok(data) => unsigned(data, 4).map(|v| v as u32).map_err(|err| err.to_string()),
                    Err(SdoTransferError::TimedOut { .. }) => continue,
                    Err(err) => Err(err.to_string()),
                };
                rows.push(ScanRow {
                    node: result.node,
                    device_type,
                    identity: [None; 4],
                });
            }
            (0x1018, sub @ 1..=4) => {
                if let Some(row) = rows.iter_mut().find(|row| row.node == result.node)
                    && let Ok(data) = &result.outcome
                    && let Some(identity) = row.identity.get_mut(usize::from(sub - 1))
                {
                    *identity = as_u32(data);
                }
            }
            _ => {}
        }
    }
    rows.sort_by_key(|row| row.node);
    rows
}

#[cfg(test)]
mod tests {
    use canopener_bus_engine::virtual_bus::{BusFrame, Timing};
    use canopener_device::application::NoApplication;
    use canopener_device::device::Device;
    use canopener_testkit::net::Net;

    use super::*;

    const EDS: &str = canopener_testkit::fixture::BASE_EDS;

    fn device(node: u8) -> Device {
        let eds = canopener_eds::load(&canopener_testkit::fixture::read(EDS).unwrap()).eds;
        let mut dev = Device::from_eds(&eds, node, Box::new(NoApplication)).unwrap();
        dev.boot(Instant::ZERO);
        while dev.poll_transmit().is_some() {}
        dev
    }

    /// Runs the fleet against `devices` until it has finished, every frame arriving 1 ms after it was
    /// sent; the results, and the bus with its recording.
    fn run(mut fleet: Fleet, devices: Vec<Device>) -> (Vec<ScanResult>, Net<Device>) {
        let mut net = Net::new(Timing::Delayed(Duration::from_millis(1)));
        for device in devices {
            net.attach(device);
        }
        fleet.start(Instant::ZERO);
        let results = net.drive(&mut fleet, Instant::from_millis(10_000), |fleet, _| {
            fleet.finished()
        });
        assert!(fleet.finished(), "the fleet did not finish: {results:?}");
        (results, net)
    }

    /// When the frames on `ids` starting with `command` arrived, in ms.
    fn arrivals(frames: &[BusFrame], ids: &[u32], command: u8) -> Vec<u64> {
        frames
            .iter()
            .filter(|f| ids.contains(&f.frame.id().as_raw()) && f.frame.data().first() == Some(&command))
            .map(|f| f.at.as_micros() / 1000)
            .collect()
    }

    #[test]
    fn all_nodes_are_asked_at_once_and_the_answering_ones_identified() {
        let nodes: Vec<u8> = (1..=127).collect();
        let timeout = Duration::from_millis(100);
        let fleet = Fleet::new(&nodes, (0x1000, 0), &IDENTITY, 127, timeout).unwrap();
        let (results, mut net) = run(fleet, vec![device(5), device(90)]);

        let answered: Vec<(u8, u16, u8, Vec<u8>)> = results
            .iter()
            .filter_map(|r| Some((r.node, r.index, r.sub, r.outcome.clone().ok()?)))
            .collect();
        assert_eq!(
            answered,
            [
                (5, 0x1000, 0, vec![0x91, 0x01, 0x0F, 0x00]),
                (90, 0x1000, 0, vec![0x91, 0x01, 0x0F, 0x00]),
                (5, 0x1018, 1, vec![0xBC, 0x0A, 0, 0]),
                (90, 0x1018, 1, vec![0xBC, 0x0A, 0, 0]),
                (5, 0x1018, 2, vec![0x01, 0x04, 0, 0]),
                (90, 0x1018, 2, vec![0x01, 0x04, 0, 0]),
                (5, 0x1018, 3, vec![0x02, 0x00, 0x01, 0]),
                (90, 0x1018, 3, vec![0x02, 0x00, 0x01, 0]),
                (5, 0x1018, 4, vec![0, 0, 0, 0]),
                (90, 0x1018, 4, vec![0, 0, 0, 0]),
            ]
        );
        // Both devices answer each round trip together, 2 ms after the request went out.
        let frames = net.bus_frames();
        assert_eq!(
            arrivals(&frames, &[0x585, 0x5DA], 0x43),
            [2, 2, 4, 4, 6, 6, 8, 8, 10, 10]
        );
        // The 125 silent node-IDs time out together, one timeout after the requests went out.
        let timed_out: Vec<&ScanResult> = results.iter().filter(|r| r.outcome.is_err()).collect();
        assert_eq!(timed_out.len(), 125);
        assert!(
            timed_out
                .iter()
                .all(|r| r.index == 0x1000 && matches!(r.outcome, Err(SdoTransferError::TimedOut { .. })))
        );
        // Their aborts (0504 0000h) went out at the timeout and arrived 1 ms later.
        let requests: Vec<u32> = (0x601..=0x67F).collect();
        assert_eq!(arrivals(&frames, &requests, 0x80), [101; 125]);
    }

    #[test]
    fn the_limit_in_flight_is_kept() {
        let nodes: Vec<u8> = (1..=10).collect();
        let timeout = Duration::from_millis(50);
        let mut fleet = Fleet::new(&nodes, (0x1000, 0), &[], 3, timeout).unwrap();
        fleet.start(Instant::ZERO);
        let mut sent = 0;
        while fleet.poll_transmit().is_some() {
            sent += 1;
        }
        assert_eq!(sent, 3);
        let (results, mut net) = run(Fleet::new(&nodes, (0x1000, 0), &[], 3, timeout).unwrap(), vec![]);
        assert_eq!(results.len(), 10);
        // Ten silent nodes, three at a time: four rounds of one timeout each.
        let requests: Vec<u32> = (0x601..=0x60A).collect();
        assert_eq!(
            arrivals(&net.bus_frames(), &requests, 0x40),
            [1, 1, 1, 51, 51, 51, 101, 101, 101, 151]
        );
    }

    #[test]
    fn aborts_count_as_answers() {
        // A device without 1018h sub 4 still identifies itself with sub 1..3.
        let follow: Vec<(u16, u8)> = vec![(0x1018, 1), (0x1018, 5)];
        let fleet = Fleet::new(&[7], (0x1000, 0), &follow, 1, Duration::from_millis(50)).unwrap();
        let (results, _) = run(fleet, vec![device(7)]);
        let summary: Vec<(u16, u8, Option<u32>)> = results
            .iter()
            .map(|r| {
                (
                    r.index,
                    r.sub,
                    r.outcome.as_ref().err().map(SdoTransferError::abort_code),
                )
            })
            .collect();
        assert_eq!(
            summary,
            [
                (0x1000, 0, None),
                (0x1018, 1, None),
                (0x1018, 5, Some(0x0609_0011))
            ]
        );
    }

    fn result(node: u8, index: u16, sub: u8, outcome: Result<Vec<u8>, SdoTransferError>) -> ScanResult {
        ScanResult {
            node,
            index,
            sub,
            outcome,
        }
    }

    #[test]
    fn rows_list_the_answering_nodes_with_identities() {
        let silent = SdoTransferError::TimedOut {
            waiting_for: "initiate upload response",
            after: Duration::from_millis(100),
        };
        let refused = SdoTransferError::AbortedByServer { code: 0x0602_0000 };
        let results = [
            result(9, 0x1000, 0, Err(refused.clone())),
            result(5, 0x1000, 0, Ok(vec![0x91, 0x01, 0x0F, 0x00])),
            result(6, 0x1000, 0, Err(silent)),
            result(5, 0x1018, 1, Ok(vec![0xBC, 0x0A, 0, 0])),
            result(5, 0x1018, 4, Err(refused)),
            result(9, 0x1018, 1, Ok(vec![1, 0, 0, 0])),
        ];
        let rows = identify(&results);
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].node, 5);
        assert_eq!(rows[0].device_type, Ok(0x000F_0191));
        assert_eq!(rows[0].identity, [Some(0xABC), None, None, None]);
        assert_eq!(rows[1].node, 9);
        assert!(rows[1].device_type.as_ref().unwrap_err().contains("0x06020000"));
        assert_eq!(rows[1].identity, [Some(1), None, None, None]);
    }
}
