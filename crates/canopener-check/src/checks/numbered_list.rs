//! `NrOfEntries` lists (`[ConnectedModules]` of a DCF, the object lists of a module): one check
//! shared by the DCF and the module checks.

use std::collections::BTreeSet;

use canopener_eds::model::{Properties, decimal_key};
use canopener_eds::section_name::SectionKind;

use super::reading::{present, strict_int};
use crate::check_info::CheckInfo;
use crate::context::Context;
use crate::finding::Finding;

/// Checks a `NrOfEntries` list (`[ConnectedModules]`, module object lists): the count is a number
/// equal to the entries, the entries are numbered 1..=count in decimal, and no other key appears.
pub(crate) fn check_numbered_list(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    section: SectionKind,
    list: &Properties,
    info: &CheckInfo,
) {
    let name = cx.display_name(section);
    let numbers: Vec<u32> = list.numbered().map(|(n, _)| n).collect();
    let help = format!(
        "set NrOfEntries={} and number the entries 1, 2, ... in decimal",
        numbers.len()
    );
    let count = match present(list.get("NrOfEntries")) {
        None => {
            out.push(
                cx.finding(
                    info,
                    section,
                    Some("NrOfEntries"),
                    format!("[{name}] has no NrOfEntries for its {} entries", numbers.len()),
                )
                .with_help(help.clone()),
            );
            None
        }
        Some(text) => match strict_int(text) {
            Some(count) if count != numbers.len() as i128 => {
                out.push(
                    cx.finding(
                        info,
                        section,
                        Some("NrOfEntries"),
                        format!(
                            "NrOfEntries={text} but [{name}] has {} numbered entries",
                            numbers.len()
                        ),
                    )
                    .with_help(help.clone()),
                );
                None
            }
            Some(count) => Some(count),
            None => {
                out.push(
                    cx.finding(
                        info,
                        section,
                        Some("NrOfEntries"),
                        format!("NrOfEntries `{text}` is not a number"),
                    )
                    .with_help(help.clone()),
                );
                None
            }
        },
    };
    for p in &list.0 {
        if p.key.eq_ignore_ascii_case("NrOfEntries") || decimal_key(&p.key).is_some() {
            continue;
        }
        out.push(
            cx.finding(
                info,
                section,
                Some(&p.key),
                format!(
                    "entry `{}` of [{name}] is not numbered 1, 2, ... in decimal",
                    p.key
                ),
            )
            .with_help(help.clone()),
        );
    }
    // Numbering is only judged when the count matches; a count mismatch is reported above.
    if let Some(count) = count {
        let present: BTreeSet<u32> = numbers.iter().copied().collect();
        for &n in &numbers {
            if n == 0 || i128::from(n) > count {
                let key = n.to_string();
                out.push(
                    cx.finding(
                        info,
                        section,
                        Some(&key),
                        format!("entry {n} of [{name}] is outside 1..={count}"),
                    )
                    .with_help(format!(
                        "number the entries 1..={count}; missing: {}",
                        (1..=numbers.len() as u32)
                            .filter(|k| !present.contains(k))
                            .map(|k| k.to_string())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )),
                );
            }
        }
    }
}
