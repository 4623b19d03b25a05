//! The run history and the uploaded descriptions, in SQLite (`rusqlite`): `DATA/canopener.sqlite`
//! with `--data DIR`, else an in-memory database that lives as long as the server (nothing is
//! written to disk without `--data`). Schema version in `PRAGMA user_version`.

use std::path::Path;
use std::sync::{Mutex, PoisonError};

use rusqlite::{Connection, OptionalExtension, params};
use serde::Serialize;

/// The database file under `--data`.
pub const FILE: &str = "canopener.sqlite";
const SCHEMA_VERSION: i64 = 1;

/// Why the store failed.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// SQLite said so.
    #[error("run history {where_}: {source}")]
    Sql {
        /// The database.
        where_: String,
        /// SQLite's reason.
        #[source]
        source: rusqlite::Error,
    },
    /// A database of a newer canopener.
    #[error("run history {0}: written by a newer canopener (schema {1}); use that version or another --data")]
    Newer(String, i64),
}

/// A run as the history lists it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunRow {
    /// Its number.
    pub id: i64,
    /// When it started (RFC 3339).
    pub started: String,
    /// `running`, `done`, `interrupted`, `silent` (the device did not answer) or `failed`.
    pub status: String,
    /// Why it failed or was interrupted.
    pub message: Option<String>,
    /// The node under test.
    pub node: u8,
    /// The bus (a spec, or `simulated`).
    pub bus: String,
    /// The description's name.
    pub eds: String,
    /// The device as the history groups runs: product and vendor from the description, and the
    /// identity (1018h) when it was read.
    pub device: String,
    /// 1018h:03 as read, the firmware's revision.
    pub revision: Option<String>,
    /// The simulated device's fault, if any.
    pub fault: Option<String>,
    /// The suites run, comma-separated.
    pub suites: String,
    /// Passes a criterion or a CiA requirement decided.
    pub pass: i64,
    /// Measurements judged against no criterion: reported apart, never as conformance passes.
    pub measured: i64,
    /// Failed.
    pub fail: i64,
    /// Undecided.
    pub inconclusive: i64,
    /// Not applicable.
    pub not_applicable: i64,
}

/// A new run's facts before it starts.
#[derive(Debug, Clone)]
pub struct NewRun<'a> {
    /// RFC 3339.
    pub started: &'a str,
    /// The node.
    pub node: u8,
    /// The bus.
    pub bus: &'a str,
    /// The description's name.
    pub eds: &'a str,
    /// The device, from the description.
    pub device: &'a str,
    /// The simulated device's fault.
    pub fault: Option<&'a str>,
    /// The suites.
    pub suites: &'a str,
}

/// How a run ended.
#[derive(Debug, Clone)]
pub struct Ended<'a> {
    /// `done`, `interrupted`, `silent` or `failed`.
    pub status: &'a str,
    /// Why, for failures.
    pub message: Option<&'a str>,
    /// The device with its identity, when read.
    pub device: Option<&'a str>,
    /// The revision read.
    pub revision: Option<&'a str>,
    /// Verdict counts: pass (decided by a criterion or a CiA requirement), measured with no
    /// criterion, fail, inconclusive, not applicable.
    pub counts: [usize; 5],
    /// The report as JSON (version 1) and as the HTML page.
    pub report: Option<(&'a str, &'a str)>,
}

/// A stored description.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct StoredDescription {
    /// Its SHA-256, the key.
    pub sha256: String,
    /// The name it was uploaded under.
    pub name: String,
}

/// The store (see the [module docs](self)).
#[derive(Debug)]
pub struct Store {
    connection: Mutex<Connection>,
    place: String,
}

