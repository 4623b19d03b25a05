//! The fault catalogue: named, documented defects a real device might have, switchable per
//! [`Device`](crate::device::Device) with [`Device::with_faults`](crate::device::Device::with_faults).
//!
//! Each [`Fault`] is a small, explicit deviation applied by the `Device` around its cores, never
//! inside them: the cores stay correct, and a device without faults behaves exactly as before.
//! A fault acts at one of six places:
//! - **on received frames**, before any core sees them (`FaultLayer::inbound`): a frame is
//!   dropped (NMT stop, NMT broadcast, LSS, TPDO remote requests) or rewritten (the SDO toggle bit
//!   is forced to what the server expects, an NMT command's node-ID becomes the device's own, a
//!   block transfer without CRC becomes an invalid command);
//! - **on sent frames**, after the cores made them and before they leave the device
//!   (`FaultLayer::outbound`): a frame is dropped (boot-up, EMCY, TPDOs in pre-operational),
//!   rewritten (heartbeat state, abort code, expedited size bit, SYNC counter, block CRC, boot-up
//!   CAN-ID, EMCY error register, 1000h's byte order, sub-index FFh, the last segment's unused
//!   bytes) or delayed and duplicated on virtual time (slow SDO, heartbeat jitter, extra heartbeats
//!   1 ms apart);
//! - **in the `Device`'s own checks** on SDO downloads: a download a correct device refuses
//!   (above HighLimit, a non-mappable object in a PDO mapping, a restricted COB-ID, a mapping
//!   outside the procedure or too long, a count to 1003h:00, a wrong signature) is stored and
//!   confirmed anyway, a process output is refused in an RPDO mapping, and a `save` or `load`
//!   signature is confirmed without storing (or restoring) anything, or everything but 1020h;
//! - **in the `Device`'s routing**: node guarding requests are answered while heartbeat runs, SDO
//!   requests in stopped, PDOs in pre-operational or stopped and remote requests for TPDOs in
//!   pre-operational reach their cores (`FaultLayer::routes`);
//! - **in what the `Device` tells its cores**: the NMT state the PDO engine, the EMCY producer and
//!   SYNC run in (`FaultLayer::core_state`), the PDO parameters the engine reads (bit 31 of TPDO
//!   COB-IDs cleared, `FaultLayer::pdo_parameters`), and 1001h, cleared after every update;
//! - **in the `Device`'s resets**: which areas of the dictionary reset node and reset
//!   communication set back to their power-on values.
//!
//! The sources of the defects: the thesis in `seeds/001` (a UWASA node tested with a Kvaser rig:
//! a write above HighLimit to 1F51h accepted, a non-mappable object accepted into a PDO mapping,
//! heartbeats 1 ms apart, no RTR on TPDOs, no LSS), the EnergyBus conformance testing paper (a
//! missing SYNC counter, a missing LSS state change during configuration), the planted defects of
//! issue 22 that an earlier CiA 301 suite did not notice (PDOs in pre-operational, NMT commands to
//! other nodes obeyed, invalid TPDOs sent, 1001h not updated, reset communication restoring the
//! application area) and field experience.

use std::collections::VecDeque;
use std::fmt;
use std::str::FromStr;
use std::time::Duration;

use canopener_can::{CanFrame, Instant, StandardId};
use canopener_od::{DynamicOd, ObjectKey};
use canopener_wire::{ERROR_CONTROL_BASE, LSS_MASTER_TO_SLAVE_ID, NMT_ID, NodeId, abort};

use crate::nmt_slave::{CommService, NmtSlaveState};

/// The SDO response delay of [`Fault::SdoSlow`] unless [`FaultSet::with_sdo_delay`] says
/// otherwise: longer than the 500 ms many SDO clients wait by default.
pub const DEFAULT_SDO_DELAY: Duration = Duration::from_millis(600);

/// The gap between a heartbeat and its copy under [`Fault::HeartbeatTooFast`].
pub const HEARTBEAT_COPY_GAP: Duration = Duration::from_millis(1);

/// One defect a simulated device can have.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Fault {
    /// No boot-up message after power-on or a reset.
    NoBootUp,
    /// The boot-up message on 700h + node-ID + 1.
    BootUpWrongId,
    /// Heartbeat and guarding answers report a valid but wrong NMT state.
    HeartbeatStateWrong,
    /// Every heartbeat is sent twice, 1 ms apart.
    HeartbeatTooFast,
    /// Every second heartbeat is 40 % of the period late.
    HeartbeatJitter,
    /// Node guarding is answered while heartbeat production runs.
    GuardingAndHeartbeat,
    /// NMT stop is ignored.
    IgnoresNmtStop,
    /// NMT commands to all nodes (node-ID 0) are ignored.
    NmtBroadcastIgnored,
    /// The SDO server does not check the toggle bit of segments.
    SdoToggleIgnored,
    /// Every SDO response is sent late.
    SdoSlow,
    /// Expedited upload responses claim 4 bytes whatever the size.
    SdoExpeditedSizeWrong,
    /// Every SDO abort carries the general error 0800 0000h.
    WrongAbortCode,
    /// Requests with an unknown command specifier are not answered.
    SdoBadCommandSilent,
    /// The CRC of a block upload is wrong.
    BlockCrcWrong,
    /// Writes above HighLimit (or below LowLimit) are accepted.
    LimitNotEnforced,
    /// A non-mappable object is accepted into a PDO mapping.
    UnmappableAccepted,
    /// A restricted CAN-ID is accepted as a PDO COB-ID.
    PdoCobIdUnchecked,
    /// Remote requests on TPDOs are not answered.
    NoTpdoRtr,
    /// No EMCY is ever sent.
    NoEmcy,
    /// The error-reset EMCY (0000h) is never sent.
    EmcyNoErrorReset,
    /// `save` to 1010h is confirmed but nothing is stored.
    StoreIgnored,
    /// The SYNC producer leaves out the counter byte.
    SyncCounterMissing,
    /// The device has no LSS slave.
    NoLss,
    /// The LSS slave never leaves the waiting state.
    LssStateNotChanged,
    /// SDO downloads to TPDO parameters 18xxh:02–06 are never answered.
    TpdoConfigSilent,
    /// SDO downloads to TPDO parameters 18xxh:02–06 are refused with the general error.
    TpdoConfigRefused,
    /// A new PDO mapping is stored and confirmed but not applied until reset communication.
    MappingNotApplied,
    /// The SYNC producer runs at twice the rate 1006h sets.
    SyncProducerFast,
    /// A TPDO event timer elapses after half the time 18xxh:05 sets.
    TpdoEventTimerFast,
    /// The error register byte of every EMCY has the generic bit (bit 0) clear.
    EmcyGenericBitClear,
    /// TPDOs are sent in pre-operational.
    TpdoInPreOperational,
    /// RPDOs received in pre-operational are acted on.
    RpdoInPreOperational,
    /// PDOs keep running in stopped.
    PdoInStopped,
    /// NMT commands addressed to another node-ID are obeyed.
    NmtOtherNodeObeyed,
    /// A TPDO is sent although 18xxh:01 bit 31 says it is not valid.
    TpdoInvalidSent,
    /// 1001h and the EMCY's error register byte stay 0 when an error occurs.
    ErrorRegisterNotUpdated,
    /// EMCYs are sent in stopped.
    EmcyInStopped,
    /// The SYNC producer keeps running in stopped.
    SyncProducerInStopped,
    /// SDO requests are answered in stopped.
    SdoInStopped,
    /// NMT reset communication also restores the application objects 2000h–9FFFh.
    ResetCommunicationRestoresApplication,
    /// NMT reset communication keeps the communication objects' values.
    ResetCommunicationKeepsValues,
    /// NMT reset node is carried out as a reset communication: 2000h–9FFFh keep their values.
    ResetNodeAsResetCommunication,
    /// 1000h is answered with its bytes in reverse order.
    DeviceTypeByteOrder,
    /// The last segment of a segmented upload says no byte is unused.
    SegmentUnusedWrong,
    /// Block transfers without CRC are refused.
    BlockCrcRequired,
    /// Any value written to 1003h:00 is taken.
    ErrorCountUnchecked,
    /// Sub-index FFh answers with the object code and the data type's low byte swapped.
    StructureEntryWrong,
    /// Process outputs (rww, wo) are refused in RPDO mappings.
    ProcessOutputRefused,
    /// Mappings are taken whatever the PDO's validity and sub-index 0.
    MappingProcedureUnchecked,
    /// Mappings with too many objects or more than 64 bits are taken.
    MappingSizeUnchecked,
    /// Any value written to 1010h/1011h saves or restores.
    SignatureUnchecked,
    /// `load` to 1011h is confirmed but nothing is restored.
    RestoreIgnored,
    /// `save` stores everything but 1020h.
    VerifyConfigurationNotStored,
    /// Remote requests for TPDOs are answered in pre-operational.
    TpdoRtrInPreOperational,
}

