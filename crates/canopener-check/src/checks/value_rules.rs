//! CiA 301 value rules of the communication objects (1000h-1FFFh) as data: every value range,
//! reserved value and dependency on another object that the project's reference notes state is one
//! row of [`table::RULES`], evaluated by the one engine here. Rows that an older hand-written check
//! already covers name that check's code and are not evaluated again; rows the notes cannot confirm
//! are listed with the reason they are not checked. `docs/cia301-value-rules.md` is generated from
//! the same rows ([`markdown`]), so the published table cannot drift from what runs.
//!
//! Values are read as the device uses them ([`reading`]): in a DCF the configured `ParameterValue`,
//! otherwise `DefaultValue`. A `$NODEID` formula is evaluated for the DCF's node-ID; in an EDS a
//! test on it counts only when node-IDs 1 and 127 give the same answer, so no rule guesses which
//! node the file will be used for.

use canopener_eds::{Object, Origin, Severity};

use super::reading::{Int, entry_name, live_object, object_finding, reading};
use crate::check_info::CheckInfo;
use crate::context::Context;
use crate::finding::Finding;

mod checks;
pub(crate) mod table;

pub(crate) use checks::CHECKS;
use table::{Check, Cond, Entry, Rule, Subs, Test};

/// Runs every rule of the table that has a code of this group.
pub(crate) fn run(cx: &Context<'_>, out: &mut Vec<Finding>) {
    for rule in table::RULES {
        let Check::New(info) = rule.check else {
            continue;
        };
        for (&index, object) in cx.eds.objects.range(rule.first..=rule.last) {
            if object.origin == Origin::Orphan {
                continue;
            }
            for sub in subjects(object, rule.subs) {
                apply(cx, out, rule, info, index, sub);
            }
        }
    }
}

/// The rows of the table as Markdown: `docs/cia301-value-rules.md`. `severity_of` gives the
/// severity of an existing check by code (the registry knows them; this module does not).
pub(crate) fn markdown(severity_of: impl Fn(&str) -> Option<Severity>) -> String {
    let rules = table::RULES;
    let added = rules.iter().filter(|r| matches!(r.check, Check::New(_))).count();
    let mapped = rules
        .iter()
        .filter(|r| matches!(r.check, Check::Existing(_)))
        .count();
    let open = rules
        .iter()
        .filter(|r| matches!(r.check, Check::NotChecked(_)))
        .count();
    let codes: std::collections::BTreeSet<&str> = rules
        .iter()
        .filter_map(|r| match r.check {
            Check::New(info) => Some(info.code),
            _ => None,
        })
        .collect();
    let mut out = String::from(
        "# CiA 301 value rules of the communication objects\n\n\
         Generated from the rule table `crates/canopener-check/src/checks/value_rules/table.rs`, which is\n\
         also what `canopener eds check` evaluates; do not edit by hand:\n\
         `CANOPENER_UPDATE_DOCS=1 cargo test -p canopener-check --test docs` rewrites it.\n\n\
         Each row is one value range, reserved value or dependency on another object of the communication\n\
         area 1000h-1FFFh, taken from the project's reference notes (`cia301-401-305-essentials.md` §n is\n\
         written `C§n`, `eds-format-and-checks.md` §n `E§n`). *Evaluated as* is the row's data as the\n\
         checker runs it: *when* the conditions under which the rule applies, *→* what must then hold\n\
         (blank for rows covered by older checks or not checked, unless a device test uses the row).\n\
         Values are the ones the device uses: `ParameterValue` in a\n\
         DCF, otherwise `DefaultValue`. Severity follows the source: a value the device must refuse or\n\
         that makes the object unusable is an error, a value that has no effect or contradicts a\n\
         recommendation is a warning (see the severity policy in [checks.md](checks.md)).\n\n",
    );
    out.push_str(&format!(
        "{} rules: {added} added as new checks ({} codes: {}), {mapped} already covered by existing checks, \
         {open} not checked (reason given).\n\n",
        rules.len(),
        codes.len(),
        codes.iter().copied().collect::<Vec<_>>().join(", ")
    ));
    out.push_str("| object | entry | kind | rule | evaluated as | severity | check | source |\n");
    out.push_str("|---|---|---|---|---|---|---|---|\n");
    for rule in rules {
        let object = if rule.first == rule.last {
            format!("{:04X}h", rule.first)
        } else {
            format!("{:04X}h-{:04X}h", rule.first, rule.last)
        };
        let entry = match rule.subs {
            Subs::Object => "value".to_owned(),
            Subs::One(sub) => format!("sub {sub}"),
            Subs::Range(a, b) => format!("sub {a}..{b}"),
        };
        let logic = logic(rule);
        let (severity, check) = match rule.check {
            Check::New(info) => (rule.severity.to_string(), format!("{} (new)", link(info.code))),
            Check::Existing(codes) => (
                severities(codes, &severity_of),
                codes.iter().map(|c| link(c)).collect::<Vec<_>>().join(", "),
            ),
            Check::NotChecked(reason) => ("–".to_owned(), format!("not checked: {reason}")),
        };
        out.push_str(&format!(
            "| {object} | {entry} | {} | {} | {logic} | {severity} | {check} | {} |\n",
            rule.kind.name(),
            rule.text.replace('|', "\\|"),
            rule.source.replace('|', "\\|")
        ));
    }
    out
}

