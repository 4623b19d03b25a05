//! The models shipped with canopener (`models/*.mbt` in this crate), by name.

/// A shipped model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shipped {
    /// The name to give on the command line (`nmt`).
    pub name: &'static str,
    /// What it covers, in one line.
    pub covers: &'static str,
    /// The model text.
    pub text: &'static str,
    /// The model tests any CANopen device (CiA 301/305 services), so it joins the composition
    /// matrix (`examples/mbt_compose.rs` in canopener-runtime: every subset of these models must pass
    /// on clean simulated devices). `false` for models that need a particular device (the EnergyBus
    /// draft needs an EnergyBus device).
    pub canopen: bool,
}

/// Every shipped model.
pub const MODELS: &[Shipped] = &[
    Shipped {
        name: "nmt",
        covers: "NMT slave: boot-up, every module-control transition (own node-ID and broadcast), heartbeat producer with period 1017h and state byte, no SDO answer in Stopped, the 1029h reaction to a signalled communication error (CiA 301 §7.3.2, §7.2.8.3, table 43)",
        text: include_str!("../models/nmt.mbt"),
        canopen: true,
    },
    Shipped {
        name: "sdo",
        covers: "SDO server, expedited and segmented: upload sizes of 1000h/1001h/1018h (size indicated or not), segmented upload of 1008h and download to 1005h with the toggle bit, aborts for an absent object and sub-index, a read-only write, an unknown command and a wrong toggle, judged with the conformance suites' accepted codes, silence in Stopped (CiA 301 §7.2.4.3); uses nmt",
        text: include_str!("../models/sdo.mbt"),
        canopen: true,
    },
    Shipped {
        name: "sync",
        covers: "SYNC producer configured over SDO: period 1006h and counter 1019h on every SYNC, including a missing counter byte; SYNC consumer: TPDO1 of synchronous type n after every n-th SYNC and never between, in Operational (CiA 301 §7.2.5, 1800h); uses nmt",
        text: include_str!("../models/sync.mbt"),
        canopen: true,
    },
    Shipped {
        name: "lss",
        covers: "LSS slave: waiting/configuration, switch state global and selective, inquire identity and node-ID, fastscan (non-configured devices are found part by part and selected, configured ones keep silent) (CiA 305)",
        text: include_str!("../models/lss.mbt"),
        canopen: true,
    },
    Shipped {
        name: "emcy",
        covers: "EMCY producer: heartbeat-consumer event 8130h with error register 11h after 1016h's time, and the error reset 0000h when heartbeats resume (CiA 301 §7.2.7); uses heartbeat",
        text: include_str!("../models/emcy.mbt"),
        canopen: true,
    },
    Shipped {
        name: "guarding",
        covers: "Node guarding after 1017h = 0: every remote request answered with the NMT state and a toggle bit that starts at 0 after initialisation and alternates (CiA 301 §7.2.8.3.2.1); uses nmt",
        text: include_str!("../models/guarding.mbt"),
        canopen: true,
    },
    Shipped {
        name: "heartbeat",
        covers: "Heartbeat consumer 1016h: timeout after the consumer time, EMCY 8130h, NMT reaction per 1029h:01 (absent = Pre-operational) signalled to nmt, which judges it in the device's heartbeat (CiA 301 §7.2.8.3.2.2, 1029h); uses nmt",
        text: include_str!("../models/heartbeat.mbt"),
        canopen: true,
    },
    Shipped {
        name: "store",
        covers: "Store and restore parameters: 1010h/1011h capability bits, the signatures \"save\"/\"load\" (wrong ones refused with 0800 0020h), a saved parameter survives reset node and reset communication, \"load\" brings the default back at the next reset node (CiA 301 §7.5.2.13-14); uses nmt",
        text: include_str!("../models/store.mbt"),
        canopen: false,
    },
    Shipped {
        name: "pdo",
        covers: "PDO mapping procedure on a TPDO (not valid, sub-index 0 = 0, entries, sub-index 0 = n, valid) with the refusals of a mapping changed while valid or while sub-index 0 is not 0, a non-mappable object, too many entries, a restricted CAN-ID and a CAN-ID changed while valid; remote requests answered in Operational (type 253 or event-driven), not in Pre-operational (CiA 301 §7.5.2.35-38, §7.2.2); uses nmt",
        text: include_str!("../models/pdo.mbt"),
        canopen: false,
    },
    Shipped {
        name: "sdo-block",
        covers: "SDO block upload (1000h, 1018h:01, 1008h; block sizes 1, 2, 127; sequence numbers, c on the last segment, end n, CRC-16 of the data checked when both sides support it) and block download (1005h, with and without CRC, a wrong CRC refused with 0504 0004h); invalid block size and sequence number refused (CiA 301 §7.2.4.3.9-16); uses nmt",
        text: include_str!("../models/sdo-block.mbt"),
        canopen: false,
    },
    Shipped {
        name: "lss-config",
        covers: "LSS configure services beside `lss`: configure node-ID (own, out of range refused), configure bit timing (table 0, reserved table refused), store configuration, activate bit timing after 1017h = 0 (no frame for twice the switch delay), configure services ignored in waiting (CiA 305); uses nmt",
        text: include_str!("../models/lss-config.mbt"),
        canopen: false,
    },
    Shipped {
        name: "life-guarding",
        covers: "Life guarding after 1017h = 0, 100Ch and 100Dh: every guarding request answered; no request for guard time x life time factor gives the life guarding event (1029h reaction, signalled to nmt) and EMCY 8130h in that window (CiA 301 §7.2.8.3.2.1); uses nmt",
        text: include_str!("../models/life-guarding.mbt"),
        canopen: false,
    },
    Shipped {
        name: "sdo-download",
        covers: "SDO downloads of several segments: 14 bytes to 1005h refused as too long (never the last segment confirmed, each confirmation with its toggle); with --set LONG_INDEX/LONG_SUB a download of several full segments, a wrong toggle refused, the bytes read back; with --set LIMIT_*/HIGH/LOW values beyond the description's limits refused (CiA 301 §7.2.4.3.3-7); uses nmt",
        text: include_str!("../models/sdo-download.mbt"),
        canopen: false,
    },
    Shipped {
        name: "energybus-objects",
        covers: "EnergyBus: the assumed CiA 454 object indices and encodings the energybus-* models use (no behaviour; docs/energybus.md)",
        text: include_str!("../models/energybus-objects.mbt"),
        canopen: false,
    },
    Shipped {
        name: "energybus-ems",
        covers: "EnergyBus EMS, device side (CiA 454, objects assumed): control word transitions and refusals, status word, automatic steps, static and dynamic TPDOs; purposes walk_to_operating, boot_with_pdos",
        text: include_str!("../models/energybus-ems.mbt"),
        canopen: false,
    },
    Shipped {
        name: "energybus-lss",
        covers: "EnergyBus: initialisation of an unconfigured device by combinations of LSS services (fastscan, switch global and selective, identify, inquire, configure node-ID, store refused, activation with boot-up; reset node forgets the node-ID); purposes initialise_by_fastscan, initialise",
        text: include_str!("../models/energybus-lss.mbt"),
        canopen: false,
    },
    Shipped {
        name: "energybus-controller",
        covers: "EnergyBus controller side (node 1 is tested, the tester plays an unconfigured device): fastscan request by request, node-ID and activation, 1017h and 1016h:01, NMT start, the EMS walk by control words, its heartbeat, NMT reset node when the device's heartbeat stops; purposes integrate_device, lost_heartbeat",
        text: include_str!("../models/energybus-controller.mbt"),
        canopen: false,
    },
];

