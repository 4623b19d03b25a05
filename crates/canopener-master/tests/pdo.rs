//! PDO configuration plans applied to a real simulated device over SDO, and the PDOs it then sends
//! or receives decoded with a `PdoLayout`: the master's view of CiA 301 §7.2.2 checked against the
//! device side's, on virtual time.

use canopener_can::Core;
use canopener_can::{CanFrame, CanId, Instant};
use canopener_device::application::NoApplication;
use canopener_device::device::Device;
use canopener_master::pdo_config::{Direction, MappedObject, PdoConfig, SdoWrite};
use canopener_master::pdo_decode::PdoLayout;
use canopener_master::value::{DisplayValue, ValueType, parse_mapping};
use canopener_od::{DataType, ObjectKey};
use canopener_wire::sdo::{InitiateData, Multiplexer, SdoRequest, SdoResponse};
use canopener_wire::{NodeId, RPDO_BASES, SDO_RX_BASE, SDO_TX_BASE, TPDO_BASES};

/// The checker's CiA 401 fixture: one TPDO and one RPDO, node-ID from the caller.
const BASE: &str = canopener_testkit::fixture::BASE_EDS;
/// CANopenNode's CiA 401 example: eight mapping entries per PDO, dummies 0002h–0007h enabled.
const IO: &str = "CANopenNode__CANopenNode__example__IO.eds";

fn eds(path: &str) -> canopener_eds::Eds {
    canopener_eds::load(&canopener_testkit::fixture::read(path).expect("EDS file")).eds
}

/// Names and data types of the objects in an EDS, as `pdo watch --eds` looks them up.
fn eds_lookup(eds: &canopener_eds::Eds) -> impl FnMut(u16, u8) -> Option<(String, DataType)> + '_ {
    move |index, sub| {
        let object = eds.object(index)?;
        let (name, attributes) = match object.subs.get(&sub) {
            Some(sub_object) => (
                format!(
                    "{}/{}",
                    object.name(),
                    sub_object.attributes.parameter_name.as_deref()?
                ),
                &sub_object.attributes,
            ),
            None if sub == 0 => (object.name().to_owned(), &object.attributes),
            None => return None,
        };
        Some((name, attributes.data_type()?))
    }
}

/// A device on virtual time, with everything it sent.
struct Bench {
    dev: Device,
    node: u8,
    now: Instant,
    sent: Vec<(Instant, CanFrame)>,
}

impl Bench {
    fn booted(path: &str, node: u8) -> Bench {
        let dev = Device::from_eds(&eds(path), node, Box::new(NoApplication)).expect("device");
        let mut bench = Bench {
            dev,
            node,
            now: Instant::ZERO,
            sent: Vec::new(),
        };
        bench.dev.boot(Instant::ZERO);
        bench.drain();
        bench.sent.clear();
        bench
    }

    fn drain(&mut self) {
        while let Some(frame) = self.dev.poll_transmit() {
            self.sent.push((self.now, frame));
        }
        while self.dev.poll_event().is_some() {}
    }

    fn advance_to(&mut self, until: Instant) {
        self.drain();
        while let Some(due) = self.dev.poll_timeout() {
            if due > until {
                break;
            }
            self.now = due.max(self.now);
            self.dev.handle_timeout(self.now);
            self.drain();
        }
        self.now = until;
    }

    fn rx(&mut self, frame: &CanFrame) {
        self.dev.handle_frame(self.now, frame);
        self.drain();
    }

    fn frame(id: u16, data: &[u8]) -> CanFrame {
        CanFrame::new(CanId::standard(id).expect("11-bit"), data).expect("frame")
    }

    /// One SDO request and the device's answer on its default SDO server.
    fn sdo(&mut self, request: SdoRequest) -> SdoResponse {
        let data = request.encode().expect("request");
        self.rx(&Bench::frame(SDO_RX_BASE + u16::from(self.node), &data));
        let reply_id = CanId::standard(SDO_TX_BASE + u16::from(self.node)).expect("11-bit");
        let idx = self
            .sent
            .iter()
            .rposition(|(_, frame)| frame.id() == reply_id)
            .expect("an SDO answer");
        let (_, frame) = self.sent.remove(idx);
        let data: [u8; 8] = frame.data().try_into().expect("8-byte SDO frame");
        SdoResponse::parse(&data).expect("SDO response")
    }

    /// Applies a plan write by write as expedited downloads, stopping at the first abort.
    fn apply(&mut self, writes: &[SdoWrite]) -> Result<(), String> {
        for write in writes {
            let mux = Multiplexer {
                index: write.index,
                sub: write.sub,
            };
            let request = SdoRequest::InitiateDownload {
                mux,
                data: InitiateData::Expedited {
                    data: write.data.clone(),
                    size_indicated: true,
                },
            };
            match self.sdo(request) {
                SdoResponse::InitiateDownload { mux: answered } if answered == mux => {}
                SdoResponse::Abort { code, .. } => return Err(format!("{write}: abort {code:08X}h")),
                other => return Err(format!("{write}: unexpected {other:?}")),
            }
        }
        Ok(())
    }

