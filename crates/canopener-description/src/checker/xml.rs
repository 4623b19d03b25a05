//! Checking CiA 311 XDD/XDC/XPD files: the reader's `X0xx` diagnostics and `X1xx` checks, and every
//! model-level check of the EDS checker run on the model read from the XML, each finding placed at
//! the XML element or attribute that produced the value it is about.
//!
//! The model-level checks and rule packs run on the reader's model directly
//! ([`Context::for_model`]): its sections are those its canonical CiA 306 text would have, and every
//! place a check asks for, a section and a key, is looked up in the reader's
//! [`canopener_xdd::Locations`], so no CiA 306 text is written and read again. The object diagnostics
//! loading gives EDS text come from the model the same way ([`canopener_eds::model_diagnostics`]).
//! Checks whose subject CiA 311 has no place for are not reported ([`applies_to_xml`]).

use std::collections::{BTreeMap, HashSet};

use canopener_check::{Context, Finding, Selection, registry};
use canopener_report::FileReport;
use canopener_rules::RulePack;
use canopener_xdd::{XddKind, XddLoaded};

/// Reader codes `eds check` leaves to a check that says the same with the severity of its rule:
/// the code and the checks that report it instead. (`eds show` still reports them.)
pub const SUPERSEDED: &[(&str, &[&str])] = &[("X035", &["C802", "C803"])];

/// How the help of a model-level check starts on XML.
const EDS_TERMS: &str =
    "in the EDS form of this file (the XML attribute or element is at the position shown): ";

/// The portability note every XML file gets (what other tools do with it).
const XML_READERS: &str = "X102";

/// Checks an XML description: `packs` and `selection` as for EDS text. The reader's codes in
/// [`SUPERSEDED`] are left out.
pub(super) fn check(
    packs: &[RulePack],
    selection: &Selection,
    path: &str,
    file_name: Option<&str>,
    bytes: &[u8],
) -> FileReport {
    let loaded = match canopener_xdd::read(bytes) {
        Ok(loaded) => loaded,
        Err(error) => {
            return FileReport {
                path: path.to_owned(),
                findings: Vec::new(),
                source: BTreeMap::new(),
                // The reader's message names line:column where the XML breaks, or what the file
                // is instead (POWERLINK, another dialect).
                problem: Some(error.to_string()),
            };
        }
    };
    let mut findings = model_findings(&loaded, packs, selection, file_name);
    // Looked up once: a file can have hundreds of reader diagnostics.
    let dropped: HashSet<&str> = if *selection == Selection::default() {
        HashSet::new()
    } else {
        registry::builtin()
            .into_iter()
            .filter(|info| !selection.selects_builtin(info))
            .map(|info| info.code)
            .collect()
    };
    findings.extend(
        loaded
            .diagnostics
            .iter()
            .filter(|d| {
                let code = d.code.as_str();
                !SUPERSEDED.iter().any(|(superseded, _)| *superseded == code) && !dropped.contains(code)
            })
            .map(|d| Finding::from_diagnostic(d, false)),
    );
    if !dropped.contains(XML_READERS)
        && let Some(info) = registry::lookup(XML_READERS)
    {
        let kind = match loaded.kind {
            XddKind::Xdd => "an XDD",
            XddKind::Xdc => "an XDC",
        };
        findings.push(Finding::new(
            info,
            loaded.locations.file,
            format!(
                "{kind}: python canopen and Lely cannot read CiA 311 files; CANopenEditor can \
                 (`canopener eds explain {XML_READERS}` for details)"
            ),
        ));
    }
    canopener_check::sort_by_position(&mut findings);
    // The reader's positions count lines by canopener_eds::lines; the source lines shown are taken
    // from the same text by the same rule.
    let text = canopener_xdd::decode(bytes).unwrap_or_default();
    FileReport::from_text(path, findings, &text)
}

