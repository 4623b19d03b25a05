//! The vendored corpus is what its manifests say: every file there byte for byte (size and SHA-256), no
//! file unlisted and no row without its file, and every licence a file is under has its text and every
//! source repository its entry in `corpus/NOTICE`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use canopener_testkit::corpus::{Kind, vendored_root};
use sha2::{Digest, Sha256};

/// One manifest row, by column name.
type Row = BTreeMap<String, String>;

fn manifest(kind: &str) -> Vec<Row> {
    let path = vendored_root().join(kind).join("MANIFEST.tsv");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header line").split('\t').collect();
    for column in [
        "local_file",
        "repo",
        "path",
        "commit",
        "bytes",
        "sha256",
        "license",
        "license_evidence",
    ] {
        assert!(header.contains(&column), "{}: no column {column}", path.display());
    }
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split('\t').collect();
            assert_eq!(cells.len(), header.len(), "{}: {line}", path.display());
            header
                .iter()
                .zip(cells)
                .map(|(column, cell)| ((*column).to_owned(), cell.to_owned()))
                .collect()
        })
        .collect()
}

/// The file names in `dir`, except its manifest.
fn files_in(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| {
            entry
                .expect("a directory entry")
                .file_name()
                .to_string_lossy()
                .into_owned()
        })
        .filter(|name| name != "MANIFEST.tsv")
        .collect()
}

/// The SPDX licence ids of an expression such as `MIT OR Apache-2.0`.
fn licence_ids(expression: &str) -> impl Iterator<Item = &str> {
    expression
        .split(|c: char| c.is_whitespace() || c == '(' || c == ')')
        .filter(|word| !word.is_empty() && !matches!(*word, "AND" | "OR" | "WITH"))
}

#[test]
fn every_vendored_file_is_its_manifest_row_byte_for_byte() {
    for (kind, dir) in [(Kind::Eds, "eds"), (Kind::Xdd, "xdd")] {
        let rows = manifest(dir);
        assert_eq!(rows.len(), kind.vendored_count(), "{dir}/MANIFEST.tsv rows");
        for row in &rows {
            let name = &row["local_file"];
            let path = vendored_root().join(dir).join(name);
            let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert_eq!(bytes.len().to_string(), row["bytes"], "{dir}/{name}: size");
            let digest: String = Sha256::digest(&bytes)
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect();
            assert_eq!(
                digest, row["sha256"],
                "{dir}/{name}: sha256 (the copy must be unmodified)"
            );
            assert!(
                !row["license_evidence"].is_empty(),
                "{dir}/{name}: no licence evidence"
            );
        }
    }
}

#[test]
fn every_file_is_listed_and_every_row_has_its_file() {
    for dir in ["eds", "xdd"] {
        let listed: BTreeSet<String> = manifest(dir)
            .into_iter()
            .map(|row| row["local_file"].clone())
            .collect();
        let present = files_in(&vendored_root().join(dir));
        let unlisted: Vec<_> = present.difference(&listed).collect();
        let missing: Vec<_> = listed.difference(&present).collect();
        assert!(
            unlisted.is_empty(),
            "corpus/{dir}: files without a MANIFEST.tsv row: {unlisted:?}"
        );
        assert!(
            missing.is_empty(),
            "corpus/{dir}: MANIFEST.tsv rows without their file: {missing:?}"
        );
    }
}

#[test]
fn every_licence_has_its_text_and_every_source_its_notice() {
    let rows: Vec<Row> = ["eds", "xdd"].into_iter().flat_map(manifest).collect();
    let used: BTreeSet<&str> = rows.iter().flat_map(|row| licence_ids(&row["license"])).collect();
    let texts = files_in(&vendored_root().join("LICENSES"));
    for id in &used {
        assert!(
            texts.contains(&format!("{id}.txt")),
            "corpus/LICENSES/{id}.txt is missing"
        );
    }
    let unused: Vec<_> = texts
        .iter()
        .filter(|text| !used.iter().any(|id| **text == format!("{id}.txt")))
        .collect();
    assert!(
        unused.is_empty(),
        "licence texts no vendored file is under: {unused:?}"
    );
    let notice = std::fs::read_to_string(vendored_root().join("NOTICE")).expect("corpus/NOTICE");
    for repo in rows.iter().map(|row| &row["repo"]).collect::<BTreeSet<_>>() {
        assert!(
            notice.contains(&format!("{repo} (https://github.com/{repo})")),
            "corpus/NOTICE has no entry for {repo}"
        );
    }
}

#[test]
fn licence_expressions_split_into_their_ids() {
    assert_eq!(
        licence_ids("MIT OR Apache-2.0").collect::<Vec<_>>(),
        ["MIT", "Apache-2.0"]
    );
    assert_eq!(
        licence_ids("(LGPL-3.0-only AND MIT)").collect::<Vec<_>>(),
        ["LGPL-3.0-only", "MIT"]
    );
}
