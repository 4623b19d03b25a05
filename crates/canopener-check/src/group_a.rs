//! Group A of `eds-format-and-checks.md` §10.

use crate::context::Context;
use crate::finding::Finding;
use crate::registry::CheckInfo;

/// The checks of this group.
pub(crate) const CHECKS: &[CheckInfo] = &[];

/// Runs the checks of this group.
pub(crate) fn run(_cx: &Context<'_>, _out: &mut Vec<Finding>) {}
