//! The master's service cores against real `canopener_device::device::Device`s on virtual time: NMT
//! module control, heartbeat and node guarding monitoring, EMCY decoding, SYNC and TIME production.
//!
//! Devices are built from the checker's fixture `base.eds` (node 5), CANopenNode's
//! `DS301_profile.eds` (node 10; SYNC, TIME, 1019h) and CANopenSocket's `CANopenSocket.eds`
//! (node 4; the only one with 100Ch/100Dh for node guarding).

use std::sync::LazyLock;
use std::time::Duration;

use canopener_bus_engine::virtual_bus::{NodeEvent, StationId};
use canopener_can::Instant;
use canopener_device::application::NoApplication;
use canopener_device::device::{Device, DeviceEvent};
use canopener_device::faults::{Fault, FaultSet};
use canopener_device::nmt_slave::NmtSlaveState;
use canopener_device::od_build::build_od;
use canopener_master::emcy_consumer::{EmcyConsumer, EmcyEvent};
use canopener_master::error_control::{ConsumerTime, GuardingConfig, MonitorEvent, NodeMonitor};
use canopener_master::nmt_master::{NmtMaster, NmtTarget, expected_state};
use canopener_master::sync_producer::{SyncConfig, SyncEvent, SyncProducer};
use canopener_master::time_producer::{TimeEvent, TimeProducer};
use canopener_od::ObjectKey;
use canopener_testkit::net::Net as TestNet;
use canopener_testkit::trace::stamp;
use canopener_wire::{NmtCommand, NodeId};

const BASE: &str = canopener_testkit::fixture::BASE_EDS;
static DS301: LazyLock<String> =
    LazyLock::new(|| vendored("CANopenNode__CANopenNode__example__DS301_profile.eds"));
static SOCKET: LazyLock<String> =
    LazyLock::new(|| vendored("CANopenNode__CANopenSocket__canopend__objDict__CANopenSocket.eds"));

fn vendored(name: &str) -> String {
    canopener_testkit::corpus::eds(name).display().to_string()
}

/// A device from `path` with dictionary values set before power-on (`(index, sub, bytes)`).
fn device(path: &str, node: u8, values: &[(u16, u8, &[u8])]) -> Device {
    let eds = canopener_eds::load(&canopener_testkit::fixture::read(path).expect("EDS file")).eds;
    let mut built = build_od(&eds, node).expect("builds");
    for (index, sub, bytes) in values {
        built
            .od
            .set_value(ObjectKey::new(*index, *sub), bytes)
            .expect("value set");
    }
    Device::new(built.od, node, Box::new(NoApplication)).expect("device")
}

fn node(raw: u8) -> NodeId {
    NodeId::new(raw).expect("node-ID")
}

/// An expedited SDO download request to `node` as compact candump text.
fn download(node: u8, index: u16, sub: u8, data: &[u8]) -> String {
    let command = 0x23 | ((4 - data.len() as u8) << 2);
    let mut bytes = vec![command, index as u8, (index >> 8) as u8, sub];
    bytes.extend_from_slice(data);
    bytes.resize(8, 0);
    let hex: String = bytes.iter().map(|b| format!("{b:02X}")).collect();
    format!("{:03X}#{hex}", 0x600 + u16::from(node))
}

canopener_testkit::cores! {
    /// Everyone on the bus: the devices and the master's service cores.
    enum Party, PartyEvent {
        Device(Device) => DeviceEvent,
        Monitor(NodeMonitor) => MonitorEvent,
        Emcy(EmcyConsumer) => EmcyEvent,
        Sync(SyncProducer) => SyncEvent,
        Time(TimeProducer) => TimeEvent,
    }
}

