//! ARCHITECTURE.md's crate graph is the one `cargo metadata` prints: a newcomer reads the documented
//! dependencies, so they cannot drift from the manifests.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

const START: &str = "<!-- crate-graph: checked against `cargo metadata` by xtask/tests/architecture.rs -->";
const END: &str = "<!-- /crate-graph -->";

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask sits in the workspace root")
        .to_path_buf()
}

/// Each workspace crate's normal (not dev, not build) dependencies on other workspace crates.
fn metadata_graph() -> BTreeMap<String, BTreeSet<String>> {
    let output = Command::new(env!("CARGO"))
        .current_dir(workspace_root())
        .args(["metadata", "--format-version", "1", "--no-deps", "--offline"])
        .output()
        .expect("cargo metadata runs");
    assert!(
        output.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let metadata: serde_json::Value =
        serde_json::from_slice(&output.stdout).expect("cargo metadata prints JSON");
    let packages = metadata["packages"].as_array().expect("packages");
    let names: BTreeSet<String> = packages
        .iter()
        .filter_map(|p| p["name"].as_str().map(str::to_owned))
        .collect();
    packages
        .iter()
        .filter(|p| p["name"] != "xtask")
        .map(|p| {
            let deps = p["dependencies"]
                .as_array()
                .expect("dependencies")
                .iter()
                .filter(|d| d["kind"].is_null())
                .filter_map(|d| d["name"].as_str())
                .filter(|name| names.contains(*name))
                .map(str::to_owned)
                .collect();
            (p["name"].as_str().expect("name").to_owned(), deps)
        })
        .collect()
}

/// The table between [`START`] and [`END`]: `| `crate` | `dep`, `dep` |` rows (`none` for no
/// dependency).
fn documented_graph(text: &str) -> BTreeMap<String, BTreeSet<String>> {
    let start = text
        .find(START)
        .unwrap_or_else(|| panic!("ARCHITECTURE.md lacks the marker {START}"));
    let end = text[start..]
        .find(END)
        .unwrap_or_else(|| panic!("ARCHITECTURE.md lacks the marker {END}"));
    let names = |cell: &str| -> BTreeSet<String> {
        cell.split(',')
            .map(|n| n.trim().trim_matches('`').to_owned())
            .filter(|n| !n.is_empty() && n != "none")
            .collect()
    };
    text[start..start + end]
        .lines()
        .filter(|l| l.starts_with("| `"))
        .map(|row| {
            let cells: Vec<&str> = row.trim_matches('|').split('|').collect();
            assert_eq!(cells.len(), 2, "a crate-graph row has two cells: {row}");
            (cells[0].trim().trim_matches('`').to_owned(), names(cells[1]))
        })
        .collect()
}

#[test]
fn the_documented_crate_graph_is_the_one_cargo_metadata_prints() {
    let text = std::fs::read_to_string(workspace_root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let documented = documented_graph(&text);
    let actual = metadata_graph();
    let mut wrong = Vec::new();
    for (krate, deps) in &actual {
        match documented.get(krate) {
            None => wrong.push(format!(
                "{krate} is missing; add the row | `{krate}` | {deps:?} |"
            )),
            Some(doc) if doc != deps => wrong.push(format!(
                "{krate}: documented {doc:?}, Cargo.toml says {deps:?} (missing {:?}, not a dependency {:?})",
                deps.difference(doc).collect::<Vec<_>>(),
                doc.difference(deps).collect::<Vec<_>>()
            )),
            Some(_) => {}
        }
    }
    for krate in documented.keys().filter(|k| !actual.contains_key(*k)) {
        wrong.push(format!("{krate} is documented but is no workspace crate"));
    }
    assert!(
        wrong.is_empty(),
        "ARCHITECTURE.md's crate graph drifted from the manifests; fix the table:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn rows_read_with_their_dependencies() {
    let text =
        format!("{START}\n| Crate | Depends on |\n|---|---|\n| `a` | none |\n| `b` | `a`, `c` |\n{END}");
    let graph = documented_graph(&text);
    assert_eq!(graph["a"], BTreeSet::new());
    assert_eq!(graph["b"], BTreeSet::from(["a".to_owned(), "c".to_owned()]));
}
