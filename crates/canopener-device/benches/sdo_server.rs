//! Frames per second of CPU time the device's protocol core handles in SDO transfers (CiA 301 §7.2.4):
//! a [`Device`] built from an EDS, booted, fed the client's request frames directly (no bus, no clock).
//!
//! Each benchmark is one whole transfer at node 22h of CANopenNode/gocanopen's `base.eds`: the
//! expedited upload of 1018h:01, the expedited download of the UNSIGNED32 2007h, and 889 bytes (127
//! segments of 7 bytes, exactly one block of 127) downloaded to and uploaded from the DOMAIN 200Fh,
//! segmented and as block transfers with CRC. Criterion's throughput is in frames: requests fed plus
//! responses drained, i.e. the frames of the transfer on the wire. The requests are encoded once with
//! `canopener_wire::sdo` (a client answers a deterministic server with the same frames every time), and
//! before timing every response of one run is compared with the one CiA 301 prescribes, so a wrong
//! answer stops the benchmark instead of being measured. Each benchmark also prints to stderr the exact
//! wire length of its frames (`canopener_can::bits`), which `bench/sdo_server.py` turns into the
//! physical limit at 1 Mbit/s.

// This is a benchmark, not library code: it reads the EDS of the device it times, so the
// workspace's sans-IO bans and its no-printing rule do not apply here.
#![allow(clippy::disallowed_methods, clippy::print_stdout, clippy::print_stderr)]

use canopener_can::Core;
use std::hint::black_box;

use canopener_can::bits::frame_bits;
use canopener_can::{CanFrame, Instant, StandardId};
use canopener_device::application::NoApplication;
use canopener_device::device::Device;
use canopener_od::ObjectKey;
use canopener_wire::crc16_ccitt;
use canopener_wire::sdo::{
    BlockSegment, InitiateData, MAX_BLOCK_SIZE, Multiplexer, SEGMENT_DATA_LEN, SdoRequest, SdoResponse,
    Segment,
};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

/// The EDS both sides of `bench/sdo_server.py` serve as well; it has an UNSIGNED32 and a DOMAIN that are
/// writable, which python canopen's LocalNode and this device can both hold.
const EDS: &str = "samsamfire__gocanopen__pkg__od__base.eds";
const NODE: u8 = 0x22;
/// 1018h:01 Vendor-ID, `DefaultValue=0x00000000` in the EDS.
const VENDOR_ID: Multiplexer = Multiplexer::new(0x1018, 1);
const VENDOR_ID_VALUE: u32 = 0;
/// 2007h "UNSIGNED32 value", rw.
const U32: Multiplexer = Multiplexer::new(0x2007, 0);
/// 200Fh "DOMAIN value", rw.
const DOMAIN: Multiplexer = Multiplexer::new(0x200F, 0);
/// 127 segments of 7 bytes: one full block, and the size the reference notes use for SDO wire times.
const LEN: usize = 889;
/// Virtual time between two frames; the transfers never get near the 1 s SDO timeout.
const FRAME_GAP_NANOS: u64 = 10_000;

/// One transfer: what the client sends, in order, and every response the server must give.
struct Transfer {
    name: &'static str,
    /// Each request with the responses it must produce (often none inside a block).
    steps: Vec<(CanFrame, Vec<[u8; 8]>)>,
}

impl Transfer {
    fn n_frames(&self) -> u64 {
        self.steps
            .iter()
            .map(|(_, responses)| 1 + responses.len() as u64)
            .sum()
    }

    /// Bits the transfer's frames occupy on the wire, from SOF to the end of the intermission.
    fn wire_bits(&self) -> u64 {
        let tx = cob_id(0x580);
        self.steps
            .iter()
            .map(|(request, responses)| {
                let answers: u32 = responses
                    .iter()
                    .map(|data| frame_bits(&CanFrame::new(tx, data).expect("8 bytes")).total)
                    .sum();
                u64::from(frame_bits(request).total + answers)
            })
            .sum()
    }
}

/// The device and its virtual clock.
struct Harness {
    dev: Device,
    now: Instant,
}

impl Harness {
    fn booted() -> Harness {
        let bytes = std::fs::read(canopener_testkit::corpus::eds(EDS)).expect("the corpus EDS");
        let eds = canopener_eds::load(&bytes).eds;
        let mut dev = Device::from_eds(&eds, NODE, Box::new(NoApplication)).expect("device");
        dev.boot(Instant::ZERO);
        while dev.poll_transmit().is_some() {}
        while dev.poll_event().is_some() {}
        Harness {
            dev,
            now: Instant::ZERO,
        }
    }

    /// Runs `transfer` as a driver would (feed, drain frames and events) and returns the frames
    /// handled, requests plus responses.
    fn run(&mut self, transfer: &Transfer) -> u64 {
        let mut n_frames = 0;
        for (request, _) in &transfer.steps {
            self.now = Instant::from_nanos(self.now.as_nanos() + FRAME_GAP_NANOS);
            self.dev.handle_frame(self.now, request);
            n_frames += 1;
            while let Some(frame) = self.dev.poll_transmit() {
                black_box(frame);
                n_frames += 1;
            }
            while let Some(event) = self.dev.poll_event() {
                black_box(event);
            }
        }
        n_frames
    }