/// A bus on virtual time (the test harness's): devices on one side, the master's cores on the other.
/// Every frame reaches every party but its sender; an unplugged device neither sends nor receives.
struct Net {
    net: TestNet<Party>,
    devices: Vec<StationId>,
    monitor: StationId,
    emcy: StationId,
    time: StationId,
    sync: Option<StationId>,
    nmt: NmtMaster,
    /// Frames on the bus as `"<ms>.<µs> <frame>"`.
    frames: Vec<String>,
    /// Monitor events as `"<ms>.<µs> <event>"` (`Display`).
    monitored: Vec<String>,
    /// EMCY consumer events, likewise.
    emcys: Vec<String>,
    device_events: Vec<(usize, DeviceEvent)>,
}

impl Net {
    fn new(devices: Vec<Device>, default_consumer: ConsumerTime) -> Net {
        let mut net = TestNet::ideal();
        let devices = devices
            .into_iter()
            .map(|mut dev| {
                dev.boot(Instant::ZERO);
                net.attach(Party::Device(dev))
            })
            .collect();
        let monitor = net.attach(Party::Monitor(NodeMonitor::new(default_consumer)));
        let emcy = net.attach(Party::Emcy(EmcyConsumer::new()));
        let time = net.attach(Party::Time(TimeProducer::new()));
        let mut net = Net {
            net,
            devices,
            monitor,
            emcy,
            time,
            sync: None,
            nmt: NmtMaster::new(),
            frames: Vec::new(),
            monitored: Vec::new(),
            emcys: Vec::new(),
            device_events: Vec::new(),
        };
        net.collect();
        net
    }

    fn now(&self) -> Instant {
        self.net.now()
    }

    fn device(&self, index: usize) -> &Device {
        match self.net.node(self.devices[index]) {
            Party::Device(dev) => dev,
            other => panic!("not a device: {other:?}"),
        }
    }

    fn monitor(&self) -> &NodeMonitor {
        match self.net.node(self.monitor) {
            Party::Monitor(monitor) => monitor,
            other => panic!("not the monitor: {other:?}"),
        }
    }

    fn monitor_mut(&mut self) -> &mut NodeMonitor {
        match self.net.node_mut(self.monitor) {
            Party::Monitor(monitor) => monitor,
            other => panic!("not the monitor: {other:?}"),
        }
    }

    fn emcy(&self) -> &EmcyConsumer {
        match self.net.node(self.emcy) {
            Party::Emcy(emcy) => emcy,
            other => panic!("not the EMCY consumer: {other:?}"),
        }
    }

    fn time_mut(&mut self) -> &mut TimeProducer {
        match self.net.node_mut(self.time) {
            Party::Time(time) => time,
            other => panic!("not the TIME producer: {other:?}"),
        }
    }

    /// Puts `sync` on the bus, in place of the SYNC producer there was.
    fn set_sync(&mut self, sync: SyncProducer) {
        match self.sync {
            Some(station) => *self.net.node_mut(station) = Party::Sync(sync),
            None => self.sync = Some(self.net.attach(Party::Sync(sync))),
        }
    }

    /// Unplugs device `index`, or plugs it back in.
    fn plug(&mut self, index: usize, plugged: bool) {
        let station = self.devices[index];
        if plugged {
            self.net.virtual_bus_mut().reconnect(station);
        } else {
            self.net.virtual_bus_mut().disconnect(station);
        }
    }

    /// Takes what went over the bus and what the parties reported into the lists the tests read.
    fn collect(&mut self) {
        self.frames.extend(self.net.frames());
        for NodeEvent { at, node, event } in self.net.events() {
            let at = stamp(at);
            match event {
                PartyEvent::Monitor(event) => self.monitored.push(format!("{at} {event}")),
                PartyEvent::Emcy(event) => self.emcys.push(format!("{at} {event}")),
                PartyEvent::Device(event) => {
                    if let Some(index) = self.devices.iter().position(|dev| *dev == node) {
                        self.device_events.push((index, event));
                    }
                }
                PartyEvent::Sync(_) | PartyEvent::Time(_) => {}
            }
        }
    }

