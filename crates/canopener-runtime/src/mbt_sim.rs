//! Model-based tests on simulated devices built from descriptions: one run on a fresh device, and
//! the `--set` values the `sdo-download` model needs from a description. CiA 301 defines no entry
//! every device has that takes a long segmented download, nor one with limits, and the model
//! language reads single values (`od`, `exists`), not a search of the dictionary. These are found
//! here, in the dictionary the description describes (the same one a simulated device is built
//! from), so that a run judges the description's own `LowLimit`/`HighLimit` (CiA 306).

use std::time::Duration;

use canopener_can::Instant;
use canopener_device::faults::Fault;
use canopener_device::od_build::build_od;
use canopener_eds::model::Eds;
use canopener_mbt::executor::{RunConfig, RunResult};
use canopener_mbt::model::Model;
use canopener_od::{DataType, Entry, Number};

use crate::mbt_run::run;
use canopener_link::link::LinkError;
use canopener_sim::error::SimError;
use canopener_sim::simulation::Simulation;

/// Why a run on a simulated device could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SimRunError {
    /// The device could not be built from its description.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The virtual bus failed.
    #[error(transparent)]
    Link(#[from] LinkError),
}

/// Tests a fresh simulated device, built from `eds` with `node_id` and `faults`, against `model` on
/// an ideal virtual bus (deterministic). The device's power-on boot-up is history (100 ms of bus
/// time pass first) when the tester starts with the model's reset stimuli.
pub fn run_simulated(
    model: &Model,
    eds: &Eds,
    node_id: u8,
    faults: &[Fault],
    config: RunConfig,
) -> Result<RunResult, SimRunError> {
    let mut bus = Simulation::ideal()
        .device(eds, node_id)
        .faults(faults.iter().copied())
        .start()?;
    bus.run_until(Instant::from_millis(100))?;
    Ok(run(
        &mut bus,
        model,
        config,
        Some(Duration::from_secs(1_000_000)),
    )?)
}

/// The last `n` steps of a run's trace, one a line (`1.250 In ?NMT !0x01 !0x05`), after its
/// verdict and reason: what a failing test prints.
pub fn outcome_tail(o: &RunResult, n: usize) -> String {
    let skip = o.trace.len().saturating_sub(n);
    let steps: Vec<String> = o
        .trace
        .iter()
        .skip(skip)
        .map(|s| format!("{:.3} {:?} {}", s.t, s.dir, s.label))
        .collect();
    format!("{:?}: {}\n  {}", o.verdict, o.reason, steps.join("\n  "))
}

/// The parameter settings a composition of `models` runs with on a device described by `eds`:
/// `given` (the user's `--set`), and for `sdo-download` the description's long and limited entries
/// ([`sdo_download_settings`]) where `given` does not name them. `mbt run`, the tests and the
/// examples all compose through this, so a model is told the same wherever it runs.
pub fn model_settings<S: AsRef<str>>(
    models: &[S],
    eds: &Eds,
    node_id: u8,
    given: &[(String, i64)],
) -> Vec<(String, i64)> {
    let mut settings: Vec<(String, i64)> = Vec::new();
    if models.iter().any(|m| m.as_ref() == "sdo-download") {
        settings.extend(
            sdo_download_settings(eds, node_id)
                .into_iter()
                .filter(|(name, _)| !given.iter().any(|(g, _)| g == name)),
        );
    }
    settings.extend(given.iter().cloned());
    settings
}

