//! `canopener pdo map`, and the SDO access both `pdo` commands share (`pdo watch` is in `pdo_watch`).
//!
//! `pdo map` configures one PDO with the dynamic mapping procedure of CiA 301 §7.2.2 on the PDO
//! parameter objects 1400h–1BFFh (§7.5.2.35–§7.5.2.38; reference §3.4) as
//! `canopener_master::pdo_config` plans it: read the current COB-ID (communication parameter sub 1),
//! plan, then send the writes one by one as expedited SDO downloads (§7.2.4.3.3), stopping at the
//! first one the device refuses or leaves unanswered and saying in which state the PDO was left.
//!
//! Refusals of the planner (too many bits, restricted CAN-IDs, ...) come before the bus is opened
//! whenever they do not depend on the device, so a typo never leaves a PDO half-configured.

use canopener_can::Core;
use std::time::Duration;

use canopener_master::pdo_config::{
    COB_ID_INVALID, Direction, MappedObject, PdoConfig, PdoConfigError, PdoName, SdoWrite,
};
use canopener_master::sdo_client::{
    DownloadMode, SdoClient, SdoClientError, SdoClientEvent, SdoTransferError, UploadMode,
};
use canopener_master::value::{ValueType, parse_mapping};
use canopener_wire::NodeId;
use canopener_wire::abort;
use serde_json::{Value, json};

use crate::args::OutputFormat;
use crate::eds::input::print_stdout;
use crate::error::{CliError, CliResult};
use crate::master::args::{PdoMapArgs, PdoWatchArgs};
use canopener_runtime::link::{BusLink, Ended, Flow, Link, drive};

use crate::master::link::open_link;

/// Exit status after Ctrl-C interrupted a command that had not finished (128 + SIGINT, as shells use).
pub(crate) const INTERRUPTED_EXIT: u8 = crate::error::exit_code::INTERRUPTED;

pub(crate) fn map(args: PdoMapArgs) -> CliResult {
    let request = MapRequest::from_args(&args)?;
    request.precheck()?;
    let link = open_link(args.master.bus.spec.as_deref(), "pdo map")?;
    let mut sdo = LinkSdo::new(link, args.target.node, args.master.timeout)?;
    let format = args.master.format;
    let current = match request.read_cob_id(&mut sdo)? {
        Some(current) => current,
        None => {
            eprintln!(
                "interrupted before anything was written: {} of node {} is unchanged",
                request.config.name(),
                request.node
            );
            return Err(CliError::Exit(INTERRUPTED_EXIT));
        }
    };
    let writes = request.plan(current)?;
    if format == OutputFormat::Text {
        print_stdout(&format!(
            "{} of node {}: COB-ID {:04X}h:01 reads {current:08X}h; {} SDO writes:\n",
            request.config.name(),
            request.node,
            request.comm_index(),
            writes.len()
        ))?;
    }
    let mut report = MapReport::new(&request, current, writes);
    let mut printed = Ok(());
    report.execute(&mut sdo, |report, step| {
        if format == OutputFormat::Text && printed.is_ok() {
            printed = print_stdout(&format!("  {}\n", report.step_line(step)));
        }
    })?;
    printed?;
    match format {
        OutputFormat::Text => {
            for step in report.first_not_run()..report.steps.len() {
                print_stdout(&format!("  {}\n", report.step_line(step)))?;
            }
            if report.failure().is_none() {
                print_stdout(&format!("{}\n", report.summary()))?;
            }
        }
        OutputFormat::Json => print_stdout(&format!("{}\n", report.to_json()))?,
    }
    report.into_result()
}

pub(crate) fn watch(args: PdoWatchArgs) -> CliResult {
    crate::master::pdo_watch::run(args)
}

/// How one SDO transfer ended, when the bus itself did not fail.
#[derive(Debug)]
pub(crate) enum Transfer<T> {
    /// The device confirmed it.
    Done(T),
    /// An abort from either side, or no answer in time.
    Failed(SdoTransferError),
    /// Ctrl-C: the transfer was aborted (0800 0000h) and nothing else should be started.
    Interrupted,
}

/// One node's object dictionary over SDO, one transfer at a time (CiA 301 §7.2.4.3).
pub(crate) trait SdoAccess {
    /// Reads `index`:`sub` (initiate SDO upload, §7.2.4.3.6).
    fn upload(&mut self, index: u16, sub: u8) -> CliResult<Transfer<Vec<u8>>>;
    /// Writes 1 to 4 bytes to `index`:`sub` (expedited SDO download, §7.2.4.3.3).
    fn download(&mut self, index: u16, sub: u8, data: Vec<u8>) -> CliResult<Transfer<()>>;
}

/// [`SdoAccess`] over a bus: the default SDO channel of one node (600h/580h + node-ID).
#[derive(Debug)]
pub(crate) struct LinkSdo {
    link: BusLink,
    client: SdoClient,
    timeout: Duration,
}

impl LinkSdo {
    pub(crate) fn new(link: BusLink, node: u8, timeout: Duration) -> CliResult<LinkSdo> {
        let client = SdoClient::new(node)
            .map_err(|err| CliError::Usage(format!("{err}; e.g. --node 5")))?
            .with_timeout(timeout);
        Ok(LinkSdo {
            link,
            client,
            timeout,
        })
    }

    /// The bus, for what comes after the SDO transfers.
    pub(crate) fn into_link(self) -> BusLink {
        self.link
    }