    /// Runs `transfer` once and panics unless every response is exactly the expected one.
    fn verify(&mut self, transfer: &Transfer) {
        for (step, (request, expected)) in transfer.steps.iter().enumerate() {
            self.now = Instant::from_nanos(self.now.as_nanos() + FRAME_GAP_NANOS);
            self.dev.handle_frame(self.now, request);
            let mut got = Vec::new();
            while let Some(frame) = self.dev.poll_transmit() {
                assert_eq!(
                    frame.id(),
                    cob_id(0x580).into(),
                    "{}: response on the wrong COB-ID",
                    transfer.name
                );
                got.push(<[u8; 8]>::try_from(frame.data()).expect("SDO responses have 8 bytes"));
            }
            while self.dev.poll_event().is_some() {}
            assert_eq!(
                &got, expected,
                "{}: responses to request {step} ({request})",
                transfer.name
            );
        }
    }
}

/// The COB-ID `base` + node-ID: 600h for requests, 580h for responses (pre-defined connection set).
fn cob_id(base: u16) -> StandardId {
    StandardId::new(base + u16::from(NODE)).expect("a node-ID added to an SDO base is a standard ID")
}

fn request(req: &SdoRequest) -> CanFrame {
    CanFrame::new(cob_id(0x600), &req.encode().expect("valid request")).expect("8 bytes")
}

fn response(res: &SdoResponse) -> [u8; 8] {
    res.encode().expect("valid response")
}

/// The 889 bytes transferred: printable text, like the strings and files SDO usually carries.
fn payload() -> Vec<u8> {
    (0..LEN).map(|i| b'A' + (i % 26) as u8).collect()
}

fn segments(data: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    data.chunks(SEGMENT_DATA_LEN).enumerate()
}

/// Expedited upload (§7.2.4.3.6): one request, one response with the value.
fn expedited_upload() -> Transfer {
    let value = VENDOR_ID_VALUE.to_le_bytes().to_vec();
    Transfer {
        name: "expedited_upload_1018h01",
        steps: vec![(
            request(&SdoRequest::InitiateUpload { mux: VENDOR_ID }),
            vec![response(&SdoResponse::InitiateUpload {
                mux: VENDOR_ID,
                data: InitiateData::Expedited {
                    data: value,
                    size_indicated: true,
                },
            })],
        )],
    }
}

/// Expedited download (§7.2.4.3.3) of 4 bytes.
fn expedited_download(value: u32) -> Transfer {
    Transfer {
        name: "expedited_download_u32",
        steps: vec![(
            request(&SdoRequest::InitiateDownload {
                mux: U32,
                data: InitiateData::Expedited {
                    data: value.to_le_bytes().to_vec(),
                    size_indicated: true,
                },
            }),
            vec![response(&SdoResponse::InitiateDownload { mux: U32 })],
        )],
    }
}

/// Segmented download (§7.2.4.3.3, §7.2.4.3.4): initiate with the size, then one confirmed segment per
/// 7 bytes with alternating toggle.
fn segmented_download(data: &[u8]) -> Transfer {
    let mut steps = vec![(
        request(&SdoRequest::InitiateDownload {
            mux: DOMAIN,
            data: InitiateData::Segmented {
                size: Some(data.len() as u32),
            },
        }),
        vec![response(&SdoResponse::InitiateDownload { mux: DOMAIN })],
    )];
    let n_segments = data.len().div_ceil(SEGMENT_DATA_LEN);
    for (idx, chunk) in segments(data) {
        let toggle = idx % 2 == 1;
        steps.push((
            request(&SdoRequest::DownloadSegment(Segment {
                toggle,
                data: chunk.to_vec(),
                last: idx + 1 == n_segments,
            })),
            vec![response(&SdoResponse::DownloadSegment { toggle })],
        ));
    }
    Transfer {
        name: "segmented_download_889",
        steps,
    }
}

/// Segmented upload (§7.2.4.3.6, §7.2.4.3.7): initiate answered with the size, then one segment per
/// request with alternating toggle.
fn segmented_upload(data: &[u8]) -> Transfer {
    let mut steps = vec![(
        request(&SdoRequest::InitiateUpload { mux: DOMAIN }),
        vec![response(&SdoResponse::InitiateUpload {
            mux: DOMAIN,
            data: InitiateData::Segmented {
                size: Some(data.len() as u32),
            },
        })],
    )];
    let n_segments = data.len().div_ceil(SEGMENT_DATA_LEN);
    for (idx, chunk) in segments(data) {
        let toggle = idx % 2 == 1;
        steps.push((
            request(&SdoRequest::UploadSegment { toggle }),
            vec![response(&SdoResponse::UploadSegment(Segment {
                toggle,
                data: chunk.to_vec(),
                last: idx + 1 == n_segments,
            }))],
        ));
    }
    Transfer {
        name: "segmented_upload_889",
        steps,
    }
}

