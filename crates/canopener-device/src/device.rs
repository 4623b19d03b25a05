//! The `Device`: every core of this crate owned together and behaving as one CANopen node (CiA 301
//! device side, CiA 305 LSS slave), sans IO.
//!
//! A [`Device`] owns the object dictionary and a pristine copy of its power-on values, the
//! [`NmtSlave`], the SDO servers (the default server 1200h and every additional server 1201h–127Fh
//! whose COB-IDs are valid in the dictionary), heartbeat producer / node guarding ([`ErrorControl`])
//! and the heartbeat consumer, the EMCY producer, the PDO engine, SYNC, TIME, store/restore with a
//! [`ParameterStore`], the LSS slave and the [`Application`].
//!
//! Feed it with [`Device::boot`] (power-on), [`Device::handle_frame`] and
//! [`Device::handle_timeout`]; drain it with [`Device::poll_transmit`], [`Device::poll_event`] and
//! [`Device::poll_timeout`]. No clock, thread or socket is used: time arrives as [`Instant`].
//!
//! What is wired (each core's own module documents its protocol):
//! - Routing follows the CiA 301 table of services per NMT state ([`NmtSlaveState::is_active`]):
//!   NMT always; node guarding requests and consumed heartbeats in Pre-operational, Operational
//!   and Stopped; SDO, SYNC, TIME in Pre-operational and Operational; PDOs in Operational (the
//!   cores themselves also check). Leaving the SDO states drops running SDO transfers without a
//!   frame. LSS runs in every NMT state (CiA 305 is independent of NMT).
//! - SDO downloads pass one set of device checks before the dictionary is touched: PDO parameters
//!   ([`PdoEngine::check_write`]), 1005h/1019h ([`SyncService::check_download`]), 1012h
//!   ([`TimeService::check_download`]), 1014h and 1003h:00 (EMCY), 1016h (heartbeat consumer), and
//!   1010h/1011h ([`StoreRestore::check_download`], which saves or forgets when the signature is
//!   right; it runs last, so a write refused by another check saves nothing). Uploads of 1003h
//!   above the number of stored errors are refused with 0800 0024h.
//! - After a download the affected core is reloaded from the dictionary (1400h–1BFFh → PDO
//!   engine, 1005h–1007h/1019h → SYNC, 1012h → TIME, 1014h/1015h/1003h → EMCY, 1016h/1017h/100Ch/
//!   100Dh → error control, 1010h/1011h → capability bits, 1201h–127Fh → additional SDO servers)
//!   and the application is told ([`Application::on_write`]); RPDO writes tell the application
//!   of every mapped entry as well.
//! - Application changes ([`AppChanges`], [`Device::app_changed`]) become PDO application events
//!   and TPDO triggers. The application may refuse a download first
//!   ([`Application::check_write`]) and hears of every reset communication with the node-ID it
//!   brings ([`Application::reset_communication`]).
//! - EMCY: a lost consumed heartbeat or lost life guarding raises 8130h, RPDO length errors
//!   8210h/8220h, the RPDO deadline 8250h, a SYNC of the wrong length 8240h, each with error
//!   register bit 4 (communication error); they clear when the cause goes away. 1001h and 1003h
//!   are mirrored into the dictionary.
//! - Resets: NMT reset node (and power-on) restores 2000h–FFFFh from the pristine copy, applies the
//!   saved application and manufacturer parameters and resets the application; reset
//!   communication (also the second half of reset node) applies the node-ID LSS configured,
//!   restores 1000h–1FFFh from the pristine copy, applies the saved communication parameters,
//!   re-creates every communication core from the dictionary and sends the boot-up message.
//!
//! Choices:
//! - The LSS slave always runs when 1018h:01 exists, whatever the EDS's `LSS_Supported` says: a
//!   simulated device is more useful with LSS, and the fault catalogue switches it off. Store
//!   configuration succeeds: the default storage keeps the node-ID and bit rate in memory (a
//!   simulated device keeps them in its state file, [`Device::with_lss_storage`]), and NMT reset
//!   node, the device's power cycle, starts it with them again.
//! - Frames from other cores during the silence of an LSS bit rate switch are dropped, not held:
//!   CiA 305 forbids sending then, and a late heartbeat is worse than a missing one.
//! - The pristine copy of a device built with [`Device::from_eds`] is rebuilt with the new
//!   node-ID when LSS changes it, so `$NODEID` defaults (PDO COB-IDs, EMCY 1014h) follow; a device
//!   made with [`Device::new`] keeps the dictionary's values as given.
//! - The error history 1003h starts empty after every reset communication (the EMCY producer is
//!   re-created with the other communication cores), as CANopenNode does.
//!
//! Faults ([`Device::with_faults`], the catalogue in [`crate::faults`]) are applied around the
//! cores, never inside them: received frames pass the fault layer before routing, sent frames
//! pass it (tagged with the core that made them) after collection, and the three "accepted
//! anyway" faults and `store-ignored` act in the device's own SDO download hooks, which the SDO
//! server calls at the end of every download, expedited, segmented or block. The NMT state a
//! core is told, the PDO parameters the engine loads, the routing per state and the areas a reset
//! restores pass the fault layer too. Without faults every one of these steps is the identity.

use std::collections::{BTreeSet, VecDeque};

use canopener_can::{CanFrame, CanId, Core, Instant, StandardId};
use canopener_eds::model::Eds;
use canopener_od::{DynamicOd, ObjectKey, OdError};
use canopener_wire::TimeOfDay;
use canopener_wire::{NodeId, abort};

use crate::application::{AppChanges, Application};
use crate::emcy::{EmcyEvent, EmcyProducer};
use crate::faults::{Fault, FaultLayer, FaultSet, Source};
use crate::heartbeat::{ConsumerEvent, ErrorControl, ErrorControlEvent, HeartbeatConsumer};
use crate::lss_slave::{BitTiming, LssEvent, LssSlave, LssStorage, LssStoreError, StoredConfiguration};
use crate::nmt_slave::{CommService, NmtEvent, NmtSlave, NmtSlaveState};
use crate::od_build::{BuildNote, OdBuildError, build_od};
use crate::pdo::{Direction, DummyUsage, Mapped, PdoConfigError, PdoEngine, PdoEvent, PdoRef};
use crate::sdo_server::{self, SdoHooks, SdoServer};
use crate::store::{MemoryStore, ParameterGroup, ParameterStore, StorageError, StoreEvent, StoreRestore};
use crate::sync::{EMCY_SYNC_LENGTH, EMCY_SYNC_TIMEOUT, SyncEvent, SyncService};
use crate::time_stamp::{ProduceError, TimeEvent, TimeService};

/// EMCY error code of a heartbeat or life guarding event (CiA 301 emergency error codes:
/// life guard error or heartbeat error).
pub const EMCY_HEARTBEAT: u16 = 0x8130;

/// Error register bit 4, communication error (CiA 301, error register).
const COMMUNICATION_ERROR: u8 = 0x10;

/// The default SDO server parameter; 1201h–127Fh are the additional servers.
const SDO_SERVER_FIRST: u16 = 0x1200;
const SDO_SERVER_LAST: u16 = 0x127F;
/// 1F80h bit 2 (CiA 302-2): set = do not enter Operational on its own.
const NMT_STARTUP_NO_AUTOSTART: u32 = 0x04;

/// Why a device cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DeviceError {
    /// The object dictionary could not be built from the EDS.
    #[error(transparent)]
    Build(#[from] OdBuildError),
    /// A node-ID outside 1..=127 (and not FFh, unconfigured).
    #[error(
        "node-ID {0} is outside 1..=127; give the device a node-ID in that range, or FFh to start it unconfigured"
    )]
    NodeId(u8),
    /// The objects an application adds to the dictionary could not be added.
    #[error("cannot add the application's objects: {0}")]
    Extension(String),
    /// An unconfigured start (node-ID FFh) on a device without LSS.
    #[error(
        "the device cannot start unconfigured (node-ID FFh): that needs LSS, which needs the identity object \
         1018h with at least the vendor-ID (sub 1); give the device a node-ID instead"
    )]
    NoLss,
}