    fn transfer(
        &mut self,
        start: impl FnOnce(&mut SdoClient, canopener_can::Instant) -> Result<(), SdoClientError>,
    ) -> CliResult<Transfer<Option<Vec<u8>>>> {
        let now = self.link.now();
        start(&mut self.client, now).map_err(|err| CliError::Internal(anyhow::anyhow!("{err}")))?;
        // The client times out on its own; this bound only matters with --timeout 0, which turns
        // the client's timeout off, so that a silent device still cannot hang the command.
        let limit = self.timeout.saturating_mul(2) + Duration::from_secs(1);
        let ended =
            drive::<_, _, _, CliError>(&mut self.link, &mut self.client, Some(now + limit), |_, event| {
                Ok(match event {
                    SdoClientEvent::Uploaded { data, .. } => Flow::Done(Ok(Some(data))),
                    SdoClientEvent::Downloaded { .. } => Flow::Done(Ok(None)),
                    SdoClientEvent::Failed { error, .. } => Flow::Done(Err(error)),
                    SdoClientEvent::Progress { .. } => Flow::Continue,
                })
            })?;
        Ok(match ended {
            Ok(Ok(data)) => Transfer::Done(data),
            Ok(Err(error)) => Transfer::Failed(error),
            Err(Ended::Deadline) => {
                self.abort(abort::PROTOCOL_TIMED_OUT)?;
                Transfer::Failed(SdoTransferError::TimedOut {
                    waiting_for: "answer of the device",
                    after: limit,
                })
            }
            Err(Ended::Cancelled) => {
                self.abort(abort::GENERAL_ERROR)?;
                Transfer::Interrupted
            }
        })
    }

    /// Ends the running transfer on the bus too, so the device does not wait for the rest of it.
    fn abort(&mut self, code: u32) -> CliResult {
        self.client.abort(self.link.now(), code);
        while let Some(frame) = self.client.poll_transmit() {
            self.link.send(&frame)?;
        }
        while self.client.poll_event().is_some() {}
        Ok(())
    }
}

impl SdoAccess for LinkSdo {
    fn upload(&mut self, index: u16, sub: u8) -> CliResult<Transfer<Vec<u8>>> {
        Ok(
            match self.transfer(|client, now| client.upload(now, index, sub, UploadMode::Normal))? {
                Transfer::Done(data) => Transfer::Done(data.unwrap_or_default()),
                Transfer::Failed(error) => Transfer::Failed(error),
                Transfer::Interrupted => Transfer::Interrupted,
            },
        )
    }

    fn download(&mut self, index: u16, sub: u8, data: Vec<u8>) -> CliResult<Transfer<()>> {
        Ok(
            match self
                .transfer(|client, now| client.download(now, index, sub, data, DownloadMode::Expedited))?
            {
                Transfer::Done(_) => Transfer::Done(()),
                Transfer::Failed(error) => Transfer::Failed(error),
                Transfer::Interrupted => Transfer::Interrupted,
            },
        )
    }
}

/// `6000:01` for messages.
pub(crate) fn object_name(index: u16, sub: u8) -> String {
    format!("{index:04X}h:{sub:02X}")
}

/// A value's little-endian bytes as one hex number, most significant first: `80000185`.
pub(crate) fn hex_value(data: &[u8]) -> String {
    data.iter().rev().map(|byte| format!("{byte:02X}")).collect()
}

/// What `pdo map` was asked to do, checked as far as it can be without the device.
#[derive(Debug)]
struct MapRequest {
    node: NodeId,
    config: PdoConfig,
}

impl MapRequest {
    fn from_args(args: &PdoMapArgs) -> CliResult<MapRequest> {
        let node = NodeId::new(args.target.node).ok_or_else(|| {
            CliError::Usage(format!(
                "--node {} is not 1..127; e.g. --node 5",
                args.target.node
            ))
        })?;
        let (direction, number) = match (args.tpdo, args.rpdo) {
            (Some(number), None) => (Direction::Tpdo, number),
            (None, Some(number)) => (Direction::Rpdo, number),
            _ => {
                return Err(CliError::Usage(
                    "give exactly one of --tpdo N or --rpdo N, e.g. --tpdo 1".to_owned(),
                ));
            }
        };
        let mapping = args
            .mapping
            .iter()
            .map(|text| parse_mapping(text).map_err(|err| CliError::Usage(err.to_string())))
            .collect::<CliResult<Vec<MappedObject>>>()?;
        let cob_id = args
            .cob_id
            .as_deref()
            .map(|text| {
                ValueType::U32
                    .parse(text)
                    .ok()
                    .and_then(|bytes| <[u8; 4]>::try_from(bytes).ok())
                    .map(u32::from_le_bytes)
                    .ok_or_else(|| {
                        CliError::Usage(format!(
                            "--cob-id `{text}` is not a 32-bit COB-ID: write it in hex or decimal, e.g. \
                             --cob-id 0x1A5 (CAN-ID 1A5h), or 0x800001A5 to leave the PDO invalid"
                        ))
                    })
            })
            .transpose()?;
        Ok(MapRequest {
            node,
            config: PdoConfig {
                direction,
                number,
                cob_id,
                transmission_type: args.transmission_type,
                inhibit_time_100us: args.inhibit,
                event_timer_ms: args.event_timer,
                sync_start: args.sync_start,
                mapping,
            },
        })
    }

    /// Refuses what the planner refuses whatever the device holds. Only a missing COB-ID of a PDO
    /// outside the pre-defined connection set waits for the device: its current one may do.
    fn precheck(&self) -> CliResult {
        match self.config.plan(self.node, None) {
            Ok(_) | Err(PdoConfigError::NeedsCobId { .. }) => Ok(()),
            Err(err) => Err(self.refused(&err)),
        }
    }

