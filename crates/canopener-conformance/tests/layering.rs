//! The crate's modules depend one way, as `ARCHITECTURE.md` says: the foundation (report model,
//! context, requirements, what a test is) below the shared procedures, those below the suites, the
//! suites below the registry, and the registry below the runner, the renderers and the tour. A suite
//! never reaches into another suite. Every `crate::…` path in every source file is checked, doc links
//! included, because a doc link a reader follows is a dependency too.

use std::path::{Path, PathBuf};

use canopener_testkit::fixture;

/// The layer of each top-level module, lowest first.
const LAYERS: &[(&str, u8)] = &[
    ("model", 0),
    ("finding", 0),
    ("junk", 0),
    ("recorder", 0),
    ("requirements", 0),
    ("device_model", 0),
    ("stimulus", 0),
    ("performance", 0),
    ("context", 0),
    ("test_def", 0),
    ("procedures", 1),
    ("cia301", 2),
    ("cia305", 2),
    ("cia313", 2),
    ("cia401", 2),
    ("catalogue", 3),
    ("cct", 3),
    ("runner", 4),
    ("render", 4),
    ("tour", 5),
];

fn layer(module: &str) -> Option<u8> {
    LAYERS
        .iter()
        .find(|(name, _)| *name == module)
        .map(|(_, layer)| *layer)
}

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for path in fixture::list(dir).expect("the crate's sources are readable") {
        if fixture::is_dir(&path) {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level module a source file belongs to (`src/cia301/pdo.rs` → `cia301`).
fn module_of(src: &Path, file: &Path) -> String {
    let relative = file.strip_prefix(src).expect("below src");
    let first = relative.components().next().expect("a file name");
    first
        .as_os_str()
        .to_string_lossy()
        .trim_end_matches(".rs")
        .to_owned()
}

#[test]
fn modules_depend_only_downwards_and_suites_never_on_each_other() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    assert!(files.len() > 30, "found only {} source files", files.len());
    let mut violations = Vec::new();
    for file in &files {
        let module = module_of(&src, file);
        if module == "lib" {
            continue;
        }
        let own = layer(&module).unwrap_or_else(|| panic!("{module} has no layer in LAYERS: add it"));
        let text = fixture::read_to_string(file).expect("readable source");
        for (number, line) in text.lines().enumerate() {
            for (at, _) in line.match_indices("crate::") {
                let target: String = line[at + "crate::".len()..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                let Some(theirs) = layer(&target) else { continue };
                let upwards = theirs > own;
                let sideways = theirs == own && own == 2 && target != module;
                if upwards || sideways {
                    violations.push(format!(
                        "{}:{}: {module} (layer {own}) uses crate::{target} (layer {theirs})",
                        file.display(),
                        number + 1
                    ));
                }
            }
        }
    }
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

#[test]
fn every_module_of_the_crate_has_a_layer() {
    let lib = fixture::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    for line in lib.lines() {
        if let Some(name) = line.strip_prefix("pub mod ").and_then(|l| l.strip_suffix(';')) {
            assert!(
                layer(name).is_some(),
                "lib.rs declares {name}, which LAYERS does not place"
            );
        }
    }
}