    /// Runs every timer due up to and including `until_ms`, then sets the clock there.
    fn advance(&mut self, until_ms: u64) {
        self.net.advance(Instant::from_millis(until_ms));
        self.collect();
    }

    /// Advances to `at_ms`, then sends `command` to `target`.
    fn nmt(&mut self, at_ms: u64, command: NmtCommand, target: NmtTarget) {
        self.advance(at_ms);
        self.nmt.send(self.net.now(), command, target);
        while let Some(frame) = self.nmt.poll_transmit() {
            self.net.send(frame);
        }
        self.collect();
    }

    /// Advances to `at_ms`, then puts `text` on the bus as sent by the master tool.
    fn inject(&mut self, at_ms: u64, text: &str) {
        self.net.inject(Instant::from_millis(at_ms), text);
        self.collect();
    }

    fn take_monitored(&mut self) -> Vec<String> {
        std::mem::take(&mut self.monitored)
    }

    fn take_emcys(&mut self) -> Vec<String> {
        std::mem::take(&mut self.emcys)
    }

    fn take_frames(&mut self) -> Vec<String> {
        std::mem::take(&mut self.frames)
    }
}

fn without_intervals(lines: Vec<String>) -> Vec<String> {
    lines
        .into_iter()
        .filter(|line| !line.contains("interval"))
        .collect()
}

#[test]
fn nmt_commands_change_the_device_state_and_the_monitor_follows() {
    let hundred_ms = 100u16.to_le_bytes();
    let mut net = Net::new(
        vec![device(BASE, 5, &[(0x1017, 0, &hundred_ms)])],
        ConsumerTime::Learn,
    );
    let five = NmtTarget::Node(node(5));
    let steps = [
        (250, NmtCommand::StartRemoteNode, five, NmtSlaveState::Operational),
        (400, NmtCommand::StopRemoteNode, five, NmtSlaveState::Stopped),
        (
            550,
            NmtCommand::EnterPreOperational,
            NmtTarget::All,
            NmtSlaveState::PreOperational,
        ),
        (700, NmtCommand::ResetNode, five, NmtSlaveState::PreOperational),
    ];
    for (at, command, target, device_state) in steps {
        net.nmt(at, command, target);
        assert_eq!(net.device(0).state(), device_state, "after {command}");
        assert_eq!(
            net.monitor().state(node(5)),
            Some(expected_state(command)),
            "after {command}"
        );
    }
    net.advance(850);
    let frames = net.take_frames();
    let error_control: Vec<&String> = frames
        .iter()
        .filter(|line| line.contains(" 000#") || line.contains(" 705#"))
        .collect();
    assert_eq!(
        error_control,
        [
            "0.000 705#00",
            "100.000 705#7F",
            "200.000 705#7F",
            "250.000 000#0105",
            "250.000 705#05",
            "350.000 705#05",
            "400.000 000#0205",
            "400.000 705#04",
            "500.000 705#04",
            "550.000 000#8000",
            "550.000 705#7F",
            "650.000 705#7F",
            "700.000 000#8105",
            "700.000 705#00",
            "800.000 705#7F",
        ]
    );
    let monitored = net.take_monitored();
    assert_eq!(
        without_intervals(monitored.clone()),
        [
            "0.000 node 5: boot-up",
            "100.000 node 5: BOOT-UP -> PRE-OPERATIONAL",
            "250.000 node 5: PRE-OPERATIONAL -> OPERATIONAL",
            "400.000 node 5: OPERATIONAL -> STOPPED",
            "550.000 node 5: STOPPED -> PRE-OPERATIONAL",
            "700.000 node 5: boot-up",
            "800.000 node 5: BOOT-UP -> PRE-OPERATIONAL",
        ]
    );
    // Every same-state gap is the 1017h period; the state-change heartbeats are no samples.
    let intervals: Vec<&String> = monitored
        .iter()
        .filter(|line| line.contains("interval"))
        .collect();
    assert_eq!(
        intervals,
        [
            "200.000 node 5: heartbeat interval 100.000 ms",
            "350.000 node 5: heartbeat interval 100.000 ms",
            "500.000 node 5: heartbeat interval 100.000 ms",
            "650.000 node 5: heartbeat interval 100.000 ms",
        ]
    );
    let status = net.monitor().status(node(5)).expect("heard");
    assert_eq!(status.learned_period, Some(Duration::from_millis(100)));
    assert!(!status.heartbeat_lost);
}