    fn plan(&self, current_cob_id: u32) -> CliResult<Vec<SdoWrite>> {
        self.config
            .plan(self.node, Some(current_cob_id))
            .map_err(|err| self.refused(&err))
    }

    fn refused(&self, err: &PdoConfigError) -> CliError {
        let pdo = match self.config.direction {
            Direction::Tpdo => format!("--tpdo {}", self.config.number),
            Direction::Rpdo => format!("--rpdo {}", self.config.number),
        };
        let example = match (self.config.direction, err) {
            (_, PdoConfigError::NeedsCobId { .. } | PdoConfigError::RestrictedCanId { .. }) => {
                format!(
                    "canopener pdo map --node {} {pdo} --cob-id 0x1A5 6000:01:8",
                    self.node
                )
            }
            (Direction::Tpdo, _) => format!(
                "canopener pdo map --node {} {pdo} 6000:01:8 6401:01:16 --type 255 --event-timer 100",
                self.node
            ),
            (Direction::Rpdo, _) => {
                format!(
                    "canopener pdo map --node {} {pdo} 6200:01:8 --type 255",
                    self.node
                )
            }
        };
        CliError::Usage(format!("{err}\nexample: {example}"))
    }

    fn comm_index(&self) -> u16 {
        self.config
            .comm_index()
            .unwrap_or(self.config.direction.comm_base())
    }

    fn mapping_index(&self) -> u16 {
        self.config
            .mapping_index()
            .unwrap_or(self.config.direction.mapping_base())
    }

    /// The COB-ID the PDO has now (communication parameter sub 1), `None` after Ctrl-C.
    fn read_cob_id(&self, sdo: &mut impl SdoAccess) -> CliResult<Option<u32>> {
        let (index, pdo, node) = (self.comm_index(), self.config.name(), self.node);
        let what = format!("reading the COB-ID of {pdo} ({})", object_name(index, 1));
        match sdo.upload(index, 1)? {
            Transfer::Done(data) => match <[u8; 4]>::try_from(data.as_slice()) {
                Ok(bytes) => Ok(Some(u32::from_le_bytes(bytes))),
                Err(_) => Err(CliError::Device(format!(
                    "node {node}, {what}: the device answered {} byte(s) ({}), but a COB-ID is UNSIGNED32; \
                     nothing was written",
                    data.len(),
                    hex_value(&data)
                ))),
            },
            Transfer::Failed(error) => {
                let hint = match error.abort_code() {
                    abort::OBJECT_DOES_NOT_EXIST | abort::SUB_INDEX_DOES_NOT_EXIST => {
                        format!(" (the device has no {pdo})")
                    }
                    _ => String::new(),
                };
                Err(CliError::Device(format!(
                    "node {node}, {what}: {error}{hint}; nothing was written"
                )))
            }
            Transfer::Interrupted => Ok(None),
        }
    }
}

/// How one write of the plan went.
#[derive(Debug)]
enum Outcome {
    Ok,
    Failed(SdoTransferError),
    Interrupted,
    NotRun,
}

/// The plan of one `pdo map` and how far it got.
#[derive(Debug)]
struct MapReport {
    node: NodeId,
    pdo: PdoName,
    comm_index: u16,
    mapping_index: u16,
    current_cob_id: u32,
    config: PdoConfig,
    steps: Vec<(SdoWrite, Outcome)>,
}

impl MapReport {
    fn new(request: &MapRequest, current_cob_id: u32, writes: Vec<SdoWrite>) -> MapReport {
        MapReport {
            node: request.node,
            pdo: request.config.name(),
            comm_index: request.comm_index(),
            mapping_index: request.mapping_index(),
            current_cob_id,
            config: request.config.clone(),
            steps: writes.into_iter().map(|write| (write, Outcome::NotRun)).collect(),
        }
    }

    /// Sends the writes in order until one fails, calling `on_step` after each one that was sent.
    fn execute(&mut self, sdo: &mut impl SdoAccess, mut on_step: impl FnMut(&MapReport, usize)) -> CliResult {
        for step in 0..self.steps.len() {
            let (write, _) = &self.steps[step];
            let outcome = match sdo.download(write.index, write.sub, write.data.clone())? {
                Transfer::Done(()) => Outcome::Ok,
                Transfer::Failed(error) => Outcome::Failed(error),
                Transfer::Interrupted => Outcome::Interrupted,
            };
            let stop = !matches!(outcome, Outcome::Ok);
            self.steps[step].1 = outcome;
            on_step(self, step);
            if stop {
                break;
            }
        }
        Ok(())
    }

    /// The step that failed or was interrupted, if any.
    fn failure(&self) -> Option<usize> {
        self.steps
            .iter()
            .position(|(_, outcome)| matches!(outcome, Outcome::Failed(_) | Outcome::Interrupted))
    }

    fn first_not_run(&self) -> usize {
        self.steps
            .iter()
            .position(|(_, outcome)| matches!(outcome, Outcome::NotRun))
            .unwrap_or(self.steps.len())
    }

    /// `3/7 1A00h:01 = 60000108h (map 6000:01:8): ok`.
    fn step_line(&self, step: usize) -> String {
        let outcome = match &self.steps[step].1 {
            Outcome::Ok => "ok".to_owned(),
            Outcome::Failed(error) => error.to_string(),
            Outcome::Interrupted => "interrupted".to_owned(),
            Outcome::NotRun => "not run".to_owned(),
        };
        format!(
            "{}/{} {}: {outcome}",
            step + 1,
            self.steps.len(),
            self.describe(step)
        )
    }