/// The settings for `sdo-download`: `LONG_INDEX`/`LONG_SUB` (a readable and writable
/// variable-length entry that takes at least 14 bytes) and `LIMIT_INDEX`/`LIMIT_SUB`/`LIMIT_SIZE`
/// with `HAS_HIGH`/`HIGH` and `HAS_LOW`/`LOW` (a writable integer entry of 1, 2 or 4 bytes with a
/// limit that its type can step beyond), each where the description has one. Only manufacturer and
/// profile entries (2000h and up) are taken: a communication entry (a PDO mapping's sub-index 0,
/// a COB-ID) has rules of its own that refuse a write for other reasons than its limits.
pub fn sdo_download_settings(eds: &Eds, node_id: u8) -> Vec<(String, i64)> {
    let Ok(built) = build_od(eds, node_id) else {
        return Vec::new();
    };
    let entries: Vec<&Entry> = built.od.iter().filter(|e| e.key().index >= 0x2000).collect();
    let mut set = Vec::new();
    let long = entries.iter().find(|e| {
        e.data_type().is_variable_length()
            && e.access().readable()
            && e.access().writable()
            && e.max_len().is_none_or(|n| n >= 14)
    });
    if let Some(e) = long {
        set.push(("LONG_INDEX".to_owned(), i64::from(e.key().index)));
        set.push(("LONG_SUB".to_owned(), i64::from(e.key().sub)));
    }
    let limited = entries.iter().find_map(|e| limits(e).map(|l| (e, l)));
    if let Some((e, (size, high, low))) = limited {
        set.push(("LIMIT_INDEX".to_owned(), i64::from(e.key().index)));
        set.push(("LIMIT_SUB".to_owned(), i64::from(e.key().sub)));
        set.push(("LIMIT_SIZE".to_owned(), size));
        if let Some(high) = high {
            set.push(("HAS_HIGH".to_owned(), 1));
            set.push(("HIGH".to_owned(), high));
        }
        if let Some(low) = low {
            set.push(("HAS_LOW".to_owned(), 1));
            set.push(("LOW".to_owned(), low));
        }
    }
    set
}

/// The size of a writable integer entry and its limits, each only if the value one beyond it fits
/// the type (a limit at the type's own bound cannot be exceeded over SDO).
fn limits(e: &Entry) -> Option<(i64, Option<i64>, Option<i64>)> {
    let t = e.data_type();
    let size = t.byte_size().filter(|s| matches!(s, 1 | 2 | 4))?;
    if !t.is_integer() || !e.access().writable() {
        return None;
    }
    let bits = 8 * size as u32;
    let (min, max) = if [DataType::INTEGER8, DataType::INTEGER16, DataType::INTEGER32].contains(&t) {
        (-(1i64 << (bits - 1)), (1i64 << (bits - 1)) - 1)
    } else {
        (0, (1i64 << bits) - 1)
    };
    let value = |n: Number| match n {
        Number::Signed(v) => Some(v),
        Number::Unsigned(v) => i64::try_from(v).ok(),
        Number::Real(_) => None,
    };
    let high = e.high_limit().and_then(value).filter(|h| *h < max);
    let low = e.low_limit().and_then(value).filter(|l| *l > min);
    (high.is_some() || low.is_some()).then_some((size as i64, high, low))
}

/// What each CANopen model of issue 23 (`sdo-block`, `sdo-download`, `pdo`, `store`,
/// `lss-config`, `life-guarding`) is composed with beyond the composition matrix (their
/// `Shipped::canopen` stays false, so the matrix does not grow to 2^13 subsets): all the shipped
/// CANopen models of the matrix (`nmt sdo sync lss emcy guarding heartbeat`), `nmt sdo`, and for
/// the two SDO transfer models each other with `nmt sdo`. `tests/mbt_models.rs` and
/// `examples/mbt_models.rs` run these lists; the model under test is added to each.
pub fn compositions_of(name: &str) -> Vec<Vec<&'static str>> {
    let matrix: Vec<&'static str> = canopener_mbt::shipped::canopen_models().map(|m| m.name).collect();
    let mut all = vec![matrix, vec!["nmt", "sdo"]];
    match name {
        "sdo-block" => all.push(vec!["nmt", "sdo", "sdo-download"]),
        "sdo-download" => all.push(vec!["nmt", "sdo", "sdo-block"]),
        _ => {}
    }
    all
}