/// Adds an application's objects to a dictionary built from an EDS for a node-ID (for example
/// [`crate::cia401::install_objects`]); applied again whenever the power-on dictionary is rebuilt
/// for a new node-ID.
pub type OdExtension = fn(&mut DynamicOd, u8) -> Result<(), String>;

/// The node-ID that starts a device unconfigured (CiA 305): silent except for LSS until an LSS master
/// configures a node-ID and switches it back to waiting.
pub const UNCONFIGURED: u8 = canopener_wire::lss::UNCONFIGURED_NODE_ID;

/// A value in the dictionary a core could not take when it was (re)created at a reset; the core
/// keeps its own default instead.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigRefused {
    /// The entry.
    pub key: ObjectKey,
    /// The SDO abort code a write of that value would have been refused with.
    pub abort_code: u32,
}

/// What a [`Device`] reports, in the order it happened.
#[derive(Debug, Clone, PartialEq)]
pub enum DeviceEvent {
    /// The NMT slave reported something: a state change, a reset, a malformed or unknown command.
    Nmt(NmtEvent),
    /// An SDO server finished a download or a transfer was aborted.
    Sdo {
        /// The server's parameter index (1200h for the default server).
        server: u16,
        /// What happened.
        event: sdo_server::Event,
    },
    /// Life guarding lost or resumed.
    ErrorControl(ErrorControlEvent),
    /// The heartbeat consumer reported something (lost, resumed, remote state).
    Heartbeat(ConsumerEvent),
    /// An EMCY frame went out: error code, error register and manufacturer data as sent.
    EmcySent {
        /// The error code (0000h for the error reset).
        code: u16,
        /// The error register sent.
        register: u8,
        /// The manufacturer-specific bytes.
        data: [u8; 5],
    },
    /// The EMCY producer dropped an EMCY.
    Emcy(EmcyEvent),
    /// The PDO engine reported something.
    Pdo(PdoEvent),
    /// SYNC reported something.
    Sync(SyncEvent),
    /// TIME reported something.
    Time(TimeEvent),
    /// The LSS slave reported something.
    Lss(LssEvent),
    /// Store/restore reported something.
    Store(StoreEvent),
    /// The parameter storage failed while saved values were applied at a reset.
    StorageFailed(StorageError),
    /// A dictionary value a core refused at a reset.
    ConfigRefused(ConfigRefused),
    /// A reset communication made a new node-ID active.
    NodeIdChanged {
        /// The node-ID before (`None`: the device was unconfigured).
        from: Option<NodeId>,
        /// The node-ID now.
        to: NodeId,
    },
}

/// One CANopen device: every core of this crate on one object dictionary.
pub struct Device {
    od: DynamicOd,
    pristine: DynamicOd,
    eds: Option<Box<Eds>>,
    notes: Vec<BuildNote>,
    /// The active node-ID; a placeholder (1) while `configured` is false.
    node: NodeId,
    /// False while the node-ID is FFh: only LSS runs (CiA 305), nothing else sends or listens.
    configured: bool,
    dummies: DummyUsage,
    nmt: NmtSlave,
    sdo: Vec<(u16, SdoServer)>,
    error_control: ErrorControl,
    consumer: HeartbeatConsumer,
    emcy: EmcyProducer,
    pdo: PdoEngine,
    sync: SyncService,
    time: TimeService,
    store: StoreRestore,
    params: Box<dyn ParameterStore>,
    lss: Option<LssSlave>,
    lss_storage: Box<dyn LssStorage>,
    /// Power-on values set by [`Device::with_value`], re-applied when the defaults are rebuilt.
    overrides: Vec<(ObjectKey, Vec<u8>)>,
    /// Objects the application adds, re-added when the defaults are rebuilt.
    extension: Option<OdExtension>,
    /// The PDO mappings as at the last reset communication: what `mapping-not-applied` keeps
    /// transmitting with.
    applied_mappings: Vec<(ObjectKey, Vec<u8>)>,
    app: Box<dyn Application>,
    /// Sources of the active 8130h EMCY: consumed nodes lost, and 0 for life guarding.
    lost: BTreeSet<u8>,
    reset_application: bool,
    /// SDO downloads are refused with 0800 0022h while Operational.
    downloads_refused_in_operational: bool,
    booted: bool,
    faults: FaultLayer,
    transmit: VecDeque<CanFrame>,
    events: VecDeque<DeviceEvent>,
}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Device")
            .field("node", &self.node)
            .field("state", &self.nmt.state())
            .field("entries", &self.od.len())
            .finish_non_exhaustive()
    }
}

impl Device {
    /// A device built from `eds` with node-ID `node_id` ([`UNCONFIGURED`] for an LSS-unconfigured
    /// start), the in-memory parameter store and `app`. The build notes are kept
    /// ([`Device::notes`]); dummy mapping follows the EDS `[DummyUsage]`. The device is in
    /// Initialisation until [`Device::boot`].
    pub fn from_eds(eds: &Eds, node_id: u8, app: Box<dyn Application>) -> Result<Device, DeviceError> {
        Device::build(eds, node_id, app, None)
    }

    /// [`Device::from_eds`] with objects `extension` adds to the dictionary (objects the EDS lacks,
    /// such as an application's test registers), also after LSS changes the node-ID.
    pub fn from_eds_extended(
        eds: &Eds,
        node_id: u8,
        app: Box<dyn Application>,
        extension: OdExtension,
    ) -> Result<Device, DeviceError> {
        Device::build(eds, node_id, app, Some(extension))
    }

    fn build(
        eds: &Eds,
        node_id: u8,
        app: Box<dyn Application>,
        extension: Option<OdExtension>,
    ) -> Result<Device, DeviceError> {
        // An unconfigured device's `$NODEID` values are rebuilt for the configured node-ID at the
        // reset communication that makes it active; until then nothing reads them.
        let build_id = if node_id == UNCONFIGURED { 1 } else { node_id };
        let mut built = build_od(eds, build_id)?;
        if let Some(extend) = extension {
            extend(&mut built.od, build_id).map_err(DeviceError::Extension)?;
        }
        let mut device = Device::new(built.od, node_id, app)?;
        device.extension = extension;
        device.notes = built.notes;
        device.dummies = dummy_usage(eds);
        device.pdo = PdoEngine::new().with_dummy_usage(device.dummies);
        device.eds = Some(Box::new(eds.clone()));
        Ok(device)
    }

    /// A device on `od` (its values are the power-on defaults) with node-ID `node_id`
    /// ([`UNCONFIGURED`] for an LSS-unconfigured start), the in-memory parameter store and `app`,
    /// accepting no dummy mapping. In Initialisation until [`Device::boot`].
    pub fn new(od: DynamicOd, node_id: u8, app: Box<dyn Application>) -> Result<Device, DeviceError> {
        let configured = node_id != UNCONFIGURED;
        let node = match NodeId::new(node_id) {
            Some(node) => node,
            None if !configured => NodeId::new(1).ok_or(DeviceError::NodeId(node_id))?,
            None => return Err(DeviceError::NodeId(node_id)),
        };
        let lss = LssSlave::from_od(&od, configured.then_some(node)).ok();
        if !configured && lss.is_none() {
            return Err(DeviceError::NoLss);
        }
        Ok(Device {
            configured,
            pristine: od.clone(),
            od,
            applied_mappings: Vec::new(),
            eds: None,
            notes: Vec::new(),
            node,
            dummies: DummyUsage::NONE,
            nmt: NmtSlave::new(node),
            sdo: Vec::new(),
            error_control: ErrorControl::new(node),
            consumer: HeartbeatConsumer::new(),
            emcy: EmcyProducer::new(node),
            pdo: PdoEngine::new(),
            sync: SyncService::new(),
            time: TimeService::new(),
            store: StoreRestore::new(),
            params: Box::new(MemoryStore::new()),
            lss,
            lss_storage: Box::new(StoredLss::default()),
            overrides: Vec::new(),
            extension: None,
            app,
            lost: BTreeSet::new(),
            reset_application: false,
            downloads_refused_in_operational: false,
            booted: false,
            faults: FaultLayer::new(FaultSet::none()),
            transmit: VecDeque::new(),
            events: VecDeque::new(),
        })
    }