    /// `1A00h:01 = 60000108h (map 6000:01:8)`.
    fn describe(&self, step: usize) -> String {
        let write = &self.steps[step].0;
        let why = match self.entry(write) {
            Some(entry) => format!("map {entry}"),
            None => write.why.to_owned(),
        };
        format!(
            "{} = {}h ({why})",
            object_name(write.index, write.sub),
            hex_value(&write.data)
        )
    }

    /// The mapping entry a write sets, if it is one.
    fn entry(&self, write: &SdoWrite) -> Option<MappedObject> {
        if write.index != self.mapping_index || write.sub == 0 {
            return None;
        }
        let bytes = <[u8; 4]>::try_from(write.data.as_slice()).ok()?;
        Some(MappedObject::from_entry(u32::from_le_bytes(bytes)))
    }

    /// What the PDO looks like after a failure at `failed`: the plan's steps before it were
    /// confirmed, the failed one may or may not have been applied when the device did not answer.
    fn left_state(&self, failed: usize) -> String {
        let pdo = self.pdo;
        if failed == 0 {
            return format!("{pdo} is unchanged");
        }
        let done = &self.steps[..failed];
        let invalid = done
            .first()
            .map_or(self.current_cob_id | COB_ID_INVALID, |(write, _)| {
                <[u8; 4]>::try_from(write.data.as_slice())
                    .map_or(self.current_cob_id | COB_ID_INVALID, u32::from_le_bytes)
            });
        let map_sub0 = |value: u8| {
            done.iter().any(|(write, _)| {
                write.index == self.mapping_index && write.sub == 0 && write.data == [value]
            })
        };
        let entries = done
            .iter()
            .filter(|(write, _)| self.entry(write).is_some())
            .count();
        let total_entries = self.config.mapping.len();
        let count = u8::try_from(total_entries).unwrap_or(u8::MAX);
        let mapping = if count > 0 && map_sub0(count) {
            format!("its new mapping in place ({total_entries} entries)")
        } else if map_sub0(0) {
            format!(
                "its mapping disabled ({:04X}h:00 = 0, {entries} of {total_entries} entries written)",
                self.mapping_index
            )
        } else {
            "its mapping as it was".to_owned()
        };
        let mut state = format!("{pdo} is left invalid (COB-ID {invalid:08X}h) with {mapping}");
        if failed + 1 == self.steps.len() {
            state.push_str(" and its parameters written; only making it valid failed");
        }
        state
    }

    fn summary(&self) -> String {
        let pdo = self.pdo;
        let node = self.node;
        let last_cob = self
            .steps
            .iter()
            .rev()
            .find(|(write, _)| write.index == self.comm_index && write.sub == 1)
            .and_then(|(write, _)| <[u8; 4]>::try_from(write.data.as_slice()).ok())
            .map_or(self.current_cob_id, u32::from_le_bytes);
        let mapping = if self.config.mapping.is_empty() {
            "nothing mapped".to_owned()
        } else {
            let entries: Vec<String> = self.config.mapping.iter().map(ToString::to_string).collect();
            let bits: u32 = self.config.mapping.iter().map(|m| u32::from(m.bits)).sum();
            format!("{} ({bits} bits)", entries.join(" "))
        };
        if last_cob & COB_ID_INVALID == 0 {
            format!("{pdo} of node {node} configured: {mapping} on COB-ID {last_cob:08X}h, valid")
        } else {
            format!("{pdo} of node {node} configured: {mapping}, left invalid (COB-ID {last_cob:08X}h)")
        }
    }

    fn to_json(&self) -> Value {
        let steps: Vec<Value> = self
            .steps
            .iter()
            .enumerate()
            .map(|(step, (write, outcome))| {
                let mut value = json!({
                    "step": step + 1,
                    "index": format!("{:04X}", write.index),
                    "sub": write.sub,
                    "value": hex_value(&write.data),
                    "why": match self.entry(write) {
                        Some(entry) => format!("map {entry}"),
                        None => write.why.to_owned(),
                    },
                });
                let (name, error) = match outcome {
                    Outcome::Ok => ("ok", None),
                    Outcome::Failed(error @ SdoTransferError::TimedOut { .. }) => ("timed out", Some(error)),
                    Outcome::Failed(error) => ("aborted", Some(error)),
                    Outcome::Interrupted => ("interrupted", None),
                    Outcome::NotRun => ("not run", None),
                };
                value["outcome"] = json!(name);
                if let Some(error) = error {
                    value["abort_code"] = json!(format!("{:08X}", error.abort_code()));
                    value["error"] = json!(error.to_string());
                }
                value
            })
            .collect();
        let mut report = json!({
            "node": self.node.get(),
            "pdo": self.pdo.to_string(),
            "communication_index": format!("{:04X}", self.comm_index),
            "mapping_index": format!("{:04X}", self.mapping_index),
            "current_cob_id": format!("{:08X}", self.current_cob_id),
            "mapping": self.config.mapping.iter().map(ToString::to_string).collect::<Vec<_>>(),
            "steps": steps,
            "configured": self.failure().is_none(),
        });
        if let Some(failed) = self.failure() {
            report["state"] = json!(self.left_state(failed));
            report["error"] = json!(self.failure_message(failed));
        }
        report
    }