impl Fault {
    /// Every fault, in catalogue order.
    pub const ALL: [Fault; 54] = [
        Fault::NoBootUp,
        Fault::BootUpWrongId,
        Fault::HeartbeatStateWrong,
        Fault::HeartbeatTooFast,
        Fault::HeartbeatJitter,
        Fault::GuardingAndHeartbeat,
        Fault::IgnoresNmtStop,
        Fault::NmtBroadcastIgnored,
        Fault::SdoToggleIgnored,
        Fault::SdoSlow,
        Fault::SdoExpeditedSizeWrong,
        Fault::WrongAbortCode,
        Fault::SdoBadCommandSilent,
        Fault::BlockCrcWrong,
        Fault::LimitNotEnforced,
        Fault::UnmappableAccepted,
        Fault::PdoCobIdUnchecked,
        Fault::NoTpdoRtr,
        Fault::NoEmcy,
        Fault::EmcyNoErrorReset,
        Fault::StoreIgnored,
        Fault::SyncCounterMissing,
        Fault::NoLss,
        Fault::LssStateNotChanged,
        Fault::TpdoConfigSilent,
        Fault::TpdoConfigRefused,
        Fault::MappingNotApplied,
        Fault::SyncProducerFast,
        Fault::TpdoEventTimerFast,
        Fault::EmcyGenericBitClear,
        Fault::TpdoInPreOperational,
        Fault::RpdoInPreOperational,
        Fault::PdoInStopped,
        Fault::NmtOtherNodeObeyed,
        Fault::TpdoInvalidSent,
        Fault::ErrorRegisterNotUpdated,
        Fault::EmcyInStopped,
        Fault::SyncProducerInStopped,
        Fault::SdoInStopped,
        Fault::ResetCommunicationRestoresApplication,
        Fault::ResetCommunicationKeepsValues,
        Fault::ResetNodeAsResetCommunication,
        Fault::DeviceTypeByteOrder,
        Fault::SegmentUnusedWrong,
        Fault::BlockCrcRequired,
        Fault::ErrorCountUnchecked,
        Fault::StructureEntryWrong,
        Fault::ProcessOutputRefused,
        Fault::MappingProcedureUnchecked,
        Fault::MappingSizeUnchecked,
        Fault::SignatureUnchecked,
        Fault::RestoreIgnored,
        Fault::VerifyConfigurationNotStored,
        Fault::TpdoRtrInPreOperational,
    ];