    /// Uses `store` for saved parameters (1010h/1011h) instead of the in-memory one. Call before
    /// [`Device::boot`], which applies the values it holds.
    pub fn with_parameter_store(mut self, store: Box<dyn ParameterStore>) -> Device {
        self.params = store;
        self
    }

    /// Sets the power-on value of `key` to `value` (checked against the entry's type, not its
    /// access), kept across every reset, for example a serial number 1018h:04 so that several
    /// devices from one EDS have distinct LSS addresses. Call before [`Device::boot`].
    pub fn with_value(mut self, key: ObjectKey, value: &[u8]) -> Result<Device, OdError> {
        self.od.set_value(key, value)?;
        self.pristine.set_value(key, value)?;
        self.overrides.retain(|(k, _)| *k != key);
        self.overrides.push((key, value.to_vec()));
        if key.index == 0x1018 {
            // The LSS address is the identity object's value at power-on.
            self.lss = LssSlave::from_od(&self.od, self.configured.then_some(self.node)).ok();
        }
        Ok(self)
    }

    /// Uses `storage` for LSS store configuration (CiA 305) instead of the in-memory one, which
    /// accepts the store and keeps the node-ID and bit rate for as long as the `Device` lives.
    pub fn with_lss_storage(mut self, storage: Box<dyn LssStorage>) -> Device {
        self.lss_storage = storage;
        self
    }

    /// Makes the device refuse every SDO download while Operational with 0800 0022h ("data cannot
    /// be transferred or stored to the application because of the present device state", CiA 301),
    /// as devices do that take parameters only in Pre-operational; uploads still work, and so do
    /// downloads in Pre-operational.
    pub fn with_downloads_refused_in_operational(mut self) -> Device {
        self.downloads_refused_in_operational = true;
        self.lock_downloads();
        self
    }

    /// Gives the device the defects in `faults` (the fault catalogue, [`crate::faults`]). Call
    /// before [`Device::boot`] so that the boot-up message is affected too.
    pub fn with_faults(mut self, faults: FaultSet) -> Device {
        self.faults = FaultLayer::new(faults);
        self
    }

    /// The device's defects.
    pub fn faults(&self) -> FaultSet {
        self.faults.faults()
    }

    /// Power-on: reset application and reset communication (defaults, then saved values), then
    /// the boot-up message and Pre-operational. Does nothing once booted.
    pub fn boot(&mut self, now: Instant) {
        if self.booted {
            return;
        }
        self.booted = true;
        self.reset(now, true);
        self.pump(now);
    }

    /// What building the dictionary from the EDS did not take as written.
    pub fn notes(&self) -> &[BuildNote] {
        &self.notes
    }

    /// The object dictionary.
    pub fn od(&self) -> &DynamicOd {
        &self.od
    }

    /// The object dictionary, for tests and the application side. Tell the device about changed
    /// mapped entries with [`Device::app_changed`].
    pub fn od_mut(&mut self) -> &mut DynamicOd {
        &mut self.od
    }

    /// The NMT state.
    pub fn state(&self) -> NmtSlaveState {
        self.nmt.state()
    }

    /// Whether the device has a node-ID; false while it is LSS-unconfigured (FFh).
    pub fn is_configured(&self) -> bool {
        self.configured
    }

    /// The active node-ID (a placeholder while [`Device::is_configured`] is false).
    pub fn node_id(&self) -> NodeId {
        self.node
    }

    /// The LSS slave, if the dictionary has an identity (1018h:01).
    pub fn lss(&self) -> Option<&LssSlave> {
        self.lss.as_ref()
    }

    /// The EMCY producer (active errors, error register, history).
    pub fn emcy(&self) -> &EmcyProducer {
        &self.emcy
    }

    /// The application side changed `keys` in the dictionary: TPDOs mapping them are sent as their
    /// transmission types say.
    pub fn app_changed(&mut self, now: Instant, keys: &[ObjectKey]) {
        for &key in keys {
            self.pdo.application_event(now, key);
        }
        self.pump(now);
    }

    /// Whether 1012h makes this device a TIME producer (bit 30).
    pub fn is_time_producer(&self) -> bool {
        self.configured && self.time.is_producer()
    }

    /// Sends a TIME frame carrying `time` (CiA 301 TIME producer, 1012h bit 30). The device has no
    /// clock of its own: its driver says when and what time it is. Refused when the device is no
    /// TIME producer or its NMT state does not run TIME.
    pub fn produce_time(&mut self, now: Instant, time: TimeOfDay) -> Result<(), ProduceError> {
        if !self.configured {
            return Err(ProduceError::NotProducer);
        }
        self.time.produce(now, time)?;
        self.pump(now);
        Ok(())
    }

    /// Handles every event the cores reported until none is left, then collects their frames.
    fn pump(&mut self, now: Instant) {
        // Bounded: every round handles events the previous one produced; cores do not loop.
        for _ in 0..64 {
            if !self.pump_once(now) {
                break;
            }
        }
        self.emcy.sync_od(&mut self.od);
        if self.faults.has(Fault::ErrorRegisterNotUpdated) {
            let _ = self.od.set_value(ObjectKey::new(0x1001, 0), &[0]);
        }
        self.collect_frames(now);
    }

    fn pump_once(&mut self, now: Instant) -> bool {
        let mut any = false;
        while let Some(event) = self.nmt.poll_event() {
            any = true;
            self.on_nmt(now, event);
        }
        let mut written = Vec::new();
        for (index, server) in &mut self.sdo {
            while let Some(event) = server.poll_event() {
                if let sdo_server::Event::Written { key } = event {
                    written.push(key);
                }
                self.events.push_back(DeviceEvent::Sdo {
                    server: *index,
                    event,
                });
            }
        }
        for key in written {
            any = true;
            self.after_download(now, key);
        }
        while let Some(event) = self.error_control.poll_event() {
            any = true;
            match event {
                ErrorControlEvent::LifeGuardingLost => self.comm_lost(now, 0),
                ErrorControlEvent::LifeGuardingResumed => self.comm_resumed(now, 0),
            }
            self.events.push_back(DeviceEvent::ErrorControl(event));
        }
        while let Some(event) = self.consumer.poll_event() {
            any = true;
            match event {
                ConsumerEvent::HeartbeatLost { node } => self.comm_lost(now, node),
                ConsumerEvent::HeartbeatResumed { node } => self.comm_resumed(now, node),
                _ => {}
            }
            self.events.push_back(DeviceEvent::Heartbeat(event));
        }
        while let Some(event) = self.sync.poll_event() {
            any = true;
            match event {
                SyncEvent::Sync { counter } => self.pdo.handle_sync(now, counter, &mut self.od),
                SyncEvent::WrongLength { expected, received } => {
                    self.emcy.raise(
                        now,
                        EMCY_SYNC_LENGTH,
                        COMMUNICATION_ERROR,
                        [expected, received, 0, 0, 0],
                    );
                }
                SyncEvent::WindowClosed => self.pdo.window_closed(),
                SyncEvent::Timeout => {
                    self.emcy
                        .raise(now, EMCY_SYNC_TIMEOUT, COMMUNICATION_ERROR, [0; 5]);
                }
                SyncEvent::Resumed => {
                    self.emcy.clear(now, EMCY_SYNC_TIMEOUT);
                }
            }
            self.events.push_back(DeviceEvent::Sync(event));
        }
        while let Some(event) = self.pdo.poll_event() {
            any = true;
            self.on_pdo(now, event);
        }
        while let Some(event) = self.time.poll_event() {
            any = true;
            self.events.push_back(DeviceEvent::Time(event));
        }
        while let Some(event) = self.lss.as_mut().and_then(LssSlave::poll_event) {
            any = true;
            if event == LssEvent::ResetCommunication {
                self.nmt.enter_local(NmtSlaveState::Initialisation);
            }
            self.events.push_back(DeviceEvent::Lss(event));
        }
        while let Some(event) = self.store.poll_event() {
            any = true;
            self.events.push_back(DeviceEvent::Store(event));
        }
        while let Some(event) = self.emcy.poll_event() {
            any = true;
            self.events.push_back(DeviceEvent::Emcy(event));
        }
        any
    }