    /// The error message of a failed plan: which step, why, the state left and how to recover.
    fn failure_message(&self, failed: usize) -> String {
        let (node, pdo, total) = (self.node, self.pdo, self.steps.len());
        let step = format!("step {} of {total}, {}", failed + 1, self.describe(failed));
        let state = self.left_state(failed);
        let recover = if failed == 0 {
            String::new()
        } else {
            format!(
                "; to recover, run this `canopener pdo map` again once the cause is fixed (it starts by making \
                 the PDO invalid, so it can be repeated from any state), or `canopener nmt reset {node}` to go \
                 back to the configuration the device saved"
            )
        };
        match &self.steps[failed].1 {
            Outcome::Interrupted => format!("{pdo} of node {node}: interrupted at {step}; {state}{recover}"),
            Outcome::Failed(error) => {
                let unsure = if matches!(error, SdoTransferError::TimedOut { .. }) {
                    " (the device did not confirm this step, so it may have been applied)"
                } else {
                    ""
                };
                let hint = self.hint(failed, error.abort_code());
                format!("{pdo} of node {node}: {step}: {error}{hint}; {state}{unsure}{recover}")
            }
            Outcome::Ok | Outcome::NotRun => format!("{pdo} of node {node}: {step}"),
        }
    }

    /// What an abort code most likely means at this step.
    fn hint(&self, step: usize, code: u32) -> String {
        let write = &self.steps[step].0;
        let direction = self.pdo.direction;
        match (self.entry(write), code) {
            (Some(entry), abort::OBJECT_NOT_MAPPABLE) => {
                let needs = match direction {
                    Direction::Tpdo => "a TPDO needs a readable object",
                    Direction::Rpdo => "an RPDO needs a writable object",
                };
                format!(
                    " ({} cannot be mapped: PDOMapping=0 in the EDS, or an access type that does not fit: {needs})",
                    object_name(entry.index, entry.sub)
                )
            }
            (Some(entry), abort::OBJECT_DOES_NOT_EXIST | abort::SUB_INDEX_DOES_NOT_EXIST) => format!(
                " ({} does not exist on the device, or the mapping has fewer than {} sub-indices)",
                object_name(entry.index, entry.sub),
                write.sub
            ),
            (_, abort::PDO_LENGTH_EXCEEDED) => {
                " (the device takes fewer bits or fewer entries in this PDO)".to_owned()
            }
            (
                _,
                abort::CANNOT_TRANSFER
                | abort::CANNOT_TRANSFER_LOCAL_CONTROL
                | abort::CANNOT_TRANSFER_DEVICE_STATE,
            ) => format!(
                " (the device may refuse PDO changes in its NMT state: `canopener nmt preop {}` first)",
                self.node
            ),
            _ => String::new(),
        }
    }

    fn into_result(self) -> CliResult {
        let Some(failed) = self.failure() else {
            return Ok(());
        };
        let message = self.failure_message(failed);
        match self.steps[failed].1 {
            Outcome::Interrupted => {
                eprintln!("{message}");
                Err(CliError::Exit(INTERRUPTED_EXIT))
            }
            _ => Err(CliError::Device(message)),
        }
    }
}

/// A device on virtual time behind an SDO client, for the unit tests of both `pdo` commands.
#[cfg(test)]
pub(crate) mod testing {
    use canopener_can::{CanFrame, Instant};
    use canopener_device::application::NoApplication;
    use canopener_device::device::Device;

    use super::*;

