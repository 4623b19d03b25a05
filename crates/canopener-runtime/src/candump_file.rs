//! candump log files on disk: reading one whole (for replay and offline decoding) and writing one as
//! frames arrive (for a live capture), never clobbering an existing log unless asked to.

use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use canopener_can::candump::{LogRecord, write_record};

/// A candump log could not be read.
#[derive(Debug, thiserror::Error)]
#[error("cannot read {}: {source}", path.display())]
pub struct ReadLogError {
    /// The file.
    pub path: PathBuf,
    /// The operating system's reason.
    #[source]
    pub source: io::Error,
}

/// A candump log could not be created or written.
#[derive(Debug, thiserror::Error)]
pub enum LogFileError {
    /// The file exists and overwriting it was not allowed.
    #[error("log file {} already exists", path.display())]
    Exists {
        /// The file.
        path: PathBuf,
        /// Always of kind [`io::ErrorKind::AlreadyExists`]; kept so front ends can report it as such.
        #[source]
        source: io::Error,
    },
    /// The file could not be created.
    #[error("cannot create log file {}: {source}", path.display())]
    Create {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: io::Error,
    },
    /// Writing or flushing the file failed; what was flushed before is in it.
    #[error("cannot write {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        #[source]
        source: io::Error,
    },
}

/// The text of the candump log at `path`. Logs are ASCII; a stray non-UTF-8 byte becomes U+FFFD, so the
/// parser reports its line instead of the whole file being refused.
pub fn read_log(path: &Path) -> Result<String, ReadLogError> {
    let bytes = std::fs::read(path).map_err(|source| ReadLogError {
        path: path.to_owned(),
        source,
    })?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// A candump log being written record by record. Records are buffered; [`LogWriter::flush`] (and
/// dropping the writer) puts them on disk.
#[derive(Debug)]
pub struct LogWriter {
    file: BufWriter<File>,
    path: PathBuf,
    line: String,
}

impl LogWriter {
    /// Refuses a `path` that already exists, unless `overwrite`. Checking before anything else is set up
    /// (a bus opened, a hub connected) reports the mistake early; [`LogWriter::create`] still refuses
    /// atomically should the file appear in between.
    pub fn check_free(path: &Path, overwrite: bool) -> Result<(), LogFileError> {
        if !overwrite && path.exists() {
            return Err(LogFileError::Exists {
                path: path.to_owned(),
                source: io::Error::from(io::ErrorKind::AlreadyExists),
            });
        }
        Ok(())
    }

    /// Creates the log at `path`; an existing file is truncated with `overwrite` and refused without it.
    pub fn create(path: &Path, overwrite: bool) -> Result<LogWriter, LogFileError> {
        let mut options = OpenOptions::new();
        options.write(true);
        if overwrite {
            options.create(true).truncate(true);
        } else {
            // create_new refuses atomically if the file appeared meanwhile: an existing log is never clobbered.
            options.create_new(true);
        }
        let path = path.to_owned();
        match options.open(&path) {
            Ok(file) => Ok(LogWriter {
                file: BufWriter::new(file),
                path,
                line: String::new(),
            }),
            Err(source) if source.kind() == io::ErrorKind::AlreadyExists => {
                Err(LogFileError::Exists { path, source })
            }
            Err(source) => Err(LogFileError::Create { path, source }),
        }
    }

    /// Appends one record as a candump line.
    pub fn write(&mut self, record: &LogRecord) -> Result<(), LogFileError> {
        self.line.clear();
        // write_record ends the line itself.
        write_record(&mut self.line, record);
        self.file
            .write_all(self.line.as_bytes())
            .map_err(|source| self.write_error(source))
    }

    /// Puts every record written so far into the file.
    pub fn flush(&mut self) -> Result<(), LogFileError> {
        self.file.flush().map_err(|source| self.write_error(source))
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn write_error(&self, source: io::Error) -> LogFileError {
        LogFileError::Write {
            path: self.path.clone(),
            source,
        }
    }
}

#[cfg(test)]
mod tests {
    use canopener_can::candump::{LogEvent, parse_log};
    use canopener_can::{CanFrame, Instant, StandardId};

    use super::*;

    fn temp_dir(name: &str) -> canopener_testkit::fixture::ScratchDir {
        canopener_testkit::fixture::ScratchDir::new(&format!("runtime-{name}"))
    }

    fn record(id: u16, data: &[u8]) -> LogRecord {
        LogRecord {
            timestamp: Instant::from_nanos(1_700_000_000_123_456_000),
            interface: "can0".into(),
            event: LogEvent::Frame(CanFrame::new(StandardId::new(id).unwrap(), data).unwrap()),
        }
    }

    #[test]
    fn written_records_read_back_as_the_same_log() {
        let dir = temp_dir("log-roundtrip");
        let path = dir.join("capture.log");
        let mut writer = LogWriter::create(&path, false).unwrap();
        writer.write(&record(0x701, &[0x05])).unwrap();
        writer.write(&record(0x000, &[0x01, 0x05])).unwrap();
        writer.flush().unwrap();
        assert_eq!(writer.path(), path);
        let text = read_log(&path).unwrap();
        assert_eq!(
            text,
            "(1700000000.123456) can0 701#05\n(1700000000.123456) can0 000#0105\n"
        );
        let (records, errors) = parse_log(&text);
        assert!(errors.is_empty());
        assert_eq!(records[1].1, record(0x000, &[0x01, 0x05]));
    }

    #[test]
    fn an_existing_log_is_kept_unless_overwriting() {
        let dir = temp_dir("log-exists");
        let path = dir.join("capture.log");
        std::fs::write(&path, "old").unwrap();
        let refused = LogWriter::check_free(&path, false).unwrap_err();
        assert!(matches!(refused, LogFileError::Exists { .. }), "{refused}");
        let refused = LogWriter::create(&path, false).unwrap_err();
        assert!(
            matches!(&refused, LogFileError::Exists { source, .. } if source.kind() == io::ErrorKind::AlreadyExists)
        );
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        LogWriter::check_free(&path, true).unwrap();
        LogWriter::create(&path, true).unwrap().flush().unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "");
    }

    #[test]
    fn missing_files_and_directories_are_errors_naming_the_path() {
        let dir = temp_dir("log-missing");
        let err = read_log(&dir.join("none.log")).unwrap_err();
        assert!(err.to_string().starts_with("cannot read "), "{err}");
        assert_eq!(err.source.kind(), io::ErrorKind::NotFound);
        let err = LogWriter::create(&dir.join("no/such/dir.log"), false).unwrap_err();
        assert!(matches!(err, LogFileError::Create { .. }), "{err}");
    }

    #[test]
    fn bytes_that_are_not_utf8_do_not_refuse_the_file() {
        let dir = temp_dir("log-lossy");
        let path = dir.join("odd.log");
        std::fs::write(&path, b"(1.000000) can0 123#00\n\xFF\n").unwrap();
        let text = read_log(&path).unwrap();
        assert!(text.starts_with("(1.000000) can0 123#00\n"));
        assert!(text.contains('\u{FFFD}'));
    }
}
