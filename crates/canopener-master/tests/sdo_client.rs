//! The SDO client against a real SDO server: `canopener_device::device::Device` built from the
//! checker's fixture EDS (`base.eds`, node 5) plus a few entries large enough for segmented and
//! block transfers, both on virtual time. Frames may be dropped on the way to show that block
//! transfers recover, and every round trip must give back exactly what was written.

use canopener_can::Core;
use std::time::Duration;

use canopener_bus_engine::virtual_bus::StationId;
use canopener_can::{CanFrame, Instant};
use canopener_device::application::NoApplication;
use canopener_device::device::Device;
use canopener_device::od_build::build_od;
use canopener_master::sdo_client::{
    DownloadMode, Protocol, SdoClient, SdoClientError, SdoClientEvent, SdoTransferError, UploadMode,
};
use canopener_od::{Access, DataType, DynamicOd, Entry, ObjectKey};
use canopener_testkit::net::Net as TestNet;
use proptest::prelude::*;

const BASE: &str = canopener_testkit::fixture::BASE_EDS;

/// A 10 000-byte DOMAIN, larger than one block sub-block (127 × 7 bytes) many times over.
const DOMAIN: ObjectKey = ObjectKey::new(0x2100, 0);
/// A VISIBLE_STRING for segmented transfers.
const STRING: ObjectKey = ObjectKey::new(0x2101, 0);

fn domain_value() -> Vec<u8> {
    (0..10_000u32).map(|n| (n * 7 % 251) as u8).collect()
}

/// The fixture dictionary with the two large entries added.
fn od() -> DynamicOd {
    let eds = canopener_eds::load(&canopener_testkit::fixture::read(BASE).expect("base.eds")).eds;
    let built = build_od(&eds, 5).expect("dictionary");
    let extra = [
        Entry::new(DOMAIN, DataType::DOMAIN, Access::Rw, &domain_value()).expect("DOMAIN"),
        Entry::new(STRING, DataType::VISIBLE_STRING, Access::Rw, b"canopener").expect("string"),
    ];
    let entries: Vec<Entry> = built.od.entries().iter().cloned().chain(extra).collect();
    DynamicOd::from_entries(entries.len(), entries).expect("dictionary with extras")
}

/// The client and the device on the test harness's virtual bus, with an optional frame filter.
struct Net {
    net: TestNet<Device>,
    dev: StationId,
    client: SdoClient,
    /// Every frame on the bus as `"<ms> <frame>"`, dropped ones marked.
    trace: Vec<String>,
}

impl Net {
    fn new(client: SdoClient) -> Net {
        Net::on(client, od())
    }

    fn on(client: SdoClient, od: DynamicOd) -> Net {
        let mut dev = Device::new(od, 5, Box::new(NoApplication)).expect("device");
        dev.boot(Instant::ZERO);
        while dev.poll_transmit().is_some() {}
        let mut net = TestNet::ideal();
        let dev = net.attach(dev);
        Net {
            net,
            dev,
            client,
            trace: Vec::new(),
        }
    }

    /// The bus loses every frame `lose` says yes to.
    fn losing(mut self, mut lose: impl FnMut(&CanFrame) -> bool + Send + 'static) -> Net {
        self.net
            .virtual_bus_mut()
            .lose_when(move |seen| lose(&seen.frame));
        self
    }

    /// Starts a transfer and runs the bus until the client is done; returns the client's events.
    fn transfer(
        &mut self,
        start: impl FnOnce(&mut SdoClient, Instant) -> Result<(), SdoClientError>,
    ) -> Vec<SdoClientEvent> {
        start(&mut self.client, self.net.now()).expect("transfer starts");
        let limit = self.net.now() + Duration::from_secs(3600);
        let events = self
            .net
            .drive(&mut self.client, limit, |client, _| !client.is_busy());
        assert!(!self.client.is_busy(), "the transfer did not end");
        self.net.events();
        for seen in self.net.bus_frames() {
            let millis = seen.at.as_nanos() / 1_000_000;
            let mark = if seen.lost { " (lost)" } else { "" };
            self.trace.push(format!("{millis} {}{mark}", seen.frame));
        }
        events
    }

    fn dev_mut(&mut self) -> &mut Device {
        self.net.node_mut(self.dev)
    }