    pub(crate) const BASE_EDS: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../canopener-check/test_data/checks/base.eds"
    );
    pub(crate) static IO_EDS: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
        canopener_testkit::corpus::eds("CANopenNode__CANopenNode__example__IO.eds")
            .display()
            .to_string()
    });

    pub(crate) fn eds(path: &str) -> canopener_eds::Eds {
        canopener_eds::load(&std::fs::read(path).expect("EDS file")).eds
    }

    /// How the device behind [`VirtualNode`] answers.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub(crate) enum Behaviour {
        /// As the device core does.
        Normal,
        /// Not at all after the first `n` requests.
        SilentAfter(usize),
        /// With a 3-byte frame instead of its answer.
        Garbage,
    }

    /// Node 5 built from an EDS, talking to an SDO client on virtual time; the frames both send
    /// are kept as `"<ms> <frame>"`.
    #[derive(Debug)]
    pub(crate) struct VirtualNode {
        pub(crate) device: Device,
        client: SdoClient,
        now: Instant,
        behaviour: Behaviour,
        requests: usize,
        pub(crate) trace: Vec<String>,
    }

    impl VirtualNode {
        pub(crate) fn new(path: &str, behaviour: Behaviour) -> VirtualNode {
            let mut device = Device::from_eds(&eds(path), 5, Box::new(NoApplication)).expect("device");
            device.boot(Instant::ZERO);
            while device.poll_transmit().is_some() {}
            VirtualNode {
                device,
                client: SdoClient::new(5).expect("client"),
                now: Instant::ZERO,
                behaviour,
                requests: 0,
                trace: Vec::new(),
            }
        }

        fn log(&mut self, frame: &CanFrame) {
            self.trace
                .push(format!("{} {frame}", self.now.as_micros() / 1000));
        }

        fn run(&mut self) -> Transfer<Option<Vec<u8>>> {
            loop {
                while let Some(request) = self.client.poll_transmit() {
                    self.log(&request);
                    self.requests += 1;
                    match self.behaviour {
                        Behaviour::SilentAfter(n) if self.requests > n => {}
                        // An abort (command 80h) gets no answer, garbage or not.
                        Behaviour::Garbage if request.data().first() == Some(&0x80) => {}
                        Behaviour::Garbage => {
                            let id = canopener_can::StandardId::new(0x585).expect("id");
                            let reply = CanFrame::new(id, &[0x60, 0x00, 0x18]).expect("frame");
                            self.log(&reply);
                            self.client.handle_frame(self.now, &reply);
                        }
                        _ => self.device.handle_frame(self.now, &request),
                    }
                }
                while let Some(reply) = self.device.poll_transmit() {
                    self.log(&reply);
                    self.client.handle_frame(self.now, &reply);
                }
                while self.device.poll_event().is_some() {}
                if let Some(event) = self.client.poll_event() {
                    // Let the abort frame of a failed transfer reach the trace.
                    while let Some(frame) = self.client.poll_transmit() {
                        self.log(&frame);
                    }
                    return match event {
                        SdoClientEvent::Uploaded { data, .. } => Transfer::Done(Some(data)),
                        SdoClientEvent::Downloaded { .. } => Transfer::Done(None),
                        SdoClientEvent::Failed { error, .. } => Transfer::Failed(error),
                        SdoClientEvent::Progress { .. } => continue,
                    };
                }
                let due = self
                    .client
                    .poll_timeout()
                    .expect("a running transfer has a timeout");
                self.now = self.now.max(due);
                self.client.handle_timeout(self.now);
            }
        }
    }

    impl SdoAccess for VirtualNode {
        fn upload(&mut self, index: u16, sub: u8) -> CliResult<Transfer<Vec<u8>>> {
            self.client
                .upload(self.now, index, sub, UploadMode::Normal)
                .expect("start upload");
            Ok(match self.run() {
                Transfer::Done(data) => Transfer::Done(data.unwrap_or_default()),
                Transfer::Failed(error) => Transfer::Failed(error),
                Transfer::Interrupted => Transfer::Interrupted,
            })
        }

        fn download(&mut self, index: u16, sub: u8, data: Vec<u8>) -> CliResult<Transfer<()>> {
            self.client
                .download(self.now, index, sub, data, DownloadMode::Expedited)
                .expect("start download");
            Ok(match self.run() {
                Transfer::Done(_) => Transfer::Done(()),
                Transfer::Failed(error) => Transfer::Failed(error),
                Transfer::Interrupted => Transfer::Interrupted,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use canopener_od::ObjectKey;

    use super::testing::{BASE_EDS, Behaviour, IO_EDS, VirtualNode};
    use super::*;

    fn request(direction: Direction, number: u16, mapping: &[&str]) -> MapRequest {
        MapRequest {
            node: NodeId::new(5).expect("node"),
            config: PdoConfig {
                direction,
                number,
                cob_id: None,
                transmission_type: None,
                inhibit_time_100us: None,
                event_timer_ms: None,
                sync_start: None,
                mapping: mapping
                    .iter()
                    .map(|text| parse_mapping(text).expect("mapping"))
                    .collect(),
            },
        }
    }

    /// Runs `pdo map` against node 5 of `eds`: the step lines, then the error if it failed.
    fn check(node: &mut VirtualNode, request: &MapRequest) -> Vec<String> {
        request.precheck().expect("precheck");
        let current = request
            .read_cob_id(node)
            .expect("no bus error")
            .expect("not interrupted");
        let writes = request.plan(current).expect("plan");
        let mut report = MapReport::new(request, current, writes);
        let mut lines = Vec::new();
        report
            .execute(node, |report, step| lines.push(report.step_line(step)))
            .expect("no bus error");
        for step in report.first_not_run()..report.steps.len() {
            lines.push(report.step_line(step));
        }
        match report.failure() {
            Some(failed) => lines.push(format!("error: {}", report.failure_message(failed))),
            None => lines.push(report.summary()),
        }
        lines
    }

    fn value(node: &VirtualNode, index: u16, sub: u8) -> Vec<u8> {
        node.device
            .od()
            .get(ObjectKey::new(index, sub))
            .expect("entry")
            .value()
            .to_vec()
    }

    #[test]
    fn maps_a_tpdo_with_the_cia_301_procedure_as_a_frame_trace() {
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::Normal);
        let mut request = request(Direction::Tpdo, 1, &["6000:01:8", "6401:01:16"]);
        request.config.transmission_type = Some(255);
        request.config.event_timer_ms = Some(100);
        assert_eq!(
            check(&mut node, &request),
            [
                "1/8 1800h:01 = 80000185h (make the PDO invalid while it changes): ok",
                "2/8 1A00h:00 = 00h (disable the mapping while its entries change): ok",
                "3/8 1A00h:01 = 60000108h (map 6000:01:8): ok",
                "4/8 1A00h:02 = 64010110h (map 6401:01:16): ok",
                "5/8 1A00h:00 = 02h (enable the mapping with its number of entries): ok",
                "6/8 1800h:02 = FFh (transmission type): ok",
                "7/8 1800h:05 = 0064h (event timer in ms): ok",
                "8/8 1800h:01 = 00000185h (make the PDO valid with its COB-ID): ok",
                "TPDO1 of node 5 configured: 6000:01:8 6401:01:16 (24 bits) on COB-ID 00000185h, valid",
            ]
        );
        assert_eq!(
            node.trace,
            [
                "0 605#4000180100000000",
                "0 585#4300180185010000",
                "0 605#2300180185010080",
                "0 585#6000180100000000",
                "0 605#2F001A0000000000",
                "0 585#60001A0000000000",
                "0 605#23001A0108010060",
                "0 585#60001A0100000000",
                "0 605#23001A0210010164",
                "0 585#60001A0200000000",
                "0 605#2F001A0002000000",
                "0 585#60001A0000000000",
                "0 605#2F001802FF000000",
                "0 585#6000180200000000",
                "0 605#2B00180564000000",
                "0 585#6000180500000000",
                "0 605#2300180185010000",
                "0 585#6000180100000000",
            ]
        );
        assert_eq!(value(&node, 0x1A00, 0), [2]);
        assert_eq!(value(&node, 0x1A00, 2), 0x6401_0110u32.to_le_bytes());
        assert_eq!(value(&node, 0x1800, 5), [100, 0]);
        assert_eq!(value(&node, 0x1800, 1), 0x185u32.to_le_bytes());
    }

    #[test]
    fn a_refused_entry_stops_the_plan_and_says_what_state_the_pdo_is_in() {
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::Normal);
        let request = request(Direction::Tpdo, 1, &["6000:01:8", "1017:00:16"]);
        assert_eq!(
            check(&mut node, &request),
            [
                "1/6 1800h:01 = 80000185h (make the PDO invalid while it changes): ok",
                "2/6 1A00h:00 = 00h (disable the mapping while its entries change): ok",
                "3/6 1A00h:01 = 60000108h (map 6000:01:8): ok",
                "4/6 1A00h:02 = 10170010h (map 1017:00:16): SDO abort 0x06040041 from the server: Object cannot \
                 be mapped to the PDO",
                "5/6 1A00h:00 = 02h (enable the mapping with its number of entries): not run",
                "6/6 1800h:01 = 00000185h (make the PDO valid with its COB-ID): not run",
                "error: TPDO1 of node 5: step 4 of 6, 1A00h:02 = 10170010h (map 1017:00:16): SDO abort 0x06040041 \
                 from the server: Object cannot be mapped to the PDO (1017h:00 cannot be mapped: PDOMapping=0 in \
                 the EDS, or an access type that does not fit: a TPDO needs a readable object); TPDO1 is left \
                 invalid (COB-ID 80000185h) with its mapping disabled (1A00h:00 = 0, 1 of 2 entries written); to \
                 recover, run this `canopener pdo map` again once the cause is fixed (it starts by making the PDO \
                 invalid, so it can be repeated from any state), or `canopener nmt reset 5` to go back to the \
                 configuration the device saved",
            ]
        );
        // The device is where the message says.
        assert_eq!(value(&node, 0x1800, 1), 0x8000_0185u32.to_le_bytes());
        assert_eq!(value(&node, 0x1A00, 0), [0]);
        assert_eq!(value(&node, 0x1A00, 1), 0x6000_0108u32.to_le_bytes());
    }

    #[test]
    fn a_mapping_longer_than_the_device_takes_is_refused_by_the_device() {
        // base.eds: 1A00h has one entry only.
        let mut node = VirtualNode::new(BASE_EDS, Behaviour::Normal);
        let lines = check(
            &mut node,
            &request(Direction::Tpdo, 1, &["6000:01:8", "6000:01:8"]),
        );
        assert_eq!(
            lines[3],
            "4/6 1A00h:02 = 60000108h (map 6000:01:8): SDO abort 0x06090011 from the server: Sub-index does not \
             exist"
        );
        assert!(
            lines[6].contains(
                "(6000h:01 does not exist on the device, or the mapping has fewer than 2 sub-indices)"
            ),
            "{lines:?}"
        );
    }

    #[test]
    fn an_rpdo_is_mapped_through_1400h_and_1600h() {
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::Normal);
        let mut request = request(Direction::Rpdo, 1, &["6200:01:8", "6200:02:8"]);
        request.config.transmission_type = Some(254);
        let lines = check(&mut node, &request);
        assert_eq!(
            lines,
            [
                "1/7 1400h:01 = 80000205h (make the PDO invalid while it changes): ok",
                "2/7 1600h:00 = 00h (disable the mapping while its entries change): ok",
                "3/7 1600h:01 = 62000108h (map 6200:01:8): ok",
                "4/7 1600h:02 = 62000208h (map 6200:02:8): ok",
                "5/7 1600h:00 = 02h (enable the mapping with its number of entries): ok",
                "6/7 1400h:02 = FEh (transmission type): ok",
                "7/7 1400h:01 = 00000205h (make the PDO valid with its COB-ID): ok",
                "RPDO1 of node 5 configured: 6200:01:8 6200:02:8 (16 bits) on COB-ID 00000205h, valid",
            ]
        );
        assert_eq!(value(&node, 0x1600, 2), 0x6200_0208u32.to_le_bytes());
    }

    #[test]
    fn a_device_falling_silent_mid_plan_times_out_naming_the_step() {
        // Answers the COB-ID read and the first two writes, then nothing.
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::SilentAfter(3));
        let lines = check(&mut node, &request(Direction::Tpdo, 1, &["6000:01:8"]));
        assert_eq!(
            lines[2],
            "3/5 1A00h:01 = 60000108h (map 6000:01:8): timed out after 1s waiting for the initiate download \
             response (abort 0x05040000 sent to the server)"
        );
        assert!(
            lines[5].contains("TPDO1 is left invalid (COB-ID 80000185h) with its mapping disabled (1A00h:00 = 0, 0 of 1 entries written) (the device did not confirm this step, so it may have been applied)"),
            "{lines:?}"
        );
        // The abort goes out when the timeout runs out, one second after the request.
        assert_eq!(
            node.trace[node.trace.len() - 2..],
            ["0 605#23001A0108010060", "1000 605#80001A0100000405"]
        );
    }

    #[test]
    fn garbage_instead_of_the_cob_id_aborts_before_anything_is_written() {
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::Garbage);
        let request = request(Direction::Tpdo, 1, &["6000:01:8"]);
        let err = request.read_cob_id(&mut node).expect_err("garbage");
        assert_eq!(err.exit_code(), 7);
        assert_eq!(
            err.to_string(),
            "node 5, reading the COB-ID of TPDO1 (1800h:01): SDO transfer aborted by the client with 0x05040001 \
             (client/server command specifier not valid or unknown): the server answered with DLC 3 (585#600018); \
             CiA 301 SDO frames have 8 bytes; nothing was written"
        );
        assert_eq!(
            node.trace.last().map(String::as_str),
            Some("0 605#8000180101000405")
        );
    }

    #[test]
    fn a_pdo_the_device_lacks_is_named() {
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::Normal);
        let mut request = request(Direction::Tpdo, 9, &["6000:01:8"]);
        request.config.cob_id = Some(0x1A5);
        let err = request.read_cob_id(&mut node).expect_err("no TPDO9");
        assert_eq!(
            err.to_string(),
            "node 5, reading the COB-ID of TPDO9 (1808h:01): SDO abort 0x06020000 from the server: Object does not \
             exist in the object dictionary (the device has no TPDO9); nothing was written"
        );
    }

    fn parse(args: &[&str]) -> CliResult<MapRequest> {
        use clap::Parser;
        let mut argv = vec!["canopener", "pdo", "map", "--bus", "virtual:x"];
        argv.extend_from_slice(args);
        let cli = crate::cli::Cli::try_parse_from(argv).expect("clap accepts it");
        match cli.command {
            crate::cli::Command::Pdo(crate::master::args::PdoCommand::Map(args)) => {
                let request = MapRequest::from_args(&args)?;
                request.precheck()?;
                Ok(request)
            }
            _ => panic!("not pdo map"),
        }
    }

    #[test]
    fn refusals_before_the_bus_exit_2_with_an_example() {
        let refused = |args: &[&str]| match parse(args) {
            Err(err @ CliError::Usage(_)) => err.to_string(),
            other => panic!("{args:?} should be refused: {other:?}"),
        };
        assert_eq!(
            refused(&[
                "--node",
                "5",
                "--tpdo",
                "1",
                "6401:01:32",
                "6401:02:32",
                "6000:01:1"
            ]),
            "the mapping takes 65 bits; a classical CAN PDO carries at most 64 (8 bytes)\n\
             example: canopener pdo map --node 5 --tpdo 1 6000:01:8 6401:01:16 --type 255 --event-timer 100"
        );
        assert_eq!(
            refused(&["--node", "5", "--rpdo", "2", "6200:01:8", "--inhibit", "10"]),
            "RPDO2 has no inhibit time: it applies to TPDOs only\n\
             example: canopener pdo map --node 5 --rpdo 2 6200:01:8 --type 255"
        );
        assert_eq!(
            refused(&["--node", "5", "--tpdo", "1", "6000:01:8", "--cob-id", "0x585"]),
            "CAN-ID 585h is restricted (default SDO, server to client) and cannot carry a PDO\n\
             example: canopener pdo map --node 5 --tpdo 1 --cob-id 0x1A5 6000:01:8"
        );
        assert!(
            refused(&["--node", "5", "--tpdo", "1", "6000:01"])
                .contains("write index:sub:bits like 6000:01:8")
        );
        assert!(
            refused(&["--node", "5", "--tpdo", "1", "6000:01:8", "--cob-id", "lots"])
                .contains("e.g. --cob-id 0x1A5")
        );
        assert!(refused(&["--node", "5", "--tpdo", "600", "6000:01:8"]).contains("numbered 1 to 512"));
        // A PDO outside the pre-defined connection set may keep the COB-ID the device gives it.
        let request =
            parse(&["--node", "5", "--tpdo", "9", "6000:01:8", "--cob-id", "1A5h"]).expect("accepted");
        assert_eq!(request.config.cob_id, Some(0x1A5));
        assert!(parse(&["--node", "5", "--tpdo", "9", "6000:01:8"]).is_ok());
    }

    #[test]
    fn the_json_report_has_every_step_and_the_failure() {
        let mut node = VirtualNode::new(&IO_EDS, Behaviour::Normal);
        let request = request(Direction::Tpdo, 1, &["1017:00:16"]);
        let current = request.read_cob_id(&mut node).unwrap().unwrap();
        let mut report = MapReport::new(&request, current, request.plan(current).unwrap());
        report.execute(&mut node, |_, _| {}).unwrap();
        let json = report.to_json();
        assert_eq!(json["pdo"], "TPDO1");
        assert_eq!(json["current_cob_id"], "00000185");
        assert_eq!(json["configured"], false);
        let outcomes: Vec<&str> = json["steps"]
            .as_array()
            .unwrap()
            .iter()
            .map(|step| step["outcome"].as_str().unwrap())
            .collect();
        assert_eq!(outcomes, ["ok", "ok", "aborted", "not run", "not run"]);
        assert_eq!(json["steps"][2]["abort_code"], "06040041");
        assert_eq!(json["steps"][2]["why"], "map 1017:00:16");
        assert_eq!(json["steps"][2]["index"], "1A00");
        assert_eq!(json["steps"][2]["value"], "10170010");
        assert!(
            json["state"]
                .as_str()
                .unwrap()
                .starts_with("TPDO1 is left invalid")
        );
        assert!(json["error"].as_str().unwrap().contains("step 3 of 5"));
        assert_eq!(report.into_result().unwrap_err().exit_code(), 7);
    }
}
