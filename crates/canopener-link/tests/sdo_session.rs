//! The SDO session against a real device core on the simulated bus, on virtual time.

use std::time::Duration;

use canopener_bus_engine::virtual_bus::Timing;
use canopener_can::{Bitrate, Instant};
use canopener_device::application::NoApplication;
use canopener_device::device::Device;
use canopener_link::cancel::Cancel;
use canopener_link::link::Link;
use canopener_link::sdo_session::{Progress, SdoError, SdoSession, SessionError};
use canopener_link::virtual_link::VirtualLink;
use canopener_master::sdo_client::{DownloadMode, Protocol, SdoTransferError, UploadMode};
use canopener_testkit::corpus;
use canopener_wire::abort;

/// CANopenNode's example I/O device: CiA 301 communication objects, and 1008h (a VISIBLE_STRING, so reading it
/// is a segmented transfer).
const IO: &str = "CANopenNode__CANopenNode__example__IO.eds";

fn device(node: u8) -> Device {
    let path = corpus::eds(IO);
    let eds = canopener_eds::load(&canopener_testkit::fixture::read(path).expect("EDS file")).eds;
    let mut device = Device::from_eds(&eds, node, Box::new(NoApplication)).expect("device");
    device.boot(Instant::ZERO);
    device
}

fn link(timing: Timing, nodes: &[u8]) -> VirtualLink<Device> {
    let mut link = VirtualLink::new(timing);
    for &node in nodes {
        link.attach(device(node));
    }
    link.virtual_bus_mut().record();
    link
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02X}")).collect()
}

fn bus_lines(link: &mut VirtualLink<Device>) -> Vec<String> {
    link.virtual_bus_mut()
        .take_recording()
        .iter()
        .map(|f| format!("{} {}", f.at.as_micros(), f.frame))
        .collect()
}

#[test]
fn reads_and_writes_a_device_on_an_ideal_bus_as_a_frame_trace() {
    let mut link = link(Timing::Ideal, &[5]);
    let mut session = SdoSession::new(&mut link, 5, Duration::from_millis(500)).unwrap();
    let vendor = session.read(0x1018, 1).unwrap();
    assert_eq!(vendor.len(), 4);
    session.write(0x1017, 0, 100u16.to_le_bytes().to_vec()).unwrap();
    assert_eq!(session.read(0x1017, 0).unwrap(), [100, 0]);
    let lines = bus_lines(&mut link);
    // The boot-up first, then request/answer pairs, all at time 0 on an ideal bus. (The example device
    // starts itself, so its operational heartbeat and TPDO are on the bus too.)
    assert_eq!(lines[0], "0 705#00");
    let sdo: Vec<&str> = lines
        .iter()
        .map(String::as_str)
        .filter(|line| line.starts_with("0 605#") || line.starts_with("0 585#"))
        .collect();
    assert_eq!(
        sdo,
        [
            "0 605#4018100100000000",
            &format!("0 585#43181001{}", hex(&vendor)),
            "0 605#2B17100064000000",
            "0 585#6017100000000000",
            "0 605#4017100000000000",
            "0 585#4B17100064000000",
        ]
    );
}

#[test]
fn a_segmented_upload_reports_progress_and_takes_bus_time() {
    let mut link = link(Timing::BitAccurate(Bitrate::M1), &[5]);
    let mut session = SdoSession::new(&mut link, 5, Duration::from_millis(500)).unwrap();
    let mut seen = Vec::new();
    let name = session
        .upload(0x1008, 0, UploadMode::Normal, &mut |p: Progress| seen.push(p))
        .unwrap();
    assert_eq!(name.protocol, Protocol::Segmented);
    assert!(!name.data.is_empty());
    assert!(!seen.is_empty(), "segmented transfers report progress");
    // Every frame lasts its real length: at 1 Mbit/s a request/answer pair takes well over 200 µs.
    assert!(name.elapsed > Duration::from_micros(200), "{:?}", name.elapsed);
}