#[test]
fn heartbeat_lost_when_the_device_stops_producing_or_is_unplugged() {
    let hundred_ms = 100u16.to_le_bytes();
    let fifty_ms = 50u16.to_le_bytes();
    let mut net = Net::new(
        vec![
            device(BASE, 5, &[(0x1017, 0, &hundred_ms)]),
            device(&DS301, 10, &[(0x1017, 0, &fifty_ms)]),
        ],
        ConsumerTime::Off,
    );
    net.monitor_mut()
        .set_consumer_time(node(5), ConsumerTime::Fixed(Duration::from_millis(150)));
    net.monitor_mut()
        .set_consumer_time(node(10), ConsumerTime::Fixed(Duration::from_millis(75)));
    // Node 5: 1017h = 0 over SDO after the heartbeat at 300 ms, back to 100 ms at 600 ms.
    net.inject(300, &download(5, 0x1017, 0, &[0, 0]));
    // Node 10: unplugged from 320 ms to 420 ms.
    net.advance(320);
    net.plug(1, false);
    net.advance(420);
    net.plug(1, true);
    net.inject(600, &download(5, 0x1017, 0, &hundred_ms));
    net.advance(750);
    let monitored = without_intervals(net.take_monitored());
    assert_eq!(
        monitored,
        [
            "0.000 node 5: boot-up",
            "0.000 node 10: boot-up",
            "50.000 node 10: BOOT-UP -> PRE-OPERATIONAL",
            "100.000 node 5: BOOT-UP -> PRE-OPERATIONAL",
            "375.000 node 10: heartbeat lost (silent for 75 ms)",
            "450.000 node 5: heartbeat lost (silent for 150 ms)",
            "450.000 node 10: heartbeat resumed",
            "700.000 node 5: heartbeat resumed",
        ]
    );
    assert!(net.frames.contains(&"300.000 585#6017100000000000".to_string()));
    let status = net.monitor().status(node(5)).expect("heard");
    assert!(!status.heartbeat_lost);
    assert_eq!(status.last_heard, Some(Instant::from_millis(700)));
}