/// `error` when every code is an error, else `error (C711, C725: warning)`.
fn severities(codes: &[&str], severity_of: &impl Fn(&str) -> Option<Severity>) -> String {
    let first = codes.first().and_then(|c| severity_of(c));
    let Some(main) = first else {
        return "–".to_owned();
    };
    let others: Vec<String> = codes
        .iter()
        .filter_map(|c| severity_of(c).filter(|s| *s != main).map(|s| format!("{c}: {s}")))
        .collect();
    if others.is_empty() {
        main.to_string()
    } else {
        format!("{main} ({})", others.join(", "))
    }
}

/// `[C870](checks.md#c870)`.
fn link(code: &str) -> String {
    format!("[{code}](checks.md#{})", code.to_ascii_lowercase())
}

/// The rule's conditions in words, for the table (empty for rows without conditions in data).
fn logic(rule: &Rule) -> String {
    if rule.then.is_empty() {
        return String::new();
    }
    let show = |conds: &[Cond]| {
        conds
            .iter()
            .map(|c| format!("{} {}", c.entry.describe(), c.test.describe()))
            .collect::<Vec<_>>()
            .join(" and ")
    };
    if rule.when.is_empty() {
        show(rule.then)
    } else {
        format!("when {} → {}", show(rule.when), show(rule.then))
    }
}

/// The sub-indices of `object` a rule is about: `None` for the object's own value.
fn subjects(object: &Object, subs: Subs) -> Vec<Option<u8>> {
    let live = |s: &u8| object.subs.get(s).is_some_and(|o| o.origin != Origin::Orphan);
    match subs {
        Subs::Object => vec![None],
        Subs::One(sub) => live(&sub).then_some(Some(sub)).into_iter().collect(),
        Subs::Range(first, last) => object
            .subs
            .range(first..=last)
            .filter(|(s, o)| o.origin != Origin::Orphan && **s != 0xFF)
            .map(|(&s, _)| Some(s))
            .collect(),
    }
}

/// The answer of a test: `Unknown` when the entry has no integer value or a `$NODEID` formula
/// answers differently for different node-IDs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Answer {
    Yes,
    No,
    Unknown,
}

/// What an entry holds, resolved against the rule's subject.
struct Resolved<'a> {
    index: u16,
    sub: Option<u8>,
    described: bool,
    value: Option<super::reading::Reading<'a>>,
}