    fn value(&self, key: ObjectKey) -> Vec<u8> {
        self.net.node(self.dev).od().read(key).expect("readable").to_vec()
    }
}

fn client() -> SdoClient {
    SdoClient::new(5).expect("node 5")
}

/// The events without progress reports.
fn outcome(events: &[SdoClientEvent]) -> Vec<SdoClientEvent> {
    events
        .iter()
        .filter(|event| !matches!(event, SdoClientEvent::Progress { .. }))
        .cloned()
        .collect()
}

fn progress(events: &[SdoClientEvent]) -> Vec<(usize, Option<usize>)> {
    events
        .iter()
        .filter_map(|event| match event {
            SdoClientEvent::Progress { done, total } => Some((*done, *total)),
            _ => None,
        })
        .collect()
}

fn uploaded(data: &[u8], key: ObjectKey, protocol: Protocol) -> Vec<SdoClientEvent> {
    vec![SdoClientEvent::Uploaded {
        index: key.index,
        sub: key.sub,
        data: data.to_vec(),
        protocol,
    }]
}

fn downloaded(key: ObjectKey, protocol: Protocol) -> Vec<SdoClientEvent> {
    vec![SdoClientEvent::Downloaded {
        index: key.index,
        sub: key.sub,
        protocol,
    }]
}

fn failure(events: &[SdoClientEvent]) -> SdoTransferError {
    match outcome(events).as_slice() {
        [SdoClientEvent::Failed { error, .. }] => error.clone(),
        other => panic!("expected one failure, got {other:?}"),
    }
}

fn upload(
    key: ObjectKey,
    mode: UploadMode,
) -> impl FnOnce(&mut SdoClient, Instant) -> Result<(), SdoClientError> {
    move |client, now| client.upload(now, key.index, key.sub, mode)
}

fn download(
    key: ObjectKey,
    data: &[u8],
    mode: DownloadMode,
) -> impl FnOnce(&mut SdoClient, Instant) -> Result<(), SdoClientError> {
    let data = data.to_vec();
    move |client, now| client.download(now, key.index, key.sub, data, mode)
}

#[test]
fn expedited_round_trip_of_the_heartbeat_time() {
    let heartbeat = ObjectKey::new(0x1017, 0);
    let mut net = Net::new(client());
    let events = net.transfer(download(heartbeat, &[0xE8, 0x03], DownloadMode::Auto));
    assert_eq!(events, downloaded(heartbeat, Protocol::Expedited));
    assert_eq!(net.value(heartbeat), [0xE8, 0x03]);
    let events = net.transfer(upload(heartbeat, UploadMode::Normal));
    assert_eq!(events, uploaded(&[0xE8, 0x03], heartbeat, Protocol::Expedited));
    assert_eq!(
        net.trace,
        [
            "0 605#2B171000E8030000",
            "0 585#6017100000000000",
            "0 605#4017100000000000",
            "0 585#4B171000E8030000",
        ]
    );
}

#[test]
fn segmented_round_trip_of_a_string() {
    let mut net = Net::new(client());
    let text = b"the quick brown fox jumps over the lazy dog";
    let events = net.transfer(download(STRING, text, DownloadMode::Auto));
    assert_eq!(outcome(&events), downloaded(STRING, Protocol::Segmented));
    assert_eq!(net.value(STRING), text);
    let events = net.transfer(upload(STRING, UploadMode::Normal));
    assert_eq!(outcome(&events), uploaded(text, STRING, Protocol::Segmented));
    // 43 bytes: the start, then one report per 7-byte segment.
    let done: Vec<usize> = progress(&events).into_iter().map(|(done, _)| done).collect();
    assert_eq!(done, [0, 7, 14, 21, 28, 35, 42, 43]);
}