#[test]
fn guarding_a_device_configured_with_100ch_100dh() {
    let guard_ms = 100u16.to_le_bytes();
    let mut net = Net::new(
        vec![device(&SOCKET, 4, &[(0x100C, 0, &guard_ms), (0x100D, 0, &[3])])],
        ConsumerTime::Off,
    );
    // This device starts operational on its own (1F80h bit 2 clear).
    assert_eq!(net.device(0).state(), NmtSlaveState::Operational);
    let config = GuardingConfig {
        guard_time: Duration::from_millis(100),
        life_time_factor: 3,
    };
    let now = net.now();
    net.monitor_mut()
        .start_guarding(now, node(4), config)
        .expect("guarding");
    net.nmt(250, NmtCommand::EnterPreOperational, NmtTarget::Node(node(4)));
    net.nmt(350, NmtCommand::StartRemoteNode, NmtTarget::Node(node(4)));
    net.advance(450);
    let frames: Vec<String> = net
        .take_frames()
        .into_iter()
        .filter(|line| line.contains(" 704#") || line.contains(" 000#"))
        .collect();
    // Answers carry the state and a toggle that starts at 0 after the boot-up.
    assert_eq!(
        frames,
        [
            "0.000 704#00",
            "0.000 704#R1",
            "0.000 704#05",
            "100.000 704#R1",
            "100.000 704#85",
            "200.000 704#R1",
            "200.000 704#05",
            "250.000 000#8004",
            "300.000 704#R1",
            "300.000 704#FF",
            "350.000 000#0104",
            "400.000 704#R1",
            "400.000 704#05",
        ]
    );
    assert_eq!(
        net.take_monitored(),
        [
            "0.000 node 4: boot-up",
            "0.000 node 4: BOOT-UP -> OPERATIONAL",
            "300.000 node 4: OPERATIONAL -> PRE-OPERATIONAL",
            "400.000 node 4: PRE-OPERATIONAL -> OPERATIONAL",
        ]
    );
    // Unplugged: no answers, so guarding is lost a life time after the last correct one. The
    // device loses life guarding too and falls back to pre-operational (1029h:01 = 0).
    net.plug(0, false);
    net.advance(750);
    net.plug(0, true);
    net.advance(850);
    assert_eq!(
        net.take_monitored(),
        [
            "700.000 node 4: node guarding lost",
            "800.000 node 4: node guarding resumed",
            "800.000 node 4: OPERATIONAL -> PRE-OPERATIONAL",
        ]
    );
    assert_eq!(net.device(0).state(), NmtSlaveState::PreOperational);
    // The first request after the loss resumed the device's life guarding: error reset.
    assert_eq!(
        net.take_emcys(),
        [
            "800.000 node 4: EMCY 0000h error reset or no error, error register 00h, manufacturer 00 00 00 00 00"
        ]
    );
    net.take_frames();
    // The master stops guarding: the device's life guarding runs out 300 ms after the last request.
    net.monitor_mut().stop_guarding(node(4));
    net.advance(1300);
    let emcys = net.take_emcys();
    assert_eq!(emcys.len(), 1, "{emcys:?}");
    assert!(
        emcys[0].starts_with(
            "1100.000 node 4: EMCY 8130h life guard error or heartbeat error, error register 11h"
        ),
        "{emcys:?}"
    );
    assert!(net.take_monitored().is_empty());
    assert!(
        !net.take_frames().iter().any(|line| line.contains("#R")),
        "no more requests"
    );
}

#[test]
fn sync_producer_drives_the_device_sync_consumer() {
    use canopener_device::sync::SyncEvent as DeviceSync;
    let mut net = Net::new(vec![device(&DS301, 10, &[(0x1019, 0, &[5])])], ConsumerTime::Off);
    let config = SyncConfig {
        counter_overflow: Some(5),
        ..SyncConfig::new(Duration::from_millis(10))
    };
    let mut sync = SyncProducer::new(config).expect("config");
    sync.start(Instant::from_millis(10));
    net.set_sync(sync);
    net.advance(75);
    let counters: Vec<Option<u8>> = net
        .device_events
        .drain(..)
        .filter_map(|(_, event)| match event {
            DeviceEvent::Sync(DeviceSync::Sync { counter }) => Some(counter),
            _ => None,
        })
        .collect();
    assert_eq!(
        counters,
        [1, 2, 3, 4, 5, 1, 2].map(Some),
        "the device's SYNC consumer accepts every counter"
    );
    let syncs: Vec<String> = net
        .take_frames()
        .into_iter()
        .filter(|line| line.contains(" 080#"))
        .collect();
    assert_eq!(syncs[0], "10.000 080#01");
    assert_eq!(syncs[6], "70.000 080#02");
    // A producer without the counter: the device expects one (1019h = 5) and raises EMCY 8240h.
    let mut plain = SyncProducer::new(SyncConfig::new(Duration::from_millis(10))).expect("config");
    plain.start(Instant::from_millis(80));
    net.set_sync(plain);
    net.advance(80);
    assert_eq!(
        net.take_emcys(),
        [
            "80.000 node 10: EMCY 8240h unexpected SYNC data length, error register 11h (generic, \
          communication), manufacturer 01 00 00 00 00"
        ]
    );
}