/// Whether a built-in check is about something CiA 311 XML has (so it runs on XML files too).
///
/// Not reported on XML (`docs/xdd-check.md` gives the reason for each): group A syntax (`C1xx`),
/// the portability lint (`T`, which predicts how tools misread CiA 306 text; `X102` says what they
/// do with XML), the loader's `P` series except its value and object checks (what it says about
/// notation and layout is about CiA 306 text, which an XML file has none of; the XML reader's `X0xx`
/// say that), and the checks listed here, whose subject the XML has no place for or which the
/// reader fills in itself.
pub fn applies_to_xml(code: &str) -> bool {
    /// Loader codes about the model rather than the text: values readable for their type, object codes,
    /// data types, PDO pairs (P073, the keys an object type requires, would repeat X014, X015,
    /// X020 and X022).
    const MODEL_LOADER_CODES: &[&str] = &[
        "P050", "P054", "P055", "P057", "P059", "P060", "P061", "P070", "P071", "P080",
    ];
    const NOT_IN_XML: &[&str] = &[
        // [FileInfo] keys CiA 311 has no attribute for or the reader writes itself (FileRevision,
        // EDSVersion=4.0, CiA 306 date notation: X030 checks the XML's), LastEDS.
        "C201", "C202", "C203", "C204", "C205", "C206", "C209", "C210",
        // [DeviceInfo] keys with no CiA 311 counterpart, notation and Booleans the reader writes
        // (X031, X023 check the XML's).
        "C301", "C302", "C303", "C305",
        // [DummyUsage] spelling: the schema enumerates the entries (X036); and dummyUsage is
        // optional in CiA 311 where CiA 306 asks for the section.
        "C351", "C352", "C354", // Object lists: the reader builds them from the indices.
        "C401", "C402", "C403",
        // A CiA 306 line limit, and notation the reader writes (accessType and PDOmapping are
        // enumerations in CiA 311: X023).
        "C501", "C503", "C504",
        // CompactSubObj and [xxxxObjectLinks] forms CiA 311 does not have.
        "C512", "C513", "C514",
    ];
    match code.chars().next() {
        Some('P') => MODEL_LOADER_CODES.contains(&code),
        Some('T') => false,
        Some('C') => !code.starts_with("C1") && !NOT_IN_XML.contains(&code),
        _ => true,
    }
}

/// The built-in checks and rule packs on the model, placed in the XML.
fn model_findings(
    loaded: &XddLoaded,
    packs: &[RulePack],
    selection: &Selection,
    file_name: Option<&str>,
) -> Vec<Finding> {
    let place = |section: Option<&str>, key: Option<&str>| loaded.locations.find(section, key);
    let diagnostics =
        canopener_eds::model_diagnostics(&loaded.eds, &|section, key| place(Some(section), key));
    let cx = Context::for_model(&loaded.eds, &diagnostics, file_name, &place);
    let mut findings: Vec<Finding> = canopener_check::check_context(&cx, selection)
        .findings
        .into_iter()
        .filter(|f| applies_to_xml(&f.diagnostic.code))
        .collect();
    for pack in packs {
        findings.extend(pack.check(&cx, selection));
    }
    for finding in &mut findings {
        // A finding about the file as a whole that names a section points at that section's element
        // when the XML has one (`no [DeviceComissioning]`: the file).
        if finding.diagnostic.span == cx.file_span()
            && let Some(section) = finding.diagnostic.section.as_deref()
        {
            finding.diagnostic.span = place(Some(section), finding.diagnostic.key.as_deref());
        }
        // The checks' advice names CiA 306 sections and keys (`set DefaultValue=2 in [1400sub0]`);
        // say so, since the position is the XML's.
        if let Some(help) = finding.diagnostic.help.take() {
            finding.diagnostic.help = Some(format!("{EDS_TERMS}{help}"));
        }
    }
    findings
}

#[cfg(test)]
mod tests {
    use canopener_check::Group;
    use canopener_eds::Severity;
    use canopener_xdd::XddCode;

    use super::*;

    /// An EDS whose 2000h default lies outside its limits (C602), written as XDD.
    const EDS: &str = "[FileInfo]\nFileName=t.eds\n[DeviceInfo]\nVendorName=v\n[1000]\n\
        ParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0\n\
        PDOMapping=0\n[2000]\nParameterName=Filter time\nObjectType=0x7\nDataType=0x0006\n\
        AccessType=rw\nDefaultValue=2000\nLowLimit=1\nHighLimit=1000\nPDOMapping=0\n";

    use super::super::tests::PACK;

    fn xml() -> String {
        let eds = canopener_eds::load(EDS.as_bytes()).eds;
        canopener_xdd::write(&eds, &canopener_xdd::WriteOptions::CANOPEN_EDITOR)
    }

    /// The 1-based line and column of the first occurrence of `needle` in `text`.
    fn position(text: &str, needle: &str) -> (u32, u32) {
        let (index, line) = text
            .lines()
            .enumerate()
            .find(|(_, l)| l.contains(needle))
            .unwrap_or_else(|| panic!("{needle} not in the XML"));
        let column = line.find(needle).map_or(0, |c| c + 1);
        (
            u32::try_from(index + 1).unwrap_or(u32::MAX),
            u32::try_from(column).unwrap_or(u32::MAX),
        )
    }

