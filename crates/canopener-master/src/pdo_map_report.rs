//! Executing a PDO configuration plan ([`pdo_config`](crate::pdo_config), CiA 301 §7.2.2 and the PDO
//! parameter objects 1400h–1BFFh, §7.5.2.35–§7.5.2.38) step by step: [`MapReport`] records how far
//! it got, and says in which state a failure left the PDO. Sending the writes over SDO is the
//! link crate's (`canopener_link::pdo_map`).

use canopener_wire::{NodeId, abort};

use crate::pdo_config::{COB_ID_INVALID, Direction, MappedObject, PdoConfig, PdoName, SdoWrite};
use crate::sdo_client::SdoTransferError;
use crate::value::{entry_label, hex_value};

/// How one write of the plan went.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StepOutcome {
    /// The device confirmed it.
    Ok,
    /// An abort from either side, or no answer in time.
    Failed(SdoTransferError),
    /// Cancelled: the transfer was aborted on the bus.
    Interrupted,
    /// Not sent, since an earlier step failed.
    NotRun,
}

/// The plan of one PDO configuration and how far it got.
#[derive(Debug, Clone)]
pub struct MapReport {
    /// The node configured.
    pub node: NodeId,
    /// The PDO.
    pub pdo: PdoName,
    /// Its communication parameter object.
    pub comm_index: u16,
    /// Its mapping parameter object.
    pub mapping_index: u16,
    /// The COB-ID it had before.
    pub current_cob_id: u32,
    /// What was asked.
    pub config: PdoConfig,
    /// The writes of the plan in order, with how each went.
    pub steps: Vec<(SdoWrite, StepOutcome)>,
}

impl MapReport {
    /// The plan `writes` for `config` on `node`, none run yet.
    pub fn new(node: NodeId, config: &PdoConfig, current_cob_id: u32, writes: Vec<SdoWrite>) -> MapReport {
        MapReport {
            node,
            pdo: config.name(),
            comm_index: config.comm_index().unwrap_or(config.direction.comm_base()),
            mapping_index: config.mapping_index().unwrap_or(config.direction.mapping_base()),
            current_cob_id,
            config: config.clone(),
            steps: writes
                .into_iter()
                .map(|write| (write, StepOutcome::NotRun))
                .collect(),
        }
    }

    /// The step that failed or was interrupted, if any.
    pub fn failure(&self) -> Option<usize> {
        self.steps
            .iter()
            .position(|(_, outcome)| matches!(outcome, StepOutcome::Failed(_) | StepOutcome::Interrupted))
    }

    /// The first step not sent (the number of steps when all were).
    pub fn first_not_run(&self) -> usize {
        self.steps
            .iter()
            .position(|(_, outcome)| matches!(outcome, StepOutcome::NotRun))
            .unwrap_or(self.steps.len())
    }

    /// `3/7 1A00h:01 = 60000108h (map 6000:01:8): ok`.
    pub fn step_line(&self, step: usize) -> String {
        let outcome = match self.steps.get(step).map(|(_, outcome)| outcome) {
            None => "no such step".to_owned(),
            Some(StepOutcome::Ok) => "ok".to_owned(),
            Some(StepOutcome::Failed(error)) => error.to_string(),
            Some(StepOutcome::Interrupted) => "interrupted".to_owned(),
            Some(StepOutcome::NotRun) => "not run".to_owned(),
        };
        format!(
            "{}/{} {}: {outcome}",
            step + 1,
            self.steps.len(),
            self.describe(step)
        )
    }

    /// `1A00h:01 = 60000108h (map 6000:01:8)`.
    pub fn describe(&self, step: usize) -> String {
        let Some((write, _)) = self.steps.get(step) else {
            return format!("step {} of {}: no such step", step + 1, self.steps.len());
        };
        let why = match self.entry(write) {
            Some(entry) => format!("map {entry}"),
            None => write.why.to_owned(),
        };
        format!(
            "{} = {}h ({why})",
            entry_label(write.index, write.sub),
            hex_value(&write.data)
        )
    }

    /// The mapping entry a write sets, if it is one.
    pub fn entry(&self, write: &SdoWrite) -> Option<MappedObject> {
        if write.index != self.mapping_index || write.sub == 0 {
            return None;
        }
        let bytes = <[u8; 4]>::try_from(write.data.as_slice()).ok()?;
        Some(MappedObject::from_entry(u32::from_le_bytes(bytes)))
    }

    /// What the PDO looks like after a failure at `failed`: the plan's steps before it were
    /// confirmed, the failed one may or may not have been applied when the device did not answer.
    pub fn left_state(&self, failed: usize) -> String {
        let pdo = self.pdo;
        if failed == 0 {
            return format!("{pdo} is unchanged");
        }
        let done = self.steps.get(..failed).unwrap_or(&self.steps);
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

    /// `TPDO1 of node 5 configured: 6000:01:8 (8 bits) on COB-ID 00000185h, valid`.
    pub fn summary(&self) -> String {
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

    /// What an abort code most likely means at `step`.
    pub fn hint(&self, step: usize, code: u32) -> Option<StepHint> {
        let write = &self.steps.get(step)?.0;
        match (self.entry(write), code) {
            (Some(entry), abort::OBJECT_NOT_MAPPABLE) => Some(StepHint::NotMappable {
                entry,
                direction: self.pdo.direction,
            }),
            (Some(entry), abort::OBJECT_DOES_NOT_EXIST | abort::SUB_INDEX_DOES_NOT_EXIST) => {
                Some(StepHint::NoSuchEntry {
                    entry,
                    sub: write.sub,
                })
            }
            (_, abort::PDO_LENGTH_EXCEEDED) => Some(StepHint::TooLong),
            (
                _,
                abort::CANNOT_TRANSFER
                | abort::CANNOT_TRANSFER_LOCAL_CONTROL
                | abort::CANNOT_TRANSFER_DEVICE_STATE,
            ) => Some(StepHint::DeviceState),
            _ => None,
        }
    }
}

/// What an abort most likely means at a step of the plan (CiA 301 §7.2.2, §7.2.4.3.17).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepHint {
    /// 0604 0041h on a mapping entry: the object cannot be mapped, or not in this direction.
    NotMappable {
        /// The entry written.
        entry: MappedObject,
        /// TPDOs need readable, RPDOs writable objects.
        direction: Direction,
    },
    /// 0602 0000h or 0609 0011h on a mapping entry: the object does not exist, or the mapping has
    /// fewer sub-indices.
    NoSuchEntry {
        /// The entry written.
        entry: MappedObject,
        /// The mapping sub-index written.
        sub: u8,
    },
    /// 0604 0042h: the device takes fewer bits or entries.
    TooLong,
    /// 0800 0020h..0800 0022h: the device refuses changes in its state (CiA 301 allows PDO changes
    /// in pre-operational).
    DeviceState,
}
