//! Issue 13 item 10: every EDS/DCF of the corpus (vendored, plus the extended corpus when present)
//! converted to XDD/XDC and back is the file it was, as `canopener eds convert` does it.
//!
//! - A configuration (a DCF, or an EDS carrying DCF keys: `[DeviceComissioning]`, `LastEDS`,
//!   `ParameterValue`, `Denotation`) becomes an XDC and comes back with `--to dcf`, exactly: every
//!   entry with a ParameterValue (or Denotation) comes back with one and no other entry gains one
//!   (issue 22), no commissioning lost. An empty `ParameterValue=` configures nothing and is not kept.
//! - A template (an EDS, or a `.dcf` that holds no configuration) becomes an XDD and comes back with
//!   `--to eds`, exactly.
//! - An `.eds` carrying DCF keys: with `[DeviceComissioning]` or `LastEDS` it is a DCF in all but name,
//!   and `--to eds` (the template) names every key it drops; with only ParameterValues, EDS -> XDD ->
//!   EDS keeps them.

use canopener_description::convert::{Target, convert};
use canopener_description::{Description, Format};
use std::collections::BTreeSet;

use canopener_eds::diff::diff;
use canopener_eds::{Eds, dcf};
use canopener_testkit::corpus::{self, Kind};

fn load(format: Format, bytes: &[u8], what: &str) -> Description {
    Description::load_as(format, bytes).unwrap_or_else(|e| panic!("{what} does not load: {e}"))
}

/// The entries (`1005`, `1018sub2`) whose `key` holds a value; an empty value configures nothing.
fn entries_with(eds: &Eds, key: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (index, object) in &eds.objects {
        if object.attributes.get(key).is_some_and(|v| !v.trim().is_empty()) {
            out.insert(format!("{index:04X}"));
        }
        for (sub, sub_object) in &object.subs {
            if sub_object
                .attributes
                .get(key)
                .is_some_and(|v| !v.trim().is_empty())
            {
                out.insert(format!("{index:04X}sub{sub:X}"));
            }
        }
    }
    out
}

/// How many entries of a model carry a ParameterValue.
fn before_count(eds: &Eds) -> usize {
    entries_with(eds, "ParameterValue").len()
}

#[test]
fn every_corpus_eds_and_dcf_survives_the_xdd_round_trip_exactly() {
    let files = corpus::files(Kind::Eds);
    assert_eq!(
        files.len(),
        corpus::expected_count(Kind::Eds),
        "every EDS/DCF of the corpus"
    );
    let mut failures = Vec::new();
    let (mut configurations, mut templates, mut eds_dropping, mut eds_keeping) = (0, 0, 0, 0);
    let mut dcf_entries = 0;
    for file in &files {
        let bytes = canopener_testkit::fixture::read(&file.path)
            .unwrap_or_else(|e| panic!("{} is not readable: {e}", file.path.display()));
        let original = load(Format::Eds, &bytes, &file.name);
        let xml = convert(&original, Target::Xdd)
            .expect("XDD is always writable")
            .bytes;
        let xdd = load(Format::Xdd, &xml, &format!("{}'s XDD", file.name));
        let configuration = dcf::is_configuration(&original.eds);
        let target = if configuration {
            configurations += 1;
            Target::Dcf {
                node_id: None,
                bitrate: None,
            }
        } else {
            templates += 1;
            Target::Eds
        };
        let back = match convert(&xdd, target) {
            Ok(back) => load(Format::Eds, &back.bytes, &format!("{} back", file.name)),
            Err(e) => {
                failures.push(format!("{}: converting back fails: {e}", file.name));
                continue;
            }
        };
        for change in diff(&original.eds, &back.eds).significant() {
            failures.push(format!(
                "{} ({}): {change}",
                file.name,
                if configuration { "XDC" } else { "XDD" }
            ));
        }
        // Issue 22: equal values are not enough. A configuration tool downloads every ParameterValue,
        // so an entry comes back with a ParameterValue (and a Denotation) exactly when it had one.
        for key in ["ParameterValue", "Denotation"] {
            let (before, after) = (entries_with(&original.eds, key), entries_with(&back.eds, key));
            if before != after {
                let gained: Vec<&String> = after.difference(&before).take(5).collect();
                let lost: Vec<&String> = before.difference(&after).take(5).collect();
                failures.push(format!(
                    "{}: {key} gained on {} entries {gained:?}, lost on {} {lost:?}",
                    file.name,
                    after.difference(&before).count(),
                    before.difference(&after).count()
                ));
            }
        }
        if configuration {
            dcf_entries += before_count(&original.eds);
        }
        if configuration && file.name.to_ascii_lowercase().ends_with(".eds") {
            let as_eds = convert(&xdd, Target::Eds).expect("an EDS is always writable");
            if xdd.eds.is_dcf() {
                // A DCF in all but name: --to eds makes the template, and names every key it drops.
                eds_dropping += 1;
                let dropped = dcf::configuration_keys(&xdd.eds);
                if as_eds.dropped != dropped || dropped.is_empty() {
                    failures.push(format!(
                        "{}: --to eds dropped DCF keys without naming them all: named {:?}, carried {:?}",
                        file.name, as_eds.dropped, dropped
                    ));
                }
            } else {
                // ParameterValue in a plain EDS: EDS -> XDD -> EDS keeps it.
                eds_keeping += 1;
                let kept = load(Format::Eds, &as_eds.bytes, &format!("{} as EDS", file.name));
                let lost: Vec<String> = diff(&original.eds, &kept.eds)
                    .significant()
                    .map(ToString::to_string)
                    .collect();
                if !as_eds.dropped.is_empty() || !lost.is_empty() {
                    failures.push(format!(
                        "{}: EDS -> XDD -> EDS lost {:?} {lost:?}",
                        file.name, as_eds.dropped
                    ));
                }
            }
        }
    }
    println!(
        "{} files: {configurations} configurations through XDC and --to dcf ({dcf_entries} entries with a \
         ParameterValue, each back with one and none added), {templates} templates through XDD and --to eds; \
         of the .eds files with DCF keys, {eds_dropping} are DCFs in all but name (--to eds names every key it \
         drops) and {eds_keeping} only carry ParameterValues (EDS -> XDD -> EDS keeps them)",
        files.len()
    );
    if files.len() == Kind::Eds.full_count() {
        assert_eq!(configurations, 70, "the corpus's configurations");
    }
    assert!(
        failures.is_empty(),
        "{} differences:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
