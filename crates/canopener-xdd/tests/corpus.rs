//! The corpus: every CANopen XDD/XDC/XPD of `xdd/` loads (the POWERLINK file is refused),
//! every EDS/DCF of `eds/` survives EDS → XDD → EDS, and where a repository ships both an XDD and
//! its EDS the two object dictionaries are compared (the differences are a snapshot: they are
//! findings about those vendors' files).
//!
//! The files are the vendored `corpus/` plus the extended corpus when present (see
//! `canopener_testkit::corpus`). The snapshots of the vendored files are always checked, those of the
//! files only the extended corpus has (`*_extended`) when it is there.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use canopener_eds::diff::{diff, diff_objects};
use canopener_eds::{Eds, ObjectListKind, Origin, Severity};
use canopener_testkit::corpus::{self, CorpusFile, Kind};
use canopener_xdd::{ObjectStyle, WriteOptions, XddCode, XddError, XddKind, XddLoaded, read, write};

fn name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn read_file(path: &Path) -> Vec<u8> {
    canopener_testkit::fixture::read(path)
        .unwrap_or_else(|e| panic!("{} is not readable: {e}", path.display()))
}

fn code_counts(loaded: &XddLoaded) -> String {
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for d in &loaded.diagnostics {
        *counts.entry(d.code.as_str()).or_default() += 1;
    }
    counts
        .iter()
        .map(|(c, n)| format!("{c}×{n}"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn every_canopen_xdd_of_the_corpus_loads_and_powerlink_is_refused() {
    let files = corpus::files(Kind::Xdd);
    assert_eq!(
        files.len(),
        corpus::expected_count(Kind::Xdd),
        "every XDD file of the corpus"
    );
    let (mut vendored, mut extended) = (String::new(), String::new());
    for CorpusFile {
        path,
        vendored: is_vendored,
        ..
    } in &files
    {
        let file = name(path);
        let report = if *is_vendored {
            &mut vendored
        } else {
            &mut extended
        };
        match read(&read_file(path)) {
            Ok(loaded) => {
                let subs: usize = loaded.eds.objects.values().map(|o| o.subs.len()).sum();
                assert!(!loaded.eds.objects.is_empty(), "{file} gave no objects");
                let version = loaded
                    .version
                    .map_or("no namespace".to_owned(), |v| format!("{v:?}"));
                let _ = writeln!(
                    report,
                    "{file}: {:?} {version}, {} objects, {subs} sub-objects; {}",
                    loaded.kind,
                    loaded.eds.objects.len(),
                    code_counts(&loaded)
                );
            }
            Err(e @ XddError::Powerlink { .. }) => {
                assert_eq!(
                    file, "gdamion__grad_project__gen_xdd__ROS_CNPLC.xdd",
                    "only the POWERLINK sample is refused"
                );
                assert!(e.to_string().starts_with(
                    "this is an Ethernet POWERLINK XDD (EPSG DS 311), not a CANopen CiA 311 device description"
                ));
                let _ = writeln!(report, "{file}: refused: {e}");
            }
            Err(e) => panic!("{file} does not load: {e}"),
        }
    }
    insta::assert_snapshot!("xdd_corpus", vendored);
    if corpus::extended_root().is_some() {
        insta::assert_snapshot!("xdd_corpus_extended", extended);
    }
}

/// Whether the EDS gives no Granularity, which CiA 311 requires (the writer does not invent one).
fn lacks_granularity(eds: &Eds) -> bool {
    eds.device_info
        .granularity
        .as_deref()
        .is_none_or(|g| g.trim().is_empty())
}

#[test]
fn every_eds_of_the_corpus_survives_eds_to_xdd_to_eds() {
    let files: Vec<PathBuf> = corpus::files(Kind::Eds)
        .into_iter()
        .map(|file| file.path)
        .collect();
    assert_eq!(
        files.len(),
        corpus::expected_count(Kind::Eds),
        "every EDS file of the corpus"
    );
    let mut failures = Vec::new();
    let (mut objects, mut entries, mut bytes, mut with_object_side_channel) =
        (0usize, 0usize, 0usize, 0usize);
    for path in &files {
        let file = name(path);
        let original = canopener_eds::load(&read_file(path)).eds;
        for style in [ObjectStyle::Reference, ObjectStyle::ReferenceAndInline] {
            let xml = write(
                &original,
                &WriteOptions {
                    style,
                    ..WriteOptions::CANOPEN_EDITOR
                },
            );
            let back = match read(xml.as_bytes()) {
                Ok(back) => back,
                Err(e) => {
                    failures.push(format!("{file} ({style:?}): our own XDD does not read: {e}"));
                    continue;
                }
            };
            let objects_diff = diff_objects(&original, &back.eds);
            for change in objects_diff.significant() {
                failures.push(format!("{file} ({style:?}): {change}"));
            }
            // `[FileInfo]` changes are not significant to `diff`, but the side channel keeps them too.
            for change in diff(&original, &back.eds)
                .changes
                .iter()
                .filter(|c| !objects_diff.changes.contains(c))
            {
                failures.push(format!("{file} ({style:?}) outside the objects: {change}"));
            }
            let sections_kept = back.eds.comments == original.comments
                && back.eds.tools == original.tools
                && back.eds.tool_sections == original.tool_sections
                && back.eds.modules == original.modules
                && back.eds.other_sections == original.other_sections
                && back.eds.commissioning_spelling == original.commissioning_spelling;
            if !sections_kept {
                failures.push(format!(
                    "{file} ({style:?}): comments, tools, modules or other sections differ"
                ));
            }
            for (index, object) in &original.objects {
                let kept = back.eds.objects.get(index).is_some_and(|b| {
                    b.object_links == object.object_links
                        && (b.origin == Origin::Orphan) == (object.origin == Origin::Orphan)
                });
                if !kept {
                    failures.push(format!(
                        "{file} ({style:?}): object links or orphan origin of {index:04X} differ"
                    ));
                }
            }
            for d in back.diagnostics.iter().filter(|d| d.severity == Severity::Error) {
                let expected = d.code == XddCode::MissingPart
                    && d.message.contains("granularity")
                    && lacks_granularity(&original);
                if !expected {
                    failures.push(format!("{file} ({style:?}): reading our own XDD reports {d}"));
                }
            }
            let configured = original.commissioning.is_some() || back.kind == XddKind::Xdc;
            if configured && original.commissioning.is_some() != back.eds.commissioning.is_some() {
                failures.push(format!("{file} ({style:?}): commissioning lost"));
            }
            let indices = |e: &Eds, k| e.object_lists.get(k).map(|l| l.indices()).unwrap_or_default();
            if ObjectListKind::ALL
                .iter()
                .any(|k| indices(&original, k) != indices(&back.eds, k))
            {
                failures.push(format!("{file} ({style:?}): object lists differ"));
            }
            if style == ObjectStyle::Reference {
                objects += original.objects.len();
                entries += original.objects.values().map(|o| 1 + o.subs.len()).sum::<usize>();
                bytes += xml.len();
                if has_object_side_channel(&xml) {
                    with_object_side_channel += 1;
                }
            }
        }
    }
    // How long this takes is for the benchmarks to say (bench/eds_load.py), not for a test.
    println!(
        "{} files, {objects} objects, {entries} objects and sub-objects, {bytes} bytes of XDD; {with_object_side_channel} files needed \
         the side channel on some object",
        files.len(),
    );
    assert!(
        failures.is_empty(),
        "{} round-trip failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Whether any object parameter (not the file parameter) carries side-channel properties.
fn has_object_side_channel(xml: &str) -> bool {
    let file_parameter = xml.find("uniqueID=\"UID_CANOPENER_EDS\"").unwrap_or(xml.len());
    xml[..file_parameter].contains("name=\"EDS:") || xml[..file_parameter].contains("name=\"EDS%:")
}

#[test]
fn every_xdd_of_the_corpus_survives_xdd_to_model_to_xdd() {
    let mut failures = Vec::new();
    for CorpusFile { path, .. } in corpus::files(Kind::Xdd) {
        let Ok(first) = read(&read_file(&path)) else {
            continue;
        };
        let xml = write(&first.eds, &WriteOptions::CANOPEN_EDITOR);
        match read(xml.as_bytes()) {
            Ok(second) => {
                for change in diff(&first.eds, &second.eds).significant() {
                    failures.push(format!("{}: {change}", name(&path)));
                }
                if second.kind != first.kind {
                    failures.push(format!(
                        "{}: {:?} came back as {:?}",
                        name(&path),
                        first.kind,
                        second.kind
                    ));
                }
            }
            Err(e) => failures.push(format!("{}: {e}", name(&path))),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// XDD files whose repository also ships the EDS (matched by repository and file stem).
const PAIRS: &[(&str, &str)] = &[
    (
        "CANopenNode__CANopenNode__example__DS301_profile.xpd",
        "CANopenNode__CANopenNode__example__DS301_profile.eds",
    ),
    (
        "CANopenNode__CANopenDemo__demo__demoDevice.xdd",
        "CANopenNode__CANopenDemo__demo__demoDevice.eds",
    ),
    (
        "CANopenNode__CANopenSocket__examples__basicDevice__basicDevice.xdd",
        "CANopenNode__CANopenSocket__examples__basicDevice__basicDevice.eds",
    ),
    (
        "canopen-python__canopen__test__sample.xdd",
        "canopen-python__canopen__test__sample.eds",
    ),
    (
        "CANopenNode__CanOpenSTM32__Elcom_e-RIO_8xx_CANopen_Profile.xdd",
        "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.eds",
    ),
    (
        "CANopenNode__CanOpenSTM32__Elcom_e-RIO_8xx_CANopen_Profile.nxdd",
        "CANopenNode__CanOpenSTM32__Elcom e-RIO 8xx CANopen Profile.dcf",
    ),
    (
        "samkwok-hkclr__canopen_module__CANopenNode_STM32__canopen_module.xpd",
        "samkwok-hkclr__canopen_module__CANopenNode_STM32__canopen_module.eds",
    ),
    (
        "wdfk-prog__canopennode-rtt__examples__demo_device__project.xdd",
        "wdfk-prog__canopennode-rtt__examples__demo_device__project.eds",
    ),
    (
        "davidsenoner__emec-drv-canopen-tester__doc__Slave_06__emecdrv5.xdd",
        "davidsenoner__emec-drv-canopen-tester__app__resources__Slave_06__emecdrv5.eds",
    ),
    (
        "iota2__CANopen-tools-suite__eds_files__sample_node_0x01.xdd",
        "iota2__CANopen-tools-suite__eds_files__sample_node_0x01.eds",
    ),
    (
        "dborgards__eds-dcf-net__tests__EdsDcfNet.Tests__Fixtures__sample_device.xdd",
        "dborgards__eds-dcf-net__benchmarks__EdsDcfNet.Benchmarks__Fixtures__sample_device.eds",
    ),
    (
        "dborgards__eds-dcf-net__tests__EdsDcfNet.Tests__Fixtures__minimal.xdc",
        "dborgards__eds-dcf-net__benchmarks__EdsDcfNet.Benchmarks__Fixtures__minimal.dcf",
    ),
];

#[test]
fn xdd_and_eds_shipped_together_describe_these_differences() {
    let (mut vendored, mut extended) = (String::new(), String::new());
    for (xdd_file, eds_file) in PAIRS {
        let (Some(xdd_path), Some(eds_path)) = (
            corpus::find(Kind::Xdd, xdd_file),
            corpus::find(Kind::Eds, eds_file),
        ) else {
            assert!(
                corpus::extended_root().is_none(),
                "the extended corpus lacks {xdd_file} or {eds_file}"
            );
            continue;
        };
        let report = if xdd_path.starts_with(corpus::vendored_root())
            && eds_path.starts_with(corpus::vendored_root())
        {
            &mut vendored
        } else {
            &mut extended
        };
        let xdd = read(&read_file(&xdd_path)).unwrap_or_else(|e| panic!("{xdd_file}: {e}"));
        let eds = canopener_eds::load(&read_file(&eds_path)).eds;
        let disabled: Vec<String> = xdd
            .diagnostics
            .iter()
            .filter(|d| d.code == XddCode::DisabledObject)
            .filter_map(|d| {
                d.message
                    .strip_prefix("object ")
                    .and_then(|m| m.get(..4))
                    .map(str::to_owned)
            })
            .collect();
        let d = diff_objects(&eds, &xdd.eds);
        let changes: Vec<String> = d
            .significant()
            .map(|c| {
                let only_in_xdd_and_disabled =
                    c.key.is_none() && disabled.iter().any(|i| c.section == i.trim_start_matches('0'));
                if only_in_xdd_and_disabled {
                    format!("{c}  (CO_disabled in the XDD)")
                } else {
                    c.to_string()
                }
            })
            .collect();
        let _ = writeln!(
            report,
            "== {eds_file} -> {xdd_file}: {} differences",
            changes.len()
        );
        for line in changes {
            let _ = writeln!(report, "{line}");
        }
    }
    insta::assert_snapshot!("vendor_pairs", vendored);
    if corpus::extended_root().is_some() {
        insta::assert_snapshot!("vendor_pairs_extended", extended);
    }
}
