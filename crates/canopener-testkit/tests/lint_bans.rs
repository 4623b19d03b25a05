//! One set of lint bans. Clippy reads the `clippy.toml` nearest to a crate, and a crate's own file
//! *replaces* the workspace root's, it does not extend it. So a crate file that copies the root's bans
//! can drop one without anyone noticing, and the crate gains a right (a clock read, a file access) that
//! ARCHITECTURE.md ("Where IO and clocks live") says it does not have.
//!
//! These tests make the rule checkable. Every workspace member is found from the root `Cargo.toml`
//! (`crates/*` and the rest), so a crate added later is covered the day it lands:
//! - a member without a `clippy.toml` of its own inherits the root's, whole;
//! - a member with one keeps every root ban except those [`LIFTS`] names for it, each with the reason,
//!   and may add bans of its own; its other settings equal the root's;
//! - every ban everywhere says why, and every lift names a member and, unless it lifts everything, root
//!   bans that exist.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use toml::{Table, Value};

/// Which of the root's bans a member's `clippy.toml` leaves out.
#[derive(Debug)]
enum Lifted {
    /// An IO edge: it may read clocks, wait, run threads and touch files and sockets, so every sans-IO ban
    /// is lifted, including bans the root gains later.
    Everything,
    /// Exactly these bans (by path, in groups), no more and no fewer.
    These(&'static [&'static [&'static str]]),
}

/// A member whose `clippy.toml` lifts bans of the root's, and why it may.
#[derive(Debug)]
struct Lift {
    /// The member's directory, relative to the workspace root.
    member: &'static str,
    lifted: Lifted,
    reason: &'static str,
}

/// The root's bans on touching files, lifted as one group by the crates that do it for the others.
const FILE_ACCESS: &[&str] = &[
    "std::fs::read",
    "std::fs::read_to_string",
    "std::fs::write",
    "std::fs::read_dir",
    "std::fs::create_dir_all",
    "std::fs::remove_file",
    "std::fs::rename",
    "std::fs::File::open",
    "std::fs::File::create",
    "std::fs::OpenOptions::open",
    "std::fs::metadata",
    "std::fs::canonicalize",
    "std::path::Path::exists",
    "std::path::Path::try_exists",
    "std::path::Path::is_file",
    "std::path::Path::is_dir",
    "std::path::Path::metadata",
    "std::path::Path::read_dir",
    "std::path::Path::canonicalize",
];

/// The only bans any crate may lift. A member with a `clippy.toml` and no row here keeps them all.
const LIFTS: &[Lift] = &[
    Lift {
        member: "crates/canopener-transport",
        lifted: Lifted::Everything,
        reason: "an IO edge: it opens the CAN, socketcand and hub sockets, reads the wall clock for \
                 timestamps and runs reader threads",
    },
    Lift {
        member: "crates/canopener-hub",
        lifted: Lifted::Everything,
        reason: "an IO edge: it listens on TCP, runs a thread per client and stamps frames with the clock",
    },
    Lift {
        member: "crates/canopener-runtime",
        lifted: Lifted::Everything,
        reason: "the shell of every front end: it reads and writes files, reads clocks, waits and runs \
                 the sans-IO cores on real links",
    },
    Lift {
        member: "crates/canopener-web",
        lifted: Lifted::Everything,
        reason: "an IO edge: an HTTP server on tokio with threads for the monitor, the tour and the runs",
    },
    Lift {
        member: "crates/canopener-files",
        lifted: Lifted::These(&[FILE_ACCESS]),
        reason: "the one crate that reads and writes files for the others (write_atomic, backups, \
                 same_file); clocks, sleeping, threads and sockets stay banned",
    },
    Lift {
        member: "crates/canopener-link",
        lifted: Lifted::These(&[&[
            "std::time::Instant::now",
            "std::time::SystemTime::now",
            "std::thread::sleep",
            "std::thread::spawn",
        ]]),
        reason: "where the master side meets a real bus: BusLink waits between receives, a DCF dump states \
                 the wall-clock time, the stimulus program has a timeout and a stderr reader thread; files \
                 and sockets stay banned",
    },
    Lift {
        member: "crates/canopener-sim",
        lifted: Lifted::These(&[&[
            "std::fs::read",
            "std::fs::read_to_string",
            "std::fs::create_dir_all",
            "std::thread::sleep",
            "std::thread::spawn",
        ]]),
        reason: "simulated devices on a real bus in real time (SimHost sleeps, a stdin reader thread) read \
                 their descriptions and state files; writes go through canopener_files",
    },
    Lift {
        member: "xtask",
        lifted: Lifted::Everything,
        reason: "automates the project (setup, tests, benchmarks, fuzzing): runs processes and touches files",
    },
    Lift {
        member: "crates/canopener-testkit",
        lifted: Lifted::These(&[FILE_ACCESS, &["std::thread::spawn"]]),
        reason: "tests of sans-IO crates read fixtures and the corpus through canopener_testkit::fixture \
                 and ::corpus, and the HTML tests drive headless Chromium with reader threads; clocks, \
                 sleeping and sockets stay banned",
    },
];

/// The keys of `clippy.toml` that hold bans; every other key is a setting.
const BAN_KEYS: &[&str] = &["disallowed-methods", "disallowed-types", "disallowed-macros"];

/// The names clippy looks for in a directory.
const CONFIG_NAMES: &[&str] = &["clippy.toml", ".clippy.toml"];

fn workspace_root() -> PathBuf {
    canopener_testkit::corpus::workspace_root()
}

fn read_table(path: &Path) -> Table {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.parse().unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The clippy configuration file in `dir`, if it has one.
fn config_in(dir: &Path) -> Option<PathBuf> {
    let found: Vec<PathBuf> = CONFIG_NAMES
        .iter()
        .map(|name| dir.join(name))
        .filter(|path| path.is_file())
        .collect();
    assert!(
        found.len() <= 1,
        "clippy refuses two configuration files: {found:?}"
    );
    found.into_iter().next()
}

/// The workspace members' directories relative to the root, from `[workspace] members` (a trailing `/*`
/// is every directory below that holds a `Cargo.toml`).
fn members(root: &Path) -> Vec<String> {
    let manifest = read_table(&root.join("Cargo.toml"));
    let patterns = manifest
        .get("workspace")
        .and_then(|w| w.get("members"))
        .and_then(Value::as_array)
        .expect("the root Cargo.toml lists [workspace] members");
    let mut members = Vec::new();
    for pattern in patterns {
        let pattern = pattern.as_str().expect("a member is a string");
        if let Some(parent) = pattern.strip_suffix("/*") {
            let dir = root.join(parent);
            for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
                let path = entry.expect("a directory entry").path();
                if path.join("Cargo.toml").is_file() {
                    let name = path.file_name().expect("a name").to_string_lossy().into_owned();
                    members.push(format!("{parent}/{name}"));
                }
            }
        } else {
            assert!(
                !pattern.contains('*'),
                "{pattern}: only a trailing /* is understood here"
            );
            members.push(pattern.to_owned());
        }
    }
    members.sort();
    members
}

/// The bans of one configuration file: path → reason, checked to be well formed.
fn bans(file: &Path, table: &Table) -> BTreeMap<String, String> {
    let mut bans = BTreeMap::new();
    for key in BAN_KEYS {
        let Some(list) = table.get(*key) else { continue };
        let list = list
            .as_array()
            .unwrap_or_else(|| panic!("{}: {key} is no list", file.display()));
        for entry in list {
            let path = entry.get("path").and_then(Value::as_str);
            let reason = entry.get("reason").and_then(Value::as_str);
            let (Some(path), Some(reason)) = (path, reason) else {
                panic!("{}: {key}: {entry} needs a path and a reason", file.display());
            };
            assert!(
                !reason.trim().is_empty(),
                "{}: {path} gives no reason",
                file.display()
            );
            let earlier = bans.insert(path.to_owned(), reason.to_owned());
            assert!(earlier.is_none(), "{}: {path} is banned twice", file.display());
        }
    }
    bans
}

/// The settings of a configuration file: everything but its bans.
fn settings(table: &Table) -> Table {
    let mut table = table.clone();
    for key in BAN_KEYS {
        table.remove(*key);
    }
    table
}

fn lift_of(member: &str) -> Option<&'static Lift> {
    LIFTS.iter().find(|lift| lift.member == member)
}

/// What is wrong with `member`'s own configuration `table` (read from `file`) against the root's.
fn member_problems(member: &str, file: &Path, root_table: &Table, table: &Table) -> Vec<String> {
    let mut problems = Vec::new();
    let root_bans = bans(file, root_table);
    let kept = bans(file, table);
    if settings(table) != settings(root_table) {
        problems.push(format!(
            "{member}: its settings {:?} differ from the root's {:?}",
            settings(table),
            settings(root_table)
        ));
    }
    let dropped: BTreeSet<&str> = root_bans
        .keys()
        .filter(|ban| !kept.contains_key(*ban))
        .map(String::as_str)
        .collect();
    match lift_of(member).map(|lift| &lift.lifted) {
        Some(Lifted::Everything) => {}
        Some(Lifted::These(lifted)) => {
            let lifted: BTreeSet<&str> = lifted.iter().flat_map(|group| group.iter().copied()).collect();
            for ban in dropped.difference(&lifted) {
                problems.push(format!(
                    "{member}: drops the root's ban on {ban}, which LIFTS does not lift"
                ));
            }
            for ban in lifted.difference(&dropped) {
                problems.push(format!(
                    "{member}: LIFTS lifts {ban}, but its clippy.toml keeps it"
                ));
            }
        }
        None => {
            for ban in &dropped {
                problems.push(format!(
                    "{member}: its clippy.toml drops the root's ban on {ban}; keep it, or add a LIFTS row \
                     with the reason"
                ));
            }
        }
    }
    problems
}

#[test]
fn every_member_keeps_the_root_bans_except_those_it_lifts_with_a_reason() {
    let root = workspace_root();
    let root_file = config_in(&root).expect("the workspace root has a clippy.toml");
    let root_table = read_table(&root_file);
    let root_bans = bans(&root_file, &root_table);
    assert!(
        root_bans.contains_key("std::time::Instant::now")
            && root_bans.contains_key("std::path::Path::exists"),
        "the root's sans-IO bans are missing: {root_bans:?}"
    );
    let members = members(&root);
    assert!(
        members.len() >= 20 && members.iter().any(|m| m == "crates/canopener-cli"),
        "found only {members:?}"
    );
    let mut problems = Vec::new();
    let mut inheriting = 0;
    for member in &members {
        // Clippy walks up from the member's directory; a file between it and the root would apply too.
        let mut dir = root.join(member);
        let own = config_in(&dir);
        while let Some(parent) = dir.parent().map(Path::to_path_buf) {
            if parent == root {
                break;
            }
            if let Some(between) = config_in(&parent) {
                problems.push(format!(
                    "{}: replaces the root's bans for {member}",
                    between.display()
                ));
            }
            dir = parent;
        }
        let Some(own) = own else {
            inheriting += 1;
            if lift_of(member).is_some() {
                problems.push(format!(
                    "{member}: LIFTS has a row for it, but it has no clippy.toml"
                ));
            }
            continue;
        };
        problems.extend(member_problems(member, &own, &root_table, &read_table(&own)));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(
        inheriting >= 10,
        "only {inheriting} members inherit the root's clippy.toml"
    );
}

#[test]
fn every_lift_names_a_member_root_bans_and_a_reason() {
    let root = workspace_root();
    let root_file = config_in(&root).expect("the workspace root has a clippy.toml");
    let root_bans = bans(&root_file, &read_table(&root_file));
    let members = members(&root);
    let mut seen = BTreeSet::new();
    for lift in LIFTS {
        assert!(seen.insert(lift.member), "{}: two LIFTS rows", lift.member);
        assert!(
            members.iter().any(|m| m == lift.member),
            "{}: no such member",
            lift.member
        );
        assert!(
            lift.reason.len() > 20,
            "{}: say why it may lift bans",
            lift.member
        );
        if let Lifted::These(lifted) = lift.lifted {
            assert!(!lifted.is_empty(), "{}: a row that lifts nothing", lift.member);
            for ban in lifted.iter().flat_map(|group| group.iter()) {
                assert!(
                    root_bans.contains_key(*ban),
                    "{}: {ban} is no ban of the root's",
                    lift.member
                );
            }
        }
    }
}

/// A clippy.toml banning `paths`, and allowing prints in tests when `print_in_tests`.
fn config(paths: &[&str], print_in_tests: bool) -> Table {
    let bans: Vec<String> = paths
        .iter()
        .map(|path| format!("{{ path = \"{path}\", reason = \"a reason\" }}"))
        .collect();
    let mut text = format!("disallowed-methods = [{}]\n", bans.join(", "));
    if print_in_tests {
        text.push_str("allow-print-in-tests = true\n");
    }
    text.parse().expect("valid TOML")
}

/// The comparison itself can fail: a member file that drops a ban, lifts one LIFTS does not name or
/// changes a setting is caught; one that adds a ban is not; an IO edge may drop anything.
/// The library crates that may panic on a `None`, an `Err` or an index outside tests, and why.
const PANICKING_LIBRARIES: &[(&str, &str)] = &[(
    "crates/canopener-testkit",
    "test support: its helpers panic on purpose, with the failure's message, as assertions do",
)];

/// The crate-level attribute that turns the three panicking lints into errors outside tests.
fn denies_panics_outside_tests(lib_rs: &str) -> bool {
    let flat: String = lib_rs.split_whitespace().collect();
    const OPENING: &str = "#![cfg_attr(not(test),deny(";
    let Some(start) = flat.find(OPENING) else {
        return false;
    };
    let list = flat[start + OPENING.len()..].split(')').next().unwrap_or("");
    [
        "clippy::unwrap_used",
        "clippy::expect_used",
        "clippy::indexing_slicing",
    ]
    .iter()
    .all(|lint| list.contains(lint))
}

#[test]
fn every_library_denies_unwrap_expect_and_indexing_outside_tests() {
    let root = workspace_root();
    let mut missing = Vec::new();
    for member in members(&root) {
        let lib = root.join(&member).join("src/lib.rs");
        if !lib.is_file() || PANICKING_LIBRARIES.iter().any(|(m, _)| *m == member) {
            continue;
        }
        let text = std::fs::read_to_string(&lib).unwrap_or_else(|e| panic!("{}: {e}", lib.display()));
        if !denies_panics_outside_tests(&text) {
            missing.push(member);
        }
    }
    assert!(
        missing.is_empty(),
        "these libraries lack #![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used, \
         clippy::indexing_slicing))], or a PANICKING_LIBRARIES row with the reason: {missing:?}"
    );
    assert!(denies_panics_outside_tests(
        "#![cfg_attr(\n    not(test),\n    deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)\n)]"
    ));
    assert!(!denies_panics_outside_tests(
        "#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]"
    ));
}

#[test]
fn a_dropped_ban_is_caught_and_an_added_one_is_allowed() {
    const READ: &str = "std::fs::read";
    const EXISTS: &str = "std::path::Path::exists";
    let root = config(&[READ, EXISTS], true);
    let keeps_and_adds = config(&[READ, EXISTS, "canopener_transport::WallClock::now"], true);
    let drops_one = config(&[READ], true);
    let other_setting = config(&[READ, EXISTS], false);
    let file = Path::new("example/clippy.toml");
    assert_eq!(
        member_problems("crates/canopener-cli", file, &root, &keeps_and_adds),
        Vec::<String>::new()
    );
    let dropped = member_problems("crates/canopener-cli", file, &root, &drops_one);
    assert_eq!(dropped.len(), 1, "{dropped:?}");
    assert!(dropped[0].contains("std::path::Path::exists"), "{dropped:?}");
    // The test kit lifts std::fs::read, so keeping it is a stale lift and dropping Path::exists is fine.
    let testkit = member_problems("crates/canopener-testkit", file, &root, &drops_one);
    assert!(
        testkit.iter().any(|p| p.contains("LIFTS lifts std::fs::read")),
        "{testkit:?}"
    );
    assert!(!testkit.iter().any(|p| p.contains("Path::exists")), "{testkit:?}");
    assert_eq!(
        member_problems("crates/canopener-hub", file, &root, &drops_one),
        Vec::<String>::new()
    );
    let settings = member_problems("crates/canopener-cli", file, &root, &other_setting);
    assert!(
        settings.len() == 1 && settings[0].contains("settings"),
        "{settings:?}"
    );
}