    fn collect_frames(&mut self, now: Instant) {
        let silent = self.lss.as_ref().is_some_and(LssSlave::is_silent);
        let mut made: Vec<(Source, CanFrame)> = Vec::new();
        if let Some(lss) = &mut self.lss {
            made.extend(std::iter::from_fn(|| lss.poll_transmit()).map(|f| (Source::Other, f)));
        }
        let lss_frames = made.len();
        made.extend(std::iter::from_fn(|| self.nmt.poll_transmit()).map(|f| (Source::Nmt, f)));
        for (_, server) in &mut self.sdo {
            made.extend(std::iter::from_fn(|| server.poll_transmit()).map(|f| (Source::Sdo, f)));
        }
        let error_control = if self.error_control.heartbeat_active() {
            let period_ms = match self.od.get(ObjectKey::new(0x1017, 0)).map(|e| e.value()) {
                Some(&[a, b]) => u16::from_le_bytes([a, b]),
                _ => 0,
            };
            Source::Heartbeat { period_ms }
        } else {
            Source::Guarding
        };
        made.extend(std::iter::from_fn(|| self.error_control.poll_transmit()).map(|f| (error_control, f)));
        while let Some(frame) = self.emcy.poll_transmit() {
            let d = frame.data();
            let dropped = self.faults.has(Fault::NoEmcy)
                || (self.faults.has(Fault::EmcyNoErrorReset) && d.starts_with(&[0, 0]));
            if let [c0, c1, reg, d3, d4, d5, d6, d7] = *d
                && !dropped
            {
                let register = if self.faults.has(Fault::ErrorRegisterNotUpdated) {
                    0
                } else {
                    reg
                };
                self.events.push_back(DeviceEvent::EmcySent {
                    code: u16::from_le_bytes([c0, c1]),
                    register,
                    data: [d3, d4, d5, d6, d7],
                });
            }
            made.push((Source::Emcy, frame));
        }
        made.extend(std::iter::from_fn(|| self.sync.poll_transmit()).map(|f| (Source::Sync, f)));
        made.extend(std::iter::from_fn(|| self.pdo.poll_transmit()).map(|f| (Source::Pdo, f)));
        made.extend(std::iter::from_fn(|| self.time.poll_transmit()).map(|f| (Source::Other, f)));
        if silent || !self.configured {
            made.truncate(lss_frames);
        }
        let mut frames = Vec::with_capacity(made.len());
        for (source, frame) in made {
            self.faults.outbound(now, source, frame, &mut frames);
        }
        self.transmit.extend(frames);
    }

    /// The PDOs reloaded from the dictionary, through the fault layer: `tpdo-invalid-sent` hands the
    /// engine TPDO COB-IDs made valid, `mapping-not-applied` and `tpdo-event-timer-fast` the view
    /// they give.
    fn reload_pdos(&mut self, now: Instant) {
        let od = self.faults.pdo_parameters(&self.od);
        match crate::faults::pdo_view(self.faults.faults(), &od, &self.applied_mappings) {
            Some(view) => self.pdo.reload(now, &view),
            None => self.pdo.reload(now, &od),
        }
    }

    /// The SYNC service reloaded from the dictionary; `sync-producer-fast` halves its period.
    fn load_sync(&mut self, now: Instant) {
        self.sync.load_od(now, &self.od);
        if self.faults.has(Fault::SyncProducerFast) {
            self.sync.set_period(now, self.sync.period_us() / 2);
        }
    }

    /// `guarding-and-heartbeat`: a node guarding request is answered even while heartbeat runs
    /// (error control ignores it then, as CiA 301 wants).
    fn fault_guarding(&mut self, now: Instant, frame: &CanFrame) {
        let own = u32::from(canopener_wire::ERROR_CONTROL_BASE) + u32::from(self.node.get());
        if self.faults.has(Fault::GuardingAndHeartbeat)
            && frame.is_remote()
            && frame.id().as_raw() == own
            && self.error_control.heartbeat_active()
        {
            let toggle = self.faults.next_guard_toggle();
            let byte = canopener_wire::encode_guard_response(self.nmt.state().reported(), toggle);
            if let Ok(answer) = CanFrame::new(frame.id(), &[byte]) {
                let mut out = Vec::new();
                self.faults.outbound(now, Source::Guarding, answer, &mut out);
                self.transmit.extend(out);
            }
        }
    }

    fn on_nmt(&mut self, now: Instant, event: NmtEvent) {
        self.events.push_back(DeviceEvent::Nmt(event));
        match event {
            NmtEvent::StateChanged { to, .. } => {
                self.faults.set_state(to);
                self.error_control.set_state(now, to);
                self.emcy
                    .set_state(now, self.faults.core_state(CommService::Emcy, to));
                self.sync
                    .set_state(now, self.faults.core_state(CommService::Sync, to));
                self.time.set_state(now, to);
                self.pdo
                    .set_state(now, self.faults.core_state(CommService::Pdo, to));
                self.lock_downloads();
                if !to.is_active(CommService::Sdo) {
                    for (_, server) in &mut self.sdo {
                        server.reset();
                    }
                }
            }
            NmtEvent::ResetApplication => {
                // `reset-node-as-reset-communication`: the application area is left as it is.
                self.reset_application = !self.faults.has(Fault::ResetNodeAsResetCommunication);
                // Reset node is the device's power cycle: it starts with what LSS stored.
                if let (Some(lss), Some(stored)) = (&mut self.lss, self.lss_storage.stored()) {
                    lss.restore_stored(stored);
                }
            }
            NmtEvent::ResetCommunication => {
                let application = std::mem::take(&mut self.reset_application);
                self.reset(now, application);
            }
            NmtEvent::Malformed(_) | NmtEvent::UnknownCommand { .. } => {}
        }
    }

    fn on_pdo(&mut self, now: Instant, event: PdoEvent) {
        self.events.push_back(DeviceEvent::Pdo(event));
        if let Some(code) = event.emcy_code() {
            let data = match event {
                PdoEvent::RpdoTooShort { number, .. }
                | PdoEvent::RpdoTooLong { number, .. }
                | PdoEvent::RpdoTimeout { number } => number.to_le_bytes(),
                _ => [0, 0],
            };
            self.emcy
                .raise(now, code, COMMUNICATION_ERROR, [data[0], data[1], 0, 0, 0]);
        }
        match event {
            PdoEvent::RpdoLengthOk { .. } => {
                self.emcy.clear(now, crate::pdo::EMCY_PDO_LENGTH_ERROR);
                self.emcy.clear(now, crate::pdo::EMCY_PDO_LENGTH_EXCEEDED);
            }
            PdoEvent::RpdoResumed { .. } => {
                self.emcy.clear(now, crate::pdo::EMCY_RPDO_TIMEOUT);
            }
            PdoEvent::RpdoWritten { number } => {
                let pdo = PdoRef {
                    direction: Direction::Receive,
                    number,
                };
                let keys: Vec<ObjectKey> = self
                    .pdo
                    .mapping(pdo)
                    .unwrap_or_default()
                    .iter()
                    .filter_map(|mapped| match mapped {
                        Mapped::Object { key, .. } => Some(*key),
                        Mapped::Dummy { .. } => None,
                    })
                    .collect();
                for key in keys {
                    let changes = self.app.on_write(now, key, &mut self.od);
                    self.apply_changes(now, &changes);
                }
            }
            _ => {}
        }
    }