fn block_segment(idx: usize, chunk: &[u8], last: bool) -> [u8; 8] {
    let mut data = [0; 7];
    data[..chunk.len()].copy_from_slice(chunk);
    BlockSegment {
        last,
        // At most 127 segments (one block), so the sequence number fits.
        seqno: (idx + 1) as u8,
        data,
    }
    .encode()
    .expect("sequence number 1..=127")
}

fn unused_in_last(data: &[u8]) -> u8 {
    ((SEGMENT_DATA_LEN - data.len() % SEGMENT_DATA_LEN) % SEGMENT_DATA_LEN) as u8
}

/// Block download (§7.2.4.3.9 to §7.2.4.3.11) of one block with CRC: initiate, 127 segments
/// acknowledged once, end with the CRC.
fn block_download(data: &[u8]) -> Transfer {
    let n_segments = data.len().div_ceil(SEGMENT_DATA_LEN);
    assert!(n_segments <= usize::from(MAX_BLOCK_SIZE), "one block only");
    let mut steps = vec![(
        request(&SdoRequest::BlockDownloadInitiate {
            mux: DOMAIN,
            crc_supported: true,
            size: Some(data.len() as u32),
        }),
        vec![response(&SdoResponse::BlockDownloadInitiate {
            mux: DOMAIN,
            crc_supported: true,
            blksize: MAX_BLOCK_SIZE,
        })],
    )];
    for (idx, chunk) in segments(data) {
        let last = idx + 1 == n_segments;
        let frame = CanFrame::new(cob_id(0x600), &block_segment(idx, chunk, last)).expect("8 bytes");
        let answers = if last {
            vec![response(&SdoResponse::BlockDownloadAck {
                ackseq: n_segments as u8,
                blksize: MAX_BLOCK_SIZE,
            })]
        } else {
            Vec::new()
        };
        steps.push((frame, answers));
    }
    steps.push((
        request(&SdoRequest::BlockDownloadEnd {
            unused: unused_in_last(data),
            crc: crc16_ccitt(data),
        }),
        vec![response(&SdoResponse::BlockDownloadEndResponse)],
    ));
    Transfer {
        name: "block_download_889",
        steps,
    }
}

/// Block upload (§7.2.4.3.13 to §7.2.4.3.15) of one block with CRC: initiate (no protocol switch),
/// start, 127 segments, the acknowledge answered by the end frame with the CRC, the end response.
fn block_upload(data: &[u8]) -> Transfer {
    let n_segments = data.len().div_ceil(SEGMENT_DATA_LEN);
    assert!(n_segments <= usize::from(MAX_BLOCK_SIZE), "one block only");
    let sub_block: Vec<[u8; 8]> = segments(data)
        .map(|(idx, chunk)| block_segment(idx, chunk, idx + 1 == n_segments))
        .collect();
    let steps = vec![
        (
            request(&SdoRequest::BlockUploadInitiate {
                mux: DOMAIN,
                crc_supported: true,
                blksize: MAX_BLOCK_SIZE,
                pst: 0,
            }),
            vec![response(&SdoResponse::BlockUploadInitiate {
                mux: DOMAIN,
                crc_supported: true,
                size: Some(data.len() as u32),
            })],
        ),
        (request(&SdoRequest::BlockUploadStart), sub_block),
        (
            request(&SdoRequest::BlockUploadAck {
                ackseq: n_segments as u8,
                blksize: MAX_BLOCK_SIZE,
            }),
            vec![response(&SdoResponse::BlockUploadEnd {
                unused: unused_in_last(data),
                crc: crc16_ccitt(data),
            })],
        ),
        (request(&SdoRequest::BlockUploadEndResponse), Vec::new()),
    ];
    Transfer {
        name: "block_upload_889",
        steps,
    }
}

fn bench_sdo_server(c: &mut Criterion) {
    let data = payload();
    let mut harness = Harness::booted();
    // Downloads first, so the uploads find the 889 bytes (and 2007h the value) in the dictionary.
    let transfers = [
        expedited_upload(),
        expedited_download(0x1234_5678),
        segmented_download(&data),
        segmented_upload(&data),
        block_download(&data),
        block_upload(&data),
    ];
    let mut group = c.benchmark_group("sdo_server");
    for transfer in &transfers {
        harness.verify(transfer);
        eprintln!(
            "wire {}: {} frames, {} bits",
            transfer.name,
            transfer.n_frames(),
            transfer.wire_bits()
        );
        let n_frames = transfer.n_frames();
        group.throughput(Throughput::Elements(n_frames));
        group.bench_function(transfer.name, |b| {
            b.iter(|| {
                let handled = harness.run(black_box(transfer));
                assert_eq!(handled, n_frames, "{}: frames handled", transfer.name);
            })
        });
    }
    group.finish();
    let od = harness.dev.od();
    assert_eq!(
        od.read(ObjectKey::new(U32.index, U32.sub)).ok(),
        Some(&0x1234_5678u32.to_le_bytes()[..])
    );
    assert_eq!(
        od.read(ObjectKey::new(DOMAIN.index, DOMAIN.sub)).ok(),
        Some(&data[..])
    );
}

criterion_group!(benches, bench_sdo_server);
criterion_main!(benches);
