//! The telegrams of an EnergyBus system as people read them: every frame decoded by the bus decoder
//! (`canopener_wire::Decoder`, as `canopener bus decode` prints it), and the EnergyBus meaning added
//! where the frame carries an EMS object: a control word written (`EMS control word := 5
//! (Compatibility check -> Limiting)`), a status word read (`EMS status word = 8000h: Operating`), the
//! current limit, and the process values of the devices' TPDOs decoded by the description's mapping.

use canopener_can::{CanFrame, Instant};
use canopener_eds::Eds;
use canopener_master::pdo_decode::PdoLayout;
use canopener_master::pdo_watch::eds_lookup;
use canopener_od::DynamicOd;
use canopener_wire::energybus::EmsProfile;
use canopener_wire::sdo::{SdoRequest, SdoResponse};
use canopener_wire::{Decoder, Payload, SdoFrame, Service, TPDO_BASES};

/// One frame with what it means.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Telegram {
    /// When it was on the bus.
    pub at: Instant,
    /// The frame.
    pub frame: CanFrame,
    /// The service by the predefined connection set.
    pub service: Service,
    /// The bus decoder's line.
    pub decoded: String,
    /// What it means for EnergyBus, if it carries an EMS object.
    pub ems: Option<String>,
}

/// Decodes the telegrams of a system built from one EnergyBus description.
#[derive(Debug)]
pub struct TelegramDecoder {
    decoder: Decoder,
    profile: EmsProfile,
    /// The layout of TPDO *n* (index *n* − 1) as the description maps it.
    tpdos: Vec<Option<PdoLayout>>,
}

impl TelegramDecoder {
    /// A decoder for devices described by `eds` with the assumed objects of `profile`.
    pub fn new(eds: &Eds, profile: EmsProfile) -> TelegramDecoder {
        // The mappings do not depend on the node-ID; any node builds the same layouts.
        let od = canopener_device::od_build::build_od(eds, 1)
            .map(|built| built.od)
            .ok();
        let tpdos = (0..TPDO_BASES.len() as u16)
            .map(|n| {
                let od: &DynamicOd = od.as_ref()?;
                PdoLayout::from_od(od, 0x1A00 + n)
                    .ok()
                    .map(|layout| layout.typed(eds_lookup(eds)))
            })
            .collect();
        TelegramDecoder {
            decoder: Decoder::new(),
            profile,
            tpdos,
        }
    }

    /// The telegram of `frame`, on the bus at `at`.
    pub fn decode(&mut self, at: Instant, frame: &CanFrame) -> Telegram {
        let decoded = self.decoder.decode(frame);
        let ems = self.ems(frame, &decoded.payload);
        Telegram {
            at,
            frame: *frame,
            service: decoded.service,
            decoded: decoded.to_string(),
            ems,
        }
    }

    fn ems(&self, frame: &CanFrame, payload: &Payload) -> Option<String> {
        let objects = self.profile.objects;
        match payload {
            Payload::Sdo(sdo) => {
                let value = sdo.expedited_value();
                let (index, written) = match &sdo.frame {
                    SdoFrame::Request(SdoRequest::InitiateDownload { mux, .. }) => (mux.index, true),
                    SdoFrame::Response(SdoResponse::InitiateUpload { mux, .. }) => (mux.index, false),
                    _ => return None,
                };
                let value = u16::try_from(value?).ok()?;
                if index == objects.control_word && written {
                    Some(format!(
                        "EMS control word := {}",
                        self.profile.describe_control(value)
                    ))
                } else if index == objects.status_word && !written {
                    Some(self.status_text(value))
                } else if index == objects.current_limit && written {
                    Some(format!("EMS current limit := {value} mA"))
                } else {
                    None
                }
            }
            Payload::Pdo { data } => {
                let id = frame.id().as_raw();
                let number = TPDO_BASES
                    .iter()
                    .position(|base| id > u32::from(*base) && id <= u32::from(*base) + 127)?;
                let layout = self.tpdos.get(number)?.as_ref()?;
                let fields = layout.decode(data).ok()?;
                let texts: Vec<String> = fields
                    .iter()
                    .map(|f| {
                        if f.index == objects.status_word {
                            self.status_text(f.raw as u16)
                        } else {
                            f.to_string()
                        }
                    })
                    .collect();
                Some(format!("TPDO{}: {}", number + 1, texts.join(", ")))
            }
            _ => None,
        }
    }

    fn status_text(&self, status: u16) -> String {
        match self.profile.state_of(status) {
            Some(state) => format!("EMS status word = {status:04X}h: {state}"),
            None => format!("EMS status word = {status:04X}h: no EMS state"),
        }
    }
}

/// `  12.345  602  [8] 2B 01 60 00 05 00 00 00  SDO rx node 2: ...  | EMS control word := 5 (...)`:
/// seconds, CAN-ID, DLC, data, the decoder's line and the EnergyBus meaning.
pub fn line(telegram: &Telegram) -> String {
    let frame = &telegram.frame;
    let data = if frame.is_remote() {
        "remote request".to_owned()
    } else {
        frame
            .data()
            .iter()
            .map(|byte| format!("{byte:02X}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let seconds = telegram.at.as_nanos() as f64 / 1e9;
    let ems = telegram
        .ems
        .as_ref()
        .map(|e| format!("  | {e}"))
        .unwrap_or_default();
    format!(
        "{seconds:9.3}  {:>3}  [{}]  {data:<23}  {}{ems}",
        frame.id(),
        frame.dlc(),
        telegram.decoded
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use canopener_device::energybus::{EDS, profile};

    fn decoder() -> TelegramDecoder {
        let eds = canopener_eds::load(EDS.as_bytes()).eds;
        let profile = profile(&eds).unwrap();
        TelegramDecoder::new(&eds, profile)
    }

    fn frame(text: &str) -> CanFrame {
        canopener_can::candump::parse_compact_frame(text).unwrap()
    }

    #[test]
    fn ems_objects_are_named() {
        let mut d = decoder();
        let t = Instant::from_millis(1500);
        let write = d.decode(t, &frame("602#2B01600005000000"));
        assert_eq!(
            write.ems.as_deref(),
            Some("EMS control word := 5 (Compatibility check -> Limiting)")
        );
        assert!(
            line(&write).starts_with("    1.500  602  [8]  2B 01 60 00 05 00 00 00  SDO"),
            "{}",
            line(&write)
        );
        let read = d.decode(t, &frame("582#4B02600000800000"));
        assert_eq!(read.ems.as_deref(), Some("EMS status word = 8000h: Operating"));
        let limit = d.decode(t, &frame("602#2B206000DC050000"));
        assert_eq!(limit.ems.as_deref(), Some("EMS current limit := 1500 mA"));
        // TPDO2 of node 2: status word, actual voltage, actual current.
        let pdo = d.decode(t, &frame("282#008019 8CDC05".replace(' ', "").as_str()));
        assert_eq!(
            pdo.ems.as_deref(),
            Some(
                "TPDO2: EMS status word = 8000h: Operating, 6040:00 Actual voltage in mV (assumed) = 35865 \
                 (0x8C19), 603E:00 Actual current in mA (assumed) = 1500 (0x05DC)"
            )
        );
        let heartbeat = d.decode(t, &frame("702#05"));
        assert_eq!(heartbeat.ems, None);
    }
}