    #[test]
    fn the_x_entries_of_the_registry_are_the_readers_codes() {
        for code in XddCode::ALL {
            let info = registry::lookup(code.as_str())
                .unwrap_or_else(|| panic!("{} has no registry entry", code.as_str()));
            assert_eq!(
                (info.slug, info.severity, info.group),
                (code.slug(), code.severity(), Group::Xml),
                "{}",
                code.as_str()
            );
        }
        let x_entries = registry::builtin()
            .iter()
            .filter(|c| c.group == Group::Xml)
            .count();
        assert_eq!(x_entries, XddCode::ALL.len() + 1, "X0xx, X101 and X102");
        assert!(registry::lookup(XML_READERS).is_some_and(|c| c.severity == Severity::Info));
    }

    #[test]
    fn model_findings_point_at_the_xml_that_gave_the_value() {
        let xml = xml();
        let report = check(&[], &Selection::default(), "t.xdd", Some("t.xdd"), xml.as_bytes());
        assert_eq!(report.problem, None);
        let c602 = report
            .findings
            .iter()
            .find(|f| f.diagnostic.code == "C602")
            .expect("the default 2000 is above HighLimit 1000");
        let parameter = position(&xml, r#"uniqueID="UID_OBJ_2000""#).0;
        let default = xml
            .lines()
            .enumerate()
            .skip(usize::try_from(parameter).unwrap_or(0))
            .find(|(_, l)| l.contains("defaultValue"))
            .map(|(i, l)| (i + 1, l.find('<').map_or(0, |c| c + 1)));
        let span = c602.diagnostic.span;
        assert_eq!(
            Some((
                usize::try_from(span.line).unwrap_or(0),
                usize::try_from(span.column).unwrap_or(0)
            )),
            default,
            "{report:?}"
        );
        assert_eq!(
            report
                .source
                .get(&span.line)
                .map(|l| l.trim_start().starts_with("<q1:defaultValue")),
            Some(true)
        );
        assert!(report.findings.iter().all(|f| applies_to_xml(&f.diagnostic.code)));
        assert!(
            c602.diagnostic
                .help
                .as_deref()
                .is_none_or(|h| h.starts_with(EDS_TERMS)),
            "help in CiA 306 terms says so: {:?}",
            c602.diagnostic.help
        );
        assert!(report.findings.iter().any(|f| f.diagnostic.code == XML_READERS));
    }

    #[test]
    fn rule_packs_see_the_model_and_report_at_the_xml_element() {
        let xml = xml();
        let pack = canopener_rules::parse_pack(PACK, "test.toml").expect("the test pack parses");
        let report = check(&[pack], &Selection::default(), "t.xdd", None, xml.as_bytes());
        let rule: Vec<(u32, u32)> = report
            .findings
            .iter()
            .filter(|f| f.diagnostic.code == "test/no-blank-names")
            .map(|f| (f.diagnostic.span.line, f.diagnostic.span.column))
            .collect();
        let at = |index: &str| position(&xml, &format!(r#"<CANopenObject index="{index}""#));
        assert_eq!(rule, [at("1000"), at("2000")]);
    }

    #[test]
    fn the_selection_applies_to_x_codes_and_unreadable_xml_is_a_problem() {
        let skip = Selection {
            skip: vec![XML_READERS.to_owned(), "C602".to_owned()],
            ..Selection::default()
        };
        let report = check(&[], &skip, "t.xdd", None, xml().as_bytes());
        assert!(
            report
                .findings
                .iter()
                .all(|f| f.diagnostic.code != XML_READERS && f.diagnostic.code != "C602")
        );
        let broken = check(
            &[],
            &Selection::default(),
            "b.xdd",
            None,
            b"<ISO15745ProfileContainer><x",
        );
        assert!(broken.findings.is_empty());
        assert!(
            broken
                .problem
                .as_deref()
                .is_some_and(|p| p.starts_with("1:") && p.contains("malformed XML")),
            "names where the XML breaks: {:?}",
            broken.problem
        );
    }

    #[test]
    fn series_that_concern_eds_text_do_not_apply() {
        for code in ["P020", "P051", "C101", "C199", "T004", "C201", "C301", "C401"] {
            assert!(!applies_to_xml(code), "{code}");
        }
        for code in [
            "P061",
            "C304",
            "C404",
            "C537",
            "C602",
            "C701",
            "C801",
            "X006",
            "X101",
            "team/rule",
        ] {
            assert!(applies_to_xml(code), "{code}");
        }
    }
}