    /// `source` (a consumed node-ID, or 0 for life guarding) was lost: EMCY 8130h unless one is
    /// active already.
    fn comm_lost(&mut self, now: Instant, source: u8) {
        if self.lost.is_empty() {
            self.emcy
                .raise(now, EMCY_HEARTBEAT, COMMUNICATION_ERROR, [source, 0, 0, 0, 0]);
        }
        self.lost.insert(source);
        self.error_behaviour();
    }

    /// CiA 301 1029h sub 1, the reaction to a communication error (heartbeat or life guarding
    /// lost; reference §2.8): 0 = Pre-operational if Operational, 1 = no change, 2 = Stopped.
    /// Without 1029h sub 1 the device reacts as CiA 301 describes for every device: a serious
    /// failure detected while Operational makes it enter Pre-operational; 1029h only makes that
    /// configurable. CCT Heartbeat 07 expects EMCY 8130h and that change. Values 3 and up are
    /// reserved or manufacturer-specific: no change.
    fn error_behaviour(&mut self) {
        const PRE_OPERATIONAL_IF_OPERATIONAL: u8 = 0;
        let reaction = match self.od.get(ObjectKey::new(0x1029, 1)).map(|e| e.value()) {
            Some(&[value]) => value,
            _ => PRE_OPERATIONAL_IF_OPERATIONAL,
        };
        match (reaction, self.nmt.state()) {
            (0, NmtSlaveState::Operational) => self.nmt.enter_local(NmtSlaveState::PreOperational),
            (2, state) if state != NmtSlaveState::Stopped => self.nmt.enter_local(NmtSlaveState::Stopped),
            _ => {}
        }
    }

    fn comm_resumed(&mut self, now: Instant, source: u8) {
        if self.lost.remove(&source) && self.lost.is_empty() {
            self.emcy.clear(now, EMCY_HEARTBEAT);
        }
    }

    fn apply_changes(&mut self, now: Instant, changes: &AppChanges) {
        for &key in &changes.changed {
            self.pdo.application_event(now, key);
        }
        for &number in &changes.trigger_tpdos {
            self.pdo.trigger_tpdo(now, number);
        }
    }

    /// An SDO download stored a value at `key`: reload the core it configures, tell the
    /// application.
    fn after_download(&mut self, now: Instant, key: ObjectKey) {
        let value = self.od.get(key).map(|e| e.value().to_vec()).unwrap_or_default();
        let u32_value = <[u8; 4]>::try_from(value.as_slice()).map(u32::from_le_bytes).ok();
        let u16_value = <[u8; 2]>::try_from(value.as_slice()).map(u16::from_le_bytes).ok();
        match key.index {
            0x1400..=0x1BFF => self.reload_pdos(now),
            0x1005..=0x1007 | 0x1019 => self.load_sync(now),
            0x1012 => self.time.load_od(&self.od),
            0x1014 => {
                if let Some(value) = u32_value {
                    // Checked by the hooks before the dictionary stored it.
                    let _ = self.emcy.set_cob_id(value);
                }
            }
            0x1015 => {
                if let Some(value) = u16_value {
                    self.emcy.set_inhibit_time(now, value);
                }
            }
            0x1003 if key.sub == 0 => {
                if let &[count] = value.as_slice() {
                    let _ = self.emcy.write_history_count(count);
                }
            }
            0x1016 => {
                if let Some(value) = u32_value {
                    let _ = self.consumer.set_entry(key.sub, value);
                }
            }
            0x1017 => {
                if let Some(value) = u16_value {
                    self.error_control.set_producer_time(now, value);
                }
            }
            0x100C => {
                if let Some(value) = u16_value {
                    self.error_control.set_guard_time(now, value);
                }
            }
            0x100D => {
                if let &[value] = value.as_slice() {
                    self.error_control.set_life_time_factor(now, value);
                }
            }
            0x1010 | 0x1011 => self.store.sync_od(&mut self.od),
            0x1201..=SDO_SERVER_LAST => self.load_sdo_servers(),
            _ => {}
        }
        let changes = self.app.on_write(now, key, &mut self.od);
        self.apply_changes(now, &changes);
    }

    /// Reset communication (and, with `application`, reset application first), as on power-on
    /// and NMT reset node / reset communication; ends with the boot-up message.
    fn reset(&mut self, now: Instant, application: bool) {
        if application {
            self.restore_defaults(0x2000..=0xFFFF);
            for group in [ParameterGroup::Application, ParameterGroup::Manufacturer] {
                self.apply_saved(group);
            }
        }
        if let Some(lss) = &mut self.lss {
            match lss.reset_communication() {
                Some(node) if !self.configured || node != self.node => {
                    self.events.push_back(DeviceEvent::NodeIdChanged {
                        from: self.configured.then_some(self.node),
                        to: node,
                    });
                    self.node = node;
                    self.configured = true;
                    if let Some(eds) = &self.eds
                        && let Ok(mut built) = build_od(eds, node.get())
                        && self
                            .extension
                            .is_none_or(|extend| extend(&mut built.od, node.get()).is_ok())
                    {
                        self.pristine = built.od;
                        for (key, value) in &self.overrides {
                            let _ = self.pristine.set_value(*key, value);
                        }
                    }
                }
                Some(_) => {}
                // LSS configured FFh: the node leaves the network until it gets a node-ID again.
                None => self.configured = false,
            }
        }
        if !application && self.faults.has(Fault::ResetCommunicationRestoresApplication) {
            self.restore_defaults(0x2000..=0x9FFF);
            for group in [ParameterGroup::Application, ParameterGroup::Manufacturer] {
                self.apply_saved(group);
            }
        }
        if application || !self.faults.has(Fault::ResetCommunicationKeepsValues) {
            self.restore_defaults(0x1000..=0x1FFF);
            self.apply_saved(ParameterGroup::Communication);
        }
        self.store.sync_od(&mut self.od);
        self.load_communication(now);
        if application {
            let changes = self.app.reset(now, &mut self.od);
            self.apply_changes(now, &changes);
        }
        let node = self.configured.then_some(self.node);
        let changes = self.app.reset_communication(now, node, &mut self.od);
        self.apply_changes(now, &changes);
        self.faults.reset_guard_toggle();
        self.nmt.set_node_id(self.node);
        if self.configured {
            self.nmt.boot(now);
        }
    }

    fn restore_defaults(&mut self, range: std::ops::RangeInclusive<u16>) {
        for entry in self.pristine.iter().filter(|e| range.contains(&e.key().index)) {
            let _ = self.od.set_value(entry.key(), entry.value());
        }
    }

    fn apply_saved(&mut self, group: ParameterGroup) {
        if let Err(error) = self.store.apply_saved(group, &mut self.od, &mut *self.params) {
            self.events.push_back(DeviceEvent::StorageFailed(error));
        }
    }