/// The shipped models that test any CANopen device (see [`Shipped::canopen`]).
pub fn canopen_models() -> impl Iterator<Item = &'static Shipped> {
    MODELS.iter().filter(|m| m.canopen)
}

/// Every shipped model of CANopen services, in or beyond the composition matrix: all but the
/// EnergyBus (CiA 454) ones, which need the emulated EnergyBus system.
pub fn all_canopen_models() -> impl Iterator<Item = &'static Shipped> {
    MODELS.iter().filter(|m| !m.name.starts_with("energybus"))
}

/// The text of the shipped model `name`.
pub fn text(name: &str) -> Option<&'static str> {
    MODELS.iter().find(|m| m.name == name).map(|m| m.text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::{Options, Source, compile};
    use crate::explore::explore;

    /// Every shipped model compiles without a diagnostic, with and without a description's
    /// values, and its state space is finite and free of evaluation errors.
    #[test]
    fn every_shipped_model_checks_and_explores() {
        for m in MODELS {
            let sources = [Source {
                origin: m.name.into(),
                text: m.text.into(),
            }];
            let (model, report) = compile(
                &sources,
                &Options {
                    node_id: 5,
                    ..Options::default()
                },
                &|n| text(n).map(str::to_owned),
            );
            let diagnostics: Vec<_> = report.iter().flat_map(|r| &r.diagnostics).collect();
            assert!(diagnostics.is_empty(), "{}: {diagnostics:#?}", m.name);
            let model = model.unwrap();
            assert!(!model.files[0].cites.is_empty(), "{} cites no clause", m.name);
            let (space, d) = explore(&model, 100_000);
            if m.name == "sdo-block" {
                // The running CRC-16 of an upload is state (65 536 values per segment byte), so
                // the space is finite but larger than the bound: only the prefix is checked.
                assert!(
                    d.iter()
                        .all(|d| d.code == crate::diagnostics::MbtCode::StateBound),
                    "{}: {d:?}",
                    m.name
                );
                continue;
            }
            assert!(d.is_empty() && !space.truncated, "{}: {d:?}", m.name);
        }
    }
}