    /// The stable kebab-case name (`canopener sim --fault NAME`).
    pub const fn name(self) -> &'static str {
        match self {
            Fault::NoBootUp => "no-boot-up",
            Fault::BootUpWrongId => "boot-up-wrong-id",
            Fault::HeartbeatStateWrong => "heartbeat-state-wrong",
            Fault::HeartbeatTooFast => "heartbeat-too-fast",
            Fault::HeartbeatJitter => "heartbeat-jitter",
            Fault::GuardingAndHeartbeat => "guarding-and-heartbeat",
            Fault::IgnoresNmtStop => "ignores-nmt-stop",
            Fault::NmtBroadcastIgnored => "nmt-broadcast-ignored",
            Fault::SdoToggleIgnored => "sdo-toggle-ignored",
            Fault::SdoSlow => "sdo-slow",
            Fault::SdoExpeditedSizeWrong => "sdo-expedited-size-wrong",
            Fault::WrongAbortCode => "wrong-abort-code",
            Fault::SdoBadCommandSilent => "sdo-bad-command-silent",
            Fault::BlockCrcWrong => "block-crc-wrong",
            Fault::LimitNotEnforced => "limit-not-enforced",
            Fault::UnmappableAccepted => "unmappable-accepted",
            Fault::PdoCobIdUnchecked => "pdo-cob-id-unchecked",
            Fault::NoTpdoRtr => "no-tpdo-rtr",
            Fault::NoEmcy => "no-emcy",
            Fault::EmcyNoErrorReset => "emcy-no-error-reset",
            Fault::StoreIgnored => "store-ignored",
            Fault::SyncCounterMissing => "sync-counter-missing",
            Fault::NoLss => "no-lss",
            Fault::LssStateNotChanged => "lss-state-not-changed",
            Fault::TpdoConfigSilent => "tpdo-config-silent",
            Fault::TpdoConfigRefused => "tpdo-config-refused",
            Fault::MappingNotApplied => "mapping-not-applied",
            Fault::SyncProducerFast => "sync-producer-fast",
            Fault::TpdoEventTimerFast => "tpdo-event-timer-fast",
            Fault::EmcyGenericBitClear => "emcy-generic-bit-clear",
            Fault::TpdoInPreOperational => "tpdo-in-pre-operational",
            Fault::RpdoInPreOperational => "rpdo-in-pre-operational",
            Fault::PdoInStopped => "pdo-in-stopped",
            Fault::NmtOtherNodeObeyed => "nmt-other-node-obeyed",
            Fault::TpdoInvalidSent => "tpdo-invalid-sent",
            Fault::ErrorRegisterNotUpdated => "error-register-not-updated",
            Fault::EmcyInStopped => "emcy-in-stopped",
            Fault::SyncProducerInStopped => "sync-producer-in-stopped",
            Fault::SdoInStopped => "sdo-in-stopped",
            Fault::ResetCommunicationRestoresApplication => "reset-communication-restores-application",
            Fault::ResetCommunicationKeepsValues => "reset-communication-keeps-values",
            Fault::ResetNodeAsResetCommunication => "reset-node-as-reset-communication",
            Fault::DeviceTypeByteOrder => "device-type-byte-order",
            Fault::SegmentUnusedWrong => "segment-unused-wrong",
            Fault::BlockCrcRequired => "block-crc-required",
            Fault::ErrorCountUnchecked => "error-count-unchecked",
            Fault::StructureEntryWrong => "structure-entry-wrong",
            Fault::ProcessOutputRefused => "process-output-refused",
            Fault::MappingProcedureUnchecked => "mapping-procedure-unchecked",
            Fault::MappingSizeUnchecked => "mapping-size-unchecked",
            Fault::SignatureUnchecked => "signature-unchecked",
            Fault::RestoreIgnored => "restore-ignored",
            Fault::VerifyConfigurationNotStored => "verify-configuration-not-stored",
            Fault::TpdoRtrInPreOperational => "tpdo-rtr-in-pre-operational",
        }
    }

    /// What the defect is, what a conformance test should catch, and where it comes from.
    pub const fn description(self) -> &'static str {
        match self {
            Fault::NoBootUp => {
                "No boot-up message (700h + node-ID, data 00h) after power-on, reset node or reset \
                 communication; the device still enters Pre-operational. A test should expect the \
                 boot-up within a bounded time after every reset. Field experience: masters that wait \
                 for the boot-up never configure such a node."
            }
            Fault::BootUpWrongId => {
                "The boot-up message goes out on 700h + node-ID + 1 (an off-by-one between the \
                 configured node-ID and the one used for error control). A test should check the \
                 boot-up's CAN-ID against the node-ID it set. Field experience."
            }
            Fault::HeartbeatStateWrong => {
                "Heartbeats and node guarding answers carry a valid but wrong state, as from a state \
                 table read one row off: 05h (Operational) in Pre-operational, 04h (Stopped) in \
                 Operational, 7Fh (Pre-operational) in Stopped; guarding answers keep their toggle bit. \
                 A consumer sees the node in the wrong state, never a lost heartbeat. A test should \
                 check the state byte in every NMT state. Field experience."
            }
            Fault::HeartbeatTooFast => {
                "Every heartbeat is followed by a copy 1 ms later, so the measured interval drops to \
                 1 ms and the average to about half of 1017h. A test should measure minimum, maximum and \
                 average heartbeat intervals against 1017h. From the thesis (UWASA node: heartbeat \
                 minimum 1 ms, average 55 ms at 1017h = 100 ms)."
            }
            Fault::HeartbeatJitter => {
                "Every second heartbeat is late by 40 % of the 1017h period (intervals of 1.4 and 0.6 \
                 periods). A test should check each interval against a tolerance (the thesis used \
                 ±5 %). Field experience (heartbeat sent from a busy main loop)."
            }
            Fault::GuardingAndHeartbeat => {
                "Node guarding requests are answered while 1017h is not 0, so heartbeat and guarding \
                 run together, which CiA 301 forbids (heartbeat wins). A test should send a guarding \
                 request while heartbeat runs and expect no answer. Field experience."
            }
            Fault::IgnoresNmtStop => {
                "The NMT stop command (02h) is ignored: the device stays in its state and keeps \
                 serving SDO and PDOs. A test should send stop and expect the Stopped state (04h) in \
                 the heartbeat and no SDO answer. Field experience."
            }
            Fault::NmtBroadcastIgnored => {
                "NMT commands addressed to all nodes (node-ID 0) are ignored; commands to the own \
                 node-ID work. A test should use both forms. Field experience."
            }
            Fault::SdoToggleIgnored => {
                "The SDO server does not check the toggle bit of download and upload segments: a \
                 repeated or out-of-order segment is taken as the next one instead of being aborted \
                 with 0503 0000h. A test should send a segment with the wrong toggle and expect the \
                 abort. Field experience (wrong toggle handling)."
            }
            Fault::SdoSlow => {
                "Every SDO response is sent late (600 ms unless configured), beyond the timeout of \
                 many clients. A test should measure SDO response times (the thesis's SDO read/write \
                 response time test). Field experience (SDO served from a slow background task)."
            }
            Fault::SdoExpeditedSizeWrong => {
                "Expedited upload responses always say 4 bytes (command 43h) whatever the object's \
                 size, so a 1- or 2-byte value is answered as 4 bytes with padding. A test should check \
                 the size indicated against the object's data type. Field experience."
            }
            Fault::WrongAbortCode => {
                "Every SDO abort carries the general error 0800 0000h instead of the code for the \
                 condition (object missing, read-only, out of range...). A test should check the exact \
                 abort code of each refusal. Field experience."
            }
            Fault::SdoBadCommandSilent => {
                "A request with an unknown client command specifier gets no answer instead of the \
                 abort 0504 0001h, so the client runs into its timeout. A test should send an \
                 invalid command and expect the abort. Field experience."
            }
            Fault::BlockCrcWrong => {
                "The CRC in the end frame of a block upload is wrong (inverted), so a client that \
                 checks it aborts with 0504 0004h. A test should upload with CRC and check it. Field \
                 experience (wrong CRC polynomial or seed)."
            }
            Fault::LimitNotEnforced => {
                "Downloads outside the EDS LowLimit/HighLimit are stored and confirmed instead of \
                 being aborted with 0609 0031h / 0609 0032h. A test should write just \
                 above HighLimit and expect the abort. From the thesis (a write above HighLimit to \
                 1F51h accepted)."
            }
            Fault::UnmappableAccepted => {
                "A mapping entry naming an object whose PDOMapping is 0 is stored and confirmed \
                 instead of being aborted with 0604 0041h. A test should try to map a non-mappable \
                 object. From the thesis (a non-mappable object accepted into a PDO mapping)."
            }
            Fault::PdoCobIdUnchecked => {
                "A PDO COB-ID with a restricted CAN-ID (NMT, SYNC, SDO, error control, LSS...) is \
                 stored and confirmed instead of being aborted with 0609 0030h. A test should write a \
                 restricted CAN-ID to 1400h/1800h sub-index 1. Field experience (CiA 301 restricted \
                 CAN-IDs)."
            }
            Fault::NoTpdoRtr => {
                "Remote requests on TPDO COB-IDs are not answered although COB-ID bit 30 allows them. \
                 A test should request each TPDO whose bit 30 is clear. From the thesis (the UWASA \
                 node did not support PDO RTR)."
            }
            Fault::NoEmcy => {
                "No EMCY frame is ever sent, though 1001h and 1003h still record errors. A test should \
                 provoke an error (a too-short RPDO, a lost heartbeat) and expect the EMCY. Field \
                 experience (missing EMCY)."
            }
            Fault::EmcyNoErrorReset => {
                "EMCYs are sent but the error reset (error code 0000h) when the last error clears is \
                 not. A test should clear the error and expect the error reset EMCY. Field experience."
            }
            Fault::StoreIgnored => {
                "Writing `save` to 1010h is confirmed but nothing is stored, so values are lost at the \
                 next reset. A test should save, reset node and read back. Field experience \
                 (store/restore ignored)."
            }
            Fault::SyncCounterMissing => {
                "The SYNC producer leaves out the counter byte although 1019h is not 0. A test should \
                 check the SYNC length and counter sequence against 1019h. From the EnergyBus paper \
                 (missing counter value in SYNC handling of the stack under test)."
            }
            Fault::NoLss => {
                "The device has no LSS slave: no answer to any LSS request, so fastscan cannot find it \
                 and its node-ID cannot be configured. A test should inquire or fastscan. From the \
                 thesis (the UWASA node did not support LSS)."
            }
            Fault::LssStateNotChanged => {
                "The LSS slave never changes from waiting to configuration: switch state global and \
                 selective, and the last fastscan step that selects a device, are ignored, so \
                 configuration commands are not answered and `lss scan --assign` configures nothing. \
                 A test should switch to configuration (each way) and configure the node-ID. From the \
                 EnergyBus paper (missing state change in the LSS state machine during configuration)."
            }
            Fault::TpdoConfigSilent => {
                "SDO downloads to a TPDO's transmission type, inhibit time, reserved sub-index, event \
                 timer or SYNC start value (1800h–19FFh sub-index 2–6) get no answer, as from a \
                 server task that blocks while it rebuilds the PDO. A test must treat the timeout as a \
                 failure, never as a missing feature. Field experience (issue 22: a timeout became \
                 'not applicable')."
            }
            Fault::TpdoConfigRefused => {
                "SDO downloads to 1800h–19FFh sub-index 2–6 are aborted with the general error \
                 0800 0000h, a code that does not say the value is unsupported (0609 0030h would). A \
                 test must fail it, not call the feature optional. Field experience (issue 22: \
                 0800 0000h became 'not applicable')."
            }
            Fault::MappingNotApplied => {
                "Writes to a PDO mapping (1600h–17FFh, 1A00h–1BFFh) are stored and confirmed and read \
                 back, but the PDOs keep the mapping they had at the last reset communication, as \
                 in a stack that builds its PDOs only at start-up. A test should map something \
                 different and observe the PDO. Field experience (issue 22: a mapping test that \
                 rewrote the existing mapping passed such a device)."
            }
            Fault::SyncProducerFast => {
                "The SYNC producer sends at twice the rate 1006h sets (a period read in the wrong \
                 unit). A test should bound the SYNC rate on both sides. Field experience (issue 22: \
                 a SYNC producer at twice the rate passed)."
            }
            Fault::TpdoEventTimerFast => {
                "An event-driven TPDO's event timer elapses after half the time 18xxh:05 sets, so the \
                 TPDO comes at twice the rate with the same data. A test should catch intervals \
                 shorter than the timer as well as longer ones. Field experience (issue 22: too short \
                 intervals were taken for application events)."
            }
            Fault::EmcyGenericBitClear => {
                "Every EMCY carries the error register with bit 0 (generic error) clear, although \
                 1001h has it set: CANopenNode sends EMCY 8210h with 10h. CiA 301 §7.5.2.2 requires \
                 the generic bit whenever any error bit is set. A test should check each EMCY's \
                 error register byte against that rule and against 1001h read after it. From \
                 CANopenNode's demo device (issue 22)."
            }
            Fault::TpdoInPreOperational => {
                "TPDOs run in pre-operational as in operational: event-timer and SYNC-triggered TPDOs \
                 are sent, though CiA 301 runs PDOs in operational only (RPDOs and remote requests \
                 are still ignored there). A test should set up a TPDO that transmits on its own and \
                 expect nothing in pre-operational. From issue 22 (a planted defect the CiA 301 suite \
                 did not notice)."
            }
            Fault::RpdoInPreOperational => {
                "RPDOs received in pre-operational are written into their mapped objects (TPDOs stay \
                 silent there). A test should send an RPDO in pre-operational and read the mapped \
                 object back by SDO: it must be unchanged. From issue 22 (a planted defect)."
            }
            Fault::PdoInStopped => {
                "PDOs keep running in stopped: TPDOs are sent (event timer, remote requests) and RPDOs \
                 are written into their mapped objects, though the device reports stopped and serves \
                 no SDO. A test should expect no TPDO and an unchanged RPDO-mapped object after \
                 stopped. Field experience (the PDO task not told about the NMT state)."
            }
            Fault::NmtOtherNodeObeyed => {
                "NMT commands addressed to another node-ID are carried out as if addressed to this \
                 node (the node-ID byte is not compared). A test should address commands to other \
                 node-IDs and expect no change. From issue 22 (a planted defect)."
            }
            Fault::TpdoInvalidSent => {
                "TPDOs are sent although 18xxh:01 bit 31 says the PDO is not valid: the device \
                 ignores the bit and runs every TPDO that has a CAN-ID. A test should make a TPDO \
                 transmit on its own, leave bit 31 set and expect nothing. From issue 22 (a planted \
                 defect)."
            }
            Fault::ErrorRegisterNotUpdated => {
                "1001h stays 00h and every EMCY carries 00h as its error register byte, while errors \
                 are still raised, sent and recorded in 1003h. A test should read 1001h while an error \
                 is active. From issue 22 (a planted defect)."
            }
            Fault::EmcyInStopped => {
                "EMCYs are sent in stopped, though CiA 301 runs EMCY in pre-operational and \
                 operational only. A test should provoke an error in stopped (a heartbeat consumer \
                 timeout) and expect no EMCY until the device leaves stopped. Field experience."
            }
            Fault::SyncProducerInStopped => {
                "A device that produces SYNC (1005h bit 30) keeps producing it in stopped, though CiA \
                 301 runs SYNC in pre-operational and operational only. A test should stop the \
                 producer's node and expect no SYNC. Field experience."
            }
            Fault::SdoInStopped => {
                "SDO requests are answered in stopped, though the heartbeat reports stopped: CiA 301 \
                 serves only NMT and error control there. A test should send an SDO request in \
                 stopped and expect no answer. Field experience."
            }
            Fault::ResetCommunicationRestoresApplication => {
                "NMT reset communication also sets the application objects 2000h–9FFFh back to their \
                 power-on values, as reset node does; CiA 301 restores only 1000h–1FFFh on reset \
                 communication. A test should change an application object, reset communication and \
                 read it back unchanged. From issue 22 (a planted defect)."
            }
            Fault::ResetCommunicationKeepsValues => {
                "NMT reset communication re-starts the communication services with the values they \
                 have instead of setting 1000h–1FFFh back to their power-on values. A test should \
                 change a communication object, reset communication and expect its default. Field \
                 experience."
            }
            Fault::ResetNodeAsResetCommunication => {
                "NMT reset node is carried out as a reset communication: 1000h–1FFFh get their \
                 power-on values, 2000h–9FFFh keep what was written. A test should change an \
                 application object, reset the node and expect its default (CCT State 01). Field \
                 experience."
            }
            Fault::DeviceTypeByteOrder => {
                "Expedited uploads of 1000h:00 carry the device type with its bytes reversed (sent \
                 big-endian), so 000F0191h reads 91010F00h. A test should read 1000h and compare it \
                 with the EDS (CCT SDO 01). Field experience (a byte order mix-up on a big-endian \
                 controller)."
            }
            Fault::SegmentUnusedWrong => {
                "The last segment of a segmented upload says no byte is unused (n = 0) whatever the \
                 length, so a client takes padding for data. A test should read a value longer than 4 \
                 bytes segment by segment and add the segments up to the size indicated (CCT SDO 16, \
                 18). Field experience."
            }
            Fault::BlockCrcRequired => {
                "Block uploads and downloads are served only with CRC: a client that asks for none \
                 (cc = 0) gets the abort 0504 0001h. CiA 301 lets the client choose. A test should run \
                 block transfers without and with CRC (CCT SDO 19-25). Field experience."
            }
            Fault::ErrorCountUnchecked => {
                "Any value written to 1003h:00 is confirmed and stored, though CiA 301 allows only 0 \
                 (clearing the error history) and wants 0609 0030h for the rest. A test should write a \
                 value above the allowed range (CCT SDO 10 writes FFh). Field experience."
            }
            Fault::StructureEntryWrong => {
                "Sub-index FFh of an object answers with the object code and the data type's low byte \
                 swapped (the record 1018h reads 00000923h instead of 00002309h). A test should read \
                 sub-index FFh and compare it with the EDS's ObjectType and DataType (CCT OD 05). \
                 Field experience."
            }
            Fault::ProcessOutputRefused => {
                "An RPDO mapping entry naming a process output (rww) or a write-only object is refused \
                 with 0604 0041h although its PDOMapping is 1: the device maps only rw objects into \
                 RPDOs. A test should map such an object into an RPDO and expect it taken (CCT PDO \
                 27). Field experience."
            }
            Fault::MappingProcedureUnchecked => {
                "A PDO mapping is taken while the PDO is valid (COB-ID bit 31 clear) and mapping \
                 entries while sub-index 0 is not 0, though CiA 301 §7.5.2.38 wants the procedure \
                 (PDO made invalid, sub-index 0 set to 0, entries, sub-index 0, PDO valid) and an \
                 abort otherwise; the entries are still checked. A test should skip a step and expect \
                 the refusal (CCT PDO 23, 24). Field experience."
            }
            Fault::MappingSizeUnchecked => {
                "A mapping whose sub-index 0 asks for more objects than the mapping has entries, or \
                 whose objects add up to more than 64 bits, is taken instead of aborted with \
                 0604 0042h. A test should try both (CCT PDO 25, 26). Field experience."
            }
            Fault::SignatureUnchecked => {
                "Any value written to 1010h/1011h sub-indices 1 and above saves or restores, not only \
                 the signatures `save` and `load`; CiA 301 wants 0800 0020h for a wrong signature. A \
                 test should write a wrong signature and expect the refusal (CCT Other 01, 03, 05, \
                 07). Field experience."
            }
            Fault::RestoreIgnored => {
                "Writing `load` to 1011h is confirmed but nothing is restored: saved values keep \
                 coming back after each reset. A test should save, restore, reset and expect the \
                 defaults (CCT Other 02, 04, 06, 08). Field experience."
            }
            Fault::VerifyConfigurationNotStored => {
                "`save` stores every parameter except 1020h (verify configuration), which comes back \
                 as 0 after the next reset, so a master that checks the configuration date and time \
                 configures the device again at every start. A test should write 1020h, save, reset \
                 and read it back (CCT Other 09). Field experience."
            }
            Fault::TpdoRtrInPreOperational => {
                "Remote requests for TPDOs are answered in pre-operational, though CiA 301 runs PDOs \
                 in operational only; event-timer and SYNC TPDOs stay silent there. A test should \
                 request a TPDO that answers RTR in operational again in pre-operational and expect \
                 nothing (CCT PDO 15). Field experience (the RTR handler not told about the NMT \
                 state)."
            }
        }
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A fault name that is not in the catalogue.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown fault `{name}`; the faults are: {}", known_names())]
pub struct UnknownFault {
    /// The name given.
    pub name: String,
}