fn resolve<'a>(cx: &Context<'a>, entry: Entry, index: u16, sub: Option<u8>) -> Resolved<'a> {
    let (index, sub) = entry.locate(index, sub);
    let object = live_object(cx, index);
    let attributes = match (object, sub) {
        (Some(object), None) => Some(&object.attributes),
        (Some(object), Some(s)) => object
            .subs
            .get(&s)
            .filter(|o| o.origin != Origin::Orphan)
            .map(|o| &o.attributes),
        (None, _) => None,
    };
    Resolved {
        index,
        sub,
        described: attributes.is_some(),
        value: attributes.and_then(|a| reading(cx, a)),
    }
}

/// The node-IDs a `$NODEID` formula is evaluated for.
fn nodes(cx: &Context<'_>) -> Vec<u8> {
    cx.eds.node_id().map_or_else(|| vec![1, 127], |id| vec![id])
}

fn evaluate(cx: &Context<'_>, cond: &Cond, index: u16, sub: Option<u8>) -> Answer {
    let this = resolve(cx, cond.entry, index, sub);
    if cond.test == Test::Described {
        return if this.described { Answer::Yes } else { Answer::No };
    }
    let Some(value) = this.value else {
        return Answer::Unknown;
    };
    let other = match cond.test {
        Test::NotAbove(entry) => match resolve(cx, entry, index, sub).value {
            Some(other) => Some(other.value),
            None => return Answer::Unknown,
        },
        _ => None,
    };
    let answers: Vec<bool> = match value.value {
        Int::Literal(v) => vec![cond.test.holds(v, other.map(|o| o.at(1)))],
        Int::NodeRelative(_) => nodes(cx)
            .into_iter()
            .map(|n| cond.test.holds(value.value.at(n), other.map(|o| o.at(n))))
            .collect(),
    };
    if answers.iter().all(|&a| a) {
        Answer::Yes
    } else if answers.iter().all(|&a| !a) {
        Answer::No
    } else {
        Answer::Unknown
    }
}

/// Evaluates one rule for one entry: when every `when` condition holds and a `then` condition does
/// not, reports it at the subject entry. Unknown answers never report (no guessing).
fn apply(
    cx: &Context<'_>,
    out: &mut Vec<Finding>,
    rule: &Rule,
    info: &CheckInfo,
    index: u16,
    sub: Option<u8>,
) {
    let subject = resolve(cx, Entry::This, index, sub);
    if !subject.described {
        return;
    }
    if rule
        .when
        .iter()
        .any(|c| evaluate(cx, c, index, sub) != Answer::Yes)
    {
        return;
    }
    let Some(failed) = rule
        .then
        .iter()
        .find(|c| evaluate(cx, c, index, sub) == Answer::No)
    else {
        return;
    };
    let mut facts: Vec<String> = Vec::new();
    for cond in rule.when.iter().chain(std::iter::once(failed)) {
        let fact = state(cx, cond.entry, index, sub);
        if !facts.contains(&fact) {
            facts.push(fact);
        }
    }
    let key = subject.value.map(|r| r.key);
    let finding = object_finding(
        cx,
        info,
        index,
        sub,
        key,
        format!("{}: {}", facts.join(", "), rule.text),
    )
    .with_severity(rule.severity)
    .with_help(rule.help);
    out.push(finding);
}