impl Store {
    /// Opens (creating) `DATA/canopener.sqlite`, or an in-memory store without `data`.
    pub fn open(data: Option<&Path>) -> Result<Store, StoreError> {
        let place = data.map_or_else(
            || "(in memory)".to_owned(),
            |d| d.join(FILE).display().to_string(),
        );
        let sql = |source| StoreError::Sql {
            where_: place.clone(),
            source,
        };
        let connection = match data {
            Some(dir) => Connection::open(dir.join(FILE)),
            None => Connection::open_in_memory(),
        }
        .map_err(sql)?;
        let version: i64 = connection
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .map_err(sql)?;
        if version > SCHEMA_VERSION {
            return Err(StoreError::Newer(place, version));
        }
        connection
            .execute_batch(
                "PRAGMA journal_mode = WAL;
                 CREATE TABLE IF NOT EXISTS runs (
                    id INTEGER PRIMARY KEY,
                    started TEXT NOT NULL,
                    status TEXT NOT NULL,
                    message TEXT,
                    node INTEGER NOT NULL,
                    bus TEXT NOT NULL,
                    eds TEXT NOT NULL,
                    device TEXT NOT NULL,
                    revision TEXT,
                    fault TEXT,
                    suites TEXT NOT NULL,
                    pass INTEGER NOT NULL DEFAULT 0,
                    fail INTEGER NOT NULL DEFAULT 0,
                    inconclusive INTEGER NOT NULL DEFAULT 0,
                    not_applicable INTEGER NOT NULL DEFAULT 0,
                    measured INTEGER NOT NULL DEFAULT 0,
                    report_json TEXT,
                    report_html TEXT);
                 CREATE INDEX IF NOT EXISTS runs_by_device ON runs (device, started);
                 CREATE TABLE IF NOT EXISTS descriptions (
                    sha256 TEXT PRIMARY KEY,
                    name TEXT NOT NULL,
                    bytes BLOB NOT NULL);
                 PRAGMA user_version = 1;",
            )
            .map_err(sql)?;
        // A history written before the "measured, no criterion" count had no column for it.
        let has_measured = connection
            .prepare("SELECT 1 FROM pragma_table_info('runs') WHERE name = 'measured'")
            .and_then(|mut q| q.exists([]))
            .map_err(sql)?;
        if !has_measured {
            connection
                .execute(
                    "ALTER TABLE runs ADD COLUMN measured INTEGER NOT NULL DEFAULT 0",
                    [],
                )
                .map_err(sql)?;
        }
        // A run that was running when an earlier server stopped without ending it.
        connection
            .execute(
                "UPDATE runs SET status = 'interrupted', message = 'the server stopped during the run' \
                 WHERE status = 'running'",
                [],
            )
            .map_err(sql)?;
        Ok(Store {
            connection: Mutex::new(connection),
            place,
        })
    }

    fn with<T>(&self, f: impl FnOnce(&Connection) -> rusqlite::Result<T>) -> Result<T, StoreError> {
        let connection = self.connection.lock().unwrap_or_else(PoisonError::into_inner);
        f(&connection).map_err(|source| StoreError::Sql {
            where_: self.place.clone(),
            source,
        })
    }

    /// Records a run that starts now; returns its number.
    pub fn begin(&self, run: &NewRun<'_>) -> Result<i64, StoreError> {
        self.with(|c| {
            c.execute(
                "INSERT INTO runs (started, status, node, bus, eds, device, fault, suites) \
                 VALUES (?1, 'running', ?2, ?3, ?4, ?5, ?6, ?7)",
                params![
                    run.started,
                    run.node,
                    run.bus,
                    run.eds,
                    run.device,
                    run.fault,
                    run.suites
                ],
            )?;
            Ok(c.last_insert_rowid())
        })
    }

    /// Records how run `id` ended.
    pub fn end(&self, id: i64, ended: &Ended<'_>) -> Result<(), StoreError> {
        let [pass, measured, fail, inconclusive, not_applicable] =
            ended.counts.map(|n| i64::try_from(n).unwrap_or(i64::MAX));
        self.with(|c| {
            c.execute(
                "UPDATE runs SET status = ?2, message = ?3, device = COALESCE(?4, device), revision = ?5, \
                 pass = ?6, fail = ?7, inconclusive = ?8, not_applicable = ?9, report_json = ?10, \
                 report_html = ?11, measured = ?12 WHERE id = ?1",
                params![
                    id,
                    ended.status,
                    ended.message,
                    ended.device,
                    ended.revision,
                    pass,
                    fail,
                    inconclusive,
                    not_applicable,
                    ended.report.map(|r| r.0),
                    ended.report.map(|r| r.1),
                    measured
                ],
            )?;
            Ok(())
        })
    }