#[test]
fn refusals_and_silence_are_transfer_errors_with_the_abort_on_the_bus() {
    let mut link = link(Timing::Ideal, &[5]);
    let mut session = SdoSession::new(&mut link, 5, Duration::from_millis(300)).unwrap();
    let refused = session.read(0x5FFF, 0).unwrap_err();
    assert!(matches!(
        refused,
        SdoError::Transfer(SdoTransferError::AbortedByServer {
            code: abort::OBJECT_DOES_NOT_EXIST
        })
    ));
    // Node 9 is not on the bus: the client gives up after its timeout and says so on the bus.
    let mut silent = SdoSession::new(&mut link, 9, Duration::from_millis(300)).unwrap();
    let started = silent.link_mut().now();
    let error = silent.read(0x1000, 0).unwrap_err();
    assert!(
        matches!(error.transfer(), Some(SdoTransferError::TimedOut { .. })),
        "{error}"
    );
    assert_eq!(
        silent.link_mut().now().saturating_duration_since(started),
        Duration::from_millis(300)
    );
    let lines = bus_lines(&mut link);
    assert_eq!(
        lines.last().map(String::as_str),
        Some("300000 609#8000100000000405")
    );
}

#[test]
fn a_cancelled_link_aborts_the_transfer_on_the_bus() {
    let cancel = Cancel::new();
    let mut link = link(Timing::Ideal, &[]).with_cancel(cancel.clone());
    link.virtual_bus_mut().record();
    cancel.cancel();
    let mut session = SdoSession::new(&mut link, 5, Duration::from_millis(300)).unwrap();
    let error = session
        .download(
            0x2000,
            0,
            vec![1, 2, 3, 4, 5, 6, 7, 8, 9],
            DownloadMode::Segmented,
            &mut |_| {},
        )
        .unwrap_err();
    assert!(
        matches!(
            error,
            SdoError::Cancelled {
                index: 0x2000,
                sub: 0
            }
        ),
        "{error}"
    );
    let lines = bus_lines(&mut link);
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert_eq!(lines[1], "0 605#8000200000000008");
}

#[test]
fn zero_timeouts_and_nodes_without_a_channel_are_refused() {
    let mut link = link(Timing::Ideal, &[]);
    assert_eq!(
        SdoSession::new(&mut link, 5, Duration::ZERO).unwrap_err(),
        SessionError::ZeroTimeout
    );
    assert!(matches!(
        SdoSession::new(&mut link, 0, Duration::from_secs(1)).unwrap_err(),
        SessionError::Client(_)
    ));
}

#[test]
fn runs_on_virtual_time_are_deterministic() {
    let run = || {
        let mut link = link(Timing::BitAccurate(Bitrate::K250), &[5, 6]);
        for node in [5, 6] {
            let mut session = SdoSession::new(&mut link, node, Duration::from_millis(200)).unwrap();
            session.read(0x1008, 0).unwrap();
            session.read(0x1018, 4).unwrap();
        }
        link.run_until(Instant::from_millis(2_000)).unwrap();
        bus_lines(&mut link)
    };
    let first = run();
    assert!(first.len() > 10);
    assert_eq!(first, run());
}

#[test]
fn block_transfers_offer_the_crc_unless_switched_off_and_read_the_same_value_either_way() {
    let mut link = link(Timing::Ideal, &[5]);
    let mut session = SdoSession::new(&mut link, 5, Duration::from_millis(500)).unwrap();
    let name = session.read(0x1008, 0).unwrap();
    let initiates = |link: &mut VirtualLink<Device>| -> Vec<String> {
        bus_lines(link)
            .into_iter()
            .filter_map(|line| line.split_once(" 605#").map(|(_, data)| data.to_owned()))
            .filter(|data| data.starts_with('A'))
            .collect()
    };
    let block = |session: &mut SdoSession<&mut VirtualLink<Device>>| {
        session.upload(0x1008, 0, UploadMode::Block, &mut |_| {}).unwrap()
    };
    // Off: the initiate has cc = 0 (A0h), the value is the same.
    session.set_block_crc(false);
    let without = block(&mut session);
    assert_eq!(
        (without.data.as_slice(), without.protocol),
        (name.as_slice(), Protocol::Block)
    );
    // On again: cc = 1 (A4h).
    session.set_block_crc(true);
    assert_eq!(block(&mut session).data, name);
    let sent = initiates(&mut link);
    assert!(sent.iter().any(|d| d.starts_with("A0081000")), "{sent:?}");
    assert!(sent.iter().any(|d| d.starts_with("A4081000")), "{sent:?}");
    assert!(
        sent.iter().position(|d| d.starts_with("A0")) < sent.iter().position(|d| d.starts_with("A4")),
        "{sent:?}"
    );
}
