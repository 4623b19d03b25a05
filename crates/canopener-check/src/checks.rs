//! The built-in checks, one module per group of the check catalogue (`docs/check-catalogue.md`,
//! groups A-K), plus the loading codes and the portability lint.
//!
//! Each module describes its own checks (`CHECKS`, a list of [`CheckInfo`]) and runs them (`run`).
//! [`GROUPS`] is the one list of them: the registry reads the descriptions from it and the runner
//! runs it, so a check module never depends on either.

use crate::check_info::CheckInfo;
use crate::context::Context;
use crate::finding::Finding;

mod cia301;
mod dcf;
mod device_info;
mod dummy_usage;
mod file_info;
mod loading;
mod modules;
mod numbered_list;
mod object_lists;
pub(crate) mod objects;
mod profiles;
mod reading;
mod syntax;
pub(crate) mod value_rules;
mod values;
mod xml;

/// A group of checks: what they are, and how to run them on one file.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CheckGroup {
    /// The descriptions of the group's checks.
    pub(crate) checks: &'static [CheckInfo],
    /// Runs every check of the group on one file, appending what it finds.
    pub(crate) run: fn(&Context<'_>, &mut Vec<Finding>),
}

/// The CiA 301 value rules of the communication objects as Markdown (`docs/cia301-value-rules.md`),
/// generated from the same rule table the checker evaluates.
pub(crate) fn value_rules_markdown(severity_of: impl Fn(&str) -> Option<canopener_eds::Severity>) -> String {
    value_rules::markdown(severity_of)
}

/// Every group of built-in checks, in the order they run: loading codes first, then the catalogue's
/// groups A-K, then portability.
pub(crate) const GROUPS: &[CheckGroup] = &[
    CheckGroup {
        checks: loading::CHECKS,
        run: loading::run,
    },
    CheckGroup {
        checks: syntax::CHECKS,
        run: syntax::run,
    },
    CheckGroup {
        checks: file_info::CHECKS,
        run: file_info::run,
    },
    CheckGroup {
        checks: device_info::CHECKS,
        run: device_info::run,
    },
    CheckGroup {
        checks: dummy_usage::CHECKS,
        run: dummy_usage::run,
    },
    CheckGroup {
        checks: object_lists::CHECKS,
        run: object_lists::run,
    },
    CheckGroup {
        checks: objects::CHECKS,
        run: objects::run,
    },
    CheckGroup {
        checks: values::CHECKS,
        run: values::run,
    },
    CheckGroup {
        checks: cia301::CHECKS,
        run: cia301::run,
    },
    CheckGroup {
        checks: value_rules::CHECKS,
        run: value_rules::run,
    },
    CheckGroup {
        checks: dcf::CHECKS,
        run: dcf::run,
    },
    CheckGroup {
        checks: modules::CHECKS,
        run: modules::run,
    },
    CheckGroup {
        checks: profiles::CHECKS,
        run: profiles::run,
    },
    CheckGroup {
        checks: crate::portability::CHECKS,
        run: crate::portability::run,
    },
    CheckGroup {
        checks: xml::CHECKS,
        run: xml::run,
    },
];