    /// Re-creates every communication core from the dictionary (reset communication).
    fn load_communication(&mut self, now: Instant) {
        let node = self.node;
        let u32_at =
            |od: &DynamicOd, index: u16, sub: u8| match od.get(ObjectKey::new(index, sub)).map(|e| e.value())
            {
                Some(&[a, b, c, d]) => Some(u32::from_le_bytes([a, b, c, d])),
                _ => None,
            };
        let u16_at = |od: &DynamicOd, index: u16| match od.get(ObjectKey::new(index, 0)).map(|e| e.value()) {
            Some(&[a, b]) => Some(u16::from_le_bytes([a, b])),
            _ => None,
        };

        self.error_control = ErrorControl::new(node);
        self.error_control
            .set_producer_time(now, u16_at(&self.od, 0x1017).unwrap_or(0));
        self.error_control
            .set_guard_time(now, u16_at(&self.od, 0x100C).unwrap_or(0));
        if let Some(&[factor]) = self.od.get(ObjectKey::new(0x100D, 0)).map(|e| e.value()) {
            self.error_control.set_life_time_factor(now, factor);
        }

        self.consumer = HeartbeatConsumer::new();
        self.lost.clear();
        let entries: Vec<(u8, u32)> = self
            .od
            .object(0x1016)
            .iter()
            .filter(|e| e.key().sub != 0)
            .filter_map(|e| Some((e.key().sub, u32::from_le_bytes(e.value().try_into().ok()?))))
            .collect();
        for (sub, value) in entries {
            if let Err(error) = self.consumer.set_entry(sub, value) {
                self.refused(ObjectKey::new(0x1016, sub), error.abort_code());
            }
        }

        let history = self.od.object(0x1003).len().saturating_sub(1);
        self.emcy = EmcyProducer::new(node);
        if history > 0 {
            self.emcy = self.emcy.clone().with_history_len(history);
        }
        if let Some(value) = u32_at(&self.od, 0x1014, 0) {
            // Through "invalid" first, so a valid COB-ID with another CAN-ID than 80h + node-ID
            // is not refused as a change while valid.
            let _ = self.emcy.set_cob_id(crate::emcy::COB_ID_INVALID);
            if let Err(error) = self.emcy.set_cob_id(value) {
                let _ = self.emcy.set_cob_id(EmcyProducer::new(node).cob_id());
                self.refused(ObjectKey::new(0x1014, 0), error.abort_code());
            }
        }
        if let Some(inhibit) = u16_at(&self.od, 0x1015) {
            self.emcy.set_inhibit_time(now, inhibit);
        }

        self.sync = SyncService::new();
        self.load_sync(now);
        self.time = TimeService::new();
        self.time.load_od(&self.od);
        self.pdo = PdoEngine::new().with_dummy_usage(self.dummies);
        self.applied_mappings = crate::faults::mappings_of(&self.od);
        self.reload_pdos(now);
        self.load_sdo_servers();

        // CiA 302-2 1F80h bit 2 = 0: a self-starting device enters Operational on its own after the
        // boot-up message (reference §2.7; TR-Electronic and CANopenNode slaves read it so). Without
        // 1F80h the device waits for the NMT master, as CiA 301 devices do.
        let self_starting =
            u32_at(&self.od, 0x1F80, 0).is_some_and(|value| value & NMT_STARTUP_NO_AUTOSTART == 0);
        self.nmt.set_auto_start(self_starting);
    }

    /// Tells every SDO server whether the present NMT state lets downloads through
    /// ([`Device::with_downloads_refused_in_operational`]).
    fn lock_downloads(&mut self) {
        let locked = self.downloads_refused_in_operational && self.nmt.state() == NmtSlaveState::Operational;
        for (_, server) in &mut self.sdo {
            server.set_downloads_allowed(!locked);
        }
    }

    fn refused(&mut self, key: ObjectKey, abort_code: u32) {
        self.events
            .push_back(DeviceEvent::ConfigRefused(ConfigRefused { key, abort_code }));
    }

    /// The default server 1200h (always, on 600h/580h + node-ID) and the additional servers whose
    /// COB-IDs in 1201h–127Fh are both valid 11-bit ones. Servers whose COB-IDs did not change keep
    /// their running transfer.
    fn load_sdo_servers(&mut self) {
        let mut wanted: Vec<(u16, CanId, CanId)> = Vec::new();
        if let Ok(server) = SdoServer::default_for_node(self.node.get()) {
            wanted.push((SDO_SERVER_FIRST, server.rx_id(), server.tx_id()));
        }
        for index in SDO_SERVER_FIRST + 1..=SDO_SERVER_LAST {
            let cob = |sub: u8| match self.od.get(ObjectKey::new(index, sub)).map(|e| e.value()) {
                Some(&[a, b, c, d]) => Some(u32::from_le_bytes([a, b, c, d])),
                _ => None,
            };
            let (Some(rx), Some(tx)) = (cob(1), cob(2)) else {
                continue;
            };
            let id = |value: u32| {
                (value & 0xE000_0000 == 0)
                    .then(|| StandardId::new((value & 0x7FF) as u16))
                    .flatten()
                    .map(CanId::from)
            };
            if let (Some(rx), Some(tx)) = (id(rx), id(tx)) {
                wanted.push((index, rx, tx));
            }
        }
        let mut old = std::mem::take(&mut self.sdo);
        for (index, rx, tx) in wanted {
            let kept = old
                .iter()
                .position(|(i, s)| *i == index && s.rx_id() == rx && s.tx_id() == tx);
            let server = match kept {
                Some(position) => old.swap_remove(position).1,
                None => SdoServer::new(rx, tx),
            };
            self.sdo.push((index, server));
        }
        self.lock_downloads();
        // Servers that went away may still hold a response to the download that removed them.
        for (_, mut server) in old {
            self.transmit
                .extend(std::iter::from_fn(|| server.poll_transmit()));
        }
    }
}

impl Core for Device {
    type Event = DeviceEvent;

    /// Feeds a received frame to every core whose COB-ID it matches, in the NMT states where CiA
    /// 301 runs that service.
    fn handle_frame(&mut self, now: Instant, frame: &CanFrame) {
        if !self.configured {
            // CiA 305: a node without a node-ID takes part in LSS only; its LSS faults hold too.
            if let Some(frame) = self.faults.inbound(frame, self.node, false)
                && let Some(lss) = &mut self.lss
            {
                lss.handle_frame_with(now, &frame, &mut *self.lss_storage);
            }
            self.pump(now);
            return;
        }
        let sdo_request = self.sdo.iter().any(|(_, server)| server.rx_id() == frame.id());
        let Some(frame) = self.faults.inbound(frame, self.node, sdo_request) else {
            return;
        };
        let frame = &frame;
        let state = self.nmt.state();
        if state.is_active(CommService::ErrorControl) {
            self.fault_guarding(now, frame);
        }
        self.nmt.handle_frame(now, frame);
        if let Some(lss) = &mut self.lss {
            lss.handle_frame_with(now, frame, &mut *self.lss_storage);
        }
        if state.is_active(CommService::ErrorControl) {
            self.error_control.handle_frame(now, frame);
            self.consumer.handle_frame(now, frame);
        }
        if state.is_active(CommService::Sdo) || self.faults.routes(CommService::Sdo, state) {
            let mut hooks = Hooks {
                app: &*self.app,
                pdo: &self.pdo,
                sync: &self.sync,
                time: &self.time,
                emcy: &self.emcy,
                consumer: &self.consumer,
                store: &mut self.store,
                params: &mut *self.params,
                faults: self.faults.faults(),
            };
            for (_, server) in &mut self.sdo {
                server.handle_frame_with(now, frame, &mut self.od, &mut hooks);
            }
        }
        if state.is_active(CommService::Sync) {
            self.sync.handle_frame(now, frame);
        }
        if state.is_active(CommService::Time) {
            self.time.handle_frame(now, frame);
        }
        if state.is_active(CommService::Pdo) || self.faults.routes(CommService::Pdo, state) {
            self.pdo.handle_frame(now, frame, &mut self.od);
        } else if frame.is_remote()
            && state == NmtSlaveState::PreOperational
            && self.faults.has(Fault::TpdoRtrInPreOperational)
        {
            self.pdo.handle_rtr(frame, &self.od);
        }
        self.pump(now);
    }

    /// Runs every timer due at `now`, in every core and the application.
    fn handle_timeout(&mut self, now: Instant) {
        if !self.configured {
            if let Some(lss) = &mut self.lss {
                lss.handle_timeout(now);
            }
            self.pump(now);
            return;
        }
        let mut released = Vec::new();
        self.faults.release(now, &mut released);
        self.transmit.extend(released);
        self.error_control.handle_timeout(now);
        self.consumer.handle_timeout(now);
        for (_, server) in &mut self.sdo {
            server.handle_timeout(now);
        }
        self.emcy.handle_timeout(now);
        self.sync.handle_timeout(now);
        self.time.handle_timeout(now);
        if let Some(lss) = &mut self.lss {
            lss.handle_timeout(now);
        }
        self.pump(now);
        self.pdo.handle_timeout(now, &self.od);
        if self.app.poll_timeout().is_some_and(|due| due <= now) {
            let changes = self.app.handle_timeout(now, &mut self.od);
            self.apply_changes(now, &changes);
        }
        self.pump(now);
    }