fn known_names() -> String {
    Fault::ALL.map(Fault::name).join(", ")
}

impl FromStr for Fault {
    type Err = UnknownFault;

    fn from_str(s: &str) -> Result<Fault, UnknownFault> {
        let wanted = s.trim();
        Fault::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(wanted))
            .ok_or_else(|| UnknownFault { name: s.to_string() })
    }
}

/// The faults of one device, and the delay of [`Fault::SdoSlow`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaultSet {
    bits: u64,
    sdo_delay: Duration,
}

impl Default for FaultSet {
    fn default() -> FaultSet {
        FaultSet::none()
    }
}

impl FaultSet {
    /// No fault: a correct device.
    pub const fn none() -> FaultSet {
        FaultSet {
            bits: 0,
            sdo_delay: DEFAULT_SDO_DELAY,
        }
    }

    /// This set with `fault` as well.
    pub const fn with(mut self, fault: Fault) -> FaultSet {
        self.bits |= 1 << fault as u64;
        self
    }

    /// This set with the SDO response delay of [`Fault::SdoSlow`] set to `delay`.
    pub const fn with_sdo_delay(mut self, delay: Duration) -> FaultSet {
        self.sdo_delay = delay;
        self
    }

    /// Adds `fault`.
    pub fn insert(&mut self, fault: Fault) {
        *self = self.with(fault);
    }