    /// Reads a 4-byte entry with an expedited upload, as the CLI reads the current COB-ID.
    fn upload_u32(&mut self, index: u16, sub: u8) -> u32 {
        match self.sdo(SdoRequest::InitiateUpload {
            mux: Multiplexer { index, sub },
        }) {
            SdoResponse::InitiateUpload { data, .. } => data.expedited_value().expect("expedited"),
            other => panic!("upload {index:04X}:{sub:02X}: {other:?}"),
        }
    }

    fn set(&mut self, index: u16, sub: u8, value: &[u8]) {
        self.dev
            .od_mut()
            .set_value(ObjectKey::new(index, sub), value)
            .expect("value");
    }

    fn start(&mut self) {
        self.rx(&Bench::frame(0x000, &[0x01, self.node]));
    }

    /// The PDOs sent on `cob_id` since the last call, as (milliseconds, data).
    fn pdos(&mut self, cob_id: u16) -> Vec<(u64, Vec<u8>)> {
        let id = CanId::standard(cob_id).expect("11-bit");
        let (pdos, rest) = std::mem::take(&mut self.sent)
            .into_iter()
            .partition(|(_, frame)| frame.id() == id);
        self.sent = rest;
        pdos.into_iter()
            .map(|(at, frame): (Instant, CanFrame)| (at.as_micros() / 1000, frame.data().to_vec()))
            .collect()
    }
}

fn mapping(texts: &[&str]) -> Vec<MappedObject> {
    texts
        .iter()
        .map(|text| parse_mapping(text).expect("mapping"))
        .collect()
}

#[test]
fn tpdo_remapped_bit_by_bit_then_sent_by_its_event_timer() {
    let node = 0x0A;
    let io_path = canopener_testkit::corpus::eds(IO).display().to_string();
    let mut bench = Bench::booted(&io_path, node);
    let io = eds(&io_path);
    let current = bench.upload_u32(0x1800, 1);
    assert_eq!(current, 0x18A);

    let config = PdoConfig {
        direction: Direction::Tpdo,
        number: 1,
        cob_id: None,
        transmission_type: Some(254),
        inhibit_time_100us: Some(0),
        event_timer_ms: Some(100),
        sync_start: None,
        // 1 bit, 7 bits, an UNSIGNED8 dummy byte, 16 bits, 8 bits: 40 bits, not all byte-aligned.
        mapping: mapping(&["6000:01:1", "6000:02:7", "0005:00:8", "6401:01:16", "6000:03:8"]),
    };
    let writes = config
        .plan(NodeId::new(node).expect("node"), Some(current))
        .expect("plan");
    assert_eq!(writes.len(), 12);
    assert_eq!(bench.apply(&writes), Ok(()));

    // The device holds exactly the mapping planned, and a layout read back from it agrees.
    let from_device = PdoLayout::from_od(bench.dev.od(), 0x1A00).expect("layout");
    let planned = PdoLayout::new(&config.mapping).expect("layout");
    assert_eq!(from_device, planned);
    let layout = from_device.typed(eds_lookup(&io));

    bench.set(0x6000, 1, &[0xFF]); // only bit 0 is mapped
    bench.set(0x6000, 2, &[0x55]); // 7 bits: 55h fits
    bench.set(0x6401, 1, &(-1234i16).to_le_bytes());
    bench.set(0x6000, 3, &[0xAB]);
    bench.start();
    bench.advance_to(Instant::from_millis(250));
    let pdos = bench.pdos(TPDO_BASES[0] + u16::from(node));
    let times: Vec<u64> = pdos.iter().map(|(at, _)| *at).collect();
    // Once on entering Operational, then every 100 ms.
    assert_eq!(times, [0, 100, 200]);
    let (_, data) = &pdos[2];
    // Bit 0 = 1, bits 1..7 = 55h, a zero dummy byte, -1234 little-endian, ABh.
    assert_eq!(data, &[0xAB, 0x00, 0x2E, 0xFB, 0xAB]);

    let fields = layout.decode(data).expect("decoded");
    let lines: Vec<String> = fields
        .iter()
        .map(|field| format!("@{}+{} {field}", field.offset, field.bits))
        .collect();
    assert_eq!(
        lines,
        [
            "@0+1 6000:01 Read input 8 bit/Input = 1 (0x1)",
            "@1+7 6000:02 Read input 8 bit/Input = 85 (0x55)",
            "@16+16 6401:01 Read analogue input 16 bit/Input = -1234 (0xFB2E)",
            "@32+8 6000:03 Read input 8 bit/Input = 171 (0xAB)",
        ]
    );
    assert_eq!(
        fields[2].value,
        DisplayValue::Signed {
            value: -1234,
            bits: 16
        }
    );
    assert_eq!(fields[2].data_type, Some(DataType::INTEGER16));
    // The same bytes through the SDO value codec give the same number.
    assert_eq!(ValueType::I16.decode(&data[2..4]).expect("i16"), fields[2].value);
}