    /// The next frame to send.
    fn poll_transmit(&mut self) -> Option<CanFrame> {
        self.transmit.pop_front()
    }

    /// The next event.
    fn poll_event(&mut self) -> Option<Self::Event> {
        self.events.pop_front()
    }

    /// When [`Device::handle_timeout`] must next be called: the earliest deadline of every core
    /// and the application.
    fn poll_timeout(&self) -> Option<Instant> {
        let lss = self.lss.as_ref().and_then(LssSlave::poll_timeout);
        if !self.configured {
            return lss;
        }
        [
            self.error_control.poll_timeout(),
            self.consumer.poll_timeout(),
            self.emcy.poll_timeout(),
            self.pdo.poll_timeout(),
            self.sync.poll_timeout(),
            self.time.poll_timeout(),
            self.app.poll_timeout(),
            lss,
        ]
        .into_iter()
        .chain(self.sdo.iter().map(|(_, server)| server.poll_timeout()))
        .chain([self.faults.poll_timeout()])
        .flatten()
        .min()
    }
}

/// The dummy types the EDS `[DummyUsage]` section enables (`DummyXXXX=1`).
fn dummy_usage(eds: &Eds) -> DummyUsage {
    let mut dummies = DummyUsage::NONE;
    if let Some(section) = &eds.dummy_usage {
        for index in 1..=7u16 {
            let enabled = section
                .get(&format!("Dummy{index:04X}"))
                .and_then(canopener_eds::model::int_of)
                == Some(1);
            if enabled {
                dummies = dummies.with(index);
            }
        }
    }
    dummies
}

/// The device's checks on SDO transfers, over the cores that own the rules.
struct Hooks<'a> {
    app: &'a dyn Application,
    pdo: &'a PdoEngine,
    sync: &'a SyncService,
    time: &'a TimeService,
    emcy: &'a EmcyProducer,
    consumer: &'a HeartbeatConsumer,
    store: &'a mut StoreRestore,
    params: &'a mut dyn ParameterStore,
    /// The device's defects: `store-ignored` confirms `save` to 1010h without storing,
    /// `restore-ignored` `load` to 1011h without restoring, `signature-unchecked` takes any value
    /// as the signature, `verify-configuration-not-stored` saves all but 1020h;
    /// `unmappable-accepted`, `pdo-cob-id-unchecked`, `mapping-procedure-unchecked` and
    /// `mapping-size-unchecked` let a mapping or COB-ID the PDO rules refuse through,
    /// `process-output-refused` refuses rww/wo objects in RPDO mappings; `error-count-unchecked`
    /// takes any value to 1003h:00; `limit-not-enforced` stores values outside LowLimit..HighLimit.
    /// All hold in every transfer mode, since the SDO server calls these hooks at the end of each.
    faults: FaultSet,
}