    /// Removes `fault`.
    pub fn remove(&mut self, fault: Fault) {
        self.bits &= !(1 << fault as u64);
    }

    /// Whether `fault` is in the set.
    pub const fn contains(&self, fault: Fault) -> bool {
        self.bits & (1 << fault as u64) != 0
    }

    /// Whether the set is empty.
    pub const fn is_empty(&self) -> bool {
        self.bits == 0
    }

    /// The faults in the set, in catalogue order.
    pub fn iter(&self) -> impl Iterator<Item = Fault> + '_ {
        Fault::ALL.into_iter().filter(|f| self.contains(*f))
    }

    /// The SDO response delay of [`Fault::SdoSlow`].
    pub const fn sdo_delay(&self) -> Duration {
        self.sdo_delay
    }
}

impl FromIterator<Fault> for FaultSet {
    fn from_iter<I: IntoIterator<Item = Fault>>(iter: I) -> FaultSet {
        iter.into_iter().fold(FaultSet::none(), FaultSet::with)
    }
}

impl From<Fault> for FaultSet {
    fn from(fault: Fault) -> FaultSet {
        FaultSet::none().with(fault)
    }
}

/// Which core made an outgoing frame, for [`FaultLayer::outbound`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Source {
    /// The NMT slave (the boot-up message).
    Nmt,
    /// An SDO server.
    Sdo,
    /// Error control while heartbeat runs, with the period in ms.
    Heartbeat { period_ms: u16 },
    /// Error control answering node guarding.
    Guarding,
    /// The EMCY producer.
    Emcy,
    /// The SYNC producer.
    Sync,
    /// The PDO engine (TPDOs).
    Pdo,
    /// Anything else (TIME, LSS).
    Other,
}