#[test]
fn block_round_trip_of_a_large_domain_with_progress() {
    let mut net = Net::new(client());
    let value: Vec<u8> = domain_value().iter().rev().copied().collect();
    let events = net.transfer(download(DOMAIN, &value, DownloadMode::Block));
    assert_eq!(outcome(&events), downloaded(DOMAIN, Protocol::Block));
    assert_eq!(net.value(DOMAIN), value);
    let reports = progress(&events);
    // 10 000 bytes are 1429 segments: 11 full sub-blocks of 127 and a last one of 32.
    assert_eq!(reports.len(), 1 + 12);
    assert_eq!(reports.first(), Some(&(0, Some(10_000))));
    assert_eq!(reports.get(1), Some(&(889, Some(10_000))));
    assert_eq!(reports.last(), Some(&(10_000, Some(10_000))));
    assert!(reports.windows(2).all(|pair| pair[0].0 <= pair[1].0));

    let events = net.transfer(upload(DOMAIN, UploadMode::Block));
    assert_eq!(outcome(&events), uploaded(&value, DOMAIN, Protocol::Block));
    let reports = progress(&events);
    assert_eq!(reports.first(), Some(&(0, Some(10_000))));
    assert_eq!(reports.last(), Some(&(10_000, Some(10_000))));
    assert_eq!(reports.len(), 1 + 12);

    // The same value segmented, for comparison: one answer per 7 bytes.
    let events = net.transfer(upload(DOMAIN, UploadMode::Normal));
    assert_eq!(outcome(&events), uploaded(&value, DOMAIN, Protocol::Segmented));
    assert_eq!(progress(&events).len(), 1 + 1429);
}

#[test]
fn block_upload_switches_to_a_normal_upload_under_the_threshold() {
    let heartbeat = ObjectKey::new(0x1017, 0);
    let mut net = Net::new(client().with_block_upload_threshold(4));
    let events = net.transfer(upload(heartbeat, UploadMode::Block));
    assert_eq!(events, uploaded(&[0, 0], heartbeat, Protocol::Expedited));
    let events = net.transfer(upload(STRING, UploadMode::Block));
    assert_eq!(outcome(&events), uploaded(b"canopener", STRING, Protocol::Block));
}

#[test]
fn device_abort_codes_surface_decoded() {
    let mut net = Net::new(client());
    let missing = ObjectKey::new(0x1234, 0);
    let error = failure(&net.transfer(upload(missing, UploadMode::Normal)));
    assert_eq!(error, SdoTransferError::AbortedByServer { code: 0x0602_0000 });
    assert_eq!(
        error.to_string(),
        "SDO abort 0x06020000 from the server: Object does not exist in the object dictionary"
    );
    let error = failure(&net.transfer(download(
        ObjectKey::new(0x1000, 0),
        &[1, 2, 3, 4],
        DownloadMode::Auto,
    )));
    assert_eq!(
        error.to_string(),
        "SDO abort 0x06010002 from the server: Attempt to write a read-only object"
    );
    let error = failure(&net.transfer(download(
        ObjectKey::new(0x1017, 0),
        &[1, 2, 3],
        DownloadMode::Auto,
    )));
    assert_eq!(error, SdoTransferError::AbortedByServer { code: 0x0607_0012 });
    let error = failure(&net.transfer(upload(ObjectKey::new(0x1018, 9), UploadMode::Block)));
    assert_eq!(error, SdoTransferError::AbortedByServer { code: 0x0609_0011 });
    let error = failure(&net.transfer(download(missing, &[0; 100], DownloadMode::Block)));
    assert_eq!(error, SdoTransferError::AbortedByServer { code: 0x0602_0000 });
    // The value range of 2000h (1..=1000) is checked when the last segment arrives.
    let error = failure(&net.transfer(download(
        ObjectKey::new(0x2000, 0),
        &[0xE9, 0x03],
        DownloadMode::Block,
    )));
    assert_eq!(error, SdoTransferError::AbortedByServer { code: 0x0609_0031 });
}

#[test]
fn block_download_recovers_a_lost_segment() {
    let mut lost = false;
    let mut net = Net::new(client()).losing(move |frame| {
        // The third segment of the first sub-block goes missing once.
        let hit = !lost && frame.id().as_raw() == 0x605 && frame.data().first() == Some(&0x03);
        lost |= hit;
        hit
    });
    let value: Vec<u8> = (0..2000u32).map(|n| n as u8).collect();
    let events = net.transfer(download(DOMAIN, &value, DownloadMode::Block));
    assert_eq!(outcome(&events), downloaded(DOMAIN, Protocol::Block));
    assert_eq!(net.value(DOMAIN), value);
    // The device acknowledged segment 2 at once; the client went on from byte 14.
    assert!(
        net.trace
            .iter()
            .any(|line| line.ends_with("585#A2027F0000000000")),
        "{:#?}",
        net.trace
    );
    let reports = progress(&events);
    assert_eq!(reports.get(1), Some(&(14, Some(2000))));
}