    /// Every run, by device and then newest first.
    pub fn list(&self) -> Result<Vec<RunRow>, StoreError> {
        self.with(|c| {
            let mut statement = c.prepare(&format!(
                "SELECT {COLUMNS} FROM runs ORDER BY device, started DESC, id DESC"
            ))?;
            let rows = statement.query_map([], row)?;
            rows.collect()
        })
    }

    /// One run.
    pub fn get(&self, id: i64) -> Result<Option<RunRow>, StoreError> {
        self.with(|c| {
            c.query_row(&format!("SELECT {COLUMNS} FROM runs WHERE id = ?1"), [id], row)
                .optional()
        })
    }

    /// A run's report: `json` or `html`.
    pub fn report(&self, id: i64, html: bool) -> Result<Option<String>, StoreError> {
        let column = if html { "report_html" } else { "report_json" };
        self.with(|c| {
            c.query_row(&format!("SELECT {column} FROM runs WHERE id = ?1"), [id], |r| {
                r.get(0)
            })
            .optional()
            .map(Option::flatten)
        })
    }

    /// The run of the same device before run `id` that has a report (what "since the last firmware"
    /// compares with).
    pub fn previous(&self, id: i64) -> Result<Option<i64>, StoreError> {
        self.with(|c| {
            c.query_row(
                "SELECT p.id FROM runs p JOIN runs r ON r.id = ?1 \
                 WHERE p.device = r.device AND p.id < r.id AND p.report_json IS NOT NULL \
                 ORDER BY p.id DESC LIMIT 1",
                [id],
                |r| r.get(0),
            )
            .optional()
        })
    }