/// Where a block upload is, as far as [`Fault::BlockCrcWrong`] needs to know.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum BlockUpload {
    #[default]
    None,
    /// The client asked for a block upload.
    Initiated,
    /// The server sends sub-block segments.
    Segments,
    /// The last segment went out; the client's acknowledgement comes next.
    LastSent,
    /// The client acknowledged the last sub-block: the end frame with the CRC comes next.
    Ending,
}

/// The state the faults need on top of the cores: delayed frames, the SDO toggle the server
/// expects, the block upload phase, the guarding toggle, the heartbeat count.
#[derive(Debug, Clone, Default)]
pub(crate) struct FaultLayer {
    faults: FaultSet,
    delayed: VecDeque<(Instant, CanFrame)>,
    /// Under [`Fault::SdoToggleIgnored`]: the toggle the server expects next, if in a segmented
    /// transfer.
    sdo_toggle: Option<bool>,
    block: BlockUpload,
    /// Under [`Fault::GuardingAndHeartbeat`]: the toggle of the next extra guarding answer.
    guard_toggle: bool,
    heartbeats: u64,
    /// The device's NMT state, as [`FaultLayer::set_state`] was last told.
    state: Option<NmtSlaveState>,
}

impl FaultLayer {
    pub(crate) fn new(faults: FaultSet) -> FaultLayer {
        FaultLayer {
            faults,
            ..FaultLayer::default()
        }
    }

    pub(crate) fn faults(&self) -> FaultSet {
        self.faults
    }

    pub(crate) fn has(&self, fault: Fault) -> bool {
        self.faults.contains(fault)
    }

    /// A received frame before the cores see it: `None` drops it. `sdo_request` says whether it
    /// arrived on an SDO server's request COB-ID.
    pub(crate) fn inbound(&mut self, frame: &CanFrame, node: NodeId, sdo_request: bool) -> Option<CanFrame> {
        if self.faults.is_empty() {
            return Some(*frame);
        }
        let raw = frame.id().as_raw();
        let data = frame.data();
        if raw == u32::from(NMT_ID)
            && !frame.is_remote()
            && let [command, target] = *data
        {
            if self.has(Fault::NmtOtherNodeObeyed) && target != 0 && target != node.get() {
                return CanFrame::new(frame.id(), &[command, node.get()]).ok();
            }
            if self.has(Fault::NmtBroadcastIgnored) && target == 0 {
                return None;
            }
            if self.has(Fault::IgnoresNmtStop) && command == 0x02 && (target == 0 || target == node.get()) {
                return None;
            }
        }
        if raw == u32::from(LSS_MASTER_TO_SLAVE_ID) {
            if self.has(Fault::NoLss) {
                return None;
            }
            // Every request that would move the slave to configuration: switch state global to
            // configuration, switch state selective, and the last fastscan step (bit checked 0 on
            // the last part, LSSNext wrapping back), which selects the device it matches.
            let to_configuration = match *data {
                [0x04, 0x01, ..] | [0x40..=0x43, ..] => true,
                [0x51, _, _, _, _, 0, sub, next] => next < sub,
                _ => false,
            };
            if self.has(Fault::LssStateNotChanged) && to_configuration {
                return None;
            }
        }
        if self.has(Fault::NoTpdoRtr)
            && frame.is_remote()
            && raw != u32::from(ERROR_CONTROL_BASE) + u32::from(node.get())
        {
            return None;
        }
        if sdo_request
            && self.has(Fault::TpdoConfigSilent)
            && let [first, lo, hi, sub, ..] = *data
            && first >> 5 == 1
            && is_tpdo_setting(u16::from_le_bytes([lo, hi]), sub)
        {
            return None;
        }
        if sdo_request && let Some(&first) = data.first() {
            // A block upload initiate (ccs 5, cs 0) or block download initiate (ccs 6, cs 0) without
            // CRC (cc = 0) becomes ccs 7, which the server aborts with 0504 0001h.
            let block_initiate = first & 0xE3 == 0xA0 || first & 0xE1 == 0xC0;
            if self.has(Fault::BlockCrcRequired) && block_initiate && first & 0x04 == 0 {
                let mut bytes = data.to_vec();
                if let Some(command) = bytes.first_mut() {
                    *command = 0xE0;
                }
                return CanFrame::new(frame.id(), &bytes).ok();
            }
            if first & 0xE3 == 0xA0 {
                self.block = BlockUpload::Initiated;
            } else if first == 0xA2 && self.block == BlockUpload::LastSent {
                self.block = BlockUpload::Ending;
            } else if first == 0x80 {
                self.block = BlockUpload::None;
            }
            if self.has(Fault::SdoToggleIgnored)
                && let Some(toggle) = self.sdo_toggle
                && matches!(first >> 5, 0 | 3)
            {
                let mut bytes = data.to_vec();
                if let Some(command) = bytes.first_mut() {
                    *command = (first & !0x10) | if toggle { 0x10 } else { 0 };
                }
                return CanFrame::new(frame.id(), &bytes).ok();
            }
        }
        Some(*frame)
    }