#[test]
fn block_upload_recovers_a_lost_segment() {
    let mut lost = false;
    let mut net = Net::new(client().with_block_size(16)).losing(move |frame| {
        let hit = !lost && frame.id().as_raw() == 0x585 && frame.data().first() == Some(&0x05);
        lost |= hit;
        hit
    });
    let events = net.transfer(upload(DOMAIN, UploadMode::Block));
    assert_eq!(
        outcome(&events),
        uploaded(&domain_value(), DOMAIN, Protocol::Block)
    );
    // Segment 6 showed the gap; the client acknowledged segment 4 and the device repeated.
    assert!(
        net.trace
            .iter()
            .any(|line| line.ends_with("605#A204100000000000")),
        "{:#?}",
        net.trace
    );
}

#[test]
fn block_upload_recovers_a_lost_last_segment_of_a_sub_block() {
    let mut lost = false;
    let mut net = Net::new(client().with_block_size(16)).losing(move |frame| {
        let hit = !lost && frame.id().as_raw() == 0x585 && frame.data().first() == Some(&0x10);
        lost |= hit;
        hit
    });
    let events = net.transfer(upload(DOMAIN, UploadMode::Block));
    assert_eq!(
        outcome(&events),
        uploaded(&domain_value(), DOMAIN, Protocol::Block)
    );
    // Nothing showed the loss but the silence: the client acknowledged segment 15 after 700 ms.
    assert!(
        net.trace.iter().any(|line| line == "700 605#A20F100000000000"),
        "{:#?}",
        net.trace
    );
}

#[test]
fn a_stopped_device_does_not_answer_and_the_client_times_out() {
    let mut net = Net::new(client().with_timeout(Duration::from_millis(500)));
    let stop = CanFrame::new(canopener_can::StandardId::ZERO, &[0x02, 0x05]).expect("NMT frame");
    net.dev_mut().handle_frame(Instant::ZERO, &stop);
    while net.dev_mut().poll_transmit().is_some() {}
    let error = failure(&net.transfer(upload(STRING, UploadMode::Normal)));
    assert_eq!(
        error,
        SdoTransferError::TimedOut {
            waiting_for: "initiate upload response",
            after: Duration::from_millis(500)
        }
    );
    assert_eq!(
        net.trace.last().map(String::as_str),
        Some("500 605#8001210000000405")
    );
}

fn modes(len: usize) -> Vec<(DownloadMode, Protocol)> {
    let mut modes = vec![
        (DownloadMode::Segmented, Protocol::Segmented),
        (DownloadMode::Block, Protocol::Block),
    ];
    if (1..=4).contains(&len) {
        modes.push((DownloadMode::Expedited, Protocol::Expedited));
        modes.push((DownloadMode::Auto, Protocol::Expedited));
    } else {
        modes.push((DownloadMode::Auto, Protocol::Segmented));
    }
    modes
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_values_round_trip_in_every_mode(
        value in proptest::collection::vec(any::<u8>(), 0..2000),
        block_size in 1u8..=127,
        crc: bool,
    ) {
        let base = od();
        for (mode, protocol) in modes(value.len()) {
            let mut net = Net::on(client().with_block_size(block_size).with_crc(crc), base.clone());
            let events = net.transfer(download(DOMAIN, &value, mode));
            prop_assert_eq!(outcome(&events), downloaded(DOMAIN, protocol));
            prop_assert_eq!(net.value(DOMAIN), value.clone());
            for upload_mode in [UploadMode::Normal, UploadMode::Block] {
                let events = net.transfer(upload(DOMAIN, upload_mode));
                let got = match outcome(&events).as_slice() {
                    [SdoClientEvent::Uploaded { data, .. }] => data.clone(),
                    other => return Err(TestCaseError::fail(format!("{mode:?}/{upload_mode:?}: {other:?}"))),
                };
                prop_assert_eq!(&got, &value);
            }
        }
    }
}