/// `1019h = 1` or `1006h is not described`.
fn state(cx: &Context<'_>, entry: Entry, index: u16, sub: Option<u8>) -> String {
    let r = resolve(cx, entry, index, sub);
    let name = entry_name(r.index, r.sub);
    match (r.described, r.value) {
        (false, _) => format!("{name} is not described"),
        (true, Some(value)) => format!("{name} = {}", value.shown()),
        (true, None) => format!("{name} has no value"),
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::run::findings_with_code as findings;

    #[test]
    fn every_new_code_has_rules_of_its_own_severity_and_every_rule_cites_a_source() {
        let mut used = BTreeSet::new();
        for rule in table::RULES {
            assert!(!rule.source.is_empty() && !rule.text.is_empty(), "{rule:?}");
            assert!(rule.first <= rule.last && (0x1000..=0x1FFF).contains(&rule.first));
            if let Check::New(info) = rule.check {
                assert_eq!(info.severity, rule.severity, "{}: {}", info.code, rule.text);
                assert!(
                    !rule.then.is_empty(),
                    "{}: a new rule must say what must hold",
                    info.code
                );
                used.insert(info.code);
            }
        }
        let described: BTreeSet<&str> = CHECKS.iter().map(|c| c.code).collect();
        assert_eq!(
            used, described,
            "every code of the group comes from at least one row"
        );
        for code in &described {
            let n: u16 = code[1..].parse().unwrap_or(0);
            assert!((870..=899).contains(&n), "{code} outside C870-C899");
        }
    }

    #[test]
    fn existing_codes_named_by_the_table_exist_with_the_rows_severity() {
        for rule in table::RULES {
            if let Check::Existing(codes) = rule.check {
                let severities: Vec<Severity> = codes
                    .iter()
                    .map(|code| {
                        crate::registry::lookup(code)
                            .unwrap_or_else(|| panic!("{code} named by the table is not a check"))
                            .severity
                    })
                    .collect();
                assert!(severities.contains(&rule.severity), "{codes:?}: {}", rule.text);
            }
        }
    }

    fn sync_file(overflow: &str) -> String {
        format!(
            "[1005]\nParameterName=COB-ID SYNC\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue=0x80\n\n\
             [1019]\nParameterName=Synchronous counter overflow value\nObjectType=0x7\nDataType=0x0005\n\
             AccessType=rw\nDefaultValue={overflow}\n"
        )
    }

    /// Every UNSIGNED8 value, not a sample: the reserved sets are exactly the ones the notes give.
    #[test]
    fn reserved_unsigned8_values_are_exactly_the_documented_ones() {
        for value in 0..=255u16 {
            let counter = !findings(&sync_file(&value.to_string()), "C870").is_empty();
            assert_eq!(counter, value == 1 || value >= 241, "1019h = {value}");
            let mapping = format!(
                "[1A00]\nParameterName=m\nObjectType=0x9\nSubNumber=1\n[1A00sub0]\nParameterName=n\n\
                 ObjectType=0x7\nDataType=0x0005\nAccessType=rw\nDefaultValue={value}\n"
            );
            let count = !findings(&mapping, "C878").is_empty();
            assert_eq!(count, (0x41..=0xFD).contains(&value), "1A00sub0 = {value}");
        }
    }

    #[test]
    fn reserved_counter_overflow_values_are_reported_and_valid_ones_are_not() {
        for bad in ["1", "241", "255"] {
            assert_eq!(findings(&sync_file(bad), "C870").len(), 1, "{bad}");
        }
        for good in ["0", "2", "240"] {
            assert!(findings(&sync_file(good), "C870").is_empty(), "{good}");
        }
        let message = &findings(&sync_file("1"), "C870")[0].diagnostic.message;
        assert!(message.starts_with("1019h = 1: "), "{message}");
    }

    #[test]
    fn node_relative_values_are_only_judged_when_every_node_agrees() {
        // A $NODEID formula whose bit 30 is set for every node-ID (the offset carries it).
        let emcy = |value: &str| {
            format!(
                "[1014]\nParameterName=COB-ID EMCY\nObjectType=0x7\nDataType=0x0007\nAccessType=rw\nDefaultValue={value}\n"
            )
        };
        assert_eq!(findings(&emcy("$NODEID+0x40000080"), "C876").len(), 1);
        assert!(findings(&emcy("$NODEID+0x80"), "C876").is_empty());
        // Bit 30 reached only for some node-IDs: unknown, not reported in an EDS.
        assert!(findings(&emcy("$NODEID+0x3FFFFFC0"), "C876").is_empty());
    }
}