    /// A frame a core made, at `now`: `out` receives what leaves the device at once; delayed
    /// frames wait for [`FaultLayer::release`].
    pub(crate) fn outbound(
        &mut self,
        now: Instant,
        source: Source,
        frame: CanFrame,
        out: &mut Vec<CanFrame>,
    ) {
        if self.faults.is_empty() {
            out.push(frame);
            return;
        }
        let data = frame.data();
        let mut bytes = data.to_vec();
        let mut id = frame.id();
        let mut delay = None;
        match source {
            Source::Nmt => {
                if bytes == [0] && self.has(Fault::NoBootUp) {
                    return;
                }
                if bytes == [0]
                    && self.has(Fault::BootUpWrongId)
                    && let Some(next) = StandardId::new((frame.id().as_raw() as u16).wrapping_add(1) & 0x7FF)
                {
                    id = next.into();
                }
            }
            Source::Heartbeat { period_ms } => {
                self.heartbeats += 1;
                self.wrong_state(&mut bytes);
                if self.has(Fault::HeartbeatJitter) && self.heartbeats.is_multiple_of(2) {
                    delay = Some(Duration::from_millis(u64::from(period_ms) * 2 / 5));
                }
                if self.has(Fault::HeartbeatTooFast)
                    && let Ok(copy) = CanFrame::new(id, &bytes)
                {
                    let at = now + delay.unwrap_or_default() + HEARTBEAT_COPY_GAP;
                    self.delay(at, copy);
                }
            }
            Source::Guarding => self.wrong_state(&mut bytes),
            Source::Sdo => {
                if !self.sdo_outbound(&mut bytes) {
                    return;
                }
                if self.has(Fault::SdoSlow) {
                    delay = Some(self.faults.sdo_delay());
                }
            }
            Source::Emcy => {
                if self.has(Fault::NoEmcy) {
                    return;
                }
                if self.has(Fault::EmcyNoErrorReset) && bytes.starts_with(&[0, 0]) {
                    return;
                }
                if self.has(Fault::EmcyGenericBitClear)
                    && let Some(register) = bytes.get_mut(2)
                {
                    *register &= !0x01;
                }
                if self.has(Fault::ErrorRegisterNotUpdated)
                    && let Some(register) = bytes.get_mut(2)
                {
                    *register = 0;
                }
            }
            // Under `rpdo-in-pre-operational` the PDO engine runs in pre-operational to take RPDOs;
            // what it would send there is held back.
            Source::Pdo
                if self.has(Fault::RpdoInPreOperational)
                    && self.state == Some(NmtSlaveState::PreOperational) =>
            {
                return;
            }
            Source::Sync => {
                if self.has(Fault::SyncCounterMissing) {
                    bytes.clear();
                }
            }
            Source::Pdo | Source::Other => {}
        }
        let Ok(frame) = CanFrame::new(id, &bytes) else {
            return;
        };
        match delay {
            Some(delay) if !delay.is_zero() => self.delay(now + delay, frame),
            _ => out.push(frame),
        }
    }

    /// Heartbeat or guarding state byte under [`Fault::HeartbeatStateWrong`].
    fn wrong_state(&self, bytes: &mut [u8]) {
        if self.has(Fault::HeartbeatStateWrong)
            && let [byte] = bytes
        {
            // Valid states only: a consumer must not be able to drop the frame as malformed.
            let state = match *byte & 0x7F {
                0x7F => 0x05,
                0x05 => 0x04,
                0x04 => 0x7F,
                other => other,
            };
            *byte = (*byte & 0x80) | state;
        }
    }

    /// An SDO response under the SDO faults; `false` drops it.
    fn sdo_outbound(&mut self, bytes: &mut [u8]) -> bool {
        let Some(&first) = bytes.first() else {
            return true;
        };
        let scs = first >> 5;
        // Toggle tracking: what the server answered decides what it expects next.
        self.sdo_toggle = match scs {
            2 | 3 => Some(false),
            0 | 1 => Some(first & 0x10 == 0),
            _ => None,
        };
        // Block upload phases: the server's own frames move them on.
        match self.block {
            // Initiate response: ss (bit 0) = 0; end: ss = 1.
            BlockUpload::Initiated if scs == 6 && first & 0x01 == 0 => self.block = BlockUpload::Segments,
            BlockUpload::Segments if first & 0x80 != 0 => self.block = BlockUpload::LastSent,
            BlockUpload::Ending if scs == 6 && first & 0x03 == 1 => {
                self.block = BlockUpload::None;
                if self.has(Fault::BlockCrcWrong)
                    && let Some([crc_lo, crc_hi]) = bytes.get_mut(1..3)
                {
                    *crc_lo = !*crc_lo;
                    *crc_hi = !*crc_hi;
                }
            }
            _ => {}
        }
        if let [0x80, _, _, _, code @ ..] = bytes
            && let Ok(code_bytes) = <[u8; 4]>::try_from(&*code)
        {
            self.block = BlockUpload::None;
            if self.has(Fault::SdoBadCommandSilent)
                && u32::from_le_bytes(code_bytes) == abort::COMMAND_SPECIFIER_INVALID
            {
                return false;
            }
            if self.has(Fault::WrongAbortCode) {
                code.copy_from_slice(&abort::GENERAL_ERROR.to_le_bytes());
            }
        }
        // An expedited upload response (scs 2, e = 1) and the entry it answers.
        if first & 0xE2 == 0x42
            && let [_, index_lo, index_hi, sub, value @ ..] = bytes
            && value.len() == 4
        {
            if self.has(Fault::DeviceTypeByteOrder) && [*index_lo, *index_hi, *sub] == [0x00, 0x10, 0x00] {
                value.reverse();
            }
            if self.has(Fault::StructureEntryWrong)
                && *sub == 0xFF
                && let [low, high, ..] = value
            {
                std::mem::swap(low, high);
            }
        }
        // The last segment of a segmented upload (scs 0, c = 1), not a block upload's sub-block.
        if let Some(command) = bytes.first_mut() {
            if self.has(Fault::SegmentUnusedWrong) && self.block == BlockUpload::None && first & 0xE1 == 0x01
            {
                *command = first & !0x0E;
            }
            if self.has(Fault::SdoExpeditedSizeWrong) && first & 0xE3 == 0x43 {
                *command = 0x43;
            }
        }
        true
    }

    /// The device entered `state` (what [`Source::Pdo`] frames are held back by depends on it).
    pub(crate) fn set_state(&mut self, state: NmtSlaveState) {
        self.state = Some(state);
    }

    /// The NMT state the device gives the core of `service` while it is in `state`: `state`
    /// itself, except where a fault runs the core in a state CiA 301 keeps it silent in
    /// (`tpdo-in-pre-operational`, `rpdo-in-pre-operational`, `pdo-in-stopped`, `emcy-in-stopped`,
    /// `sync-producer-in-stopped`).
    pub(crate) fn core_state(&self, service: CommService, state: NmtSlaveState) -> NmtSlaveState {
        use NmtSlaveState::{Operational, PreOperational, Stopped};
        let pdo_in_pre_operational =
            self.has(Fault::TpdoInPreOperational) || self.has(Fault::RpdoInPreOperational);
        match (service, state) {
            (CommService::Pdo, PreOperational) if pdo_in_pre_operational => Operational,
            (CommService::Pdo, Stopped) if self.has(Fault::PdoInStopped) => Operational,
            (CommService::Emcy, Stopped) if self.has(Fault::EmcyInStopped) => PreOperational,
            (CommService::Sync, Stopped) if self.has(Fault::SyncProducerInStopped) => PreOperational,
            _ => state,
        }
    }