    /// Keeps a description; returns its key.
    pub fn put_description(&self, name: &str, bytes: &[u8]) -> Result<String, StoreError> {
        use sha2::Digest;
        let sha: String = sha2::Sha256::digest(bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        self.with(|c| {
            c.execute(
                "INSERT INTO descriptions (sha256, name, bytes) VALUES (?1, ?2, ?3) \
                 ON CONFLICT (sha256) DO UPDATE SET name = excluded.name",
                params![sha, name, bytes],
            )?;
            Ok(())
        })?;
        Ok(sha)
    }

    /// A kept description: name and bytes.
    pub fn description(&self, sha256: &str) -> Result<Option<(String, Vec<u8>)>, StoreError> {
        self.with(|c| {
            c.query_row(
                "SELECT name, bytes FROM descriptions WHERE sha256 = ?1",
                [sha256],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .optional()
        })
    }

    /// Every kept description, by name.
    pub fn descriptions(&self) -> Result<Vec<StoredDescription>, StoreError> {
        self.with(|c| {
            let mut statement = c.prepare("SELECT sha256, name FROM descriptions ORDER BY name, sha256")?;
            let rows = statement.query_map([], |r| {
                Ok(StoredDescription {
                    sha256: r.get(0)?,
                    name: r.get(1)?,
                })
            })?;
            rows.collect()
        })
    }
}

const COLUMNS: &str = "id, started, status, message, node, bus, eds, device, revision, fault, suites, \
                       pass, fail, inconclusive, not_applicable, measured";

fn row(r: &rusqlite::Row<'_>) -> rusqlite::Result<RunRow> {
    Ok(RunRow {
        id: r.get(0)?,
        started: r.get(1)?,
        status: r.get(2)?,
        message: r.get(3)?,
        node: r.get(4)?,
        bus: r.get(5)?,
        eds: r.get(6)?,
        device: r.get(7)?,
        revision: r.get(8)?,
        fault: r.get(9)?,
        suites: r.get(10)?,
        pass: r.get(11)?,
        fail: r.get(12)?,
        inconclusive: r.get(13)?,
        not_applicable: r.get(14)?,
        measured: r.get(15)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn new_run<'a>(device: &'a str, started: &'a str) -> NewRun<'a> {
        NewRun {
            started,
            node: 5,
            bus: "simulated",
            eds: "io.eds",
            device,
            fault: None,
            suites: "cia301",
        }
    }

    #[test]
    fn runs_are_listed_by_device_and_date_and_compared_with_the_previous_of_their_device() {
        let store = Store::open(None).unwrap();
        let a1 = store.begin(&new_run("A", "2026-01-01T10:00:00Z")).unwrap();
        let b1 = store.begin(&new_run("B", "2026-01-01T11:00:00Z")).unwrap();
        let a2 = store.begin(&new_run("A", "2026-01-02T10:00:00Z")).unwrap();
        assert_eq!(store.get(a2).unwrap().unwrap().status, "running");
        let ended = |status| Ended {
            status,
            message: None,
            device: None,
            revision: Some("0x00010002"),
            counts: [3, 1, 1, 0, 2],
            report: Some(("{}", "<html></html>")),
        };
        store.end(a1, &ended("done")).unwrap();
        store.end(b1, &ended("done")).unwrap();
        assert_eq!(store.previous(a2).unwrap(), Some(a1));
        assert_eq!(store.previous(b1).unwrap(), None);
        let order: Vec<(String, i64)> = store
            .list()
            .unwrap()
            .into_iter()
            .map(|r| (r.device, r.id))
            .collect();
        assert_eq!(
            order,
            [("A".to_owned(), a2), ("A".to_owned(), a1), ("B".to_owned(), b1)]
        );
        let done = store.get(a1).unwrap().unwrap();
        assert_eq!(
            (done.pass, done.measured, done.fail, done.not_applicable),
            (3, 1, 1, 2)
        );
        assert_eq!(store.report(a1, true).unwrap().as_deref(), Some("<html></html>"));
        assert_eq!(store.report(a2, false).unwrap(), None);
    }

    #[test]
    fn descriptions_are_kept_by_content() {
        let store = Store::open(None).unwrap();
        let key = store.put_description("io.eds", b"[FileInfo]\n").unwrap();
        assert_eq!(key.len(), 64);
        assert_eq!(
            store.put_description("renamed.eds", b"[FileInfo]\n").unwrap(),
            key
        );
        assert_eq!(
            store.description(&key).unwrap(),
            Some(("renamed.eds".to_owned(), b"[FileInfo]\n".to_vec()))
        );
        assert_eq!(store.descriptions().unwrap().len(), 1);
        assert_eq!(store.description("nope").unwrap(), None);
    }

    /// A history written before the "measured, no criterion" column opens, and its runs read with 0.
    #[test]
    fn a_history_without_the_measured_column_gains_it() {
        let dir = std::env::temp_dir().join(format!("canopener-web-store-{}", std::process::id()));
        canopener_files::create_dir_all(&dir).unwrap();
        {
            let old = Connection::open(dir.join(FILE)).unwrap();
            old.execute_batch(
                "CREATE TABLE runs (id INTEGER PRIMARY KEY, started TEXT NOT NULL, status TEXT NOT NULL,
                    message TEXT, node INTEGER NOT NULL, bus TEXT NOT NULL, eds TEXT NOT NULL,
                    device TEXT NOT NULL, revision TEXT, fault TEXT, suites TEXT NOT NULL,
                    pass INTEGER NOT NULL DEFAULT 0, fail INTEGER NOT NULL DEFAULT 0,
                    inconclusive INTEGER NOT NULL DEFAULT 0, not_applicable INTEGER NOT NULL DEFAULT 0,
                    report_json TEXT, report_html TEXT);
                 INSERT INTO runs (started, status, node, bus, eds, device, suites, pass)
                    VALUES ('2026-01-01T00:00:00Z', 'done', 5, 'simulated', 'io.eds', 'A', 'cia301', 7);
                 PRAGMA user_version = 1;",
            )
            .unwrap();
        }
        let store = Store::open(Some(&dir)).unwrap();
        let runs = store.list().unwrap();
        assert_eq!(
            runs.iter().map(|r| (r.pass, r.measured)).collect::<Vec<_>>(),
            [(7, 0)]
        );
        drop(store);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