#[test]
fn tpdo_on_sync_decoded_from_the_devices_own_mapping() {
    let node = 5;
    let mut bench = Bench::booted(BASE, node);
    let config = PdoConfig {
        direction: Direction::Tpdo,
        number: 1,
        cob_id: None,
        transmission_type: Some(2),
        inhibit_time_100us: None,
        event_timer_ms: None,
        sync_start: None,
        mapping: mapping(&["6000:01:8"]),
    };
    let writes = config.plan(NodeId::new(node).expect("node"), None).expect("plan");
    assert_eq!(bench.apply(&writes), Ok(()));
    let base = eds(BASE);
    let layout = PdoLayout::from_od(bench.dev.od(), 0x1A00)
        .expect("layout")
        .typed(eds_lookup(&base));

    bench.set(0x6000, 1, &[0x3C]);
    bench.start();
    assert_eq!(bench.pdos(0x185), [], "synchronous: nothing before a SYNC");
    // Transmission type 2: every second SYNC, the first SYNC seen counting as one (CiA 301 "every
    // n-th SYNC", counted as lely and CANopenNode do).
    for ms in [10, 20, 30, 40] {
        bench.advance_to(Instant::from_millis(ms));
        bench.rx(&Bench::frame(0x080, &[]));
    }
    let pdos = bench.pdos(TPDO_BASES[0] + u16::from(node));
    assert_eq!(pdos, [(20, vec![0x3C]), (40, vec![0x3C])]);
    let fields = layout.decode(&pdos[0].1).expect("decoded");
    assert_eq!(fields.len(), 1);
    assert_eq!(
        fields[0].to_string(),
        "6000:01 Read input 8-bit/Read input 1h to 8h = 60 (0x3C)"
    );
}

#[test]
fn rpdo_plan_then_the_device_and_the_layout_agree_on_a_frame() {
    let node = 5;
    let mut bench = Bench::booted(BASE, node);
    let config = PdoConfig {
        direction: Direction::Rpdo,
        number: 1,
        cob_id: None,
        transmission_type: Some(255),
        inhibit_time_100us: None,
        event_timer_ms: None,
        sync_start: None,
        mapping: mapping(&["6200:01:8"]),
    };
    let writes = config.plan(NodeId::new(node).expect("node"), None).expect("plan");
    let steps: Vec<String> = writes.iter().map(ToString::to_string).collect();
    assert_eq!(
        steps,
        [
            "1400h:01 = 80000205h (make the PDO invalid while it changes)",
            "1600h:00 = 00h (disable the mapping while its entries change)",
            "1600h:01 = 62000108h (mapping entry)",
            "1600h:00 = 01h (enable the mapping with its number of entries)",
            "1400h:02 = FFh (transmission type)",
            "1400h:01 = 00000205h (make the PDO valid with its COB-ID)",
        ]
    );
    assert_eq!(bench.apply(&writes), Ok(()));
    bench.start();
    let frame = [0xA5];
    bench.rx(&Bench::frame(RPDO_BASES[0] + u16::from(node), &frame));
    assert_eq!(
        bench.dev.od().read(ObjectKey::new(0x6200, 1)).expect("6200h"),
        [0xA5]
    );
    let layout = PdoLayout::from_od(bench.dev.od(), 0x1600).expect("layout");
    let fields = layout.decode(&frame).expect("decoded");
    assert_eq!(fields[0].value.as_u64(), Some(0xA5));
    // A frame the device would refuse as too short (EMCY 8210h) is an error here too.
    assert!(layout.decode(&[]).is_err());
}

#[test]
fn the_device_refuses_what_the_plan_cannot_know() {
    // 2000h exists but is not mappable: only the device can say so, with 0604 0041h, and applying
    // stops at that write.
    let node = 5;
    let mut bench = Bench::booted(BASE, node);
    let config = PdoConfig {
        direction: Direction::Tpdo,
        number: 1,
        cob_id: None,
        transmission_type: None,
        inhibit_time_100us: None,
        event_timer_ms: None,
        sync_start: None,
        mapping: mapping(&["2000:00:16"]),
    };
    let writes = config.plan(NodeId::new(node).expect("node"), None).expect("plan");
    assert_eq!(
        bench.apply(&writes),
        Err("1A00h:01 = 20000010h (mapping entry): abort 06040041h".to_owned())
    );
}