    /// Whether a received frame goes to the core of `service` in `state` although CiA 301's table
    /// keeps the service silent there (`sdo-in-stopped`, `rpdo-in-pre-operational`,
    /// `pdo-in-stopped`).
    pub(crate) fn routes(&self, service: CommService, state: NmtSlaveState) -> bool {
        use NmtSlaveState::{PreOperational, Stopped};
        match (service, state) {
            (CommService::Sdo, Stopped) => self.has(Fault::SdoInStopped),
            (CommService::Pdo, PreOperational) => self.has(Fault::RpdoInPreOperational),
            (CommService::Pdo, Stopped) => self.has(Fault::PdoInStopped),
            _ => false,
        }
    }

    /// The dictionary the PDO engine reads its parameters from: `od` itself, or under
    /// [`Fault::TpdoInvalidSent`] a copy in which every TPDO COB-ID (1800h–19FFh:01) with a CAN-ID
    /// has bit 31 ("not valid") cleared.
    pub(crate) fn pdo_parameters<'od>(&self, od: &'od DynamicOd) -> std::borrow::Cow<'od, DynamicOd> {
        if !self.has(Fault::TpdoInvalidSent) {
            return std::borrow::Cow::Borrowed(od);
        }
        let mut copy = od.clone();
        for index in 0x1800..=0x19FFu16 {
            let key = ObjectKey::new(index, 1);
            if let Some(&[a, b, c, d]) = od.get(key).map(|e| e.value()) {
                let cob = u32::from_le_bytes([a, b, c, d]);
                if cob & 0x7FF != 0 {
                    let _ = copy.set_value(key, &(cob & 0x7FFF_FFFF).to_le_bytes());
                }
            }
        }
        std::borrow::Cow::Owned(copy)
    }

    /// The next guarding toggle under [`Fault::GuardingAndHeartbeat`].
    pub(crate) fn next_guard_toggle(&mut self) -> bool {
        let toggle = self.guard_toggle;
        self.guard_toggle = !toggle;
        toggle
    }

    /// Forgets the guarding toggle (a reset communication).
    pub(crate) fn reset_guard_toggle(&mut self) {
        self.guard_toggle = false;
    }

    fn delay(&mut self, at: Instant, frame: CanFrame) {
        // Kept in order of due time; equal times keep their order.
        let position = self.delayed.partition_point(|(due, _)| *due <= at);
        self.delayed.insert(position, (at, frame));
    }

    /// Frames whose delay is over at `now`.
    pub(crate) fn release(&mut self, now: Instant, out: &mut Vec<CanFrame>) {
        while let Some((due, _)) = self.delayed.front()
            && *due <= now
        {
            if let Some((_, frame)) = self.delayed.pop_front() {
                out.push(frame);
            }
        }
    }

    /// When the next delayed frame is due.
    pub(crate) fn poll_timeout(&self) -> Option<Instant> {
        self.delayed.front().map(|(due, _)| *due)
    }
}

/// A TPDO communication parameter sub-index [`Fault::TpdoConfigSilent`] and
/// [`Fault::TpdoConfigRefused`] act on: transmission type, inhibit time, reserved, event timer,
/// SYNC start value (1800h–19FFh sub-index 2–6).
pub(crate) fn is_tpdo_setting(index: u16, sub: u8) -> bool {
    (0x1800..=0x19FF).contains(&index) && (2..=6).contains(&sub)
}

/// The dictionary the PDO engine is to load its PDOs from under [`Fault::MappingNotApplied`] and
/// [`Fault::TpdoEventTimerFast`]: `od` with the mappings of `applied` (the last reset communication)
/// and the TPDO event timers halved; `None` when neither fault is set (the PDOs load from `od`).
pub(crate) fn pdo_view(
    faults: FaultSet,
    od: &DynamicOd,
    applied: &[(ObjectKey, Vec<u8>)],
) -> Option<DynamicOd> {
    let mapping = faults.contains(Fault::MappingNotApplied);
    let timer = faults.contains(Fault::TpdoEventTimerFast);
    if !mapping && !timer {
        return None;
    }
    let mut view = od.clone();
    if mapping {
        for (key, value) in applied {
            let _ = view.set_value(*key, value);
        }
    }
    if timer {
        for entry in od.iter() {
            let key = entry.key();
            if (0x1800..=0x19FF).contains(&key.index)
                && key.sub == 5
                && let &[a, b] = entry.value()
            {
                let _ = view.set_value(key, &(u16::from_le_bytes([a, b]) / 2).to_le_bytes());
            }
        }
    }
    Some(view)
}

/// A PDO mapping parameter: 1600h–17FFh or 1A00h–1BFFh.
pub(crate) fn is_mapping(index: u16) -> bool {
    matches!(index, 0x1600..=0x17FF | 0x1A00..=0x1BFF)
}

/// The mapping parameters of `od` as they are now (what [`Fault::MappingNotApplied`] keeps applying).
pub(crate) fn mappings_of(od: &DynamicOd) -> Vec<(ObjectKey, Vec<u8>)> {
    od.iter()
        .filter(|e| is_mapping(e.key().index))
        .map(|e| (e.key(), e.value().to_vec()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_kebab_case_and_parse_back() {
        let mut names: Vec<&str> = Fault::ALL.iter().map(|f| f.name()).collect();
        for (fault, name) in Fault::ALL.iter().zip(&names) {
            assert!(name.chars().all(|c| c.is_ascii_lowercase() || c == '-'), "{name}");
            assert_eq!(name.parse::<Fault>(), Ok(*fault));
            assert!(!fault.description().is_empty());
            assert_eq!(fault.to_string(), *name);
        }
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), Fault::ALL.len());
        assert!(Fault::ALL.len() >= 20);
    }

    #[test]
    fn unknown_name_lists_the_known_ones() {
        let error = "no-such-fault".parse::<Fault>().unwrap_err();
        let text = error.to_string();
        assert!(text.contains("no-such-fault"), "{text}");
        assert!(
            text.contains("no-boot-up") && text.contains("lss-state-not-changed"),
            "{text}"
        );
    }

    #[test]
    fn fault_set_operations() {
        let mut set: FaultSet = [Fault::NoLss, Fault::NoEmcy].into_iter().collect();
        assert!(set.contains(Fault::NoLss) && set.contains(Fault::NoEmcy));
        assert!(!set.contains(Fault::NoBootUp));
        set.remove(Fault::NoLss);
        set.insert(Fault::SdoSlow);
        assert_eq!(set.iter().collect::<Vec<_>>(), [Fault::SdoSlow, Fault::NoEmcy]);
        assert!(FaultSet::none().is_empty());
        assert_eq!(FaultSet::from(Fault::SdoSlow).sdo_delay(), DEFAULT_SDO_DELAY);
        assert_eq!(
            FaultSet::none()
                .with_sdo_delay(Duration::from_millis(50))
                .sdo_delay(),
            Duration::from_millis(50)
        );
    }
}