#[test]
fn time_producer_reaches_the_device_time_consumer() {
    use canopener_device::time_stamp::TimeEvent as DeviceTime;
    let consumer = 0x8000_0100u32.to_le_bytes();
    let mut net = Net::new(
        vec![device(&DS301, 10, &[(0x1012, 0, &consumer)])],
        ConsumerTime::Off,
    );
    // 2024-01-01 12:00:00.000 UTC.
    let noon = canopener_wire::since_1984_from_unix_millis(1_704_110_400_000).expect("after 1984");
    net.time_mut().set_clock(Instant::from_millis(100), noon);
    net.time_mut()
        .start_periodic(Instant::from_millis(100), Duration::from_secs(1))
        .expect("clock set");
    net.advance(2100);
    let times: Vec<String> = net
        .device_events
        .drain(..)
        .filter_map(|(_, event)| match event {
            DeviceEvent::Time(DeviceTime::Time { time }) => Some(time.to_string()),
            _ => None,
        })
        .collect();
    assert_eq!(
        times,
        [
            "2024-01-01 12:00:00.000",
            "2024-01-01 12:00:01.000",
            "2024-01-01 12:00:02.000"
        ]
    );
    assert!(net.frames.contains(&"100.000 100#002E93021239".to_string()));
}

#[test]
fn emcy_from_an_rpdo_length_error_and_its_reset() {
    let mut net = Net::new(vec![device(BASE, 5, &[])], ConsumerTime::Off);
    net.nmt(1, NmtCommand::StartRemoteNode, NmtTarget::All);
    net.inject(4, "205#");
    net.inject(5, "205#01");
    assert_eq!(
        net.take_emcys(),
        [
            "4.000 node 5: EMCY 8210h PDO not processed due to length error, error register 11h \
             (generic, communication), manufacturer 01 00 00 00 00",
            "5.000 node 5: EMCY 0000h error reset or no error, error register 00h, manufacturer 00 00 00 00 00",
        ]
    );
    assert_eq!(net.emcy().error_register(node(5)), Some(0));
}

#[test]
fn faulty_heartbeats_are_reported() {
    let hundred_ms = 100u16.to_le_bytes();
    let wrong_state =
        device(BASE, 5, &[(0x1017, 0, &hundred_ms)]).with_faults(FaultSet::from(Fault::HeartbeatStateWrong));
    let too_fast =
        device(&DS301, 10, &[(0x1017, 0, &hundred_ms)]).with_faults(FaultSet::from(Fault::HeartbeatTooFast));
    let mut net = Net::new(vec![wrong_state, too_fast], ConsumerTime::Learn);
    net.nmt(150, NmtCommand::StartRemoteNode, NmtTarget::Node(node(5)));
    net.advance(330);
    let monitored = net.take_monitored();
    let node5: Vec<&String> = monitored.iter().filter(|line| line.contains("node 5:")).collect();
    assert_eq!(
        node5,
        [
            // The fault reports a wrong but valid state (operational while
            // pre-operational, stopped while operational), so a consumer sees
            // state changes that never happened, not a lost heartbeat.
            "0.000 node 5: boot-up",
            "100.000 node 5: BOOT-UP -> OPERATIONAL",
            "150.000 node 5: OPERATIONAL -> STOPPED",
            "250.000 node 5: heartbeat interval 100.000 ms",
        ]
    );
    // Heartbeats 1 ms apart pull the minimum interval down to 1 ms.
    let node10: Vec<&String> = monitored
        .iter()
        .filter(|line| line.contains("node 10: heartbeat interval"))
        .collect();
    assert_eq!(
        node10,
        [
            "101.000 node 10: heartbeat interval 1.000 ms",
            "200.000 node 10: heartbeat interval 99.000 ms",
            "201.000 node 10: heartbeat interval 1.000 ms",
            "300.000 node 10: heartbeat interval 99.000 ms",
            "301.000 node 10: heartbeat interval 1.000 ms",
        ]
    );
    assert!(
        !monitored.iter().any(|line| line.contains("lost")),
        "{monitored:?}"
    );
}
