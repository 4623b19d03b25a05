//! Model-based testing on a link: the driver loop of [`canopener_mbt::executor::Executor`]. The same
//! run works on a real bus on the wall clock and on a [`VirtualLink`](crate::virtual_link::VirtualLink)
//! with simulated devices on virtual time, where it is deterministic.

use std::time::Duration;

use canopener_mbt::executor::{Executor, Outcome, RunConfig};
use canopener_mbt::model::Model;

use crate::link::{Ended, Flow, Link, LinkError, drive};

/// Tests the device behind `link` against `model` until the executor decides, `limit` passes
/// (a `pass` if nothing failed so far) or the link is cancelled (`inconclusive`).
pub fn run<L: Link + ?Sized>(
    link: &mut L,
    model: &Model,
    config: RunConfig,
    limit: Option<Duration>,
) -> Result<Outcome, LinkError> {
    let start = link.now();
    let mut executor = Executor::new(model, config, start);
    let deadline = limit.map(|limit| start + limit);
    let ended = drive(link, &mut executor, deadline, |_, outcome| {
        Ok::<_, LinkError>(Flow::Done(outcome))
    })?;
    Ok(match ended {
        Ok(outcome) => outcome,
        Err(Ended::Deadline) => executor.finish("the time limit passed without a failure"),
        Err(Ended::Cancelled) => {
            let mut outcome = executor.finish("cancelled");
            outcome.verdict = canopener_mbt::executor::Verdict::Inconclusive;
            outcome
        }
    })
}