impl SdoHooks for Hooks<'_> {
    fn check_download(&mut self, key: ObjectKey, data: &[u8], od: &DynamicOd) -> Result<(), u32> {
        if self.faults.contains(Fault::TpdoConfigRefused)
            && crate::faults::is_tpdo_setting(key.index, key.sub)
        {
            return Err(abort::GENERAL_ERROR);
        }
        self.app.check_write(key, data, od)?;
        let procedure_unchecked = self.faults.contains(Fault::MappingProcedureUnchecked);
        let checked = match self.pdo.check_write(key, data, od) {
            Err(PdoConfigError::MappingWhileValid { .. } | PdoConfigError::MappingWhileEnabled { .. })
                if procedure_unchecked =>
            {
                // The entry itself is still checked, as if the procedure had been followed.
                self.pdo
                    .check_write(key, data, &mapping_procedure_followed(key, od))
            }
            result => result,
        };
        match checked {
            Err(PdoConfigError::NotMappable { .. }) if self.faults.contains(Fault::UnmappableAccepted) => {}
            Err(PdoConfigError::RestrictedCanId { .. }) if self.faults.contains(Fault::PdoCobIdUnchecked) => {
            }
            Err(PdoConfigError::TooManyObjects { .. } | PdoConfigError::LengthExceeded { .. })
                if self.faults.contains(Fault::MappingSizeUnchecked) => {}
            result => result.map_err(|e| e.abort_code())?,
        }
        if self.faults.contains(Fault::ProcessOutputRefused) && process_output_in_rpdo(key, data, od) {
            return Err(abort::OBJECT_NOT_MAPPABLE);
        }
        self.sync.check_download(key, data).map_err(|e| e.abort_code())?;
        self.time.check_download(key, data).map_err(|e| e.abort_code())?;
        match (key.index, key.sub, data) {
            (0x1014, 0, &[a, b, c, d]) => {
                let mut emcy = self.emcy.clone();
                emcy.set_cob_id(u32::from_le_bytes([a, b, c, d]))
                    .map_err(|e| e.abort_code())?;
            }
            (0x1003, 0, &[count]) if !self.faults.contains(Fault::ErrorCountUnchecked) => {
                let mut emcy = self.emcy.clone();
                emcy.write_history_count(count).map_err(|e| e.abort_code())?;
            }
            (0x1016, sub, &[a, b, c, d]) if sub != 0 => {
                let mut consumer = self.consumer.clone();
                consumer
                    .set_entry(sub, u32::from_le_bytes([a, b, c, d]))
                    .map_err(|e| e.abort_code())?;
            }
            _ => {}
        }
        if self.faults.contains(Fault::StoreIgnored) && key.index == 0x1010 && data == b"save" {
            return Ok(());
        }
        if self.faults.contains(Fault::RestoreIgnored) && key.index == 0x1011 && data == b"load" {
            return Ok(());
        }
        // Under `signature-unchecked` any 4 bytes to a group of 1010h/1011h act as the signature.
        let data = match (key.index, key.sub, data.len()) {
            (0x1010, 1.., 4) if self.faults.contains(Fault::SignatureUnchecked) => b"save",
            (0x1011, 1.., 4) if self.faults.contains(Fault::SignatureUnchecked) => b"load",
            _ => data,
        };
        // Last: a `save` here stores the dictionary at once, so every other check must have passed.
        let result = if self.faults.contains(Fault::VerifyConfigurationNotStored) {
            let mut params = WithoutVerifyConfiguration(&mut *self.params);
            self.store.check_download(key, data, od, &mut params)
        } else {
            self.store.check_download(key, data, od, self.params)
        };
        result.map_err(|e| e.abort_code())
    }

    fn write(&mut self, key: ObjectKey, data: &[u8], od: &mut DynamicOd) -> Result<(), OdError> {
        match od.write(key, data) {
            Err(OdError::ValueTooHigh { .. } | OdError::ValueTooLow { .. })
                if self.faults.contains(Fault::LimitNotEnforced) =>
            {
                od.set_value(key, data)
            }
            result => result,
        }
    }

    fn check_upload(&mut self, key: ObjectKey, _od: &DynamicOd) -> Result<(), u32> {
        if key.index == 0x1003 && key.sub != 0 {
            // A sub-index the dictionary has but the history does not reach: 0800 0024h.
            match self.emcy.read_history(key.sub) {
                Err(error) if error.abort_code() == abort::NO_DATA_AVAILABLE => {
                    return Err(error.abort_code());
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// `od` as the mapping procedure would leave it for a write to `key` (CiA 301 §7.5.2.38): the PDO
/// not valid (COB-ID bit 31 set) and, for an entry, sub-index 0 at 0. What
/// [`Fault::MappingProcedureUnchecked`] checks a mapping write against.
fn mapping_procedure_followed(key: ObjectKey, od: &DynamicOd) -> DynamicOd {
    let mut view = od.clone();
    if let Some((pdo, false)) = PdoRef::from_index(key.index) {
        let cob_key = ObjectKey::new(pdo.comm_index(), 1);
        if let Some(&[a, b, c, d]) = od.get(cob_key).map(|e| e.value()) {
            let invalid = u32::from_le_bytes([a, b, c, d]) | 0x8000_0000;
            let _ = view.set_value(cob_key, &invalid.to_le_bytes());
        }
        if key.sub != 0 {
            let _ = view.set_value(ObjectKey::new(key.index, 0), &[0]);
        }
    }
    view
}

/// Whether `data` written to `key` maps a process output (rww) or write-only object into an RPDO:
/// what [`Fault::ProcessOutputRefused`] refuses.
fn process_output_in_rpdo(key: ObjectKey, data: &[u8], od: &DynamicOd) -> bool {
    let &[_, sub, lo, hi] = data else { return false };
    if !(0x1600..=0x17FF).contains(&key.index) || key.sub == 0 {
        return false;
    }
    let mapped = ObjectKey::new(u16::from_le_bytes([lo, hi]), sub);
    od.get(mapped)
        .is_some_and(|e| matches!(e.access(), canopener_od::Access::Rww | canopener_od::Access::Wo))
}

/// A parameter store that saves everything but 1020h (verify configuration):
/// [`Fault::VerifyConfigurationNotStored`].
struct WithoutVerifyConfiguration<'a>(&'a mut dyn ParameterStore);

impl ParameterStore for WithoutVerifyConfiguration<'_> {
    fn save(&mut self, group: ParameterGroup, values: &[(ObjectKey, Vec<u8>)]) -> Result<(), StorageError> {
        let kept: Vec<(ObjectKey, Vec<u8>)> = values
            .iter()
            .filter(|(k, _)| k.index != 0x1020)
            .cloned()
            .collect();
        self.0.save(group, &kept)
    }

    fn load(&mut self, group: ParameterGroup) -> Result<Option<crate::store::Snapshot>, StorageError> {
        self.0.load(group)
    }

    fn clear(&mut self, group: ParameterGroup) -> Result<(), StorageError> {
        self.0.clear(group)
    }
}

/// The default LSS storage: accepts store configuration and keeps what was stored in memory for as
/// long as the `Device` lives, so NMT reset node starts the device with it again.
#[derive(Debug, Default)]
struct StoredLss {
    stored: Option<StoredConfiguration>,
}

impl LssStorage for StoredLss {
    fn store(&mut self, node_id: Option<NodeId>, bit_timing: Option<BitTiming>) -> Result<(), LssStoreError> {
        self.stored = Some(StoredConfiguration { node_id, bit_timing });
        Ok(())
    }

    fn stored(&self) -> Option<StoredConfiguration> {
        self.stored
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::application::NoApplication;
    use canopener_can::Core;
    use canopener_od::{Access, DataType, Entry};
    use canopener_testkit::frames::any_frame;
    use canopener_testkit::trace::{Trace, ms};
    use proptest::prelude::*;

    /// A minimal dictionary: 1001h, 1003h with 2 entries, 1014h, 1017h = 50 ms, 1018h:01, and an
    /// additional SDO server 1201h on 641h/5C1h.
    fn od() -> DynamicOd {
        let mut od = DynamicOd::with_capacity(16);
        let mut add = |index: u16, sub: u8, data_type: DataType, access: Access, value: &[u8]| {
            let entry = Entry::new(ObjectKey::new(index, sub), data_type, access, value).expect("entry");
            od.insert(entry).expect("room");
        };
        add(0x1001, 0, DataType::UNSIGNED8, Access::Ro, &[0]);
        add(0x1003, 0, DataType::UNSIGNED8, Access::Rw, &[0]);
        add(0x1003, 1, DataType::UNSIGNED32, Access::Ro, &[0; 4]);
        add(0x1003, 2, DataType::UNSIGNED32, Access::Ro, &[0; 4]);
        add(
            0x1014,
            0,
            DataType::UNSIGNED32,
            Access::Rw,
            &0x87u32.to_le_bytes(),
        );
        add(0x1017, 0, DataType::UNSIGNED16, Access::Rw, &50u16.to_le_bytes());
        add(
            0x1018,
            1,
            DataType::UNSIGNED32,
            Access::Ro,
            &0xABCu32.to_le_bytes(),
        );
        add(
            0x1201,
            1,
            DataType::UNSIGNED32,
            Access::Rw,
            &0x641u32.to_le_bytes(),
        );
        add(
            0x1201,
            2,
            DataType::UNSIGNED32,
            Access::Rw,
            &0x5C1u32.to_le_bytes(),
        );
        od
    }

    fn device() -> Trace<Device> {
        let dev = Device::new(od(), 7, Box::new(NoApplication)).expect("device");
        Trace::new(dev)
    }

    #[test]
    fn nothing_before_boot_then_boot_up_and_heartbeats() {
        let mut t = device();
        t.rx(ms(1), "000#0107");
        t.rx(ms(2), "607#4017100000000000");
        assert_eq!(t.core.state(), NmtSlaveState::Initialisation);
        assert_eq!(t.core.poll_timeout(), None);
        t.core.boot(ms(10));
        t.now = ms(10);
        t.advance(ms(110));
        assert_eq!(t.sent(), ["10.000 707#00", "60.000 707#7F", "110.000 707#7F"]);
    }

    #[test]
    fn additional_sdo_server_from_1201h_and_its_reload() {
        let mut t = device();
        t.core.boot(ms(0));
        t.rx(ms(1), "641#4017100000000000");
        // Move 1201h's request COB-ID: invalid first, then 642h.
        t.rx(ms(2), "641#2301120141060080");
        t.rx(ms(3), "641#4017100000000000");
        t.rx(ms(4), "607#2301120142060000");
        t.rx(ms(5), "642#4017100000000000");
        let sent: Vec<String> = t.sent().into_iter().filter(|s| !s.contains(" 707#")).collect();
        assert_eq!(
            sent,
            [
                "1.000 5C1#4B17100032000000",
                "2.000 5C1#6001120100000000",
                "4.000 587#6001120100000000",
                "5.000 5C1#4B17100032000000",
            ]
        );
    }

    #[test]
    fn emcy_cob_id_from_the_dictionary_and_history_upload_limits() {
        let mut t = device();
        t.core.boot(ms(0));
        t.rx(ms(1), "000#0107");
        t.rx(ms(2), "080#00");
        // 1019h does not exist, so a SYNC with data is the wrong length: EMCY 8240h on 087h, data
        // expected 0, received 1.
        let sent = t.sent();
        assert!(
            sent.contains(&"2.000 087#4082110001000000".to_string()),
            "{sent:?}"
        );
        t.rx(ms(3), "607#4003100200000000");
        assert_eq!(t.sent(), ["3.000 587#8003100224000008"]);
        t.rx(ms(4), "607#4003100100000000");
        assert_eq!(t.sent(), ["4.000 587#4303100140820001"]);
    }

    #[test]
    fn stopped_drops_a_running_sdo_transfer_silently() {
        let mut t = device();
        t.core.boot(ms(0));
        // Segmented download initiate of 1018h... any 4-byte entry: 1017h with size 2.
        t.rx(ms(1), "607#2117100002000000");
        t.rx(ms(2), "000#0207");
        t.advance(ms(3_000));
        let sent: Vec<String> = t.sent().into_iter().filter(|s| !s.contains(" 707#")).collect();
        assert_eq!(sent, ["1.000 587#6017100000000000"]);
    }

    #[test]
    fn invalid_node_id_is_refused() {
        assert!(matches!(
            Device::new(od(), 128, Box::new(NoApplication)),
            Err(DeviceError::NodeId(128))
        ));
    }

    proptest! {
        #[test]
        fn arbitrary_frames_never_panic(frames in proptest::collection::vec((any_frame(), 0u64..30), 0..80)) {
            let mut t = device();
            t.core.boot(ms(0));
            let mut now = 0;
            for (frame, dt) in frames {
                now += dt;
                t.advance(ms(now));
                t.core.handle_frame(ms(now), &frame);
            }
            t.advance(ms(now + 3_000));
        }
    }
}
